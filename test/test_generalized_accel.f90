!> The accelerations of generalized systems, M(t, q) a = Q: the small-matrix path (stack
!! buffer, dpotf2 + two dtrsv) and the large one (n > 32, allocated, dpotrf) both solve
!! M a = Q to round-off (residual, and agreement with an LU solve); a non-finite entry
!! anywhere in M (also only in its lower triangle, or +Inf on the diagonal) is reported as
!! CM_NONFINITE, an indefinite M as CM_SINGULAR.
module test_gen_accel_types
    use conmech_kinds, only: dp
    use conmech_generalized, only: generalized_system
    implicit none
    private
    public :: dense_system

    !> M(q) = diag(1 + i) + s s^T with s_i = sin(q_i) (symmetric positive definite, full),
    !! Q_i = cos(i q_i) + v_i; `bad` > 0 puts `badval` into M(bad_i, bad_j) after that.
    type, extends(generalized_system) :: dense_system
        integer :: bad_i = 0, bad_j = 0
        real(dp) :: badval = 0.0_dp
    contains
        procedure :: mass => ds_mass
        procedure :: forces => ds_forces
    end type dense_system

contains

    subroutine ds_mass(self, t, q, mm)
        class(dense_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        integer :: i, j
        do j = 1, self%ndof
            do i = 1, self%ndof
                mm(i, j) = sin(q(i))*sin(q(j))
            end do
            mm(j, j) = mm(j, j) + 1.0_dp + j
        end do
        if (self%bad_i > 0) mm(self%bad_i, self%bad_j) = self%badval
    end subroutine ds_mass

    subroutine ds_forces(self, t, q, v, f)
        class(dense_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        integer :: i
        do i = 1, self%ndof
            f(i) = cos(i*q(i)) + v(i)
        end do
    end subroutine ds_forces
end module test_gen_accel_types

program test_generalized_accel
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_positive_inf
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_generalized, only: generalized_accel
    use conmech_lapack, only: la_solve
    use conmech_testing, only: test_suite
    use test_gen_accel_types
    implicit none
    ! (the checks run in a procedure: allocatables of the main program are never freed,
    ! which the leak sanitizer would report)
    call run()
contains
    subroutine run()
        type(test_suite) :: ts
        type(dense_system) :: sys
        integer, parameter :: sizes(6) = [1, 2, 16, 32, 33, 48]
        integer :: k, n, i, info
        real(dp), allocatable :: q(:), v(:), a(:), mm(:, :), f(:), x(:, :)
        character(len=:), allocatable :: msg
        character(len=8) :: lab

        ts%name = "test_generalized_accel"
        do k = 1, size(sizes)
            n = sizes(k)
            write (lab, '(i0)') n
            sys%ndof = n
            q = [(0.3_dp*i, i = 1, n)]
            v = [(0.1_dp*i, i = 1, n)]
            allocate (a(n), mm(n, n), f(n), x(n, 1))
            call generalized_accel(sys, 0.0_dp, q, v, a, info, msg)
            call ts%check(info == CM_SUCCESS .and. msg == "success", &
                          "n = "//trim(lab)//": success")
            call sys%mass(0.0_dp, q, mm)
            call sys%forces(0.0_dp, q, v, f)
            call ts%check_less(maxval(abs(matmul(mm, a) - f))/maxval(abs(f)), 1.0e-14_dp, &
                               "n = "//trim(lab)//": residual |M a - Q| / |Q|")
            call la_solve(mm, reshape(f, [n, 1]), x, info)
            call ts%check_less(maxval(abs(a - x(:, 1)))/maxval(abs(x(:, 1))), 1.0e-13_dp, &
                               "n = "//trim(lab)//": Cholesky + dtrsv equal LU (dgesv)")
            ! the same without a message argument
            a = 0.0_dp
            call generalized_accel(sys, 0.0_dp, q, v, a, info)
            call ts%check_less(maxval(abs(a - x(:, 1)))/maxval(abs(x(:, 1))), 1.0e-13_dp, &
                               "n = "//trim(lab)//": same without msg")
            if (n >= 2) then
                ! NaN only in the strictly lower triangle (which the Cholesky factor never reads)
                sys%bad_i = n
                sys%bad_j = 1
                sys%badval = ieee_value(1.0_dp, ieee_quiet_nan)
                call generalized_accel(sys, 0.0_dp, q, v, a, info, msg)
                call ts%check(info == CM_NONFINITE .and. index(msg, "non-finite") > 0, &
                              "n = "//trim(lab)//": NaN in the lower triangle -> CM_NONFINITE")
                ! +Inf on the diagonal (a Cholesky factorisation would not fail on it)
                sys%bad_i = 1
                sys%badval = ieee_value(1.0_dp, ieee_positive_inf)
                call generalized_accel(sys, 0.0_dp, q, v, a, info)
                call ts%check(info == CM_NONFINITE, "n = "//trim(lab)//": +Inf on the diagonal")
                ! an indefinite mass matrix
                sys%bad_i = n
                sys%bad_j = n
                sys%badval = -1.0_dp
                call generalized_accel(sys, 0.0_dp, q, v, a, info, msg)
                call ts%check(info == CM_SINGULAR .and. index(msg, "singular") > 0, &
                              "n = "//trim(lab)//": indefinite M -> CM_SINGULAR")
                sys%bad_i = 0
                sys%bad_j = 0
            end if
            deallocate (a, mm, f, x)
        end do
        call ts%finish()
    end subroutine run
end program test_generalized_accel
