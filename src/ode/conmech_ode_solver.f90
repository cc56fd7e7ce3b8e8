!> conmech's integrators: `ode_solve` (outputs, t_eval, dense output, events, a step hook)
!! and `ode_integrate` (the lean path: y advanced from t0 to t1 in place, nothing stored;
!! shooting, variational equations, batch sweeps), for every method of the table
!! (conmech_ode_methods): fixed-step RK4; DOPRI5, DOP853 and Verner's 9(8) pair with
!! Hairer's step-size control; Radau IIA (stiff); Gauss-Legendre (symplectic).
!!
!! Both are the one driver loop (conmech_ode_driver) over a stepper of the method
!! (conmech_ode_stepper's contract); a caller's own stepper type runs through the same loop
!! when given as `stepper`. The pieces: options, counters and method codes
!! (conmech_ode_options), the method table (conmech_ode_methods), the steppers
!! (conmech_rk_stepper, conmech_radau_stepper, conmech_gauss), event location on the last
!! step (conmech_ode_event_locate), the dense solution (conmech_ode_dense) and the result
!! (conmech_ode_result). This module re-exports their public names, so
!! `use conmech_ode_solver` gives the whole integrator API.
!!
!! All state lives in local variables: routines are safe to call from many threads at once.
module conmech_ode_solver
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system, ode_events, ode_step_hook
    use conmech_ode_options, only: ode_options, ode_stats, METHOD_RK4, METHOD_DOPRI5, &
        METHOD_DOP853, METHOD_VERNER98, METHOD_RADAU5, METHOD_GAUSS4, METHOD_GAUSS6, &
        METHOD_RATTLE
    use conmech_ode_dense, only: dense_solution
    use conmech_ode_result, only: ode_result, start_outputs, shrink_result
    use conmech_ode_stepper, only: ode_stepper, stepper_pack, stepper_unpack, &
        check_first_step, check_interval, tolerance_vectors, FORM_HAIRER, FORM_POWER
    use conmech_state_packer, only: state_packer
    use conmech_ode_methods, only: method_from_name, new_stepper, method_info, method_entry
    use conmech_ode_driver, only: ode_drive
    use conmech_rk_stepper, only: rk_stepper, rk_init, rk_start, rk_step
    implicit none
    private

    public :: METHOD_RK4, METHOD_DOPRI5, METHOD_DOP853, METHOD_VERNER98
    public :: METHOD_RADAU5, METHOD_GAUSS4, METHOD_GAUSS6, METHOD_RATTLE
    public :: ode_options, ode_result, ode_stats, dense_solution
    public :: ode_solve, ode_integrate, method_from_name, method_info, method_entry
    public :: ode_stepper, ode_drive, stepper_pack, stepper_unpack, state_packer
    public :: check_first_step, check_interval, tolerance_vectors, FORM_HAIRER, FORM_POWER
    public :: rk_stepper, rk_init, rk_start, rk_step     ! the stepper, for step-by-step use

contains

    !> Solve y' = f(t, y), y(t_span(1)) = y0 on t_span (forward or backward in time).
    !!
    !! Without `t_eval` the result holds every accepted step (if options%save_steps, else
    !! the end points only); with `t_eval` (sorted in the direction of integration and
    !! inside t_span) it holds the solution there, from the dense output. Events are
    !! located on the dense output to near machine precision; a terminal event ends the
    !! integration at its `count`-th occurrence (status CM_EVENT_STOP), which is the last
    !! output point. `stepper`:
    !! a caller's own stepper (any extension of `ode_stepper`) instead of the one of
    !! options%method.
    subroutine ode_solve(sys, t_span, y0, options, res, t_eval, events, hook, stepper)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: y0(:)
        type(ode_options), intent(in) :: options
        type(ode_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        class(ode_step_hook), intent(inout), optional :: hook
        class(ode_stepper), intent(inout), optional :: stepper
        class(ode_stepper), allocatable :: own
        real(dp), allocatable :: y(:)
        integer :: info
        character(len=:), allocatable :: msg

        call start_outputs(res, size(y0))
        y = y0
        if (present(stepper)) then
            call ode_drive(stepper, sys, t_span(1), t_span(2), y, options, res%stats, &
                           res%status, msg, res, t_eval, events, hook)
        else
            call new_stepper(options%method, own, info, msg)
            if (info /= CM_SUCCESS) then
                call fail(res, info, msg)
                if (options%trim_outputs) call shrink_result(res)
                return
            end if
            call ode_drive(own, sys, t_span(1), t_span(2), y, options, res%stats, &
                           res%status, msg, res, t_eval, events, hook)
        end if
        ! the outputs of a run refused before its start (the driver cuts the others)
        if (options%trim_outputs) call shrink_result(res)
        res%message = msg
        res%success = res%status >= 0
    end subroutine ode_solve

    !> Advance y from t0 to t1 in place, storing nothing: the lean path for shooting,
    !! variational equations and sweeps (any method of the table). On failure y is the
    !! state where the integration stopped (its time in `message`).
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
        class(ode_stepper), allocatable :: stp
        character(len=:), allocatable :: msg
        call new_stepper(options%method, stp, info, msg)
        if (info == CM_SUCCESS) call ode_drive(stp, sys, t0, t1, y, options, st, info, msg, &
                                               hook=hook)
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

end module conmech_ode_solver
