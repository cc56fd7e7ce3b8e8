!> RATTLE for mechanical systems with holonomic constraints (Andersen 1983;
!! Hairer-Lubich-Wanner, Geometric Numerical Integration, VII.1): `rattle_solve` is
!! `constrained_solve` with METHOD_RATTLE, fixed step options%ode%first_step. The stepper:
!! conmech_rattle_stepper; one step and its constraint solves: conmech_rattle_step.
module conmech_rattle
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_events
    use conmech_ode_options, only: METHOD_RATTLE
    use conmech_constrained_system, only: constrained_system
    use conmech_constrained_solver, only: constrained_options, constrained_result, &
        constrained_solve
    implicit none
    private

    public :: rattle_solve

contains

    !> Integrate a holonomic constrained system from (q0, v0) over t_span with RATTLE,
    !! fixed step options%ode%first_step. Result and options as `constrained_solve`
    !! (projection, rtol, atol are not used; proj_tol and proj_max_iter control the
    !! position solve; max_steps bounds the number of steps). t_eval points between grid
    !! points and events come from RATTLE side steps from the grid point before (every
    !! output on the manifold to round-off; event times of the method's order 2).
    subroutine rattle_solve(sys, t_span, q0, v0, options, res, t_eval, events)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: q0(:), v0(:)
        type(constrained_options), intent(in) :: options
        type(constrained_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)
        !> event functions of (t, [q; v])
        class(ode_events), intent(in), optional :: events
        type(constrained_options) :: opt
        opt = options
        opt%ode%method = METHOD_RATTLE
        call constrained_solve(sys, t_span, q0, v0, opt, res, t_eval, events)
    end subroutine rattle_solve

end module conmech_rattle
