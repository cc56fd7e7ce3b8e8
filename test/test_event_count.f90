!> Terminal counts and SciPy's rule at t0 (ode_events%count, %zero_at_t0), on
!! g(t) = sin(50 t) + level with y' = 1, y = t (zeros in closed form; DOP853 at 1e-10).
!! - level 0.9 with resolution 0.01 (every zero found): a terminal event of count 5 stops
!!   the run at the 5th zero, reports the first five, and takes the steps of the run with
!!   a non-terminal event up to there (the count lives in the run, no restart); without a
!!   count a terminal event stops at the first zero, as count 1; count 0 is refused.
!! - level 0 (g = 0 at t0, rising): the rule off (the default) reports nothing at t0, the
!!   first zero is pi/50; on, the zero at t0 is reported with y0 and counted (a terminal
!!   count of 1 ends the run at t0 after one step, status CM_EVENT_STOP); a falling-only
!!   event is not reported at t0 (the first step moves g up).
program test_event_count
    use conmech
    use conmech_testing, only: test_suite
    use ode_test_events, only: sine_event
    implicit none

    type(test_suite) :: ts
    type(ode_function) :: f
    type(ode_options) :: opt
    type(ode_result) :: full, five, one, counted1
    type(sine_event) :: ev
    real(dp) :: truth(32)
    integer :: k, nt

    ts%name = "test_event_count"
    do k = 0, 15
        truth(2*k + 1) = (pi + asin(0.9_dp) + 2*pi*k)/50.0_dp
        truth(2*k + 2) = (2*pi - asin(0.9_dp) + 2*pi*k)/50.0_dp
    end do
    f%f => unit_speed
    opt%method = METHOD_DOP853
    opt%rtol = 1.0e-10_dp
    opt%atol = 1.0e-10_dp

    ! ------------------------------------------------------------ terminal counts
    ev%direction = [0]
    ev%resolution = [0.01_dp]
    ev%terminal = [.false.]
    ev%count = [5]             ! ignored: not terminal
    call ode_solve(f, [0.0_dp, 2.0_dp], [0.0_dp], opt, full, events=ev)
    call ts%check(full%status == CM_SUCCESS .and. full%nev == 32, &
                  "not terminal: all 32 zeros, the count ignored")
    ev%terminal = [.true.]
    call ode_solve(f, [0.0_dp, 2.0_dp], [0.0_dp], opt, five, events=ev)
    call ts%check(five%status == CM_EVENT_STOP .and. five%nev == 5, &
                  "count 5: stopped at the 5th zero, five reported")
    if (five%nev == 5) then
        call ts%check_less(maxval(abs(five%ev_t(1:5) - truth(1:5))), 1.0e-12_dp, &
                           "the five zeros at their closed form")
        call ts%check(five%t(five%nt) == five%ev_t(5) .and. five%y(1, five%nt) == &
                      five%ev_y(1, 5), "the run ends at the 5th zero's state")
    end if
    nt = five%nt - 1
    if (nt <= full%nt) then
        call ts%check(all(five%t(1:nt) == full%t(1:nt)) .and. &
                      five%stats%naccept == nt, "the steps of the non-terminal run")
    else
        call ts%check(.false., "the steps of the non-terminal run")
    end if
    deallocate (ev%count)
    call ode_solve(f, [0.0_dp, 2.0_dp], [0.0_dp], opt, one, events=ev)
    ev%count = [1]
    call ode_solve(f, [0.0_dp, 2.0_dp], [0.0_dp], opt, counted1, events=ev)
    call ts%check(one%status == CM_EVENT_STOP .and. one%nev == 1 .and. &
                  counted1%nev == 1 .and. one%nt == counted1%nt, &
                  "no count: the first zero, as count 1")
    if (one%nev == 1) call ts%check(one%ev_t(1) == counted1%ev_t(1) .and. &
                                    abs(one%ev_t(1) - truth(1)) < 1.0e-12_dp, &
                                    "the first zero, the same with count 1")
    ev%count = [0]
    call ode_solve(f, [0.0_dp, 2.0_dp], [0.0_dp], opt, one, events=ev)
    call ts%check(one%status == CM_BAD_INPUT .and. index(one%message, "count") > 0, &
                  "count 0 refused: "//one%message)

    ! ------------------------------------------------------------ zero at t0
    deallocate (ev%count, ev%resolution)
    ev%level = 0.0_dp
    ev%terminal = [.false.]
    call ode_solve(f, [0.0_dp, 0.1_dp], [0.0_dp], opt, full, events=ev)
    call ts%check(full%nev == 1, "rule off: no event at t0, one zero in (0, 0.1]")
    if (full%nev == 1) call ts%check_close(full%ev_t(1), pi/50.0_dp, 1.0e-12_dp, &
                                           "rule off: the zero at pi/50")
    ev%zero_at_t0 = .true.
    call ode_solve(f, [0.0_dp, 0.1_dp], [0.0_dp], opt, full, events=ev)
    call ts%check(full%nev == 2, "rule on: the zero at t0 reported too")
    if (full%nev == 2) call ts%check(full%ev_t(1) == 0.0_dp .and. full%ev_y(1, 1) == 0.0_dp &
                                     .and. full%ev_id(1) == 1, "at t0 with y0")
    ev%direction = [-1]
    call ode_solve(f, [0.0_dp, 0.1_dp], [0.0_dp], opt, full, events=ev)
    call ts%check(full%nev == 1, "rule on, falling only: not at t0 (g rises)")
    ev%direction = [1]
    ev%terminal = [.true.]
    call ode_solve(f, [0.0_dp, 0.1_dp], [0.0_dp], opt, one, events=ev)
    call ts%check(one%status == CM_EVENT_STOP .and. one%nev == 1 .and. &
                  one%stats%naccept == 1, "terminal, count 1: stopped after the first step")
    if (one%nev == 1) call ts%check(one%ev_t(1) == 0.0_dp .and. one%nt == 2 .and. &
                                    all(one%t(1:one%nt) == 0.0_dp) .and. &
                                    all(one%y(1, 1:one%nt) == 0.0_dp), &
                                    "the run ends at t0 with y0")
    ev%count = [2]
    ev%direction = [0]
    call ode_solve(f, [0.0_dp, 0.1_dp], [0.0_dp], opt, one, events=ev)
    call ts%check(one%status == CM_EVENT_STOP .and. one%nev == 2, &
                  "terminal, count 2: t0 counted, stopped at the next zero")
    if (one%nev == 2) call ts%check_close(one%t(one%nt), pi/50.0_dp, 1.0e-12_dp, &
                                          "stopped at pi/50")
    call ts%finish()

contains

    subroutine unit_speed(t, y, dydt)
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        dydt = 1.0_dp
    end subroutine unit_speed

end program test_event_count
