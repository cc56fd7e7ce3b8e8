!> The implicit methods behind `ode_solve`: a submodule of conmech_ode_solver (so that
!! conmech_radau and conmech_gauss can use the solver's option and result types while
!! `ode_solve` dispatches to them) that routes METHOD_RADAU5 to `radau_solve` and
!! METHOD_GAUSS4 / METHOD_GAUSS6 to `gauss_solve`.
submodule(conmech_ode_solver) conmech_radau_dispatch
    use conmech_gauss, only: gauss_solve
    implicit none

contains

    module subroutine implicit_solve(sys, t_span, y0, options, res, t_eval, events)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: y0(:)
        type(ode_options), intent(in) :: options
        type(ode_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        select case (options%method)
        case (METHOD_GAUSS4)
            call gauss_solve(sys, 2, t_span, y0, options, res, t_eval, events)
        case (METHOD_GAUSS6)
            call gauss_solve(sys, 3, t_span, y0, options, res, t_eval, events)
        case (METHOD_RATTLE)
            res%message = "bad input: RATTLE is a method for constrained systems " &
                          //"(rattle_solve, constrained.solve)"
        case default
            res%message = "bad input: unknown method"
        end select
        if (.not. allocated(res%t)) then
            allocate (res%t(0), res%y(size(y0), 0), res%ev_t(0), res%ev_y(size(y0), 0), &
                      res%ev_id(0))
        end if
    end subroutine implicit_solve

end submodule conmech_radau_dispatch
