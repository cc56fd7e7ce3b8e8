!> Support of the flat implicit stepper routines (python/conmech/flat/
!! flat_implicit_stepper.f90): one action of the step-by-step mode of `radau_solve` or
!! `gauss_solve` on the caller's packed state.
module conmech_flat_implicit_stepper_support
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: ode_options, METHOD_RADAU5, METHOD_GAUSS4, METHOD_GAUSS6
    use conmech_ode_result, only: ode_result
    use conmech_radau, only: radau_solve, RADAU_NR, RADAU_NI, RADAU_NW
    use conmech_gauss, only: gauss_solve, GAUSS_NR, GAUSS_NI, GAUSS_NW
    use conmech_flat_ode_support, only: copy_message
    implicit none
    private
    public :: radau_action, gauss_action

contains

    !> action 0: start at (t0, y0) towards t_bound; 1: one accepted step. The state
    !! (r, iv, w) is updated in place; info < 0 and the message on failure.
    subroutine radau_action(sys, action, n, t0, t_bound, y0, rtol, atol, first_step, &
                            max_step, max_steps, r, iv, w, info, message)
        class(ode_system), intent(in) :: sys
        integer(c_int), intent(in) :: action, n, max_steps
        real(c_double), intent(in) :: t0, t_bound, y0(n), rtol(n), atol(n)
        real(c_double), intent(in) :: first_step, max_step
        real(c_double), intent(inout) :: r(RADAU_NR), w(n, RADAU_NW + 4*n)
        integer(c_int), intent(inout) :: iv(RADAU_NI + 2*n)
        integer(c_int), intent(out) :: info
        character(len=*), intent(out) :: message
        type(ode_options) :: opt
        type(ode_result) :: res
        real(dp) :: span(2)

        if (n < 1 .or. (action /= 0 .and. action /= 1)) then
            info = CM_BAD_INPUT
            call copy_message("bad input: n must be positive and action 0 or 1", message)
            return
        end if
        opt%method = METHOD_RADAU5
        opt%rtol_vec = rtol
        opt%atol_vec = atol
        opt%first_step = first_step
        opt%max_step = max_step
        opt%max_steps = max_steps
        span = [t0, t_bound]
        if (action == 1) span = r(1:2)
        call radau_solve(sys, span, y0, opt, res, r_state=r, i_state=iv, w_state=w, &
                         action=action)
        info = res%status
        call copy_message(res%message, message)
    end subroutine radau_action

    !> The same for the Gauss methods (method METHOD_GAUSS4 or METHOD_GAUSS6), fixed step
    !! from first_step over [t0, t_bound].
    subroutine gauss_action(sys, action, n, method, t0, t_bound, y0, first_step, &
                            max_steps, r, iv, w, info, message)
        class(ode_system), intent(in) :: sys
        integer(c_int), intent(in) :: action, n, method, max_steps
        real(c_double), intent(in) :: t0, t_bound, y0(n), first_step
        real(c_double), intent(inout) :: r(GAUSS_NR), w(n, GAUSS_NW)
        integer(c_int), intent(inout) :: iv(GAUSS_NI)
        integer(c_int), intent(out) :: info
        character(len=*), intent(out) :: message
        type(ode_options) :: opt
        type(ode_result) :: res
        real(dp) :: span(2)

        if (n < 1 .or. (action /= 0 .and. action /= 1) .or. &
            (method /= METHOD_GAUSS4 .and. method /= METHOD_GAUSS6)) then
            info = CM_BAD_INPUT
            call copy_message("bad input: n must be positive, action 0 or 1, method a "// &
                              "Gauss method", message)
            return
        end if
        opt%method = method
        opt%first_step = first_step
        opt%max_steps = max_steps
        span = [t0, t_bound]
        if (action == 1) span = r(1:2)
        call gauss_solve(sys, method - METHOD_GAUSS4 + 2, span, y0, opt, res, r_state=r, &
                         i_state=iv, w_state=w, action=action)
        info = res%status
        call copy_message(res%message, message)
    end subroutine gauss_action

end module conmech_flat_implicit_stepper_support
