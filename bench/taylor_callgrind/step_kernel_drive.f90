!> Kepler e = 0.9, one period per repetition, rtol = atol = 1e-12: the loop of
!! taylor_propagate (no storage) with the step's operations of the library
!! (conmech_taylor_core, the recurrences through a procedure pointer as c_ode_system calls
!! them: G) or with the kernel written out for the model (step_kernel_kepler.f90, also
!! through a pointer: K); J: the recurrences alone, 73 expansions (the steps of a period)
!! per repetition, all about the same state; D: the same, each waiting for the previous
!! one's last coefficients (a serial chain). Prints the steps, the rejected steps, the final
!! state's bits, its closure error and the time per period (us).
!!   step_kernel_drive G|K|J|D REPS
program drive
    use, intrinsic :: iso_c_binding
    use, intrinsic :: iso_fortran_env, only: int64
    use conmech_taylor_core
    use conmech_c_system, only: c_taylor_fn
    use conmech_symbolic_taylor_fixed, only: conmech_taylor_fixed
    use kepler_kernel, only: kepler_step
    implicit none
    integer, parameter :: dp = c_double, n = 4, p = 15, nw = 10
    abstract interface
        subroutine kern_fn(t, h, c, w, rtol, atol, eps, decay, e, dy, err, fin, rho, par) bind(c)
            import :: c_double, c_int
            real(c_double), value :: t, h, eps, decay
            real(c_double), intent(in) :: c(*), rtol(*), atol(*), par(*)
            real(c_double), intent(inout) :: w(*), e(*)
            real(c_double), intent(out) :: dy(*), err, rho
            integer(c_int), intent(out) :: fin
        end subroutine kern_fn
    end interface
    procedure(c_taylor_fn), pointer :: jf
    procedure(kern_fn), pointer :: kf
    character(len=8) :: mode, a
    integer :: reps, r, ic, io, nst, nrej, i
    integer(c_int) :: fi
    real(dp) :: ynew(n), jets(0:p, nw, 2), rtol(n), atol(n), e(n), dy(n), y0(n), y(n), par(1)
    real(dp) :: t, tlo, h, tf, eps, decay, rho, err, ecc, hmax
    logical :: hit, fin
    integer(int64) :: c0, c1, cr
    call get_command_argument(1, mode)
    call get_command_argument(2, a)
    read (a, *) reps
    t = 0.0_dp
    call c_f_procpointer(c_funloc(conmech_taylor_fixed), jf)
    call c_f_procpointer(c_funloc(kepler_step), kf)
    par = 0.0_dp
    ecc = 0.9_dp
    y0 = [1.0_dp - ecc, 0.0_dp, 0.0_dp, sqrt((1.0_dp + ecc)/(1.0_dp - ecc))]
    rtol = 1.0e-12_dp
    atol = 1.0e-12_dp
    eps = 1.0e-12_dp
    decay = exp(-2.0_dp - 0.7_dp/real(p - 1, dp))
    tf = 2.0_dp*acos(-1.0_dp)
    hmax = tf
    call system_clock(c0, cr)
    if (mode(1:1) == "J") then
        jets = 0.0_dp
        jets(0, 1:n, 1) = y0
        do r = 1, reps*73
            call jf(t, p, jets(:, :, 1), par)
        end do
        call system_clock(c1)
        print '(a, 1x, f8.3, a)', "J 73 expansions", real(c1 - c0, dp)/real(cr, dp)/reps*1e6, " us"
        stop
    end if
    if (mode(1:1) == "D") then
        ! each expansion waits for the last coefficients of the previous one (y0 + 0 w(p, :):
        ! the same state, but a data dependency the compiler keeps), the recurrences as a
        ! serial chain, as in the integration (the next step size needs them)
        do r = 1, reps
            jets(0, 1:n, 1) = y0
            do i = 1, 73
                call jf(t, p, jets(:, :, 1), par)
                jets(0, 1:n, 1) = y0 + 0.0_dp*jets(p, 1:n, 1)
            end do
        end do
        call system_clock(c1)
        print '(a, 1x, es10.3, 1x, f8.3, a)', "D", jets(0, 1, 1), &
            real(c1 - c0, dp)/real(cr, dp)/reps*1e6, " us"
        stop
    end if
    do r = 1, reps
        jets = 0.0_dp
        ic = 1
        t = 0.0_dp
        tlo = 0.0_dp
        nst = 0
        nrej = 0
        jets(0, 1:n, ic) = y0
        call jf(t, p, jets(:, :, ic), par)
        call taylor_next_rho(n, n, p, jets(:, :, ic), rtol, atol, eps, decay, e, rho)
        h = min(rho, hmax)
        do
            io = 3 - ic
            do
                hit = .false.
                if (t + h - tf >= 0.0_dp) then
                    h = (tf - t) - tlo
                    hit = .true.
                end if
                nst = nst + 1
                if (mode(1:1) == "G") then
                    call taylor_eval_jet(n, p, jets(:, :, ic), h, jets(:, :, io), ynew, &
                                         dy)
                    call jf(t + h, p, jets(:, :, io), par)
                    call taylor_check_jet(n, p, h, jets(:, :, io), dy, e, err, fin)
                else
                    call kf(t, h, jets(:, :, ic), jets(:, :, io), rtol, atol, eps, decay, e, &
                            dy, err, fi, rho, par)
                    fin = fi == 1
                end if
                if (err <= TAYLOR_CHECK_MAX) exit
                nrej = nrej + 1
                h = taylor_shrink(h, err, p)
            end do
            ic = io
            if (hit) then
                t = tf
                tlo = 0.0_dp
            else
                call taylor_add_time(t, tlo, h)
            end if
            if (mode(1:1) == "G") then
                call taylor_next_rho(n, n, p, jets(:, :, ic), rtol, atol, eps, decay, e, rho)
            end if
            h = min(rho, hmax)
            if (hit) exit
        end do
    end do
    call system_clock(c1)
    y = jets(0, 1:n, ic)
    print '(a, 1x, i0, 1x, i0, 4(1x, z16.16), 1x, es10.3, 1x, f8.3, a)', trim(mode), nst, nrej, &
        (y(i), i = 1, n), maxval(abs(y - y0)), real(c1 - c0, dp)/real(cr, dp)/reps*1e6, " us"
end program drive
