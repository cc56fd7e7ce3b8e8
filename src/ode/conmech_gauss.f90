!> Gauss-Legendre collocation through the one driver loop: `gauss_solve` is `ode_solve`
!! with METHOD_GAUSS4 (s = 2) or METHOD_GAUSS6 (s = 3); the method itself is
!! conmech_gauss_stepper (re-exported here with its tableau).
module conmech_gauss
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_system, ode_events
    use conmech_ode_options, only: ode_options, METHOD_GAUSS4, METHOD_GAUSS6
    use conmech_ode_result, only: ode_result
    use conmech_ode_solver, only: ode_solve
    use conmech_gauss_stepper, only: gauss_stepper, gauss_tableau
    implicit none
    private

    public :: gauss_solve, gauss_stepper, gauss_tableau

contains

    !> Solve y' = f(t, y) on t_span with the s-stage Gauss method (s = 2: METHOD_GAUSS4,
    !! s = 3: METHOD_GAUSS6), fixed step opt%first_step; outputs as `ode_solve`.
    subroutine gauss_solve(sys, s, t_span, y0, opt, res, t_eval, events)
        class(ode_system), intent(in) :: sys
        integer, intent(in) :: s
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: y0(:)
        type(ode_options), intent(in) :: opt
        type(ode_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        type(ode_options) :: o
        o = opt
        o%method = merge(METHOD_GAUSS4, METHOD_GAUSS6, s == 2)
        if (s /= 2 .and. s /= 3) o%method = 0
        call ode_solve(sys, t_span, y0, o, res, t_eval, events)
    end subroutine gauss_solve

end module conmech_gauss
