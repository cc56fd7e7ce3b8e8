!> Explicit Runge-Kutta integrators: fixed-step RK4, and adaptive DOPRI5 and DOP853 with
!! Hairer's step-size control, dense output and event location.
!!
!! Verner's 9(8) pair (METHOD_VERNER98) is the high-order choice for tight tolerances
!! (rtol below about 1e-10): same control with exponent 1/9, step ratios [1/3, 6].
!!
!! Two entry points:
!! - `ode_solve` stores the solution (every accepted step, or the points of `t_eval`),
!!   the dense output if asked for, and the events, in an `ode_result`;
!! - `ode_integrate` is the lean path: it advances y from t0 to t1 in place and stores
!!   nothing (used by shooting, variational equations and batch sweeps).
!!
!! Step-size control follows Hairer's dopri5.f/dop853.f: error norm
!! sqrt(mean((err_i/sk_i)^2)), sk_i = atol_i + rtol_i max(|y_i|, |ynew_i|) (DOP853 blends its
!! 5th- and 3rd-order estimators), safety 0.9, step ratio bounds [0.2, 10] (DOPRI5, with
!! Lund stabilisation beta = 0.04) and [1/3, 6] (DOP853), no step growth right after a
!! rejection, Hairer's initial-step heuristic (hinit), FSAL reuse, at most `max_steps`
!! attempted steps, failure when 0.1|h| <= |t| eps.
!!
!! All state lives in local variables: routines are safe to call from many threads at once.
module conmech_ode_solver
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_quiet_nan
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system, ode_events, ode_step_hook
    use conmech_rk_tableaus, only: rk_tableau, dopri5_tableau, dop853_tableau, &
        verner98_tableau
    implicit none
    private

    integer, parameter, public :: METHOD_RK4 = 1     !! classical RK4, fixed step
    integer, parameter, public :: METHOD_DOPRI5 = 2  !! Dormand-Prince 5(4), dense order 4
    integer, parameter, public :: METHOD_DOP853 = 3  !! Dormand-Prince 8(5,3), dense order 7
    integer, parameter, public :: METHOD_VERNER98 = 4 !! Verner 9(8), dense order 8
    ! implicit methods (conmech_radau, conmech_gauss; reached through implicit_solve)
    integer, parameter, public :: METHOD_RADAU5 = 5  !! Radau IIA order 5, stiff, adaptive
    integer, parameter, public :: METHOD_GAUSS4 = 6  !! Gauss-Legendre s = 2, fixed step
    integer, parameter, public :: METHOD_GAUSS6 = 7  !! Gauss-Legendre s = 3, fixed step
    integer, parameter, public :: METHOD_RATTLE = 8  !! constrained systems only (rattle_solve)

    integer, parameter :: FORM_HAIRER = 1   !! y0 + x (F1 + (1-x)(F2 + x (F3 + ...)))
    integer, parameter :: FORM_POWER = 2    !! y0 + x F1 + x^2 F2 + ... + x^nf F_nf

    public :: ode_options, ode_result, ode_stats, dense_solution
    public :: ode_solve, ode_integrate, method_from_name

    !> Options of the integrators. Zero means "use the method's default" for
    !! first_step, safety, fac_min, fac_max; beta < 0 means the default.
    type :: ode_options
        integer :: method = METHOD_DOP853
        real(dp) :: rtol = 1.0e-3_dp               !! relative tolerance (scalar)
        real(dp) :: atol = 1.0e-6_dp               !! absolute tolerance (scalar)
        real(dp), allocatable :: rtol_vec(:)       !! per-component rtol (overrides rtol)
        real(dp), allocatable :: atol_vec(:)       !! per-component atol (overrides atol)
        real(dp) :: first_step = 0.0_dp            !! initial step (RK4: the step); 0 = auto
        real(dp) :: max_step = huge(1.0_dp)        !! largest |h|
        integer :: max_steps = 100000              !! attempted steps before giving up
        real(dp) :: safety = 0.0_dp                !! Hairer's safe (default 0.9)
        real(dp) :: fac_min = 0.0_dp               !! smallest step ratio hnew/h
        real(dp) :: fac_max = 0.0_dp               !! largest step ratio hnew/h
        real(dp) :: beta = -1.0_dp                 !! Lund stabilisation exponent
        logical :: dense_output = .false.          !! keep a dense_solution in the result
        logical :: save_steps = .true.             !! without t_eval: store every step
        logical :: hit_t_eval = .false.            !! shorten steps to land on t_eval points
                                                   !! (outputs are step ends, not interpolated)
    end type ode_options

    !> Counters of one integration.
    type :: ode_stats
        integer :: nfev = 0       !! right-hand side evaluations
        integer :: naccept = 0    !! accepted steps
        integer :: nreject = 0    !! rejected steps
        real(dp) :: h_next = 0.0_dp   !! step size proposed for a continuation
        integer :: njev = 0       !! Jacobian evaluations (implicit methods)
        integer :: nlu = 0        !! LU decompositions (implicit methods)
    end type ode_stats

    !> Piecewise polynomial dense output, Hairer's form on each step [t0, t0 + h]:
    !! y(t0 + x h) = y0 + x (F1 + (1-x)(F2 + x (F3 + (1-x)(F4 + ...)))).
    type :: dense_solution
        integer :: n = 0            !! dimension
        integer :: nseg = 0         !! number of steps stored
        integer :: nf = 0           !! number of F coefficients (3 RK4, 4 DOPRI5, 7 DOP853,
                                    !! 8 VERNER98)
        integer :: form = FORM_HAIRER   !! polynomial form of the coefficients
        real(dp) :: t_first = 0.0_dp, t_last = 0.0_dp
        real(dp), allocatable :: ts(:), hs(:)      !! step start and signed length
        real(dp), allocatable :: coef(:, :, :)     !! (n, 0:nf, nseg); coef(:,0,:) = y0
    contains
        procedure :: eval => dense_eval
        procedure :: eval_many => dense_eval_many
    end type dense_solution

    !> Result of `ode_solve`.
    type :: ode_result
        integer :: status = CM_BAD_INPUT
        character(len=:), allocatable :: message
        logical :: success = .false.
        type(ode_stats) :: stats
        integer :: nt = 0                          !! number of output points
        real(dp), allocatable :: t(:)              !! (nt)
        real(dp), allocatable :: y(:, :)           !! (n, nt)
        integer :: nev = 0                         !! number of events found
        real(dp), allocatable :: ev_t(:)           !! (nev) event times
        real(dp), allocatable :: ev_y(:, :)        !! (n, nev) states at the events
        integer, allocatable :: ev_id(:)           !! (nev) which event function
        type(dense_solution) :: sol                !! if options%dense_output
    end type ode_result

    interface
        !> The implicit methods (METHOD_RADAU5, METHOD_GAUSS4, METHOD_GAUSS6), implemented
        !! in the submodule conmech_radau_dispatch; arguments as ode_solve.
        module subroutine implicit_solve(sys, t_span, y0, options, res, t_eval, events)
            class(ode_system), intent(in) :: sys
            real(dp), intent(in) :: t_span(2)
            real(dp), intent(in) :: y0(:)
            type(ode_options), intent(in) :: options
            type(ode_result), intent(out) :: res
            real(dp), intent(in), optional :: t_eval(:)
            class(ode_events), intent(in), optional :: events
        end subroutine implicit_solve
    end interface

