!> Flat f2py layer (conventions in flat_ode.f90): conmech's status codes and their default
!! messages (src/core/conmech_status.f90), so that the Python package maps a status to an
!! exception from the Fortran definitions instead of copies of the numbers.
!! Nothing is saved between calls; nothing stops or prints.

!> The status codes, in the order of conmech_status.
subroutine flat_status_codes(success, event_stop, too_many_steps, step_too_small, &
                             nonfinite, bad_input, singular, no_convergence, &
                             lapack_error, user_error)
    use, intrinsic :: iso_c_binding, only: c_int
    use conmech_status, only: CM_SUCCESS, CM_EVENT_STOP, CM_TOO_MANY_STEPS, &
        CM_STEP_TOO_SMALL, CM_NONFINITE, CM_BAD_INPUT, CM_SINGULAR, CM_NO_CONVERGENCE, &
        CM_LAPACK_ERROR, CM_USER_ERROR
    implicit none
    integer(c_int), intent(out) :: success, event_stop, too_many_steps, step_too_small
    integer(c_int), intent(out) :: nonfinite, bad_input, singular, no_convergence
    integer(c_int), intent(out) :: lapack_error, user_error
    success = CM_SUCCESS
    event_stop = CM_EVENT_STOP
    too_many_steps = CM_TOO_MANY_STEPS
    step_too_small = CM_STEP_TOO_SMALL
    nonfinite = CM_NONFINITE
    bad_input = CM_BAD_INPUT
    singular = CM_SINGULAR
    no_convergence = CM_NO_CONVERGENCE
    lapack_error = CM_LAPACK_ERROR
    user_error = CM_USER_ERROR
end subroutine flat_status_codes

!> The default message of a status code (status_message), blank-padded.
subroutine flat_status_message(info, message)
    use, intrinsic :: iso_c_binding, only: c_int
    use conmech_status, only: status_message
    implicit none
    integer(c_int), intent(in) :: info
    character(len=256), intent(out) :: message
    message = status_message(info)
end subroutine flat_status_message
