!> Events sampled inside the steps and the Jacobian structure of Radau.
!! - g(t) = sin(50 t) + 0.9 on [0, 2] (32 zeros in closed form, the closest 0.018 apart) with
!!   y' = 1, y = t (a state that does not limit the steps): DOP853 at 1e-10 with SciPy's
!!   rule (no resolution) misses zeros; with resolution 0.01 every one is found, at its
!!   closed-form time, with the same steps and the same evaluations of f.
!! - A banded system (tridiagonal diffusion with a cubic sink, n = 60) by Radau: the
!!   sparsity pattern groups the columns into 3 (Curtis-Powell-Reid), each Jacobian costs 3
!!   evaluations of f instead of 60, the steps are those of the dense differences and the
!!   end state agrees with theirs.
program test_event_resolution
    use conmech
    use conmech_testing, only: test_suite
    use ode_test_events, only: sine_event
    use conmech_ode_methods, only: new_stepper
    use conmech_radau_stepper, only: radau_stepper
    implicit none

    integer, parameter :: N = 60
    type(test_suite) :: ts
    type(ode_function) :: f, fb
    type(ode_options) :: opt
    type(ode_result) :: plain, fine, dense, grouped
    type(sine_event) :: ev
    real(dp) :: truth(32)
    class(ode_stepper), allocatable :: stp
    integer, allocatable :: col_ptr(:), row_idx(:)
    integer :: info, k, j, nz
    character(len=:), allocatable :: msg

    ts%name = "test_event_resolution"
    ! ------------------------------------------------------------ events
    do k = 0, 15
        truth(2*k + 1) = (acos(-1.0_dp) + asin(0.9_dp) + 2*acos(-1.0_dp)*k)/50.0_dp
        truth(2*k + 2) = (2*acos(-1.0_dp) - asin(0.9_dp) + 2*acos(-1.0_dp)*k)/50.0_dp
    end do
    f%f => unit_speed
    ev%direction = [0]
    ev%terminal = [.false.]
    opt%method = METHOD_DOP853
    opt%rtol = 1.0e-10_dp
    opt%atol = 1.0e-10_dp
    call ode_solve(f, [0.0_dp, 2.0_dp], [0.0_dp], opt, plain, events=ev)
    call ts%check(plain%success .and. plain%nev < 32, "SciPy's rule misses zeros")
    ev%resolution = [0.01_dp]
    call ode_solve(f, [0.0_dp, 2.0_dp], [0.0_dp], opt, fine, events=ev)
    call ts%check(fine%success .and. fine%nev == 32, "resolution 0.01: 32 zeros")
    if (fine%nev == 32) call ts%check_less(maxval(abs(fine%ev_t(1:32) - truth)), &
                                               1.0e-12_dp, "each zero at its closed form")
    call ts%check(fine%stats%nfev == plain%stats%nfev .and. fine%nt == plain%nt, &
                  "the same steps and evaluations of f")
    ev%resolution = [-1.0_dp]
    call ode_solve(f, [0.0_dp, 2.0_dp], [0.0_dp], opt, fine, events=ev)
    call ts%check(fine%status == CM_BAD_INPUT .and. index(fine%message, "resolution") > 0, &
                  "a negative resolution refused: "//fine%message)

    ! ------------------------------------------------------------ Jacobian structure
    fb%f => band
    opt = ode_options()
    opt%method = METHOD_RADAU5
    opt%rtol = 1.0e-6_dp
    opt%atol = 1.0e-9_dp
    call ode_solve(fb, [0.0_dp, 1.0_dp], start(), opt, dense)
    ! the tridiagonal pattern by columns, 1-based
    allocate (col_ptr(N + 1), row_idx(3*N - 2))
    nz = 0
    do j = 1, N
        col_ptr(j) = nz + 1
        do k = max(1, j - 1), min(N, j + 1)
            nz = nz + 1
            row_idx(nz) = k
        end do
    end do
    col_ptr(N + 1) = nz + 1
    call new_stepper(METHOD_RADAU5, stp, info, msg)
    select type (stp)
    type is (radau_stepper)
        call stp%jstruct%set_pattern(N, col_ptr, row_idx, info, msg)
        call ts%check(info == CM_SUCCESS .and. stp%jstruct%ngroups == 3, &
                      "tridiagonal pattern: 3 groups")
    end select
    call ode_solve(fb, [0.0_dp, 1.0_dp], start(), opt, grouped, stepper=stp)
    call ts%check(dense%success .and. grouped%success, "both runs succeed")
    call ts%check(grouped%stats%njev == dense%stats%njev .and. &
                  grouped%stats%nlu == dense%stats%nlu .and. &
                  dense%stats%nfev - grouped%stats%nfev == (N - 3)*dense%stats%njev, &
                  "3 evaluations per Jacobian instead of 60, the same steps")
    call ts%check_less(maxval(abs(grouped%y(:, grouped%nt) - dense%y(:, dense%nt))), &
                       1.0e-8_dp, "end states agree")
    call new_stepper(METHOD_RADAU5, stp, info, msg)
    select type (stp)
    type is (radau_stepper)
        col_ptr(2) = 0
        call stp%jstruct%set_pattern(N, col_ptr, row_idx, info, msg)
        call ts%check(info == CM_BAD_INPUT .and. index(msg, "jac_sparsity") > 0, &
                      "a malformed pattern refused: "//msg)
    end select
    ! a main program's variables are never freed by themselves
    deallocate (stp, col_ptr, row_idx, msg)
    call ts%finish()

contains

    subroutine unit_speed(t, y, dydt)
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        dydt = 1.0_dp
    end subroutine unit_speed

    function start() result(y)
        real(dp) :: y(N)
        integer :: i
        y = [(1.0_dp - real(i - 1, dp)/real(N - 1, dp), i = 1, N)]
    end function start

    !> y_i' = 100 (y_{i-1} - 2 y_i + y_{i+1}) - y_i^3 (zero outside the chain)
    subroutine band(t, y, dydt)
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        dydt = -2.0_dp*y
        dydt(2:) = dydt(2:) + y(:N - 1)
        dydt(:N - 1) = dydt(:N - 1) + y(2:)
        dydt = 100.0_dp*dydt - y**3
    end subroutine band

end program test_event_resolution
