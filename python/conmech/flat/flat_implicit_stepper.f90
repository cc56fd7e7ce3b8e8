!> Flat f2py layer of the implicit steppers (conmech.Radau, conmech.Gauss4, conmech.Gauss6
!! in conmech/_implicit_stepper.py). Radau IIA:
!! the stepper's whole state lives in arrays owned by the Python object (r, iv, w; layout
!! in conmech_radau: RADAU_NR, RADAU_NI, RADAU_NW), updated in place by every call, so that
!! nothing is kept in Fortran between calls. action: 0 start at (t0, y0), 1 one accepted
!! step towards t_bound (the step of solve_ivp(method="Radau"), bit for bit). Gauss:
!! the same with r(8), iv(8), w(n, 6) (conmech_gauss: GAUSS_NR, GAUSS_NI, GAUSS_NW).
!! Conventions as in flat_ode.f90.

!> Sizes of the packed state: r(nr), iv(ni + 2 n), w(n, nw + 4 n).
subroutine flat_radau_stepper_sizes(nr, ni, nw)
    use, intrinsic :: iso_c_binding, only: c_int
    use conmech_radau, only: RADAU_NR, RADAU_NI, RADAU_NW
    implicit none
    integer(c_int), intent(out) :: nr, ni, nw
    nr = RADAU_NR
    ni = RADAU_NI
    nw = RADAU_NW
end subroutine flat_radau_stepper_sizes

!> One stepper action for a Python right-hand side fun(t, y) and, if has_jac /= 0, a
!! Python Jacobian jac(t, y) -> (n, n) (else forward differences).
subroutine flat_radau_stepper_callback(fun, jac, action, n, t0, t_bound, y0, has_jac, rtol, &
                                       atol, first_step, max_step, max_steps, r, iv, w, &
                                       info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_flat_ode_support, only: callback_jac_system
    use conmech_flat_implicit_stepper_support, only: radau_action
    implicit none
    integer(c_int), intent(in) :: action, n, has_jac, max_steps
    real(c_double), intent(in) :: t0, t_bound, y0(n), rtol(n), atol(n)
    real(c_double), intent(in) :: first_step, max_step
    real(c_double), intent(inout) :: r(20), w(n, 9 + 4*n)
    integer(c_int), intent(inout) :: iv(20 + 2*n)
    integer(c_int), intent(out) :: info
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
    sys%f => fun
    sys%n = n
    if (has_jac /= 0) sys%jac => jac
    call radau_action(sys, action, n, t0, t_bound, y0, rtol, atol, first_step, max_step, &
                      max_steps, r, iv, w, info, message)
end subroutine flat_radau_stepper_callback

!> One stepper action for the built-in (or compiled) system `name` with parameters
!! params(1:np); its analytic Jacobian if it has one, else forward differences.
subroutine flat_radau_stepper_builtin(name, np, params, nspec, spec, action, n, t0, t_bound, &
                                      y0, rtol, atol, first_step, max_step, max_steps, r, &
                                      iv, w, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_flat_spec, only: spec_system, spec_dimension
    use conmech_flat_ode_support, only: copy_message
    use conmech_flat_implicit_stepper_support, only: radau_action
    implicit none
    character(len=*), intent(in) :: name
    integer(c_int), intent(in) :: np
    real(c_double), intent(in) :: params(max(np, 1))
    integer(c_int), intent(in) :: nspec
    integer(8), intent(in) :: spec(max(nspec, 1))  ! c_int64_t (f2py: long_long)
    integer(c_int), intent(in) :: action, n, max_steps
    real(c_double), intent(in) :: t0, t_bound, y0(n), rtol(n), atol(n)
    real(c_double), intent(in) :: first_step, max_step
    real(c_double), intent(inout) :: r(20), w(n, 9 + 4*n)
    integer(c_int), intent(inout) :: iv(20 + 2*n)
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
    class(ode_system), allocatable :: sys
    character(len=:), allocatable :: msg
    call spec_system(name, real(params(1:np), dp), nspec, spec, sys, info, msg)
    if (info /= CM_SUCCESS) then
        call copy_message(msg, message)
        return
    end if
    if (spec_dimension(name, nspec, spec) /= n) then
        info = CM_BAD_INPUT
        call copy_message("bad input: y0 has the wrong size for the system '"//trim(name) &
                          //"'", message)
        return
    end if
    call radau_action(sys, action, n, t0, t_bound, y0, rtol, atol, first_step, max_step, &
                      max_steps, r, iv, w, info, message)
end subroutine flat_radau_stepper_builtin

!> Gauss method (6 GAUSS4, 7 GAUSS6), fixed step first_step: one action for a Python
!! right-hand side fun(t, y).
subroutine flat_gauss_stepper_callback(fun, action, n, method, t0, t_bound, y0, first_step, &
                                       max_steps, r, iv, w, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_flat_ode_support, only: callback_system
    use conmech_flat_implicit_stepper_support, only: gauss_action
    implicit none
    integer(c_int), intent(in) :: action, n, method, max_steps
    real(c_double), intent(in) :: t0, t_bound, y0(n), first_step
    real(c_double), intent(inout) :: r(8), w(n, 6)
    integer(c_int), intent(inout) :: iv(8)
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
!f2py external fun
    interface
        subroutine fun(t, y, dydt, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dydt(n)
        end subroutine fun
    end interface
    type(callback_system) :: sys
    sys%f => fun
    sys%n = n
    call gauss_action(sys, action, n, method, t0, t_bound, y0, first_step, max_steps, r, iv, &
                      w, info, message)
end subroutine flat_gauss_stepper_callback

!> Gauss method for the built-in (or compiled) system `name` with parameters params(1:np).
subroutine flat_gauss_stepper_builtin(name, np, params, nspec, spec, action, n, method, t0, &
                                      t_bound, y0, first_step, max_steps, r, iv, w, info, &
                                      message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_flat_spec, only: spec_system, spec_dimension
    use conmech_flat_ode_support, only: copy_message
    use conmech_flat_implicit_stepper_support, only: gauss_action
    implicit none
    character(len=*), intent(in) :: name
    integer(c_int), intent(in) :: np
    real(c_double), intent(in) :: params(max(np, 1))
    integer(c_int), intent(in) :: nspec
    integer(8), intent(in) :: spec(max(nspec, 1))  ! c_int64_t (f2py: long_long)
    integer(c_int), intent(in) :: action, n, method, max_steps
    real(c_double), intent(in) :: t0, t_bound, y0(n), first_step
    real(c_double), intent(inout) :: r(8), w(n, 6)
    integer(c_int), intent(inout) :: iv(8)
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
    class(ode_system), allocatable :: sys
    character(len=:), allocatable :: msg
    call spec_system(name, real(params(1:np), dp), nspec, spec, sys, info, msg)
    if (info /= CM_SUCCESS) then
        call copy_message(msg, message)
        return
    end if
    if (spec_dimension(name, nspec, spec) /= n) then
        info = CM_BAD_INPUT
        call copy_message("bad input: y0 has the wrong size for the system '"//trim(name) &
                          //"'", message)
        return
    end if
    call gauss_action(sys, action, n, method, t0, t_bound, y0, first_step, max_steps, r, iv, &
                      w, info, message)
end subroutine flat_gauss_stepper_builtin
