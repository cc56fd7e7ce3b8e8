!> Radau IIA with a mass matrix through the one driver loop: `radau_solve`, the entry for
!! M y' = f(t, y) with a constant, possibly singular M (differential-algebraic systems of
!! index up to 3; the error of index-k components is weighted by |h|^(k-1), as RADAU5's
!! NIND2 and NIND3).
!! Without M it is `ode_solve` with METHOD_RADAU5. The method itself: conmech_radau_stepper.
module conmech_radau
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_system, ode_events
    use conmech_ode_options, only: ode_options, METHOD_RADAU5
    use conmech_ode_result, only: ode_result
    use conmech_ode_solver, only: ode_solve
    use conmech_radau_stepper, only: radau_stepper
    implicit none
    private

    public :: radau_solve

contains

    !> Solve M y' = f(t, y) (M = I without `mass`) on t_span with Radau IIA (order 5);
    !! outputs as `ode_solve` (every accepted step, or t_eval interpolated on the collocation
    !! polynomial; dense output; events). res%stats counts nfev, njev, nlu, naccept,
    !! nreject.
    subroutine radau_solve(sys, t_span, y0, opt, res, t_eval, events, mass, index2, dae_index)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: y0(:)
        type(ode_options), intent(in) :: opt
        type(ode_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        !> constant mass matrix M of M y' = f(t, y) (n x n, may be singular: a DAE)
        real(dp), intent(in), optional :: mass(:, :)
        !> the index-2 algebraic components (their error is scaled by h, as RADAU5)
        logical, intent(in), optional :: index2(:)
        !> the index (1, 2 or 3) of every component (instead of index2)
        integer, intent(in), optional :: dae_index(:)
        type(radau_stepper) :: stp
        type(ode_options) :: o
        if (present(mass)) stp%mass = mass
        if (present(index2)) stp%index2 = index2
        if (present(dae_index)) stp%dae_index = dae_index
        o = opt
        o%method = METHOD_RADAU5
        call ode_solve(sys, t_span, y0, o, res, t_eval, events, stepper=stp)
    end subroutine radau_solve

end module conmech_radau
