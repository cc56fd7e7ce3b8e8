!> The `accelerations_jacobian` hook of generalized systems (what compiled trees use, spec
!! slot 19: d a/d[q, v] from the derivatives of the recursive algorithms, no factorisation
!! of M): the first-order form's Jacobian is [0 I; d a/d[q, v]] from the hook, equal to
!! the Jacobian of the plain system by central differences, and `has_jacobian` is true
!! with the hook alone.
module test_accel_jac_types
    use conmech_kinds, only: dp
    use conmech_generalized, only: generalized_system
    implicit none
    private
    public :: diag_system, jac_system

    !> M(q) = diag(1 + i + sin(q_i)^2), Q_i = -sin(q_i) - 0.1 v_i cos(q_1) (coupled to q_1).
    type, extends(generalized_system) :: diag_system
    contains
        procedure :: mass => d_mass
        procedure :: forces => d_forces
    end type diag_system

    !> The same system with its accelerations and their Jacobian written by hand.
    type, extends(diag_system) :: jac_system
    contains
        procedure :: accelerations_jacobian => j_jac
        procedure :: has_accelerations_jacobian => j_has
    end type jac_system

contains

    subroutine d_mass(self, t, q, mm)
        class(diag_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        integer :: i
        mm = 0.0_dp
        do i = 1, self%ndof
            mm(i, i) = 1.0_dp + i + sin(q(i))**2
        end do
    end subroutine d_mass

    subroutine d_forces(self, t, q, v, f)
        class(diag_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = -sin(q) - 0.1_dp*v*cos(q(1))
    end subroutine d_forces

    subroutine j_jac(self, t, q, v, a, jac)
        class(jac_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: a(:), jac(:, :)
        integer :: i, n
        real(dp) :: m, f, s, c
        n = self%ndof
        jac = 0.0_dp
        do i = 1, n
            s = sin(q(i))
            c = cos(q(i))
            m = 1.0_dp + i + s**2
            f = -s - 0.1_dp*v(i)*cos(q(1))
            a(i) = f/m
            jac(i, i) = jac(i, i) + (-c*m - f*2.0_dp*s*c)/m**2
            jac(i, 1) = jac(i, 1) + 0.1_dp*v(i)*sin(q(1))/m
            jac(i, n + i) = -0.1_dp*cos(q(1))/m
        end do
    end subroutine j_jac

    logical function j_has(self)
        class(jac_system), intent(in) :: self
        j_has = .true.
    end function j_has
end module test_accel_jac_types

program test_generalized_accel_jacobian
    use conmech_kinds, only: dp
    use conmech_generalized, only: generalized_ode
    use conmech_testing, only: test_suite
    use test_accel_jac_types
    implicit none
    call run()
contains
    subroutine run()
        type(test_suite) :: ts
        type(generalized_ode) :: plain, hooked
        real(dp) :: y(6), j1(6, 6), j2(6, 6), a(3), ja(3, 6), f(6)
        integer :: i

        ts%name = "test_generalized_accel_jacobian"
        allocate (plain%mech, source=diag_system(ndof=3))
        allocate (hooked%mech, source=jac_system(ndof=3))
        y = [0.3_dp, -1.2_dp, 2.0_dp, 0.5_dp, 0.1_dp, -0.7_dp]
        call ts%check(.not. plain%has_jacobian(), "no analytic Jacobian without a hook")
        call ts%check(hooked%has_jacobian(), "the accelerations_jacobian hook is one")
        call plain%jacobian(0.0_dp, y, j1)           ! central differences
        call hooked%jacobian(0.0_dp, y, j2)
        call ts%check_less(maxval(abs(j1 - j2)), 1.0e-7_dp, &
                           "hook = central differences of the plain system")
        call hooked%mech%accelerations_jacobian(0.0_dp, y(1:3), y(4:6), a, ja)
        call ts%check(all(j2(4:6, :) == ja), "the lower block is the hook's, bit for bit")
        call ts%check(all(j2(1:3, 1:3) == 0.0_dp), "upper left block zero")
        do i = 1, 3
            call ts%check(j2(i, 3 + i) == 1.0_dp, "upper right block identity")
        end do
        call hooked%rhs(0.0_dp, y, f)
        call ts%check_less(maxval(abs(f(4:6) - a)), 1.0e-15_dp, "hook's a = M^-1 Q")
        call ts%finish()
    end subroutine run
end program test_generalized_accel_jacobian
