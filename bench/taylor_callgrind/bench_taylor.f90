!> Kepler e = 0.9, one period per repetition, rtol = atol = TOL (default 1e-12), on the
!! generated symbolic Kepler module (test/taylor_kepler_model.f90):
!!   bench_taylor taylor|fixed|dop853 integrate|solve REPS [TOL]
!! fixed: Taylor with the recurrences written out for the order (the module
!! conmech_symbolic_taylor_fixed that conmech.symbolic.taylor.fixed_order_source writes for
!! the same equations, as solve_ivp uses them).
!! integrate: ode_integrate (no storage); solve: ode_solve (every step stored, as
!! conmech.solve_ivp does). For callgrind (bench/callgrind_taylor.sh): instructions per
!! period = (count at REPS = 11 - count at REPS = 1)/10.
program bench_taylor
    use conmech
    use conmech_ode_options, only: METHOD_TAYLOR
    use taylor_kepler_model
    use kepler_fixed_jet, only: kepler_fixed
    implicit none
    character(len=16) :: meth, mode, a
    integer :: reps, r, info
    real(dp) :: tol, y(4), y0(4), e, err
    class(kepler_sym), allocatable :: kep
    type(ode_options) :: opt
    type(ode_stats) :: st
    type(ode_result) :: res
    call get_command_argument(1, meth)
    call get_command_argument(2, mode)
    call get_command_argument(3, a)
    read (a, *) reps
    tol = 1.0e-12_dp
    if (command_argument_count() >= 4) then
        call get_command_argument(4, a)
        read (a, *) tol
    end if
    if (trim(meth) == "fixed") then
        allocate (kepler_fixed :: kep)
    else
        allocate (kepler_sym :: kep)
    end if
    e = 0.9_dp
    y0 = [1.0_dp - e, 0.0_dp, 0.0_dp, sqrt((1.0_dp + e)/(1.0_dp - e))]
    opt%method = METHOD_DOP853
    if (trim(meth) /= "dop853") opt%method = METHOD_TAYLOR
    opt%rtol = tol
    opt%atol = tol
    err = 0.0_dp
    do r = 1, reps
        y = y0
        if (trim(mode) == "solve") then
            call ode_solve(kep, [0.0_dp, 2.0_dp*acos(-1.0_dp)], y0, opt, res)
            y = res%y(:, res%nt)
            st = res%stats
        else
            call ode_integrate(kep, 0.0_dp, 2.0_dp*acos(-1.0_dp), y, opt, info, st)
        end if
        err = max(err, maxval(abs(y - y0)))
    end do
    print '(a, 1x, a, 1x, es10.3, 1x, i0, 1x, i0)', trim(meth), trim(mode), err, st%nfev, &
        st%naccept
end program bench_taylor
