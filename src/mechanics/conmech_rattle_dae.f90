!> Radau IIA on the constrained layer: `radau_constrained_solve` is `constrained_solve`
!! with METHOD_RADAU5, the equations of motion as the stabilised index-2 DAE of Gear,
!! Gupta and Leimkuhler (conmech_constrained_dae): both constraint levels hold at every
!! step end to the Newton tolerance, no drift, no projection; a constant mass matrix.
module conmech_rattle_dae
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_events
    use conmech_ode_options, only: METHOD_RADAU5
    use conmech_constrained_system, only: constrained_system
    use conmech_constrained_solver, only: constrained_options, constrained_result, &
        constrained_solve
    implicit none
    private

    public :: radau_constrained_solve

contains

    !> Integrate a constrained system with Radau IIA (order 5, adaptive: options%ode%rtol,
    !! atol, first_step, max_step, max_steps) in the stabilised index-2 form. The
    !! projection options are not used. Events are functions of (t, [q; v]), located on
    !! Radau's collocation polynomial (event states on the constraints to the tolerance).
    subroutine radau_constrained_solve(sys, t_span, q0, v0, options, res, t_eval, events)
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
        opt%ode%method = METHOD_RADAU5
        call constrained_solve(sys, t_span, q0, v0, opt, res, t_eval, events)
    end subroutine radau_constrained_solve

end module conmech_rattle_dae
