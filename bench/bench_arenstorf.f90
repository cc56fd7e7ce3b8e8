!> Pure Fortran benchmark: cost of one Arenstorf period with DOP853 and DOPRI5 at tol 1e-10,
!! against the cost of the right-hand side alone, so the per-step overhead of the
!! integrator can be read off.   Run: fpm run --example bench_arenstorf --profile release
program bench_arenstorf
    use conmech
    implicit none
    type(arenstorf) :: sys
    type(ode_options) :: opt
    type(ode_stats) :: st
    real(dp) :: y0(4), y(4), f(4), t_per, t_rhs, tsum, period, err
    integer :: rep, nrep, info, m, i, nfev, nacc
    integer(8) :: c0, c1, rate
    character(len=8), parameter :: names(3) = ["RK4     ", "DOPRI5  ", "DOP853  "]

    y0 = [0.994_dp, 0.0_dp, 0.0_dp, -2.00158510637908252240537862224_dp]
    period = 17.0652165601579625588917206249_dp

    ! cost of one right-hand side evaluation
    nrep = 2000000
    y = y0
    tsum = 0.0_dp
    call system_clock(c0, rate)
    do i = 1, nrep
        y(1) = y0(1) + 1.0e-9_dp*real(mod(i, 7), dp)
        call sys%rhs(0.0_dp, y, f)
        tsum = tsum + f(3)
    end do
    call system_clock(c1)
    t_rhs = real(c1 - c0, dp)/real(rate, dp)/nrep
    write (*, '(a,f10.4,a,es10.2,a)') "rhs alone: ", t_rhs*1.0e6_dp, " us per call (checksum ", &
        tsum, ")"
    write (*, '(a)') "method   us/period   nfev/period   steps   closure-err   " // &
        "integrator time / (nfev * rhs time)"
    do m = METHOD_DOPRI5, METHOD_DOP853
        opt%method = m
        opt%rtol = 1.0e-10_dp
        opt%atol = 1.0e-10_dp
        nrep = 200
        call system_clock(c0)
        do rep = 1, nrep
            y = y0
            call ode_integrate(sys, 0.0_dp, period, y, opt, info, st)
        end do
        call system_clock(c1)
        t_per = real(c1 - c0, dp)/real(rate, dp)/nrep
        nfev = st%nfev
        nacc = st%naccept
        err = maxval(abs(y - y0))
        write (*, '(a8,f11.1,i13,i9,es13.2,f14.2)') names(m), t_per*1.0e6_dp, nfev, nacc, err, &
            t_per/(nfev*t_rhs)
        if (info /= 0) write (*, '(a,i0)') "  failed with status ", info
    end do
end program bench_arenstorf
