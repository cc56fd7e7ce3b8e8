!> Status codes shared by every routine of conmech, and their default messages.
!!
!! Library routines never stop or print: they return an integer status (`info`) and,
!! where it helps, a message that names the problem. Zero and positive values are
!! successes (positive: a successful run that ended early, e.g. on a terminal event).
module conmech_status
    implicit none
    private

    integer, parameter, public :: CM_SUCCESS = 0         !! finished normally
    integer, parameter, public :: CM_EVENT_STOP = 1      !! stopped on a terminal event
    integer, parameter, public :: CM_TOO_MANY_STEPS = -1 !! max_steps exceeded
    integer, parameter, public :: CM_STEP_TOO_SMALL = -2 !! step size underflow
    integer, parameter, public :: CM_NONFINITE = -3      !! NaN or Inf in the state or rhs
    integer, parameter, public :: CM_BAD_INPUT = -4      !! invalid argument
    integer, parameter, public :: CM_SINGULAR = -5       !! singular matrix (mass, KKT, Newton)
    integer, parameter, public :: CM_NO_CONVERGENCE = -6 !! an iteration did not converge
    integer, parameter, public :: CM_LAPACK_ERROR = -7   !! LAPACK reported an argument error
    integer, parameter, public :: CM_USER_ERROR = -8     !! a user callback reported failure

    public :: status_message, status_is_success

contains

    !> Default human-readable text for a status code.
    pure function status_message(info) result(msg)
        integer, intent(in) :: info
        character(len=:), allocatable :: msg
        select case (info)
        case (CM_SUCCESS)
            msg = "success"
        case (CM_EVENT_STOP)
            msg = "a termination event occurred"
        case (CM_TOO_MANY_STEPS)
            msg = "too many steps: the maximum number of steps was reached"
        case (CM_STEP_TOO_SMALL)
            msg = "step size too small: the step size underflowed"
        case (CM_NONFINITE)
            msg = "non-finite value (NaN or Inf) in the state or the right-hand side"
        case (CM_BAD_INPUT)
            msg = "bad input"
        case (CM_SINGULAR)
            msg = "singular matrix"
        case (CM_NO_CONVERGENCE)
            msg = "iteration did not converge"
        case (CM_LAPACK_ERROR)
            msg = "LAPACK reported an illegal argument"
        case (CM_USER_ERROR)
            msg = "a user callback reported an error"
        case default
            msg = "unknown status"
        end select
    end function status_message

    !> True for success-like codes (CM_SUCCESS, CM_EVENT_STOP).
    elemental function status_is_success(info) result(ok)
        integer, intent(in) :: info
        logical :: ok
        ok = info >= 0
    end function status_is_success

end module conmech_status
