!> The one driver loop of conmech's integrators: any `ode_stepper` (RK, Radau IIA, Gauss,
!! RATTLE, a user's own) advanced from t0 to tf with
!! - the outputs: every accepted step, or the end points only (options%save_steps false),
!!   or the points of t_eval, from the stepper's continuous extension (or, in hit mode,
!!   options%hit_t_eval, at step ends that land on them);
!! - events located on the continuous extension (conmech_ode_event_locate), in time order,
!!   a terminal one ending the run at its state at its `count`-th occurrence (status
!!   CM_EVENT_STOP; the occurrences left are the run's, the events stay intent(in)); an
!!   event with a `resolution` is also sampled inside each step, so that no two crossings
!!   cancel; with `zero_at_t0`, an event zero at t0 is tested on the first step by SciPy's
!!   rule (a stop there ends the run at t0 with y0, after that one step);
!! - the step hook (`ode_step_hook`: after every accepted step, and at every event state),
!!   which may change y (a projection onto a manifold), count or stop the run;
!! - the dense solution (options%dense_output): the steps' polynomials, segment by segment;
!! - the counters and the status, and y at the end (where the run stopped on failure);
!! - with `resume`, a stepper that stands at (t0, y) where its last run ended continued
!!   (`ode_stepper%resume`) instead of started again, where its method allows it.
!! `ode_solve`, `ode_integrate` and `constrained_solve` are this loop with a stepper from
!! the method table. Nothing per stage here: one polymorphic call per step.
module conmech_ode_driver
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_text, only: rtoa
    use conmech_ode_system, only: ode_system, ode_events, ode_step_hook
    use conmech_ode_options, only: ode_options, ode_stats
    use conmech_ode_dense, only: dense_init, dense_push
    use conmech_ode_result, only: ode_result, push_point, shrink_result
    use conmech_ode_stepper, only: ode_stepper, check_t_eval
    use conmech_ode_event_locate, only: find_events, check_events, event_counts
    implicit none
    private
    public :: ode_drive

contains

    !> Integrate y' = f(t, y) from (t0, y) to tf with the stepper stp (a fresh object of
    !! the method options%method, or the caller's own stepper type). y: the state at the
    !! end (where the run stopped). res (optional): the outputs, events and dense solution
    !! as the module documentation says; st: the counters.
    subroutine ode_drive(stp, sys, t0, tf, y, opt, st, info, msg, res, t_eval, events, hook, &
                         resume)
        class(ode_stepper), intent(inout) :: stp
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
        !> continue stp where it stands when that is (t0, y) at the end of its last run
        !! (the same options) and its method can (ode_stepper%resume)
        logical, intent(in), optional :: resume

        real(dp), allocatable :: g_old(:), ytmp(:), y_stop(:)
        integer, allocatable :: ev_left(:)
        logical, allocatable :: at_start(:)
        real(dp) :: t, t_stop, target, h_next
        integer :: n, i_eval, n_eval, hinfo
        logical :: need_dense, keep_dense, has_events, store_steps, stop_now, changed
        logical :: hit_mode, resumed
        character(len=:), allocatable :: smsg

        n = size(y)
        st = ode_stats()
        has_events = present(events)
        if (has_events) has_events = events%n_events() > 0
        n_eval = 0
        if (present(t_eval)) n_eval = size(t_eval)
        if (n_eval > 0) then
            call check_t_eval(t0, tf, t_eval, info, msg)
            if (info /= CM_SUCCESS) return
        end if
        if (has_events) then
            call check_events(events, info, msg)
            if (info /= CM_SUCCESS) return
        end if
        ! tf may be infinite (SciPy's t_span = [t0, inf]): the run ends at a terminal
        ! event, a hook's stop, or max_steps; fixed-step methods refuse it in their setup
        resumed = .false.
        if (present(resume)) then
            if (resume .and. tf /= t0 .and. stp%t == t0 .and. allocated(stp%y)) then
                if (size(stp%y) == n) then
                    if (all(stp%y == y)) call stp%resume(tf, opt, resumed)
                end if
            end if
        end if
        if (resumed) then
            info = CM_SUCCESS
            msg = "success"
        else
            call stp%init(t0, tf, y, opt, info, msg, allow_inf=.true.)
            if (info /= CM_SUCCESS) return
        end if
        if (present(res)) then
            if (.not. allocated(res%t)) allocate (res%t(0), res%y(n, 0))
            if (.not. allocated(res%ev_t)) allocate (res%ev_t(0), res%ev_y(n, 0), &
                                                     res%ev_id(0))
        end if

        store_steps = present(res) .and. n_eval == 0
        if (store_steps) store_steps = opt%save_steps
        hit_mode = opt%hit_t_eval .and. n_eval > 0 .and. stp%lands_on_target
        keep_dense = present(res) .and. opt%dense_output .and. stp%nf > 0
        need_dense = has_events .or. (n_eval > 0 .and. .not. hit_mode) .or. keep_dense

        ! outputs at the start
        t = t0
        i_eval = 1
        if (present(res)) then
            if (n_eval == 0) call push_point(res, t, y)
            if (keep_dense) call dense_init(res%sol, n, stp%nf, stp%form, t0)
        end if
        do while (i_eval <= n_eval)
            if (t_eval(i_eval) /= t0) exit
            call push_point(res, t0, y)
            i_eval = i_eval + 1
        end do
        if (tf == t0) then
            call finish_outputs()
            return
        end if

        if (.not. resumed) call stp%start(sys, info, msg)
        st = stp%st
        if (info /= CM_SUCCESS) then
            call finish_outputs()
            return
        end if
        if (has_events) then
            allocate (g_old(events%n_events()), y_stop(n))
            call events%eval(t0, y, g_old)
            ev_left = event_counts(events)
            ! the events SciPy's rule tests at t0 (on the first step only)
            at_start = events%zero_at_t0 .and. g_old == 0.0_dp
        end if
        if (n_eval > 0) allocate (ytmp(n))
        ! without dense output, a hook that may change y gets f evaluated once, after it
        stp%defer_f = present(hook) .and. .not. need_dense

        ! ---------------------------------------------------------------- main loop
        do
            ! the point the step lands on if it reaches it: tf, or in hit mode the next
            ! t_eval point
            target = tf
            if (hit_mode .and. i_eval <= n_eval) target = t_eval(i_eval)
            call stp%step(sys, target, info, smsg)
            if (info /= CM_SUCCESS) then
                msg = smsg
                h_next = stp%h
                t = stp%t
                exit
            end if
            h_next = stp%h_done
            t = stp%t
            ! the continuous extension where something reads it: events and the dense
            ! solution on every step, t_eval only on a step that holds its next point
            ! (DOP853's and Verner's extra stages cost evaluations, as in SciPy)
            if (need_dense) then
                if (has_events .or. keep_dense) then
                    call stp%dense(sys)
                else if (i_eval <= n_eval) then
                    if ((t_eval(i_eval) - stp%t)*stp%posneg < 0.0_dp) call stp%dense(sys)
                end if
            end if

            stop_now = .false.
            t_stop = stp%t
            if (has_events) then
                call find_events(stp, events, g_old, at_start, ev_left, stop_now, t_stop, &
                                 y_stop, info, msg, res, hook)
                at_start = .false.
                if (info /= CM_SUCCESS) exit
            end if

            ! outputs inside the step from the continuous extension; a point at the step's
            ! end is written after the step hook, with the final state
            do while (i_eval <= n_eval)
                if (stop_now) then
                    if ((t_eval(i_eval) - t_stop)*stp%posneg > 0.0_dp) exit
                else
                    if ((t_eval(i_eval) - stp%t)*stp%posneg >= 0.0_dp) exit
                end if
                call stp%eval(t_eval(i_eval), ytmp, info, msg)
                if (info /= CM_SUCCESS) exit
                call push_point(res, t_eval(i_eval), ytmp)
                i_eval = i_eval + 1
            end do
            if (info /= CM_SUCCESS) exit
            if (keep_dense) call dense_push(res%sol, stp%t_old, stp%h_done, stp%fc, t_stop)

            if (stop_now) then
                stp%y = y_stop
                stp%t = t_stop
                t = t_stop
                if (store_steps) call push_point(res, t, stp%y)
                info = CM_EVENT_STOP
                msg = "a termination event occurred"
                exit
            end if

            changed = .false.
            hinfo = 0
            if (present(hook)) call hook%after_step(stp%t, stp%y, changed, hinfo)
            ! f at the step's end where the method deferred it (or the hook changed y)
            if (changed .or. stp%f_stale) call stp%refresh_f(sys)
            if (present(hook)) then
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
                msg = "non-finite right-hand side at t ="//rtoa(t)
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
            if (opt%trim_outputs) call shrink_result(res)
            if (keep_dense) res%sol%t_last = t
        end subroutine finish_outputs

    end subroutine ode_drive

end module conmech_ode_driver
