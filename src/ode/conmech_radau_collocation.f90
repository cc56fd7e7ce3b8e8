!> The collocation polynomial of a Radau IIA step (degree 3, power basis of
!! x = (s - t)/h): its coefficients from the stage increments, and its extrapolation to
!! the nodes of the next step (the Newton starting values). Dense output and events
!! evaluate it as the stepper's continuous extension (conmech_ode_dense's power form).
module conmech_radau_collocation
    use conmech_kinds, only: dp
    use conmech_radau_coefficients, only: C1, C2
    use conmech_ode_dense, only: power_basis_matrix
    implicit none
    private

    public :: radau_collocation_basis, radau_collocation_update, radau_extrapolate

contains

    !> The nodes cvec = (c1, c2, 1) and the matrix pmat taking the stage increments
    !! (z1, z2, z3) to the power-basis coefficients fc(:, 1:3).
    pure subroutine radau_collocation_basis(cvec, pmat)
        real(dp), intent(out) :: cvec(3)
        real(dp), intent(out) :: pmat(3, 3)
        cvec = [C1, C2, 1.0_dp]
        pmat = power_basis_matrix(cvec)
    end subroutine radau_collocation_basis

    !> The collocation polynomial u(x) = sum_j fc(:, j) x^j of the step from y with the
    !! stage increments z1, z2, z3.
    pure subroutine radau_collocation_update(pmat, y, z1, z2, z3, fc)
        real(dp), intent(in) :: pmat(3, 3)
        real(dp), contiguous, intent(in) :: y(:), z1(:), z2(:), z3(:)
        real(dp), contiguous, intent(inout) :: fc(:, 0:)
        integer :: j
        fc(:, 0) = y
        do j = 1, 3
            fc(:, j) = pmat(j, 1)*z1 + pmat(j, 2)*z2 + pmat(j, 3)*z3
        end do
    end subroutine radau_collocation_update

    !> Starting stage increments of the next step (ratio = h_new/h_old): u(xi) - u(1) at
    !! xi = 1 + c_i ratio, the previous polynomial extrapolated.
    pure subroutine radau_extrapolate(fc, cvec, ratio, z1, z2, z3)
        real(dp), contiguous, intent(in) :: fc(:, 0:)
        real(dp), intent(in) :: cvec(3)
        real(dp), intent(in) :: ratio
        real(dp), contiguous, intent(inout) :: z1(:), z2(:), z3(:)
        real(dp) :: xi
        xi = 1.0_dp + cvec(1)*ratio
        z1 = fc(:, 1)*(xi - 1.0_dp) + fc(:, 2)*(xi**2 - 1.0_dp) + fc(:, 3)*(xi**3 - 1.0_dp)
        xi = 1.0_dp + cvec(2)*ratio
        z2 = fc(:, 1)*(xi - 1.0_dp) + fc(:, 2)*(xi**2 - 1.0_dp) + fc(:, 3)*(xi**3 - 1.0_dp)
        xi = 1.0_dp + cvec(3)*ratio
        z3 = fc(:, 1)*(xi - 1.0_dp) + fc(:, 2)*(xi**2 - 1.0_dp) + fc(:, 3)*(xi**3 - 1.0_dp)
    end subroutine radau_extrapolate

end module conmech_radau_collocation
