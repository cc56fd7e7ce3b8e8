!> Integrator tests: observed orders of RK4, DOPRI5, DOP853 and of their dense outputs,
!! the Kepler orbit (closure, energy, event times), outputs, and bad input.
program test_ode
    use conmech
    use conmech_testing, only: test_suite
    use ode_test_events, only: radial_events, circle_projection
    implicit none

    type(test_suite) :: ts
    real(dp) :: ecc = 0.5_dp   !! eccentricity of the test orbit
    real(dp), parameter :: period = 2.0_dp*pi

    ts%name = "test_ode"
    ecc = 0.2_dp      ! orders: a mild orbit, so that the step sizes are asymptotic
    call test_orders()
    call test_dense_orders()
    ecc = 0.5_dp
    call test_kepler_tolerance()
    call test_kepler_events()
    call test_outputs()
    call test_backward()
    call test_bad_input()
    call test_failures()
    call test_hook()
    call test_tight_tolerance()
    call ts%finish()

contains

    !> Exact Kepler orbit (a = mu = 1, eccentricity ecc) starting at pericentre at t = 0.
    subroutine kepler_exact(t, y)
        real(dp), intent(in) :: t
        real(dp), intent(out) :: y(4)
        real(dp) :: e_anom, d, b
        integer :: it
        e_anom = t
        do it = 1, 50
            d = (e_anom - ecc*sin(e_anom) - t)/(1.0_dp - ecc*cos(e_anom))
            e_anom = e_anom - d
            if (abs(d) < 1.0e-16_dp) exit
        end do
        b = sqrt(1.0_dp - ecc**2)
        y(1) = cos(e_anom) - ecc
        y(2) = b*sin(e_anom)
        y(3) = -sin(e_anom)/(1.0_dp - ecc*cos(e_anom))
        y(4) = b*cos(e_anom)/(1.0_dp - ecc*cos(e_anom))
    end subroutine kepler_exact

    !> Options that force constant steps h on an adaptive method (no rejections).
    function fixed_options(method, h) result(opt)
        integer, intent(in) :: method
        real(dp), intent(in) :: h
        type(ode_options) :: opt
        opt%method = method
        opt%first_step = h
        opt%max_step = h
        opt%rtol = 1.0e6_dp
        opt%atol = 1.0e6_dp
    end function fixed_options

    !> Least-squares slope of log(err) against log(h).
    pure function slope(h, err) result(p)
        real(dp), intent(in) :: h(:), err(:)
        real(dp) :: p, xm, ym
        xm = sum(log(h))/size(h)
        ym = sum(log(err))/size(err)
        p = sum((log(h) - xm)*(log(err) - ym))/sum((log(h) - xm)**2)
    end function slope

    subroutine test_orders()
        integer, parameter :: nn(4, 4) = reshape([64, 64, 24, 8, 96, 96, 28, 12, &
                                                  128, 128, 32, 16, 192, 192, 36, 20], [4, 4])
        type(kepler_2d) :: sys
        type(ode_result) :: res
        real(dp) :: y0(4), yex(4), h(4), err(4), p
        real(dp), parameter :: tend = 3.0_dp
        integer :: i, m
        character(len=8), parameter :: names(4) = ["RK4     ", "DOPRI5  ", "DOP853  ", &
                                                   "VERNER98"]
        integer, parameter :: expected(4) = [4, 5, 8, 9]
        call kepler_exact(0.0_dp, y0)
        call kepler_exact(tend, yex)
        do m = METHOD_RK4, METHOD_VERNER98
            do i = 1, 4
                h(i) = tend/nn(m, i)
                call ode_solve(sys, [0.0_dp, tend], y0, fixed_options(m, h(i)), res)
                err(i) = maxval(abs(res%y(:, res%nt) - yex))
            end do
            p = slope(h, err)
            call ts%check_close(p, real(expected(m), dp), 0.5_dp, &
                                "observed order of "//trim(names(m)))
            call ts%check(res%stats%naccept == nn(m, 4) .and. res%stats%nreject == 0, &
                          "fixed-step options give exactly N steps, no rejections")
        end do
    end subroutine test_orders

    !> One step from the exact state; the dense output's largest error at theta = 0.1, 0.3,
    !! ..., 0.9 scales as h^(q+1) for an interpolant of order q.
    subroutine test_dense_orders()
        type(kepler_2d) :: sys
        type(ode_options) :: opt
        type(ode_result) :: res
        real(dp) :: y0(4), ye(4), yd(4), h(4), err(4), p, t0
        integer :: i, m, j
        integer, parameter :: expected(4) = [3, 4, 7, 8]
        character(len=8), parameter :: names(4) = ["RK4     ", "DOPRI5  ", "DOP853  ", &
                                                   "VERNER98"]
        t0 = 0.0_dp
        call kepler_exact(t0, y0)
        do m = METHOD_RK4, METHOD_VERNER98
            ! DOP853 and Verner reach round-off sooner: larger steps
            if (m == METHOD_VERNER98) then
                h = [0.6_dp, 0.5_dp, 0.4_dp, 0.3_dp]
            else if (m == METHOD_DOP853) then
                h = [0.32_dp, 0.24_dp, 0.16_dp, 0.12_dp]
            else
                h = [0.2_dp, 0.1_dp, 0.05_dp, 0.025_dp]
            end if
            do i = 1, 4
                opt = fixed_options(m, h(i))
                opt%dense_output = .true.
                call ode_solve(sys, [t0, t0 + h(i)], y0, opt, res)
                err(i) = 0.0_dp
                do j = 1, 9, 2
                    call res%sol%eval(t0 + 0.1_dp*j*h(i), yd)
                    call kepler_exact(t0 + 0.1_dp*j*h(i), ye)
                    err(i) = max(err(i), maxval(abs(yd - ye)))
                end do
            end do
            p = slope(h, err) - 1.0_dp
            call ts%check_close(p, real(expected(m), dp), 0.5_dp, &
                                "dense output order of "//trim(names(m)))
        end do
    end subroutine test_dense_orders

    subroutine test_kepler_tolerance()
        type(kepler_2d) :: sys
        type(ode_options) :: opt
        type(ode_result) :: res
        real(dp) :: y0(4), closure(3), energy(3), tols(3), e0
        integer :: i, m
        tols = [1.0e-6_dp, 1.0e-9_dp, 1.0e-12_dp]
        call kepler_exact(0.0_dp, y0)
        e0 = sys%energy(y0)
        do m = METHOD_DOPRI5, METHOD_DOP853
            do i = 1, 3
                opt%method = m
                opt%rtol = tols(i)
                opt%atol = tols(i)
                call ode_solve(sys, [0.0_dp, period], y0, opt, res)
                closure(i) = maxval(abs(res%y(:, res%nt) - y0))
                energy(i) = abs(sys%energy(res%y(:, res%nt)) - e0)
            end do
            call ts%check(closure(1) > closure(2) .and. closure(2) > closure(3), &
                          "Kepler closure error decreases with the tolerance")
            call ts%check(energy(1) > energy(3), "Kepler energy error decreases with tol")
            call ts%check_less(closure(1)/tols(1), 1.0e3_dp, "closure within 1e3 tol at 1e-6")
            call ts%check_less(closure(3), 1.0e-8_dp, "closure at tol 1e-12")
            call ts%check_less(closure(3)/closure(1), 1.0e-4_dp, &
                               "closure shrinks >= 1e4 over 6 decades of tol")
        end do
    end subroutine test_kepler_tolerance

    subroutine test_kepler_events()
        type(kepler_2d) :: sys
        type(ode_options) :: opt
        type(ode_result) :: res
        type(radial_events) :: ev
        real(dp) :: y0(4), want
        integer :: i
        logical :: ok
        call kepler_exact(0.0_dp, y0)
        opt%rtol = 1.0e-12_dp
        opt%atol = 1.0e-12_dp
        ev%direction = [0, -1]
        ev%terminal = [.false., .false.]
        call ode_solve(sys, [0.0_dp, 2.2_dp*period], y0, opt, res, events=ev)
        ! event 1 (both directions): T/2, T, 3T/2, 2T; event 2 (falling: apocentres): T/2, 3T/2
        call ts%check(res%nev == 6, "six event crossings over 2.2 periods")
        ok = .true.
        do i = 1, res%nev
            if (res%ev_id(i) == 1) then
                want = 0.5_dp*period*nint(res%ev_t(i)/(0.5_dp*period))
            else
                want = period*(nint((res%ev_t(i) - 0.5_dp*period)/period) + 0.5_dp)
            end if
            if (abs(res%ev_t(i) - want) > 1.0e-10_dp) ok = .false.
        end do
        call ts%check(ok, "peri/apocentre times to 1e-10")
        call ts%check(count(res%ev_id == 2) == 2, "falling direction finds apocentres only")
        ! terminal event at the first apocentre
        ev%terminal = [.false., .true.]
        call ode_solve(sys, [0.0_dp, 2.2_dp*period], y0, opt, res, events=ev)
        call ts%check(res%status == CM_EVENT_STOP, "terminal event stops with status 1")
        call ts%check_close(res%t(res%nt), 0.5_dp*period, 1.0e-10_dp, "stop time = T/2")
        call ts%check_close(res%y(1, res%nt), -(1.0_dp + ecc), 1.0e-10_dp, &
                            "state at the apocentre")
    end subroutine test_kepler_events

    subroutine test_outputs()
        type(kepler_2d) :: sys
        type(ode_options) :: opt
        type(ode_result) :: res
        real(dp) :: y0(4), te(7), ye(4), yd(4), emax, dmax
        integer :: i
        call kepler_exact(0.0_dp, y0)
        te = [0.0_dp, 0.5_dp, 1.0_dp, 2.5_dp, 3.0_dp, 5.9_dp, period]
        opt%rtol = 1.0e-11_dp
        opt%atol = 1.0e-11_dp
        opt%dense_output = .true.
        call ode_solve(sys, [0.0_dp, period], y0, opt, res, t_eval=te)
        call ts%check(res%nt == 7 .and. all(res%t == te), "t_eval points returned in order")
        emax = 0.0_dp
        dmax = 0.0_dp
        do i = 1, 7
            call kepler_exact(te(i), ye)
            emax = max(emax, maxval(abs(res%y(:, i) - ye)))
            call res%sol%eval(te(i), yd)
            dmax = max(dmax, maxval(abs(yd - res%y(:, i))))
        end do
        call ts%check_less(emax, 1.0e-8_dp, "t_eval values match the exact orbit")
        call ts%check_less(dmax, 1.0e-14_dp, "dense output object agrees with t_eval values")
        ! per-component tolerances equal to the scalar ones give the same steps
        opt%dense_output = .false.
        opt%rtol_vec = [1.0e-11_dp, 1.0e-11_dp, 1.0e-11_dp, 1.0e-11_dp]
        opt%atol_vec = opt%rtol_vec
        block
            type(ode_result) :: r2
            call ode_solve(sys, [0.0_dp, period], y0, opt, r2, t_eval=te)
            call ts%check(r2%stats%nfev + 0 <= res%stats%nfev .and. &
                          maxval(abs(r2%y - res%y)) < 1.0e-15_dp, &
                          "per-component tolerances reproduce scalar ones")
        end block
    end subroutine test_outputs

    subroutine test_backward()
        type(harmonic_oscillator) :: sys
        type(ode_options) :: opt
        type(ode_result) :: res
        opt%rtol = 1.0e-10_dp
        opt%atol = 1.0e-10_dp
        sys%omega = 2.0_dp
        call ode_solve(sys, [0.0_dp, -5.0_dp], [1.0_dp, 0.0_dp], opt, res)
        call ts%check(res%success, "backward integration succeeds")
        call ts%check_close(res%y(1, res%nt), cos(10.0_dp), 1.0e-8_dp, "backward x(-5)")
        call ts%check_close(res%y(2, res%nt), 2.0_dp*sin(10.0_dp), 1.0e-8_dp, "backward v(-5)")
    end subroutine test_backward

    subroutine test_bad_input()
        type(harmonic_oscillator) :: sys
        type(ode_options) :: opt
        type(ode_result) :: res
        real(dp) :: nan
        nan = 0.0_dp
        nan = nan/nan
        opt%rtol = -1.0_dp
        call ode_solve(sys, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], opt, res)
        call ts%check(res%status == CM_BAD_INPUT .and. index(res%message, "rtol") > 0, &
                      "negative rtol is bad input naming rtol")
        opt = ode_options()
        opt%atol = -1.0e-3_dp
        call ode_solve(sys, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], opt, res)
        call ts%check(res%status == CM_BAD_INPUT .and. index(res%message, "atol") > 0, &
                      "negative atol is bad input naming atol")
        opt = ode_options()
        call ode_solve(sys, [0.0_dp, 1.0_dp], [1.0_dp, nan], opt, res)
        call ts%check(res%status == CM_BAD_INPUT .and. index(res%message, "y0") > 0, &
                      "NaN in y0 is bad input naming y0")
        opt%method = METHOD_RK4
        call ode_solve(sys, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], opt, res)
        call ts%check(res%status == CM_BAD_INPUT .and. index(res%message, "RK4") > 0, &
                      "RK4 without a step is bad input")
        opt = ode_options()
        call ode_solve(sys, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], opt, res, t_eval=[0.5_dp, 2.0_dp])
        call ts%check(res%status == CM_BAD_INPUT .and. index(res%message, "t_eval") > 0, &
                      "t_eval outside t_span is bad input")
        call ode_solve(sys, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], opt, res, t_eval=[0.5_dp, 0.2_dp])
        call ts%check(res%status == CM_BAD_INPUT, "unsorted t_eval is bad input")
        opt%atol_vec = [1.0e-6_dp, 1.0e-6_dp, 1.0e-6_dp]
        call ode_solve(sys, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], opt, res)
        call ts%check(res%status == CM_BAD_INPUT .and. index(res%message, "atol") > 0, &
                      "wrong-size atol is bad input")
        opt = ode_options()
        opt%max_step = -1.0_dp
        call ode_solve(sys, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], opt, res)
        call ts%check(res%status == CM_BAD_INPUT .and. index(res%message, "max_step") > 0, &
                      "negative max_step is bad input")
        opt = ode_options()
        opt%method = 17
        call ode_solve(sys, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], opt, res)
        call ts%check(res%status == CM_BAD_INPUT, "unknown method is bad input")
    end subroutine test_bad_input

    subroutine test_failures()
        type(ode_function) :: sys
        type(ode_options) :: opt
        type(ode_result) :: res
        type(harmonic_oscillator) :: ho
        ! too many steps
        opt%max_steps = 10
        opt%rtol = 1.0e-12_dp
        opt%atol = 1.0e-12_dp
        call ode_solve(ho, [0.0_dp, 100.0_dp], [1.0_dp, 0.0_dp], opt, res)
        call ts%check(res%status == CM_TOO_MANY_STEPS .and. .not. res%success, &
                      "max_steps exceeded is reported")
        ! blow-up y' = y^2, y(0) = 1 at t = 1
        opt = ode_options()
        sys%f => blowup
        call ode_solve(sys, [0.0_dp, 2.0_dp], [1.0_dp], opt, res)
        call ts%check(res%status < 0 .and. abs(res%t(res%nt) - 1.0_dp) < 1.0e-2_dp, &
                      "blow-up at t=1 stops with a failure status near t=1: "//res%message)
        ! rhs that becomes NaN for t > 0.5
        sys%f => sqrt_rhs
        call ode_solve(sys, [0.0_dp, 1.0_dp], [1.0_dp], opt, res)
        call ts%check(res%status == CM_NONFINITE, "NaN right-hand side reported: "//res%message)
    end subroutine test_failures

    !> A step hook that projects onto the invariant circle removes the energy drift.
    subroutine test_hook()
        type(harmonic_oscillator) :: sys
        type(ode_options) :: opt
        type(ode_result) :: res, plain
        type(circle_projection) :: proj
        real(dp) :: drift_plain, drift_proj
        opt%method = METHOD_DOPRI5
        opt%rtol = 1.0e-6_dp
        opt%atol = 1.0e-6_dp
        call ode_solve(sys, [0.0_dp, 500.0_dp], [1.0_dp, 0.0_dp], opt, plain)
        call ode_solve(sys, [0.0_dp, 500.0_dp], [1.0_dp, 0.0_dp], opt, res, hook=proj)
        drift_plain = abs(sum(plain%y(:, plain%nt)**2) - 1.0_dp)
        drift_proj = maxval(abs(sum(res%y**2, dim=1) - 1.0_dp))
        call ts%check(drift_plain > 1.0e-5_dp, "without the hook the energy drifts")
        call ts%check_less(drift_proj, 1.0e-14_dp, "with the projecting hook it does not")
        call ts%check(proj%calls == res%stats%naccept, "the hook runs once per accepted step")
        proj%calls = 0
        proj%max_calls = 5
        call ode_solve(sys, [0.0_dp, 500.0_dp], [1.0_dp, 0.0_dp], opt, res, hook=proj)
        call ts%check(res%status == CM_EVENT_STOP .and. res%stats%naccept == 5, &
                      "a hook can stop the run")
        ! hit_t_eval: the outputs are projected step ends, exactly on the circle
        block
            real(dp) :: te(50)
            integer :: i
            te = [(10.0_dp*i, i=1, 50)]
            proj%calls = 0
            proj%max_calls = huge(1)
            opt%method = METHOD_DOP853
            call ode_solve(sys, [0.0_dp, 500.0_dp], [1.0_dp, 0.0_dp], opt, res, t_eval=te, &
                           hook=proj)
            call ts%check(res%nt == 50, "t_eval by interpolation between projected steps")
            drift_plain = maxval(abs(sum(res%y**2, dim=1) - 1.0_dp))
            opt%hit_t_eval = .true.
            call ode_solve(sys, [0.0_dp, 500.0_dp], [1.0_dp, 0.0_dp], opt, res, t_eval=te, &
                           hook=proj)
            drift_proj = maxval(abs(sum(res%y**2, dim=1) - 1.0_dp))
            call ts%check(res%nt == 50 .and. all(res%t == te), "hit_t_eval returns t_eval")
            call ts%check(drift_plain > 1.0e-10_dp .and. drift_proj < 1.0e-15_dp, &
                          "hit_t_eval outputs are projected points, interpolated ones are not")
            ! DOP853 with a hook and no dense output: f once per accepted step, after the hook
            call ts%check(res%stats%nfev == 11*(res%stats%naccept + res%stats%nreject) + &
                          res%stats%naccept + 2, &
                          "one evaluation per projected step (FSAL deferred)")
        end block
    end subroutine test_hook

    !> At tol 1e-13 the Verner pair is more accurate than DOP853 for no more evaluations.
    !> Work at equal accuracy: at tol 1e-12 the Verner pair's error is at most half of
    !! DOP853's for at most 1.2x its evaluations (a 2-period orbit with e = 0.5).
    subroutine test_tight_tolerance()
        type(kepler_2d) :: sys
        type(ode_options) :: opt
        type(ode_result) :: r8, r9
        real(dp) :: y0(4), yex(4), e8, e9
        call kepler_exact(0.0_dp, y0)
        call kepler_exact(2.0_dp*period, yex)
        opt%rtol = 1.0e-12_dp
        opt%atol = 1.0e-12_dp
        opt%method = METHOD_DOP853
        call ode_solve(sys, [0.0_dp, 2.0_dp*period], y0, opt, r8)
        opt%method = METHOD_VERNER98
        call ode_solve(sys, [0.0_dp, 2.0_dp*period], y0, opt, r9)
        e8 = maxval(abs(r8%y(:, r8%nt) - yex))
        e9 = maxval(abs(r9%y(:, r9%nt) - yex))
        write (*, '(a,2es10.2,2i7)') "  tol 1e-12 errors DOP853/VERNER98 and nfev:", e8, e9, &
            r8%stats%nfev, r9%stats%nfev
        call ts%check(r9%success .and. e9 < 0.5_dp*e8 .and. &
                      r9%stats%nfev < 1.2_dp*r8%stats%nfev, &
                      "VERNER98: half DOP853's error at tol 1e-12 for <= 1.2x the nfev")
        call ts%check(method_from_name("RKV98") == METHOD_VERNER98, "method name RKV98")
    end subroutine test_tight_tolerance

    subroutine blowup(t, y, dydt)
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        dydt(1) = y(1)**2
    end subroutine blowup

    subroutine sqrt_rhs(t, y, dydt)
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        if (t > 0.5_dp) then
            dydt(1) = sqrt(0.5_dp - t)
        else
            dydt(1) = 1.0_dp
        end if
    end subroutine sqrt_rhs

end program test_ode
