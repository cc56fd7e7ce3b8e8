!> Flat f2py layer of the stepper (conmech.DOP853, conmech.RK45, ... in conmech/_stepper.py):
!! the stepper's whole state lives in arrays owned by the Python object (r, iv, w; layout
!! in conmech_flat_stepper_support), copied in and out by every call, so that nothing is
!! kept in Fortran between calls. action: 0 init at (t0, y0), 1 one accepted step towards
!! t_bound, 2 dense coefficients of the last step (in w). Conventions as in flat_ode.f90.

!> Sizes of the packed state: nr reals, ni integers, nw columns of length n.
subroutine flat_stepper_sizes(nr, ni, nw)
    use, intrinsic :: iso_c_binding, only: c_int
    use conmech_flat_stepper_support, only: NR_STATE, NI_STATE, NW_STATE
    implicit none
    integer(c_int), intent(out) :: nr, ni, nw
    nr = NR_STATE
    ni = NI_STATE
    nw = NW_STATE
end subroutine flat_stepper_sizes

!> (r(20), iv(20), w(n, 34): the literal sizes NR_STATE, NI_STATE, NW_STATE of the support
!! module, checked by the Python layer against flat_stepper_sizes.)

!> One stepper action for a Python right-hand side fun(t, y) (f2py callback).
subroutine flat_stepper_callback(fun, action, n, t0, t_bound, y0, method, rtol, atol, &
                                 first_step, max_step, max_steps, r, iv, w, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_flat_ode_support, only: callback_system
    use conmech_flat_stepper_support, only: stepper_action
    implicit none
    integer(c_int), intent(in) :: action, n, method, max_steps
    real(c_double), intent(in) :: t0, t_bound, y0(n), rtol(n), atol(n)
    real(c_double), intent(in) :: first_step, max_step
    real(c_double), intent(inout) :: r(20), w(n, 34)
    integer(c_int), intent(inout) :: iv(20)
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
    call stepper_action(sys, action, n, t0, t_bound, y0, method, rtol, atol, first_step, &
                        max_step, max_steps, r, iv, w, info, message)
end subroutine flat_stepper_callback

!> One stepper action for the built-in system `name` with parameters params(1:np).
subroutine flat_stepper_builtin(name, np, params, nspec, spec, action, n, t0, t_bound, y0, &
                                method, rtol, &
                                atol, first_step, max_step, max_steps, r, iv, w, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_flat_spec, only: spec_system, spec_dimension
    use conmech_flat_ode_support, only: copy_message
    use conmech_flat_stepper_support, only: stepper_action
    implicit none
    character(len=*), intent(in) :: name
    integer(c_int), intent(in) :: np
    real(c_double), intent(in) :: params(max(np, 1))
    integer(c_int), intent(in) :: nspec
    integer(8), intent(in) :: spec(max(nspec, 1))  ! c_int64_t (f2py: long_long)
    integer(c_int), intent(in) :: action, n, method, max_steps
    real(c_double), intent(in) :: t0, t_bound, y0(n), rtol(n), atol(n)
    real(c_double), intent(in) :: first_step, max_step
    real(c_double), intent(inout) :: r(20), w(n, 34)
    integer(c_int), intent(inout) :: iv(20)
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
    call stepper_action(sys, action, n, t0, t_bound, y0, method, rtol, atol, first_step, &
                        max_step, max_steps, r, iv, w, info, message)
end subroutine flat_stepper_builtin
