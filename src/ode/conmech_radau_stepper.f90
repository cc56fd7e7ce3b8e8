!> Radau IIA step by step (SciPy's OdeSolver use; conmech.Radau in Python): a
!! `radau_stepper` holds the whole state of a `radau_solve` integration in plain arrays
!! (layout: conmech_radau_state, RADAU_NR, RADAU_NI, RADAU_NW), `radau_stepper_init` starts at
!! (t0, y0), each `radau_stepper_step` makes one accepted step: the steps of `radau_solve`,
!! bit for bit. No state outside the object (thread-safe for distinct objects).
module conmech_radau_stepper
    use conmech_kinds, only: dp
    use conmech_status, only: CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_result
    use conmech_radau, only: radau_solve, RADAU_NR, RADAU_NI, RADAU_NW, RADAU_WY
    implicit none
    private

    public :: radau_stepper, radau_stepper_init, radau_stepper_step

    !> A step-by-step Radau IIA integration (SciPy's OdeSolver use): the whole state in
    !! plain arrays (layout above), so that it can live in a caller's arrays between
    !! calls. `radau_stepper_init` starts at (t0, y0), each `radau_stepper_step` makes one
    !! accepted step, the same steps as `radau_solve` (bit for bit).
    type :: radau_stepper
        real(dp), allocatable :: r(:)        !! real scalars; r(RADAU_RT) = t
        integer, allocatable :: iv(:)        !! integers, logicals (0/1), pivots
        real(dp), allocatable :: w(:, :)     !! columns of length n; w(:, RADAU_WY) = y
    end type radau_stepper

contains

    !> Start a step-by-step integration of y' = f(t, y) at (t0, y0) towards tf (options
    !! as `radau_solve`: tolerances, first_step, max_step, max_steps; no mass matrix).
    subroutine radau_stepper_init(st, sys, t0, tf, y0, opt, info, message)
        type(radau_stepper), intent(out) :: st
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t0, tf
        real(dp), intent(in) :: y0(:)
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: message
        type(ode_result) :: res
        integer :: n
        n = size(y0)
        allocate (st%r(RADAU_NR), st%iv(RADAU_NI + 2*n), st%w(n, RADAU_NW + 4*n))
        st%iv = 0
        call radau_solve(sys, [t0, tf], y0, opt, res, r_state=st%r, i_state=st%iv, &
                         w_state=st%w, action=0)
        info = res%status
        message = res%message
    end subroutine radau_stepper_init

    !> One accepted step of a started integration (the step of `radau_solve`); on failure
    !! info < 0 with the message (the time in it). opt: as given to radau_stepper_init.
    subroutine radau_stepper_step(st, sys, opt, info, message)
        type(radau_stepper), intent(inout) :: st
        class(ode_system), intent(in) :: sys
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: message
        type(ode_result) :: res
        real(dp), allocatable :: ycopy(:)
        real(dp) :: span(2)
        if (.not. allocated(st%w)) then
            info = CM_BAD_INPUT
            message = "bad input: the Radau stepper was not started (radau_stepper_init)"
            return
        end if
        ycopy = st%w(:, RADAU_WY)        ! (no aliasing with the packed state)
        span = st%r(1:2)
        call radau_solve(sys, span, ycopy, opt, res, r_state=st%r, i_state=st%iv, &
                         w_state=st%w, action=1)
        info = res%status
        message = res%message
    end subroutine radau_stepper_step

end module conmech_radau_stepper
