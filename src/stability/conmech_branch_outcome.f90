!> What a branch of a continuation has besides its points, for the branches of periodic
!! orbits (conmech_branch_types) and of equilibria (conmech_eq_branch_types): the status of
!! `outcome`, the numbers of points and special points, and the stop where the corrector
!! does not converge with the smallest step allowed.
module conmech_branch_outcome
    use conmech_kinds, only: dp
    use conmech_status, only: CM_NO_CONVERGENCE
    use conmech_outcome, only: outcome
    implicit none
    private

    public :: branch_outcome

    type, extends(outcome) :: branch_outcome
        integer :: npoints = 0
        integer :: nspecial = 0
    contains
        procedure :: corrector_stalled => branch_corrector_stalled
    end type branch_outcome

contains

    !> The branch stops at p, its last point (CM_NO_CONVERGENCE): the corrector did not
    !! converge with ds >= ds_min, for `reason`. `what` names the continuation.
    subroutine branch_corrector_stalled(self, what, p, reason)
        class(branch_outcome), intent(inout) :: self
        character(len=*), intent(in) :: what
        real(dp), intent(in) :: p
        character(len=*), intent(in) :: reason
        character(len=32) :: buf
        write (buf, '(es23.15)') p
        call self%fail(CM_NO_CONVERGENCE, what//" stopped at p = "//trim(adjustl(buf))// &
                                          ": the corrector did not converge with ds >= "// &
                                          "ds_min ("//reason//")")
    end subroutine branch_corrector_stalled

end module conmech_branch_outcome
