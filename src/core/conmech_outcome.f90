!> The status of a computed object (a periodic orbit, a branch of orbits or of equilibria,
!! a Riccati solution, a controller design): an info code of conmech_status and a message.
!! The result types extend `outcome`; `fail` sets both at once where a computation stops.
module conmech_outcome
    use conmech_status, only: CM_BAD_INPUT
    implicit none
    private

    public :: outcome

    type :: outcome
        integer :: info = CM_BAD_INPUT          !! CM_SUCCESS or the reason it stopped
        character(len=:), allocatable :: message
    contains
        procedure :: fail => outcome_fail
        procedure :: fail_with_cause => outcome_fail_with_cause
    end type outcome

contains

    !> info and message together (a failed or stopped computation).
    pure subroutine outcome_fail(self, info, message)
        class(outcome), intent(inout) :: self
        integer, intent(in) :: info
        character(len=*), intent(in) :: message
        self%info = info
        self%message = message
    end subroutine outcome_fail

    !> `fail` with the message of the step that failed appended (": cause") when it left
    !! one (an unallocated cause: the message alone).
    pure subroutine outcome_fail_with_cause(self, info, message, cause)
        class(outcome), intent(inout) :: self
        integer, intent(in) :: info
        character(len=*), intent(in) :: message
        character(len=:), allocatable, intent(in) :: cause
        if (allocated(cause)) then
            call self%fail(info, message//": "//cause)
        else
            call self%fail(info, message)
        end if
    end subroutine outcome_fail_with_cause

end module conmech_outcome
