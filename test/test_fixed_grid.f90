!> The grid of the fixed-step methods: the fewest equal steps not longer than first_step,
!! whole multiples up to round-off not given an extra step, and the max_steps check.
program test_fixed_grid
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_TOO_MANY_STEPS
    use conmech_fixed_grid, only: grid_steps, check_grid_steps, grid_time
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    character(len=:), allocatable :: msg
    integer :: info, k, n
    logical :: ok

    ts%name = "test_fixed_grid"
    call ts%check(grid_steps(1.0_dp, 1.0_dp, 0.1_dp) == 0, "empty interval: no step")
    call ts%check(grid_steps(0.0_dp, 1.0_dp, 0.1_dp) == 10, &
                  "1/0.1 in floating point is not exactly 10, the grid has 10 steps")
    call ts%check(grid_steps(0.0_dp, 1.0_dp, 0.3_dp) == 4, "[0, 1] in steps <= 0.3: 4")
    call ts%check(grid_steps(2.0_dp, -1.0_dp, 0.5_dp) == 6, "backward [2, -1]: 6 steps")
    call ts%check(grid_steps(0.0_dp, 1.0e-9_dp, 1.0_dp) == 1, "a step longer than t_span: 1")
    ! the steps h = (tf - t0)/n are never longer than first_step (up to the slack), and
    ! one step fewer would be longer
    ok = .true.
    do k = 1, 200
        n = grid_steps(0.0_dp, 7.0_dp, 7.0_dp/real(k, dp))
        if (n /= k) ok = .false.
        n = grid_steps(0.0_dp, 7.0_dp, 7.0_dp/(real(k, dp) + 0.5_dp))
        if (n /= k + 1) ok = .false.
    end do
    call ts%check(ok, "exact multiples give k steps, k + 1/2 of them round up to k + 1")
    ! the last grid point is tf itself, where t_start + n h misses it by round-off
    ! (3*0.1 = 0.30000000000000004 in binary floating point)
    n = grid_steps(0.0_dp, 0.3_dp, 0.1_dp)
    call ts%check(n == 3 .and. 3*0.1_dp /= 0.3_dp, "[0, 0.3] in steps of 0.1: 3, inexact")
    call ts%check(grid_time(0.0_dp, 0.3_dp, 0.1_dp, n, n) == 0.3_dp, "last grid point: tf")
    call ts%check(grid_time(0.0_dp, 0.3_dp, 0.1_dp, 2, n) == 2*0.1_dp, &
                  "inner grid point k: t_start + k h")
    msg = "kept"
    call check_grid_steps(10, 10, info, msg)
    call ts%check(info == CM_SUCCESS .and. msg == "kept", "max_steps reached, not exceeded")
    call check_grid_steps(11, 10, info, msg)
    call ts%check(info == CM_TOO_MANY_STEPS .and. index(msg, "needs 11 steps") > 0, &
                  "one step over max_steps: CM_TOO_MANY_STEPS naming the grid's length")
    deallocate (msg)
    call ts%finish()
end program test_fixed_grid
