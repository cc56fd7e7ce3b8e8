!> Transverse models (`transverse_model`) of conmech's mechanical systems.
!!
!! - `generalized_model`: a system in generalized coordinates, x = [q, v]; its energy
!!   (when it defines one) for the reduction.
!! - `constrained_model`: a system in excessive coordinates, x = [q, v], integrated in the
!!   index-1 form (`constrained_ode`). The motion lies on the invariant manifold
!!   phi(q) = 0, G(q) v = 0, A(q) v + b(q) = 0, whose normals are the rows
!!
!!       [G, 0],   [d(G v)/dq, G],   [d(A v + b)/dq, A]
!!
!!   (2 n_hol + n_nh rows). d(G v)/dq and d(A v + b)/dq are fourth-order central
!!   differences of G and A, b (step eps^(1/5) max(|q_j|, 1)). Rheonomic constraints make
!!   the system non-autonomous: refused by the callers.
module conmech_transverse_mech
    use conmech_kinds, only: dp
    use conmech_generalized, only: generalized_system
    use conmech_constrained_system, only: constrained_system
    use conmech_transverse_model, only: transverse_model
    implicit none
    private
    public :: generalized_model, constrained_model

    !> A generalized-coordinate system's energy.
    type, extends(transverse_model) :: generalized_model
        class(generalized_system), allocatable :: mech
    contains
        procedure :: has_energy => gm_has_energy
        procedure :: energy => gm_energy
    end type generalized_model

    !> A constrained system's manifold normals and energy.
    type, extends(transverse_model) :: constrained_model
        class(constrained_system), allocatable :: mech
    contains
        procedure :: n_normals => cm_n_normals
        procedure :: normals => cm_normals
        procedure :: has_energy => cm_has_energy
        procedure :: energy => cm_energy
    end type constrained_model

contains

    logical function gm_has_energy(self)
        class(generalized_model), intent(in) :: self
        gm_has_energy = self%mech%has_energy()
    end function gm_has_energy

    real(dp) function gm_energy(self, t, x) result(e)
        class(generalized_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        integer :: nd
        nd = self%mech%ndof
        e = self%mech%energy(t, x(1:nd), x(nd + 1:2*nd))
    end function gm_energy

    integer function cm_n_normals(self)
        class(constrained_model), intent(in) :: self
        cm_n_normals = 2*self%mech%n_hol + self%mech%n_nh
    end function cm_n_normals

    subroutine cm_normals(self, t, x, c)
        class(constrained_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        real(dp), intent(out) :: c(:, :)
        real(dp), parameter :: off(4) = [2.0_dp, 1.0_dp, -1.0_dp, -2.0_dp]
        real(dp), parameter :: wt(4) = [-1.0_dp, 8.0_dp, -8.0_dp, 1.0_dp]
        real(dp) :: q(self%mech%n), v(self%mech%n), qp(self%mech%n)
        real(dp) :: g(max(self%mech%n_hol, 1), self%mech%n)
        real(dp) :: a(max(self%mech%n_nh, 1), self%mech%n), b(max(self%mech%n_nh, 1))
        real(dp) :: h
        integer :: n, mh, mn, j, i
        n = self%mech%n
        mh = self%mech%n_hol
        mn = self%mech%n_nh
        q = x(1:n)
        v = x(n + 1:2*n)
        c(1:2*mh + mn, :) = 0.0_dp
        if (mh > 0) then
            call self%mech%phi_jac(t, q, g(1:mh, :))
            c(1:mh, 1:n) = g(1:mh, :)
            c(mh + 1:2*mh, n + 1:2*n) = g(1:mh, :)
        end if
        if (mn > 0) then
            call self%mech%nh_matrix(t, q, a(1:mn, :), b(1:mn))
            c(2*mh + 1:2*mh + mn, n + 1:2*n) = a(1:mn, :)
        end if
        qp = q
        do j = 1, n
            h = epsilon(1.0_dp)**0.2_dp*max(abs(q(j)), 1.0_dp)
            do i = 1, 4
                qp(j) = q(j) + off(i)*h
                if (mh > 0) then
                    call self%mech%phi_jac(t, qp, g(1:mh, :))
                    c(mh + 1:2*mh, j) = c(mh + 1:2*mh, j) + wt(i)*matmul(g(1:mh, :), v)/ &
                                        (12.0_dp*h)
                end if
                if (mn > 0) then
                    call self%mech%nh_matrix(t, qp, a(1:mn, :), b(1:mn))
                    c(2*mh + 1:2*mh + mn, j) = c(2*mh + 1:2*mh + mn, j) + &
                                               wt(i)*(matmul(a(1:mn, :), v) + b(1:mn))/ &
                                               (12.0_dp*h)
                end if
            end do
            qp(j) = q(j)
        end do
    end subroutine cm_normals

    logical function cm_has_energy(self)
        class(constrained_model), intent(in) :: self
        cm_has_energy = self%mech%has_energy()
    end function cm_has_energy

    real(dp) function cm_energy(self, t, x) result(e)
        class(constrained_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        integer :: n
        n = self%mech%n
        e = self%mech%energy(t, x(1:n), x(n + 1:2*n))
    end function cm_energy

end module conmech_transverse_mech
