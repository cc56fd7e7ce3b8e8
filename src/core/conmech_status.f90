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

    integer, parameter :: msg_len = 65

    !> The default message of each code, indexed by the code: from CM_USER_ERROR (-8)
    !! up to CM_EVENT_STOP (1).
    character(len=msg_len), parameter :: messages(CM_USER_ERROR:CM_EVENT_STOP) = [ &
        character(len=msg_len) :: &
        "a user callback reported an error", &
        "LAPACK reported an illegal argument", &
        "iteration did not converge", &
        "singular matrix", &
        "bad input", &
        "non-finite value (NaN or Inf) in the state or the right-hand side", &
        "step size too small: the step size underflowed", &
        "too many steps: the maximum number of steps was reached", &
        "success", &
        "a termination event occurred"]

contains

    !> Default human-readable text for a status code.
    pure function status_message(info) result(msg)
        integer, intent(in) :: info
        character(len=:), allocatable :: msg
        if (info < lbound(messages, 1) .or. info > ubound(messages, 1)) then
            msg = "unknown status"
        else
            msg = trim(messages(info))
        end if
    end function status_message

    !> True for success-like codes (CM_SUCCESS, CM_EVENT_STOP).
    elemental function status_is_success(info) result(ok)
        integer, intent(in) :: info
        logical :: ok
        ok = info >= 0
    end function status_is_success

end module conmech_status
