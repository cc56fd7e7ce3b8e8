!> Explicit Runge-Kutta integrators: fixed-step RK4, and adaptive DOPRI5 and DOP853 with
!! Hairer's step-size control, dense output and event location.
!!
!! Verner's 9(8) pair (METHOD_VERNER98) is the high-order choice for tight tolerances
!! (rtol below about 1e-10): same control with exponent 1/9, step ratios [1/3, 6].
!!
!! Two entry points, both short loops over the stepper of conmech_rk_stepper:
!! - `ode_solve` stores the solution (every accepted step, or the points of `t_eval`),
!!   the dense output if asked for, and the events, in an `ode_result`;
!! - `ode_integrate` is the lean path: it advances y from t0 to t1 in place and stores
!!   nothing (used by shooting, variational equations and batch sweeps).
!!
!! The pieces live in their own modules: options, counters and method codes
!! (conmech_ode_options), the stepper (conmech_rk_stepper: init, step with step control,
!! dense output of the last step), the stage kernels (conmech_rk_kernels), event location
!! on the last step (conmech_ode_event_locate), the dense solution (conmech_ode_dense) and
!! the result with its buffers (conmech_ode_result). This module re-exports their public
!! names, so `use conmech_ode_solver` gives the whole integrator API.
!!
!! All state lives in local variables: routines are safe to call from many threads at once.
module conmech_ode_solver
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system, ode_events, ode_step_hook
    use conmech_ode_options, only: ode_options, ode_stats, method_from_name, METHOD_RK4, &
        METHOD_DOPRI5, METHOD_DOP853, METHOD_VERNER98, METHOD_RADAU5, METHOD_GAUSS4, &
        METHOD_GAUSS6, METHOD_RATTLE
    use conmech_ode_dense, only: dense_solution, dense_init, dense_push
    use conmech_ode_result, only: ode_result, push_point, shrink_result
    use conmech_rk_stepper, only: rk_stepper, rk_init, rk_start, rk_step
    use conmech_ode_event_locate, only: find_events
    implicit none
    private

    public :: METHOD_RK4, METHOD_DOPRI5, METHOD_DOP853, METHOD_VERNER98
    public :: METHOD_RADAU5, METHOD_GAUSS4, METHOD_GAUSS6, METHOD_RATTLE
    public :: ode_options, ode_result, ode_stats, dense_solution
    public :: ode_solve, ode_integrate, method_from_name
    public :: rk_stepper, rk_init, rk_start, rk_step     ! the stepper, for step-by-step use

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
                    ! max(i - 1, 1): at i = 1 the difference is 0 (nothing to compare)
                    if ((t_eval(i) - t_eval(max(i - 1, 1)))*(t_span(2) - t_span(1)) < 0.0_dp) then
                        call fail(res, CM_BAD_INPUT, "bad input: t_eval must be sorted in " &
                                  //"the direction of integration")
                        return
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
    !! The implicit methods (METHOD_RADAU5, METHOD_GAUSS4, METHOD_GAUSS6) run through
    !! `ode_solve`'s implicit driver keeping the end point only (no step hook: CM_BAD_INPUT);
    !! on failure y is the state where the integration stopped (its time in `message`).
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
        if (options%method >= METHOD_RADAU5) then
            if (present(hook)) then
                info = CM_BAD_INPUT
                msg = "bad input: step hooks need an explicit method"
            else
                call integrate_implicit(sys, t0, t1, y, options, info, st, msg)
            end if
        else
            call drive(sys, t0, t1, y, options, st, info, msg, hook=hook)
        end if
        if (present(stats)) stats = st
        if (present(message)) message = msg
    end subroutine ode_integrate

    !> ode_integrate with an implicit method: ode_solve's implicit driver, end point only.
    subroutine integrate_implicit(sys, t0, t1, y, options, info, st, msg)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t0, t1
        real(dp), intent(inout) :: y(:)
        type(ode_options), intent(in) :: options
        integer, intent(out) :: info
        type(ode_stats), intent(out) :: st
        character(len=:), allocatable, intent(out) :: msg
        type(ode_options) :: oo
        type(ode_result) :: r
        oo = options
        oo%save_steps = .false.
        oo%dense_output = .false.
        call implicit_solve(sys, [t0, t1], y, oo, r)
        info = r%status
        if (allocated(r%message)) then
            msg = r%message
        else
            msg = "success"
        end if
        st = r%stats
        if (size(r%t) > 0 .and. size(r%y, 1) == size(y)) y = r%y(:, size(r%t))
    end subroutine integrate_implicit

    subroutine fail(res, info, msg)
        type(ode_result), intent(inout) :: res
        integer, intent(in) :: info
        character(len=*), intent(in) :: msg
        res%status = info
        res%message = msg
        res%success = .false.
    end subroutine fail

    !> The common driver: a loop over the stepper with outputs, events and the step hook.
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

        type(rk_stepper) :: stp
        real(dp), allocatable :: g_old(:), ytmp(:)
        real(dp) :: t, t_stop, target, h_next
        integer :: n, i_eval, n_eval, hinfo
        logical :: need_dense, has_events, store_steps, stop_now, changed, hit_mode
        character(len=32) :: buf
        character(len=:), allocatable :: smsg

        n = size(y)
        st = ode_stats()
        has_events = present(events)
        if (has_events) has_events = events%n_events() > 0
        n_eval = 0
        if (present(t_eval)) n_eval = size(t_eval)
        store_steps = present(res) .and. n_eval == 0
        if (store_steps) store_steps = opt%save_steps
        hit_mode = opt%hit_t_eval .and. n_eval > 0
        need_dense = has_events .or. (n_eval > 0 .and. .not. hit_mode)
        if (present(res)) need_dense = need_dense .or. opt%dense_output

        call rk_init(stp, t0, tf, y, opt, info, msg)
        if (info /= CM_SUCCESS) return
        if (has_events) then
            if (.not. allocated(events%terminal)) then
                info = CM_BAD_INPUT
                msg = "bad input: events%terminal must be allocated"
                return
            else if (size(events%terminal) /= size(events%direction)) then
                info = CM_BAD_INPUT
                msg = "bad input: events%terminal and events%direction differ in size"
                return
            end if
        end if

        ! outputs at the start
        t = t0
        i_eval = 1
        if (present(res)) then
            if (store_steps .or. (.not. opt%save_steps .and. n_eval == 0)) &
                call push_point(res, t, y)
            if (opt%dense_output) call dense_init(res%sol, n, stp%nf, stp%form, t0)
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

        call rk_start(stp, sys, info, msg)
        st = stp%st
        if (info /= CM_SUCCESS) return
        if (has_events) then
            allocate (g_old(events%n_events()))
            call events%eval(t0, y, g_old)
        end if
        if (n_eval > 0 .or. has_events) allocate (ytmp(n))
        ! without dense output, a step hook that may change y gets f evaluated once, after it
        stp%defer_fsal = present(hook) .and. .not. need_dense .and. &
                         opt%method /= METHOD_DOPRI5

        ! ---------------------------------------------------------------- main loop
        do
            ! the point the step must land on if it reaches it: tf, or in hit mode the next
            ! t_eval point
            target = tf
            if (hit_mode .and. i_eval <= n_eval) target = t_eval(i_eval)
            call rk_step(stp, sys, target, info, smsg)
            if (info /= CM_SUCCESS) then
                msg = smsg
                h_next = stp%h
                t = stp%t
                exit
            end if
            h_next = stp%h_done
            t = stp%t
            if (need_dense) call stp%dense(sys)

            stop_now = .false.
            t_stop = stp%t
            if (has_events) call find_events(stp, events, g_old, stop_now, t_stop, res)

            ! outputs inside the step from the dense output; a point at the step's end is
            ! written after the step hook, with the final state
            if (n_eval > 0) then
                do while (i_eval <= n_eval)
                    if (stop_now) then
                        if ((t_eval(i_eval) - t_stop)*stp%posneg > 0.0_dp) exit
                    else
                        if ((t_eval(i_eval) - stp%t)*stp%posneg >= 0.0_dp) exit
                    end if
                    call stp%eval(t_eval(i_eval), ytmp)
                    call push_point(res, t_eval(i_eval), ytmp)
                    i_eval = i_eval + 1
                end do
            end if
            if (present(res)) then
                if (opt%dense_output) call dense_push(res%sol, stp%t_old, stp%h_done, &
                                                      stp%fc, t_stop)
            end if

            if (stop_now) then
                call stp%eval(t_stop, ytmp)
                stp%y = ytmp
                t = t_stop
                if (store_steps) call push_point(res, t, stp%y)
                info = CM_EVENT_STOP
                msg = "a termination event occurred"
                exit
            end if

            if (present(hook)) then
                call hook%after_step(stp%t, stp%y, changed, hinfo)
                if (changed .or. stp%defer_fsal) call stp%refresh_f(sys)
                if (hinfo /= 0) then
                    if (store_steps) call push_point(res, t, stp%y)
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
            if (.not. stp%f_finite()) then
                info = CM_NONFINITE
                write (buf, '(es14.6)') t
                msg = "non-finite right-hand side at t ="//trim(buf)
                exit
            end if
            if (store_steps) call push_point(res, t, stp%y)
            do while (i_eval <= n_eval)
                if (t_eval(i_eval) /= t) exit
                call push_point(res, t, stp%y)
                i_eval = i_eval + 1
            end do
            if (stp%last) exit
        end do

        y = stp%y
        st = stp%st
        st%h_next = h_next
        call finish_outputs()

    contains

        subroutine finish_outputs()
            if (.not. present(res)) return
            if (.not. opt%save_steps .and. n_eval == 0) then
                if (t /= t0 .or. res%nt == 0) call push_point(res, t, y)
            end if
            call shrink_result(res)
            if (opt%dense_output) res%sol%t_last = t
        end subroutine finish_outputs

    end subroutine drive

end module conmech_ode_solver