contains

    !> Method code from a name: "RK4", "DOPRI5"/"RK45", "DOP853", "VERNER98"/"RKV98",
    !! "RADAU5"/"Radau", "GAUSS4", "GAUSS6", "RATTLE"; 0 if unknown.
    pure function method_from_name(name) result(m)
        character(len=*), intent(in) :: name
        integer :: m
        select case (trim(adjustl(name)))
        case ("RK4", "rk4")
            m = METHOD_RK4
        case ("DOPRI5", "dopri5", "RK45", "rk45")
            m = METHOD_DOPRI5
        case ("DOP853", "dop853")
            m = METHOD_DOP853
        case ("VERNER98", "verner98", "RKV98", "rkv98", "Vern9")
            m = METHOD_VERNER98
        case ("RADAU5", "radau5", "Radau", "RADAU", "radau")
            m = METHOD_RADAU5
        case ("GAUSS4", "gauss4")
            m = METHOD_GAUSS4
        case ("GAUSS6", "gauss6")
            m = METHOD_GAUSS6
        case ("RATTLE", "rattle")
            m = METHOD_RATTLE
        case default
            m = 0
        end select
    end function method_from_name

    !> Solve y' = f(t, y), y(t_span(1)) = y0 on t_span (forward or backward in time).
    !!
    !! Without `t_eval` the result holds every accepted step (if options%save_steps, else
    !! the end points only); with `t_eval` (sorted in the direction of integration and
    !! inside t_span) it holds the solution there, from the dense output. Events are
    !! located on the dense output to near machine precision; a terminal event ends the
    !! integration there (status CM_EVENT_STOP) and is the last output point.
    subroutine ode_solve(sys, t_span, y0, options, res, t_eval, events, hook)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: y0(:)
        type(ode_options), intent(in) :: options
        type(ode_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        class(ode_step_hook), intent(inout), optional :: hook
        real(dp), allocatable :: y(:)
        integer :: i
        character(len=:), allocatable :: msg

        if (options%method >= METHOD_RADAU5) then
            if (present(hook)) then
                call fail(res, CM_BAD_INPUT, "bad input: step hooks need an explicit method")
            else
                call implicit_solve(sys, t_span, y0, options, res, t_eval, events)
            end if
            return
        end if
        allocate (y(size(y0)))
        y = y0
        allocate (res%t(0), res%y(size(y0), 0), res%ev_t(0), res%ev_y(size(y0), 0), &
                  res%ev_id(0))
        if (present(t_eval)) then
            if (size(t_eval) > 0) then
                if (any(.not. ieee_is_finite(t_eval))) then
                    call fail(res, CM_BAD_INPUT, "bad input: t_eval contains non-finite values")
                    return
                end if
                do i = 1, size(t_eval)
                    if ((t_eval(i) - t_span(1))*(t_span(2) - t_eval(i)) < 0.0_dp) then
                        call fail(res, CM_BAD_INPUT, "bad input: t_eval values must lie in t_span")
                        return
                    end if
                    if (i > 1) then
                        if ((t_eval(i) - t_eval(i - 1))*(t_span(2) - t_span(1)) < 0.0_dp) then
                            call fail(res, CM_BAD_INPUT, "bad input: t_eval must be sorted in " &
                                      //"the direction of integration")
                            return
                        end if
                    end if
                end do
            end if
        end if
        call drive(sys, t_span(1), t_span(2), y, options, res%stats, res%status, msg, &
                   res, t_eval, events, hook)
        res%message = msg
        res%success = res%status >= 0
    end subroutine ode_solve

    !> Advance y from t0 to t1 in place, storing nothing. Fast path for shooting.
    subroutine ode_integrate(sys, t0, t1, y, options, info, stats, message, hook)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t0, t1
        real(dp), intent(inout) :: y(:)
        type(ode_options), intent(in) :: options
        integer, intent(out) :: info
        type(ode_stats), intent(out), optional :: stats
        character(len=:), allocatable, intent(out), optional :: message
        class(ode_step_hook), intent(inout), optional :: hook
        type(ode_stats) :: st
        character(len=:), allocatable :: msg
        call drive(sys, t0, t1, y, options, st, info, msg, hook=hook)
        if (present(stats)) stats = st
        if (present(message)) message = msg
    end subroutine ode_integrate

    subroutine fail(res, info, msg)
        type(ode_result), intent(inout) :: res
        integer, intent(in) :: info
        character(len=*), intent(in) :: msg
        res%status = info
        res%message = msg
        res%success = .false.
    end subroutine fail

    !> The common driver of every method.
    subroutine drive(sys, t0, tf, y, opt, st, info, msg, res, t_eval, events, hook)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t0, tf
        real(dp), intent(inout) :: y(:)
        type(ode_options), intent(in) :: opt
        type(ode_stats), intent(inout) :: st
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(ode_result), intent(inout), optional :: res
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        class(ode_step_hook), intent(inout), optional :: hook

        type(rk_tableau) :: tab
        real(dp), allocatable :: k(:, :), ynew(:), ytmp(:), sk(:), rtolv(:), atolv(:)
        real(dp), allocatable :: fc(:, :), g_old(:), g_new(:), ye(:), zero(:)
        real(dp) :: t, h, hnew, hmax, posneg, err, fac11, fac, facold, safe, facc1, facc2
        real(dp) :: expo1, beta, t_stop, te
        integer :: n, nf, nsteps, ne, n_nonfinite, ie, iev, ifsal, form
        integer :: i_eval, n_eval, nev_step
        logical :: adaptive, need_dense, reject, last, has_events, store_steps, stop_now
        logical :: changed, hit, hit_mode, defer_fsal
        integer :: hinfo
        real(dp) :: target, t_new, h_fixed, h_unclipped
        real(dp), allocatable :: ev_times(:)
        integer, allocatable :: ev_ids(:)
        character(len=32) :: buf

        n = size(y)
        st = ode_stats()
        info = CM_SUCCESS
        msg = "success"
        has_events = present(events)
        if (has_events) has_events = events%n_events() > 0
        n_eval = 0
        if (present(t_eval)) n_eval = size(t_eval)
        store_steps = present(res) .and. n_eval == 0
        if (store_steps) store_steps = opt%save_steps
        hit_mode = opt%hit_t_eval .and. n_eval > 0
        need_dense = has_events .or. (n_eval > 0 .and. .not. hit_mode)
        if (present(res)) need_dense = need_dense .or. opt%dense_output

        ! ---------------------------------------------------------------- validation
        call validate(info, msg)
        if (info /= CM_SUCCESS) return
        posneg = sign(1.0_dp, tf - t0)
        allocate (rtolv(n), atolv(n))
        if (allocated(opt%rtol_vec)) then
            rtolv = opt%rtol_vec
        else
            rtolv = opt%rtol
        end if
        if (allocated(opt%atol_vec)) then
            atolv = opt%atol_vec
        else
            atolv = opt%atol
        end if
        rtolv = max(rtolv, 100.0_dp*epsilon(1.0_dp))   ! as SciPy: rtol >= 100 eps

        form = FORM_HAIRER
        select case (opt%method)
        case (METHOD_RK4)
            adaptive = .false.
            nf = 3
            tab%stages = 4
            ifsal = 13
        case (METHOD_DOPRI5)
            adaptive = .true.
            tab = dopri5_tableau()
            nf = 4
            ifsal = 7
            safe = 0.9_dp; facc1 = 1.0_dp/0.2_dp; facc2 = 1.0_dp/10.0_dp; beta = 0.04_dp
            if (opt%beta >= 0.0_dp) beta = opt%beta
            expo1 = 0.2_dp - beta*0.75_dp
        case (METHOD_VERNER98)
            adaptive = .true.
            tab = verner98_tableau()
            nf = 8
            form = FORM_POWER
            ifsal = 17
            safe = 0.9_dp; facc1 = 1.0_dp/0.333_dp; facc2 = 1.0_dp/6.0_dp; beta = 0.0_dp
            if (opt%beta >= 0.0_dp) beta = opt%beta
            expo1 = 1.0_dp/9.0_dp - beta*0.2_dp
        case default
            adaptive = .true.
            tab = dop853_tableau()
            nf = 7
            ifsal = 13
            safe = 0.9_dp; facc1 = 1.0_dp/0.333_dp; facc2 = 1.0_dp/6.0_dp; beta = 0.0_dp
            if (opt%beta >= 0.0_dp) beta = opt%beta
            expo1 = 1.0_dp/8.0_dp - beta*0.2_dp
        end select
        if (opt%safety > 0.0_dp) safe = opt%safety
        if (opt%fac_min > 0.0_dp) facc1 = 1.0_dp/opt%fac_min
        if (opt%fac_max > 0.0_dp) facc2 = 1.0_dp/opt%fac_max
        hmax = min(abs(opt%max_step), abs(tf - t0))
        n_nonfinite = 0

        allocate (k(n, 21), ynew(n), ytmp(n), sk(n), fc(n, 0:nf), zero(n))
        zero = 0.0_dp
        t = t0

        ! outputs at the start
        i_eval = 1
        if (present(res)) then
            if (store_steps .or. (.not. opt%save_steps .and. n_eval == 0)) &
                call push_point(res, t, y)
            if (opt%dense_output) call dense_init(res%sol, n, nf, form, t0)
        end if
        if (n_eval > 0) then
            do while (i_eval <= n_eval)
                if (t_eval(i_eval) /= t0) exit
                call push_point(res, t0, y)
                i_eval = i_eval + 1
            end do
        end if
        if (tf == t0) then
            call finish_outputs()
            return
        end if

        call sys%rhs(t, y, k(:, 1))
        st%nfev = st%nfev + 1
        if (.not. all(ieee_is_finite(k(:, 1)))) then
            info = CM_NONFINITE
            msg = "the right-hand side is not finite at the initial point"
            return
        end if
        if (has_events) then
            ne = events%n_events()
            allocate (g_old(ne), g_new(ne), ye(n), ev_times(ne), ev_ids(ne))
            call events%eval(t, y, g_old)
        end if

        ! initial step
        if (adaptive) then
            if (opt%first_step > 0.0_dp) then
                h = min(opt%first_step, hmax)*posneg
            else
                h = hinit()
            end if
        else
            nsteps = max(1, ceiling(abs(tf - t0)/opt%first_step*(1.0_dp - 1.0e-12_dp)))
            h = (tf - t0)/real(nsteps, dp)
        end if
        h_fixed = h
        ! without dense output, a step hook that may change y gets f evaluated once, after it
        defer_fsal = present(hook) .and. .not. need_dense .and. opt%method /= METHOD_DOPRI5

        facold = 1.0e-4_dp
        reject = .false.
        last = .false.
        nsteps = 0
        ! ---------------------------------------------------------------- main loop
        do
            if (nsteps >= opt%max_steps) then
                info = CM_TOO_MANY_STEPS
                write (buf, '(es14.6)') t
                msg = "too many steps: max_steps reached at t ="//trim(buf)
                exit
            end if
            if (0.1_dp*abs(h) <= abs(t)*epsilon(1.0_dp) .or. abs(h) < tiny(1.0_dp)) then
                write (buf, '(es14.6)') t
                if (n_nonfinite > 0) then
                    info = CM_NONFINITE
                    msg = "non-finite values in the right-hand side near t ="//trim(buf)
                else
                    info = CM_STEP_TOO_SMALL
                    msg = "step size too small at t ="//trim(buf)
                end if
                exit
            end if
            ! the point the step must land on if it reaches it: tf, or in hit mode the next
            ! t_eval point (Hairer's rule: stretch the step by up to 1 % to reach it)
            target = tf
            if (hit_mode .and. i_eval <= n_eval) target = t_eval(i_eval)
            hit = .false.
            h_unclipped = h
            if (adaptive) then
                if ((t + 1.01_dp*h - target)*posneg > 0.0_dp) then
                    h = target - t
                    hit = .true.
                end if
            else
                h = h_fixed
                if ((target - t)*posneg <= abs(h)*(1.0_dp + 1.0e-8_dp)) then
                    h = target - t
                    hit = .true.
                end if
            end if
            last = hit .and. target == tf
            nsteps = nsteps + 1

            select case (opt%method)
            case (METHOD_RK4)
                call rk4_step()
                err = 0.0_dp
                if (.not. all(ieee_is_finite(ynew))) err = ieee_value(1.0_dp, ieee_quiet_nan)
            case (METHOD_DOPRI5)
                call dopri5_step()
            case (METHOD_VERNER98)
                call verner_step()
            case default
                call dop853_step()
            end select

            if (.not. (err <= 1.0_dp)) then
                ! ------------------------------------------------ rejected step
                if (.not. adaptive) then
                    info = CM_NONFINITE
                    write (buf, '(es14.6)') t
                    msg = "non-finite state in a fixed step from t ="//trim(buf)
                    exit
                end if
                if (err /= err .or. err > huge(1.0_dp)) then
                    ! non-finite error estimate: cut the step hard
                    n_nonfinite = n_nonfinite + 1
                    if (n_nonfinite > 40) then
                        info = CM_NONFINITE
                        write (buf, '(es14.6)') t
                        msg = "non-finite values in the right-hand side near t ="//trim(buf)
                        exit
                    end if
                    h = h*0.1_dp
                else
                    n_nonfinite = 0
                    fac11 = err**expo1
                    h = h/min(facc1, fac11/safe)
                end if
                reject = .true.
                if (st%naccept >= 1) st%nreject = st%nreject + 1
                cycle
            end if

            ! ---------------------------------------------------- accepted step
            n_nonfinite = 0
            st%naccept = st%naccept + 1
            if (adaptive) then
                fac11 = err**expo1
                fac = fac11/facold**beta
                fac = max(facc2, min(facc1, fac/safe))
                hnew = h/fac
                facold = max(err, 1.0e-4_dp)
                ! a step shortened to land on a point does not shrink the next one
                if (hit) hnew = posneg*max(abs(hnew), abs(h_unclipped))
            else
                hnew = h_fixed
            end if
            t_new = t + h
            if (hit) t_new = target
            ! the new right-hand side (FSAL): all but DOPRI5 evaluate it here
            if (opt%method /= METHOD_DOPRI5 .and. .not. defer_fsal) then
                call sys%rhs(t_new, ynew, k(:, ifsal))
                st%nfev = st%nfev + 1
            end if
            if (need_dense) call dense_coefs()

            stop_now = .false.
            t_stop = t_new
            if (has_events) call find_events()

            ! outputs inside the step from the dense output; a point at the step's end is
            ! written after the step hook, with the final state
            if (n_eval > 0) then
                do while (i_eval <= n_eval)
                    if (stop_now) then
                        if ((t_eval(i_eval) - t_stop)*posneg > 0.0_dp) exit
                    else
                        if ((t_eval(i_eval) - t_new)*posneg >= 0.0_dp) exit
                    end if
                    call interp(fc, form, (t_eval(i_eval) - t)/h, ytmp)
                    call push_point(res, t_eval(i_eval), ytmp)
                    i_eval = i_eval + 1
                end do
            end if
            if (present(res)) then
                if (opt%dense_output) call dense_push(res%sol, t, h, fc, t_stop)
            end if

            if (stop_now) then
                call interp(fc, form, (t_stop - t)/h, ytmp)
                y = ytmp
                t = t_stop
                if (store_steps) call push_point(res, t, y)
                info = CM_EVENT_STOP
                msg = "a termination event occurred"
                exit
            end if

            y = ynew
            t = t_new
            if (.not. defer_fsal) k(:, 1) = k(:, ifsal)
            if (present(hook)) then
                call hook%after_step(t, y, changed, hinfo)
                if (changed .or. defer_fsal) then
                    call sys%rhs(t, y, k(:, 1))
                    st%nfev = st%nfev + 1
                end if
                if (hinfo /= 0) then
                    if (store_steps) call push_point(res, t, y)
                    if (hinfo < 0) then
                        info = hinfo
                        msg = "stopped by the step hook"
                        if (allocated(hook%message)) msg = hook%message
                    else
                        info = CM_EVENT_STOP
                        msg = "stopped by the step hook"
                    end if
                    exit
                end if
            end if
            if (.not. all(ieee_is_finite(k(:, 1)))) then
                info = CM_NONFINITE
                write (buf, '(es14.6)') t
                msg = "non-finite right-hand side at t ="//trim(buf)
                exit
            end if
            if (store_steps) call push_point(res, t, y)
            do while (i_eval <= n_eval)
                if (t_eval(i_eval) /= t) exit
                call push_point(res, t, y)
                i_eval = i_eval + 1
            end do
            if (last) exit
            if (adaptive) then
                if (abs(hnew) > hmax) hnew = posneg*hmax
                if (reject) hnew = posneg*min(abs(hnew), abs(h))
            end if
            reject = .false.
            h = hnew
        end do

        st%h_next = h
        call finish_outputs()

    contains

        subroutine validate(info, msg)
            integer, intent(out) :: info
            character(len=:), allocatable, intent(out) :: msg
            info = CM_BAD_INPUT
            if (n < 1) then
                msg = "bad input: y0 is empty"
            else if (.not. all(ieee_is_finite(y))) then
                msg = "bad input: y0 contains NaN or Inf"
            else if (.not. (ieee_is_finite(t0) .and. ieee_is_finite(tf))) then
                msg = "bad input: t_span must be finite"
            else if (opt%method < METHOD_RK4 .or. opt%method > METHOD_VERNER98) then
                msg = "bad input: unknown method"
            else if (.not. allocated(opt%rtol_vec) .and. .not. (opt%rtol >= 0.0_dp)) then
                msg = "bad input: rtol must be non-negative"
            else if (.not. allocated(opt%atol_vec) .and. .not. (opt%atol >= 0.0_dp)) then
                msg = "bad input: atol must be non-negative"
            else if (.not. opt%max_step > 0.0_dp) then
                msg = "bad input: max_step must be positive"
            else if (.not. opt%first_step >= 0.0_dp) then
                msg = "bad input: first_step must be positive"
            else if (opt%max_steps < 1) then
                msg = "bad input: max_steps must be positive"
            else if (opt%method == METHOD_RK4 .and. .not. opt%first_step > 0.0_dp) then
                msg = "bad input: RK4 is a fixed-step method and needs a step (first_step > 0)"
            else if (opt%method /= METHOD_RK4 .and. opt%first_step > abs(tf - t0) .and. &
                     tf /= t0) then
                msg = "bad input: first_step exceeds the length of t_span"
            else
                info = CM_SUCCESS
                msg = "success"
            end if
            if (info /= CM_SUCCESS) return
            if (allocated(opt%rtol_vec)) call check_tol_vec(opt%rtol_vec, "rtol", info, msg)
            if (info /= CM_SUCCESS) return
            if (allocated(opt%atol_vec)) call check_tol_vec(opt%atol_vec, "atol", info, msg)
            if (info == CM_SUCCESS .and. has_events) then
                if (.not. allocated(events%terminal)) then
                    info = CM_BAD_INPUT
                    msg = "bad input: events%terminal must be allocated"
                else if (size(events%terminal) /= size(events%direction)) then
                    info = CM_BAD_INPUT
                    msg = "bad input: events%terminal and events%direction differ in size"
                end if
            end if
        end subroutine validate

        subroutine check_tol_vec(v, name, info, msg)
            real(dp), intent(in) :: v(:)
            character(len=*), intent(in) :: name
            integer, intent(inout) :: info
            character(len=:), allocatable, intent(inout) :: msg
            if (size(v) /= n) then
                info = CM_BAD_INPUT
                msg = "bad input: "//name//" must be a scalar or have the size of y0"
            else if (.not. all(v >= 0.0_dp)) then
                info = CM_BAD_INPUT
                msg = "bad input: "//name//" must be non-negative"
            end if
        end subroutine check_tol_vec

        !> Hairer's initial step size (hinit of dopri5.f / dop853.f).
        function hinit() result(hh)
            real(dp) :: hh, dnf, dny, der2, der12, h1
            integer :: iord
            iord = tab%order
            sk = atolv + rtolv*abs(y)
            dnf = sum((k(:, 1)/sk)**2)
            dny = sum((y/sk)**2)
            if (dnf <= 1.0e-10_dp .or. dny <= 1.0e-10_dp) then
                hh = 1.0e-6_dp
            else if (dnf > huge(1.0_dp) .or. dny > huge(1.0_dp)) then
                ! the sums of squares overflowed (huge states): the ratio from norm2
                hh = norm2(y/sk)/norm2(k(:, 1)/sk)*0.01_dp
                dnf = huge(1.0_dp)
            else
                hh = sqrt(dny/dnf)*0.01_dp
            end if
            hh = min(hh, hmax)*posneg
            ytmp = y + hh*k(:, 1)
            call sys%rhs(t + hh, ytmp, k(:, 2))
            st%nfev = st%nfev + 1
            der2 = norm2((k(:, 2) - k(:, 1))/sk)/abs(hh)
            if (der2 /= der2) der2 = huge(1.0_dp)
            der12 = max(abs(der2), sqrt(dnf))
            if (der12 <= 1.0e-15_dp) then
                h1 = max(1.0e-6_dp, abs(hh)*1.0e-3_dp)
            else
                h1 = (0.01_dp/der12)**(1.0_dp/real(iord, dp))
            end if
            hh = min(100.0_dp*abs(hh), h1, hmax)*posneg
        end function hinit

        !> sqrt(mean((v/sk)^2)), the error norm; norm2 (overflow-safe) when the fast sum of
        !! squares overflows.
        function rms_scaled(v, sc) result(r)
            real(dp), intent(in) :: v(:), sc(:)
            real(dp) :: r
            r = sqrt(sum((v/sc)**2)/real(size(v), dp))
            if (r > huge(1.0_dp)) r = norm2(v/sc)/sqrt(real(size(v), dp))
        end function rms_scaled

        !> out = base + sum_{j <= m} w(j) k(:, j). Small systems loop over the components
        !! outside (one pass, the sum in a register; multiplying the tableau's zeros is
        !! cheaper than skipping them), large ones over the stages (contiguous columns of k,
        !! zero weights skipped).
        subroutine lincomb(base, w, m, out)
            real(dp), intent(in) :: base(:), w(:)
            integer, intent(in) :: m
            real(dp), intent(out) :: out(:)
            integer :: i, j
            real(dp) :: acc
            if (n <= 32) then
                do i = 1, n
                    acc = base(i)
                    do j = 1, m
                        acc = acc + w(j)*k(i, j)
                    end do
                    out(i) = acc
                end do
            else
                out = base
                do j = 1, m
                    if (w(j) /= 0.0_dp) out = out + w(j)*k(:, j)
                end do
            end if
        end subroutine lincomb

        !> Stages s1..s2 of the tableau; stage s uses a(s, 1:s-1).
        subroutine stages(s1, s2)
            integer, intent(in) :: s1, s2
            integer :: s
            real(dp) :: ha(21)
            do s = s1, s2
                ha(1:s - 1) = h*tab%a(s, 1:s - 1)
                call lincomb(y, ha, s - 1, ytmp)
                call sys%rhs(t + tab%c(s)*h, ytmp, k(:, s))
            end do
            st%nfev = st%nfev + (s2 - s1 + 1)
        end subroutine stages

        subroutine rk4_step()
            real(dp) :: h2
            h2 = 0.5_dp*h
            ytmp = y + h2*k(:, 1)
            call sys%rhs(t + h2, ytmp, k(:, 2))
            ytmp = y + h2*k(:, 2)
            call sys%rhs(t + h2, ytmp, k(:, 3))
            ytmp = y + h*k(:, 3)
            call sys%rhs(t + h, ytmp, k(:, 4))
            st%nfev = st%nfev + 3
            ynew = y + (h/6.0_dp)*(k(:, 1) + 2.0_dp*(k(:, 2) + k(:, 3)) + k(:, 4))
        end subroutine rk4_step

        subroutine dopri5_step()
            call stages(2, 6)
            call lincomb(y, h*tab%b(1:6), 6, ynew)
            call sys%rhs(t + h, ynew, k(:, 7))
            st%nfev = st%nfev + 1
            call lincomb(zero, tab%e, 7, ytmp)
            sk = atolv + rtolv*max(abs(y), abs(ynew))
            err = abs(h)*rms_scaled(ytmp, sk)
            if (.not. all(ieee_is_finite(ynew))) err = ieee_value(1.0_dp, ieee_quiet_nan)
        end subroutine dopri5_step

        subroutine dop853_step()
            real(dp) :: err5, err3, deno
            call stages(2, 12)
            ! ytmp = sum b_j k_j (8th-order increment / h)
            call lincomb(zero, tab%b, 12, ytmp)
            ynew = y + h*ytmp
            sk = atolv + rtolv*max(abs(y), abs(ynew))
            ! 3rd-order estimator: b.k - bhh.k
            err3 = sum(((ytmp - tab%bhh(1)*k(:, 1) - tab%bhh(9)*k(:, 9) &
                         - tab%bhh(12)*k(:, 12))/sk)**2)
            call lincomb(zero, tab%e, 12, ytmp)
            err5 = sum((ytmp/sk)**2)
            deno = err5 + 0.01_dp*err3
            if (deno <= 0.0_dp) deno = 1.0_dp
            if (err5 > huge(1.0_dp) .or. err3 > huge(1.0_dp)) then
                ! the sums of squares overflowed (huge states): the same norm from norm2
                err5 = norm2(ytmp/sk)
                err3 = norm2(((ynew - y)/h - tab%bhh(1)*k(:, 1) - tab%bhh(9)*k(:, 9) &
                              - tab%bhh(12)*k(:, 12))/sk)
                err = abs(h)*err5/sqrt(real(n, dp)*(1.0_dp + 0.01_dp*(err3/err5)**2))
            else
                ! (err5/sqrt(deno): no overflow of 1/deno when both underflow, tiny states)
                err = abs(h)*err5/sqrt(real(n, dp)*deno)
            end if
            if (.not. all(ieee_is_finite(ynew))) err = ieee_value(1.0_dp, ieee_quiet_nan)
        end subroutine dop853_step

        subroutine verner_step()
            call stages(2, 16)
            call lincomb(y, h*tab%b(1:15), 15, ynew)
            call lincomb(zero, tab%e, 16, ytmp)
            sk = atolv + rtolv*max(abs(y), abs(ynew))
            err = abs(h)*rms_scaled(ytmp, sk)
            if (.not. all(ieee_is_finite(ynew))) err = ieee_value(1.0_dp, ieee_quiet_nan)
        end subroutine verner_step

        !> Coefficients of the continuous extension of the accepted step into fc.
        subroutine dense_coefs()
            integer :: s, j, i
            fc(:, 0) = y
            fc(:, 1) = ynew - y
            select case (opt%method)
            case (METHOD_RK4)
                fc(:, 2) = h*k(:, 1) - fc(:, 1)
                fc(:, 3) = 2.0_dp*fc(:, 1) - h*(k(:, 1) + k(:, 13))
            case (METHOD_DOPRI5)
                fc(:, 2) = h*k(:, 1) - fc(:, 1)
                fc(:, 3) = 2.0_dp*fc(:, 1) - h*(k(:, 1) + k(:, 7))
                fc(:, 4) = 0.0_dp
                do j = 1, 7
                    if (tab%d(1, j) /= 0.0_dp) fc(:, 4) = fc(:, 4) + (h*tab%d(1, j))*k(:, j)
                end do
            case (METHOD_VERNER98)
                ! stages 18..21 (stage 17 is the FSAL stage), then the power-form weights
                call stages(18, 21)
                do j = 1, 8
                    fc(:, j) = 0.0_dp
                    do i = 1, 21
                        if (tab%p(i, j) /= 0.0_dp) fc(:, j) = fc(:, j) + (h*tab%p(i, j))*k(:, i)
                    end do
                end do
            case default
                ! three extra stages 14..16 (they use the FSAL stage 13)
                do s = 14, 16
                    ytmp = y
                    do j = 1, s - 1
                        if (tab%a(s, j) /= 0.0_dp) ytmp = ytmp + (h*tab%a(s, j))*k(:, j)
                    end do
                    call sys%rhs(t + tab%c(s)*h, ytmp, k(:, s))
                end do
                st%nfev = st%nfev + 3
                fc(:, 2) = h*k(:, 1) - fc(:, 1)
                fc(:, 3) = 2.0_dp*fc(:, 1) - h*(k(:, 13) + k(:, 1))
                do i = 1, 4
                    fc(:, 3 + i) = 0.0_dp
                    do j = 1, 16
                        if (tab%d(i, j) /= 0.0_dp) &
                            fc(:, 3 + i) = fc(:, 3 + i) + (h*tab%d(i, j))*k(:, j)
                    end do
                end do
            end select
        end subroutine dense_coefs

        !> Locate the zero crossings of the event functions in the accepted step.
        subroutine find_events()
            integer :: i, j, nfound, order(size(g_new))
            real(dp) :: tmin
            logical :: cross
            call events%eval(t + h, ynew, g_new)
            nfound = 0
            do i = 1, ne
                cross = .false.
                if (g_old(i) < 0.0_dp .and. g_new(i) >= 0.0_dp .and. &
                    events%direction(i) >= 0) cross = .true.
                if (g_old(i) > 0.0_dp .and. g_new(i) <= 0.0_dp .and. &
                    events%direction(i) <= 0) cross = .true.
                if (cross) then
                    nfound = nfound + 1
                    ev_ids(nfound) = i
                    if (g_new(i) == 0.0_dp) then
                        ev_times(nfound) = t + h
                    else
                        ev_times(nfound) = event_root(i, g_old(i), g_new(i))
                    end if
                end if
            end do
            g_old = g_new
            if (nfound == 0) return
            ! order by time in the direction of integration (insertion sort, few events)
            do i = 1, nfound
                order(i) = i
            end do
            do i = 2, nfound
                j = i
                do while (j > 1)
                    if ((ev_times(order(j)) - ev_times(order(j - 1)))*posneg >= 0.0_dp) exit
                    iev = order(j); order(j) = order(j - 1); order(j - 1) = iev
                    j = j - 1
                end do
            end do
            tmin = t + h
            do j = 1, nfound
                i = order(j)
                te = ev_times(i)
                ie = ev_ids(i)
                if (stop_now .and. (te - tmin)*posneg > 0.0_dp) exit
                if (te == t + h) then
                    ye = ynew
                else
                    call interp(fc, form, (te - t)/h, ye)
                end if
                if (present(res)) call push_event(res, te, ye, ie)
                if (events%terminal(ie) .and. .not. stop_now) then
                    stop_now = .true.
                    tmin = te
                    t_stop = te
                end if
            end do
        end subroutine find_events

        !> Root of event ie on the dense output of the current step (Brent's method).
        function event_root(ie, ga, gb) result(root)
            integer, intent(in) :: ie
            real(dp), intent(in) :: ga, gb
            real(dp) :: root
            real(dp) :: a, b, c, fa, fb, fcc, d, e, tol, m, p, q, r, s
            integer :: it
            real(dp) :: gv(ne)
            a = 0.0_dp; b = 1.0_dp; fa = ga; fb = gb
            c = a; fcc = fa; d = b - a; e = d
            do it = 1, 200
                if (abs(fcc) < abs(fb)) then
                    a = b; b = c; c = a
                    fa = fb; fb = fcc; fcc = fa
                end if
                tol = 2.0_dp*epsilon(1.0_dp)*abs(t + b*h)/abs(h) + 0.5_dp*tiny(1.0_dp)
                tol = max(tol, 2.0_dp*epsilon(1.0_dp))
                m = 0.5_dp*(c - b)
                if (abs(m) <= tol .or. fb == 0.0_dp) exit
                if (abs(e) < tol .or. abs(fa) <= abs(fb)) then
                    d = m; e = m
                else
                    s = fb/fa
                    if (a == c) then
                        p = 2.0_dp*m*s
                        q = 1.0_dp - s
                    else
                        q = fa/fcc
                        r = fb/fcc
                        p = s*(2.0_dp*m*q*(q - r) - (b - a)*(r - 1.0_dp))
                        q = (q - 1.0_dp)*(r - 1.0_dp)*(s - 1.0_dp)
                    end if
                    if (p > 0.0_dp) then
                        q = -q
                    else
                        p = -p
                    end if
                    if (2.0_dp*p < min(3.0_dp*m*q - abs(tol*q), abs(e*q))) then
                        e = d
                        d = p/q
                    else
                        d = m; e = m
                    end if
                end if
                a = b; fa = fb
                if (abs(d) > tol) then
                    b = b + d
                else
                    b = b + sign(tol, m)
                end if
                call interp(fc, form, b, ye)
                call events%eval(t + b*h, ye, gv)
                fb = gv(ie)
                if ((fb > 0.0_dp .and. fcc > 0.0_dp) .or. (fb < 0.0_dp .and. fcc < 0.0_dp)) then
                    c = a; fcc = fa; d = b - a; e = d
                end if
            end do
            root = t + b*h
        end function event_root

        subroutine finish_outputs()
            if (.not. present(res)) return
            if (.not. opt%save_steps .and. n_eval == 0) then
                if (t /= t0 .or. res%nt == 0) call push_point(res, t, y)
            end if
            call shrink_result(res)
            if (opt%dense_output) res%sol%t_last = t
        end subroutine finish_outputs

    end subroutine drive

    !> Continuous extension at x = (t - t0)/h: Hairer's form
    !! y0 + x (F1 + (1-x)(F2 + x (F3 + ...))) or the power form y0 + sum_j x^j F_j.
    pure subroutine interp(fc, form, x, yout)
        real(dp), intent(in) :: fc(:, 0:)
        integer, intent(in) :: form
        real(dp), intent(in) :: x
        real(dp), intent(out) :: yout(:)
        integer :: j, nf
        real(dp) :: x1
        nf = ubound(fc, 2)
        if (form == FORM_POWER) then
            yout = fc(:, nf)
            do j = nf - 1, 1, -1
                yout = fc(:, j) + x*yout
            end do
            yout = fc(:, 0) + x*yout
            return
        end if
        x1 = 1.0_dp - x
        yout = fc(:, nf)
        do j = nf - 1, 1, -1
            if (mod(j, 2) == 1) then
                yout = fc(:, j) + x1*yout
            else
                yout = fc(:, j) + x*yout
            end if
        end do
        yout = fc(:, 0) + x*yout
    end subroutine interp

    subroutine push_point(res, t, y)
        type(ode_result), intent(inout) :: res
        real(dp), intent(in) :: t, y(:)
        real(dp), allocatable :: tt(:), yy(:, :)
        integer :: cap
        cap = size(res%t)
        if (res%nt >= cap) then
            cap = max(16, 2*cap)
            allocate (tt(cap), yy(size(y), cap))
            tt(1:res%nt) = res%t(1:res%nt)
            yy(:, 1:res%nt) = res%y(:, 1:res%nt)
            call move_alloc(tt, res%t)
            call move_alloc(yy, res%y)
        end if
        res%nt = res%nt + 1
        res%t(res%nt) = t
        res%y(:, res%nt) = y
    end subroutine push_point

    subroutine push_event(res, t, y, id)
        type(ode_result), intent(inout) :: res
        real(dp), intent(in) :: t, y(:)
        integer, intent(in) :: id
        real(dp), allocatable :: tt(:), yy(:, :)
        integer, allocatable :: ii(:)
        integer :: cap
        cap = size(res%ev_t)
        if (res%nev >= cap) then
            cap = max(8, 2*cap)
            allocate (tt(cap), yy(size(y), cap), ii(cap))
            tt(1:res%nev) = res%ev_t(1:res%nev)
            yy(:, 1:res%nev) = res%ev_y(:, 1:res%nev)
            ii(1:res%nev) = res%ev_id(1:res%nev)
            call move_alloc(tt, res%ev_t)
            call move_alloc(yy, res%ev_y)
            call move_alloc(ii, res%ev_id)
        end if
        res%nev = res%nev + 1
        res%ev_t(res%nev) = t
        res%ev_y(:, res%nev) = y
        res%ev_id(res%nev) = id
    end subroutine push_event

    subroutine shrink_result(res)
        type(ode_result), intent(inout) :: res
        real(dp), allocatable :: tt(:), yy(:, :)
        integer, allocatable :: ii(:)
        if (size(res%t) /= res%nt) then
            tt = res%t(1:res%nt)
            yy = res%y(:, 1:res%nt)
            call move_alloc(tt, res%t)
            call move_alloc(yy, res%y)
        end if
        if (size(res%ev_t) /= res%nev) then
            tt = res%ev_t(1:res%nev)
            yy = res%ev_y(:, 1:res%nev)
            ii = res%ev_id(1:res%nev)
            call move_alloc(tt, res%ev_t)
            call move_alloc(yy, res%ev_y)
            call move_alloc(ii, res%ev_id)
        end if
    end subroutine shrink_result

    subroutine dense_init(sol, n, nf, form, t0)
        type(dense_solution), intent(out) :: sol
        integer, intent(in) :: n, nf, form
        real(dp), intent(in) :: t0
        sol%n = n
        sol%nf = nf
        sol%form = form
        sol%nseg = 0
        sol%t_first = t0
        sol%t_last = t0
        allocate (sol%ts(16), sol%hs(16), sol%coef(n, 0:nf, 16))
    end subroutine dense_init

    subroutine dense_push(sol, t, h, fc, t_end)
        type(dense_solution), intent(inout) :: sol
        real(dp), intent(in) :: t, h, fc(:, 0:), t_end
        real(dp), allocatable :: ts(:), hs(:), cc(:, :, :)
        integer :: cap
        cap = size(sol%ts)
        if (sol%nseg >= cap) then
            cap = 2*cap
            allocate (ts(cap), hs(cap), cc(sol%n, 0:sol%nf, cap))
            ts(1:sol%nseg) = sol%ts(1:sol%nseg)
            hs(1:sol%nseg) = sol%hs(1:sol%nseg)
            cc(:, :, 1:sol%nseg) = sol%coef(:, :, 1:sol%nseg)
            call move_alloc(ts, sol%ts)
            call move_alloc(hs, sol%hs)
            call move_alloc(cc, sol%coef)
        end if
        sol%nseg = sol%nseg + 1
        sol%ts(sol%nseg) = t
        sol%hs(sol%nseg) = h
        sol%coef(:, :, sol%nseg) = fc
        sol%t_last = t_end
    end subroutine dense_push

    !> Evaluate the dense output at t (extrapolates from the end steps outside the range).
    subroutine dense_eval(self, t, y)
        class(dense_solution), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(out) :: y(:)
        integer :: lo, hi, mid
        real(dp) :: dir
        if (self%nseg == 0) then
            y = 0.0_dp
            return
        end if
        dir = sign(1.0_dp, self%hs(1))
        lo = 1
        hi = self%nseg
        ! last segment whose start is <= t (in the direction of integration)
        do while (lo < hi)
            mid = (lo + hi + 1)/2
            if ((t - self%ts(mid))*dir >= 0.0_dp) then
                lo = mid
            else
                hi = mid - 1
            end if
        end do
        call interp(self%coef(:, :, lo), self%form, (t - self%ts(lo))/self%hs(lo), y)
    end subroutine dense_eval

    !> Evaluate the dense output at many times: y(:, i) at t(i).
    subroutine dense_eval_many(self, t, y)
        class(dense_solution), intent(in) :: self
        real(dp), intent(in) :: t(:)
        real(dp), intent(out) :: y(:, :)
        integer :: i
        do i = 1, size(t)
            call self%eval(t(i), y(:, i))
        end do
    end subroutine dense_eval_many

end module conmech_ode_solver
