!> The `accelerations` hook of generalized systems (what compiled planar trees use, spec
!! slot 17): a system that computes a = M^{-1} Q itself gets the same accelerations and
!! the same trajectory as the Cholesky path of its mass matrix and forces; non-finite
!! accelerations are CM_NONFINITE with a message, and stop an integration with
!! success = false.
module test_accel_hook_types
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use conmech_kinds, only: dp
    use conmech_generalized, only: generalized_system
    implicit none
    private
    public :: diag_system, hook_system

    !> M(q) = diag(1 + i + sin(q_i)^2), Q_i = -sin(q_i) - 0.1 v_i (a row of pendulums).
    type, extends(generalized_system) :: diag_system
    contains
        procedure :: mass => d_mass
        procedure :: forces => d_forces
    end type diag_system

    !> The same system with its own accelerations (NaN from `nan_after` > 0 on: |q_1| >
    !! nan_after).
    type, extends(diag_system) :: hook_system
        real(dp) :: nan_after = 0.0_dp
    contains
        procedure :: accelerations => h_accel
        procedure :: has_accelerations => h_has
    end type hook_system

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
        f = -sin(q) - 0.1_dp*v
    end subroutine d_forces

    subroutine h_accel(self, t, q, v, a)
        class(hook_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: a(:)
        integer :: i
        do i = 1, self%ndof
            a(i) = (-sin(q(i)) - 0.1_dp*v(i))/(1.0_dp + i + sin(q(i))**2)
        end do
        if (self%nan_after > 0.0_dp .and. abs(q(1)) > self%nan_after) &
            a(1) = ieee_value(1.0_dp, ieee_quiet_nan)
    end subroutine h_accel

    logical function h_has(self)
        class(hook_system), intent(in) :: self
        h_has = .true.
    end function h_has
end module test_accel_hook_types

program test_generalized_accel_hook
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_generalized, only: generalized_accel, generalized_solve
    use conmech_ode_solver, only: ode_options, ode_result
    use conmech_testing, only: test_suite
    use test_accel_hook_types
    implicit none
    call run()
contains
    subroutine run()
        type(test_suite) :: ts
        type(diag_system) :: plain
        type(hook_system) :: hook
        real(dp) :: q(3), v(3), a1(3), a2(3)
        integer :: info
        character(len=:), allocatable :: msg
        type(ode_options) :: opt
        type(ode_result) :: r1, r2

        ts%name = "test_generalized_accel_hook"
        plain%ndof = 3
        hook%ndof = 3
        q = [0.3_dp, -1.2_dp, 2.0_dp]
        v = [0.5_dp, 0.1_dp, -0.7_dp]
        call ts%check(.not. plain%has_accelerations(), "no hook by default")
        call generalized_accel(plain, 0.0_dp, q, v, a1, info)
        call generalized_accel(hook, 0.0_dp, q, v, a2, info, msg)
        call ts%check(info == CM_SUCCESS .and. msg == "success", "hook: success")
        call ts%check_less(maxval(abs(a1 - a2))/maxval(abs(a1)), 1.0e-15_dp, &
                           "hook equals the Cholesky path")
        opt%rtol = 1.0e-12_dp
        opt%atol = 1.0e-12_dp
        call generalized_solve(plain, [0.0_dp, 5.0_dp], q, v, opt, r1)
        call generalized_solve(hook, [0.0_dp, 5.0_dp], q, v, opt, r2)
        call ts%check(r1%success .and. r2%success, "both integrations succeed")
        call ts%check_less(maxval(abs(r1%y(:, r1%nt) - r2%y(:, r2%nt))), 1.0e-11_dp, &
                           "same trajectory with and without the hook")
        hook%nan_after = 0.1_dp
        call generalized_accel(hook, 0.0_dp, q, v, a2, info, msg)
        call ts%check(info == CM_NONFINITE .and. index(msg, "non-finite") > 0, &
                      "non-finite accelerations -> CM_NONFINITE with a message")
        ! q_1 starts at 0 and passes 0.1 on the way: the integration stops there
        hook%nan_after = 0.1_dp
        call generalized_solve(hook, [0.0_dp, 5.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], &
                               [1.0_dp, 0.0_dp, 0.0_dp], opt, r2)
        call ts%check(.not. r2%success .and. r2%status /= CM_SUCCESS, &
                      "NaN during the integration: success = false")
        call ts%check(r2%t(r2%nt) > 0.0_dp .and. r2%t(r2%nt) < 1.0_dp, &
                      "it stops near the time |q_1| reaches 0.1")
        call ts%finish()
    end subroutine run
end program test_generalized_accel_hook
