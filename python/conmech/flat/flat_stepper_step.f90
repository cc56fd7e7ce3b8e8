!> The step and dense-output actions of the steppers (conmech/_stepper.py) with only the
!! arguments they read: the method, the state arrays r(nr), iv(ni), w(n, nw) and the system.
!! Everything else (tolerances, t_bound, the Jacobian's structure) is inside the packed
!! state, so a step from Python converts a dozen arguments instead of the ~27 of
!! flat_stepper_callback / flat_stepper_builtin (f2py's conversion of each argument is
!! most of the glue's cost). action: 1 one accepted step, 2 the dense coefficients of the
!! last step; other actions are refused (they need the full argument list).

!> A step or dense output for a Python right-hand side fun(t, y) and, if has_jac /= 0, its
!! Jacobian jac(t, y) -> (n, n).
subroutine flat_stepper_step_callback(fun, jac, action, method, has_jac, n, nr, ni, nw, r, &
                                      iv, w, sizes, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_status, only: CM_BAD_INPUT
    use conmech_flat_ode_support, only: callback_jac_system, copy_message
    use conmech_flat_stepper_support, only: stepper_action
    implicit none
    integer(c_int), intent(in) :: action, method, has_jac, n, nr, ni, nw
    real(c_double), intent(inout) :: r(max(nr, 1)), w(n, max(nw, 1))
    integer(c_int), intent(inout) :: iv(max(ni, 1))
    integer(c_int), intent(out) :: sizes(3), info
    character(len=256), intent(out) :: message
!f2py external fun, jac
    interface
        subroutine fun(t, y, dydt, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dydt(n)
        end subroutine fun
        subroutine jac(t, y, dfdy, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dfdy(n, n)
        end subroutine jac
    end interface
    type(callback_jac_system) :: sys
    integer(c_int) :: none(1)
    real(c_double) :: unused(n)
    sizes = 0
    if (action /= 1 .and. action /= 2) then
        info = CM_BAD_INPUT
        call copy_message("bad input: action must be 1 (step) or 2 (dense output)", message)
        return
    end if
    none = 0
    unused = 0.0_c_double
    sys%f => fun
    sys%n = n
    if (has_jac /= 0) sys%jac => jac
    ! t0, t_bound, y0, tolerances and the pattern are not read by a step: placeholders
    call stepper_action(sys, action, n, nr, ni, nw, 0.0_c_double, 0.0_c_double, unused, &
                        method, unused, unused, 0.0_c_double, 0.0_c_double, 1, 0, -1, &
                        none, none, r, iv, w, sizes, info, message)
end subroutine flat_stepper_step_callback

!> A step or dense output for the built-in (or compiled) system `name` with parameters
!! params(1:np).
subroutine flat_stepper_step_builtin(name, np, params, nspec, spec, action, method, n, nr, &
                                     ni, nw, r, iv, w, sizes, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_flat_spec, only: spec_system
    use conmech_flat_ode_support, only: copy_message
    use conmech_flat_stepper_support, only: stepper_action
    implicit none
    character(len=*), intent(in) :: name
    integer(c_int), intent(in) :: np
    real(c_double), intent(in) :: params(max(np, 1))
    integer(c_int), intent(in) :: nspec
    integer(8), intent(in) :: spec(max(nspec, 1))  ! c_int64_t (f2py: long_long)
    integer(c_int), intent(in) :: action, method, n, nr, ni, nw
    real(c_double), intent(inout) :: r(max(nr, 1)), w(n, max(nw, 1))
    integer(c_int), intent(inout) :: iv(max(ni, 1))
    integer(c_int), intent(out) :: sizes(3), info
    character(len=256), intent(out) :: message
    class(ode_system), allocatable :: sys
    character(len=:), allocatable :: msg
    integer(c_int) :: none(1)
    real(c_double) :: unused(n)
    sizes = 0
    if (action /= 1 .and. action /= 2) then
        info = CM_BAD_INPUT
        call copy_message("bad input: action must be 1 (step) or 2 (dense output)", message)
        return
    end if
    ! the dimension was checked against the system when the state was made (action 0)
    call spec_system(name, real(params(1:np), dp), nspec, spec, sys, info, msg)
    if (info /= CM_SUCCESS) then
        call copy_message(msg, message)
        return
    end if
    none = 0
    unused = 0.0_c_double
    call stepper_action(sys, action, n, nr, ni, nw, 0.0_c_double, 0.0_c_double, unused, &
                        method, unused, unused, 0.0_c_double, 0.0_c_double, 1, 0, -1, &
                        none, none, r, iv, w, sizes, info, message)
end subroutine flat_stepper_step_builtin
