!> The grid of a fixed-step method: first_step is the longest step, and [t0, tf] is cut
!! into the fewest equal steps not longer than it (a relative 1e-12 of slack, so that an
!! interval that is a whole number of steps up to round-off is not given one step more).
module conmech_fixed_grid
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_TOO_MANY_STEPS
    use conmech_text, only: itoa
    implicit none
    private

    public :: grid_steps, check_grid_steps, grid_time

contains

    !> The number of equal steps of at most `step` on [t0, tf]: 0 for an empty interval,
    !! else ceiling(|tf - t0|/step) up to the slack, at least 1.
    pure integer function grid_steps(t0, tf, step) result(nsteps)
        real(dp), intent(in) :: t0, tf, step
        nsteps = 0
        if (tf /= t0) nsteps = max(1, ceiling(abs(tf - t0)/step*(1.0_dp - 1.0e-12_dp)))
    end function grid_steps

    !> The time of grid point k of nsteps steps of h from t_start: tf itself at the end
    !! (no round-off from t_start + nsteps h).
    pure real(dp) function grid_time(t_start, tf, h, k, nsteps) result(t)
        real(dp), intent(in) :: t_start, tf, h
        integer, intent(in) :: k, nsteps
        if (k == nsteps) then
            t = tf
        else
            t = t_start + real(k, dp)*h
        end if
    end function grid_time

    !> CM_TOO_MANY_STEPS, with a message that gives the grid's length, when the grid has
    !! more than max_steps steps; else CM_SUCCESS and msg unchanged.
    subroutine check_grid_steps(nsteps, max_steps, info, msg)
        integer, intent(in) :: nsteps, max_steps
        integer, intent(out) :: info
        character(len=:), allocatable, intent(inout) :: msg
        info = CM_SUCCESS
        if (nsteps > max_steps) then
            info = CM_TOO_MANY_STEPS
            msg = "too many steps: the run needs "//itoa(nsteps)//" steps of first_step, " &
                  //"more than max_steps"
        end if
    end subroutine check_grid_steps

end module conmech_fixed_grid
