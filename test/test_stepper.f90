!> The stepper driven step by step (rk_init, rk_start, rk_step, dense, eval) reproduces
!! ode_integrate and ode_solve bit for bit; failures are reported by rk_step.
program test_stepper
    use conmech
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    type(kepler_2d) :: sys
    type(ode_options) :: opt
    type(ode_stats) :: st
    type(ode_result) :: res
    type(rk_stepper) :: stp
    real(dp) :: y0(4), y(4), ym(4), tm, tf
    integer :: info, nsteps, m
    character(len=:), allocatable :: msg
    logical :: same_dense

    ts%name = "test_stepper"
    y0 = [0.4_dp, 0.0_dp, 0.0_dp, 2.0_dp]       ! e = 0.6, period 2 pi
    tf = 2.0_dp*acos(-1.0_dp)
    do m = METHOD_DOPRI5, METHOD_VERNER98
        opt%method = m
        opt%rtol = 1.0e-9_dp
        opt%atol = 1.0e-9_dp
        y = y0
        call ode_integrate(sys, 0.0_dp, tf, y, opt, info, st)
        call rk_init(stp, 0.0_dp, tf, y0, opt, info, msg)
        call rk_start(stp, sys, info, msg)
        nsteps = 0
        do while (info == CM_SUCCESS .and. .not. stp%last)
            call rk_step(stp, sys, tf, info, msg)
            nsteps = nsteps + 1
        end do
        call ts%check(info == CM_SUCCESS .and. stp%t == tf .and. all(stp%y == y) .and. &
                      stp%st%nfev == st%nfev .and. nsteps == st%naccept, &
                      "a loop of rk_step is ode_integrate bit for bit, method "//achar(48 + m))
        call ts%check_less(maxval(abs(stp%y - y0)), 1.0e-6_dp, &
                           "one period of the e = 0.6 orbit closes")
    end do

    ! dense output of one step against ode_solve's t_eval (both interpolate the same step)
    opt%method = METHOD_DOP853
    call rk_init(stp, 0.0_dp, tf, y0, opt, info, msg)
    call rk_start(stp, sys, info, msg)
    call rk_step(stp, sys, tf, info, msg)
    call rk_step(stp, sys, tf, info, msg)
    call stp%dense(sys)
    tm = 0.5_dp*(stp%t_old + stp%t)
    call stp%eval(tm, ym)
    call ode_solve(sys, [0.0_dp, tf], y0, opt, res, t_eval=[tm])
    same_dense = all(res%y(:, 1) == ym)
    call ts%check(same_dense .and. stp%t_old < tm .and. tm < stp%t, &
                  "dense output of the last step = ode_solve's t_eval value")

    ! failures come back from rk_step with their status
    opt%max_steps = 3
    call rk_init(stp, 0.0_dp, 100.0_dp, y0, opt, info, msg)
    call rk_start(stp, sys, info, msg)
    do while (info == CM_SUCCESS .and. .not. stp%last)
        call rk_step(stp, sys, 100.0_dp, info, msg)
    end do
    call ts%check(info == CM_TOO_MANY_STEPS .and. index(msg, "too many steps") > 0, &
                  "rk_step reports max_steps: "//msg)
    opt%max_steps = 100000
    call rk_init(stp, 0.0_dp, tf, [real(dp) ::], opt, info, msg)
    call ts%check(info == CM_BAD_INPUT, "rk_init rejects an empty y0: "//msg)
    call ts%finish()
    if (allocated(msg)) deallocate (msg)   ! main-program variables are not freed at exit:
                                           ! LeakSanitizer would report them
end program test_stepper
