!> The step and dense-output actions of the steppers (conmech/ivp/stepper.py) with only the
!! arguments they read: the method, the state arrays r(nr), iv(ni), w(n, nw) (their sizes
!! taken from the arrays) and the system; no sizes are returned. Everything else
!! (tolerances, t_bound, the Jacobian's structure) is inside the packed state, so a step
!! from Python converts ten arguments instead of the ~27 of flat_stepper_callback /
!! flat_stepper_builtin (f2py's conversion of each argument and each returned array is
!! most of the glue's cost). action: 1 one accepted step, 2 the dense coefficients of the
!! last step; other actions are refused (they need the full argument list).
!! The failure's message is written into msg(256), a buffer of the caller's (its bytes,
!! blank-padded), only when info /= 0: a 256-character output would be allocated, padded
!! and converted by f2py at every step, which cost more than the rest of the wrapper.

!> A step or dense output for a Python right-hand side fun(t, y) and, if has_jac /= 0, its
!! Jacobian jac(t, y) -> (n, n).
subroutine flat_stepper_step_callback(fun, jac, action, method, has_jac, n, nr, ni, nw, r, &
                                      iv, w, msg, info)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_signed_char
    use conmech_status, only: CM_SUCCESS
    use conmech_flat_adapters, only: callback_jac_system
    use conmech_flat_stepper_support, only: step_action
    implicit none
    integer(c_int), intent(in) :: action, method, has_jac, n, nr, ni, nw
    real(c_double), intent(inout) :: r(nr), w(n, nw)
    integer(c_int), intent(inout) :: iv(ni)
    integer(c_signed_char), intent(inout) :: msg(256)
    integer(c_int), intent(out) :: info
    include "flat_stepper_callbacks.inc"
    type(callback_jac_system) :: sys
    character(len=256) :: message
    sys%f => fun
    sys%n = n
    if (has_jac /= 0) sys%jac => jac
    call step_action(sys, action, method, n, nr, ni, nw, r, iv, w, info, message)
    if (info /= CM_SUCCESS) msg = transfer(message, msg)
end subroutine flat_stepper_step_callback

!> A step or dense output for the built-in (or compiled) system `name` with parameters
!! params(1:np).
subroutine flat_stepper_step_builtin(name, np, params, nspec, spec, action, method, n, nr, &
                                     ni, nw, r, iv, w, msg, info)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_signed_char
    use conmech_status, only: CM_SUCCESS
    use conmech_ode_system, only: ode_system
    use conmech_flat_stepper_support, only: step_action, stepper_system
    implicit none
    include "flat_spec_args.inc"
    integer(c_int), intent(in) :: action, method, n, nr, ni, nw
    real(c_double), intent(inout) :: r(nr), w(n, nw)
    integer(c_int), intent(inout) :: iv(ni)
    integer(c_signed_char), intent(inout) :: msg(256)
    integer(c_int), intent(out) :: info
    class(ode_system), allocatable :: sys
    character(len=256) :: message
    ! the dimension was checked against the system when the state was made (action 0)
    call stepper_system(name, params(1:np), nspec, spec, 0_c_int, sys, info, message)
    if (info == CM_SUCCESS) call step_action(sys, action, method, n, nr, ni, nw, r, iv, w, &
                                             info, message)
    if (info /= CM_SUCCESS) msg = transfer(message, msg)
end subroutine flat_stepper_step_builtin
