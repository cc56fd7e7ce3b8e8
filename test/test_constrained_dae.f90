!> A particle on the unit sphere with a configuration-dependent, non-diagonal mass matrix,
!! velocity-dependent forces and a non-holonomic constraint: every block of the Radau
!! Jacobians of the constrained DAE forms is exercised (their second derivatives by the
!! library's central-difference defaults; phi_jac exact, so that the right-hand sides are
!! smooth to round-off for the difference check).
module test_constrained_dae_system
    use conmech
    implicit none
    private
    public :: sphere_bead
    type, extends(constrained_system) :: sphere_bead
    contains
        procedure :: mass => sb_mass
        procedure :: forces => sb_forces
        procedure :: phi => sb_phi
        procedure :: phi_jac => sb_phi_jac
        procedure :: nh_matrix => sb_nh
    end type sphere_bead
contains
    subroutine sb_mass(self, t, q, mm)
        class(sphere_bead), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = 0.0_dp
        mm(1, 1) = 1.0_dp + q(1)**2
        mm(2, 2) = 1.5_dp + q(3)**2
        mm(3, 3) = 2.0_dp
        mm(1, 2) = 0.3_dp*q(2)
        mm(2, 1) = mm(1, 2)
    end subroutine sb_mass
    subroutine sb_forces(self, t, q, v, f)
        class(sphere_bead), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = [-0.2_dp*v(1)*abs(v(1)), sin(q(1)) - 0.1_dp*v(2), -9.81_dp + q(2)*v(3)]
    end subroutine sb_forces
    subroutine sb_phi(self, t, q, c)
        class(sphere_bead), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c(1) = 0.5_dp*(q(1)**2 + q(2)**2 + q(3)**2 - 1.0_dp)
    end subroutine sb_phi
    subroutine sb_phi_jac(self, t, q, g)
        class(sphere_bead), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        g(1, :) = q
    end subroutine sb_phi_jac
    subroutine sb_nh(self, t, q, a, b)
        class(sphere_bead), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: a(:, :), b(:)
        a(1, :) = [q(3), 0.2_dp*q(1), -q(1)]
        b(1) = 0.1_dp*sin(t)
    end subroutine sb_nh
end module test_constrained_dae_system

!> The Jacobians of the index-2 (GGL) and index-3 forms against differences of their
!! right-hand sides, and Radau IIA on both forms against projected DOP853.
program test_constrained_dae
    use conmech
    use conmech_testing, only: test_suite
    use conmech_radau_stepper, only: radau_stepper
    use conmech_constrained_dae, only: ggl_system, ggl_setup
    use conmech_constrained_index3, only: index3_system, index3_setup
    use test_constrained_dae_system, only: sphere_bead
    implicit none
    type(test_suite) :: ts
    type(sphere_bead) :: sb
    type(ggl_system) :: g2
    type(index3_system) :: g3
    type(radau_stepper) :: stp
    type(constrained_options) :: opt
    type(constrained_result) :: ref, r
    real(dp), allocatable :: y0(:), rv(:), av(:)
    real(dp) :: q0(3), v0(3), lam(2), acc(3)
    real(dp), parameter :: tols(4) = [1.0e-4_dp, 1.0e-6_dp, 1.0e-8_dp, 1.0e-11_dp]
    character(len=8) :: tag
    integer :: k

    ts%name = "test_constrained_dae"
    sb%n = 3
    sb%n_hol = 1
    sb%n_nh = 1
    q0 = [0.6_dp, 0.0_dp, -0.8_dp]
    v0 = [0.8_dp, 0.3_dp, 0.6_dp]
    acc = [0.3_dp, -1.2_dp, 0.7_dp]
    lam = [0.4_dp, -0.9_dp]

    call ggl_setup(sb, 0.3_dp, q0, v0, lam, 1.0e-8_dp, 1.0e-8_dp, g2, y0, stp, rv, av)
    y0(2*3 + 2 + 1) = 0.05_dp      ! a nonzero mu exercises d(G^T mu)/dq
    call check_jacobian(g2, 0.3_dp, y0, "GGL (index-2) Jacobian")
    call index3_setup(sb, q0, v0, acc, lam, g3, y0, stp)
    call check_jacobian(g3, 0.3_dp, y0, "index-3 Jacobian")
    deallocate (g2%mech, g3%mech, y0, rv, av)   ! program variables are not freed at its end

    ! Radau on both forms against projected DOP853 at tight tolerance
    opt%ode%rtol = 1.0e-12_dp
    opt%ode%atol = 1.0e-12_dp
    call constrained_solve(sb, [0.0_dp, 1.0_dp], q0, v0, opt, ref, [1.0_dp])
    call ts%check(ref%success, "DOP853 reference: "//ref%message)
    opt%ode%method = METHOD_RADAU5
    opt%ode%rtol = 1.0e-9_dp
    opt%ode%atol = 1.0e-9_dp
    do k = 2, 3
        opt%dae_index = k
        call constrained_solve(sb, [0.0_dp, 1.0_dp], q0, v0, opt, r, [1.0_dp])
        call ts%check(r%success, "Radau: "//r%message)
        if (.not. r%success) cycle
        call ts%check_less(maxval(abs(r%q(:, 1) - ref%q(:, 1))), &
                           1.0e-9_dp, "Radau q vs DOP853")
        call ts%check_less(maxval(abs(r%acc(:, 1) - ref%acc(:, 1))), 1.0e-8_dp, &
                           "Radau accelerations vs DOP853")
        call ts%check_less(r%res_pos(1), 1.0e-9_dp, "Radau max |phi|")
    end do
    ! The index-3 form over loose to tight tolerances. With holonomic and non-holonomic
    ! constraints together, the non-holonomic multipliers share the h^-2 round-off of the
    ! holonomic ones (they are solved from one coupled system), so their error is scaled
    ! as index 3; scaled as index 2 the Newton iteration stalls on that round-off.
    opt%dae_index = 3
    do k = 1, size(tols)
        opt%ode%rtol = tols(k)
        opt%ode%atol = tols(k)
        write (tag, '(es8.1)') tols(k)
        call constrained_solve(sb, [0.0_dp, 1.0_dp], q0, v0, opt, r, [1.0_dp])
        call ts%check(r%success, "Radau index 3, tol "//tag//": "//r%message)
        if (.not. r%success) cycle
        call ts%check_less(maxval(abs(r%q(:, 1) - ref%q(:, 1))), &
                           max(10.0_dp*tols(k), 1.0e-10_dp), "Radau index 3 q vs DOP853, tol "//tag)
    end do
    call ts%finish()

contains

    !> The assembled Jacobian against central differences of the right-hand side.
    subroutine check_jacobian(sys, t, y, what)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        character(len=*), intent(in) :: what
        real(dp) :: jac(size(y), size(y)), fd(size(y), size(y)), fp(size(y)), fm(size(y))
        real(dp) :: yp(size(y)), h
        integer :: j
        call sys%jacobian(t, y, jac)
        yp = y
        do j = 1, size(y)
            h = 1.0e-6_dp*max(abs(y(j)), 1.0_dp)
            yp(j) = y(j) + h
            call sys%rhs(t, yp, fp)
            yp(j) = y(j) - h
            call sys%rhs(t, yp, fm)
            yp(j) = y(j)
            fd(:, j) = (fp - fm)/(2.0_dp*h)
        end do
        call ts%check_less(maxval(abs(jac - fd))/max(maxval(abs(fd)), 1.0_dp), 1.0e-7_dp, &
                           what)
    end subroutine check_jacobian

end program test_constrained_dae
