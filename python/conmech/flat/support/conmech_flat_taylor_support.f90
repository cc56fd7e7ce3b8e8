!> Support of the flat layer for Taylor's method with compiled events (compiled into the
!! extension, not wrapped): `run_taylor_solve` runs `ode_solve` with a Taylor stepper that
!! knows the events' series routine (so that no crossing inside a step is missed, see
!! conmech_taylor_events) and hands the result to `store` like run_solve.
module conmech_flat_taylor_support
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t, c_intptr_t, &
                                           c_funptr, c_null_funptr, c_f_procpointer
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: METHOD_TAYLOR
    use conmech_ode_solver, only: ode_options, ode_result, ode_solve
    use conmech_taylor_stepper, only: taylor_stepper
    use conmech_taylor_events, only: taylor_events
    use conmech_flat_ode_support, only: copy_message, store_result, set_flat_options
    implicit none
    private
    public :: run_taylor_solve

contains

    !> ode_solve with METHOD_TAYLOR and the compiled events at address evaddr (series
    !! routine with evnw work columns; ne events with directions ev_dir and terminal counts
    !! ev_term, SciPy's rule for an event zero at t0); counts = [nfev, njev, nlu, naccept,
    !! nreject, steps shortened by events].
    subroutine run_taylor_solve(sys, n, t_span, y0, rtol, atol, first_step, max_step, &
                                max_steps, dense, neval, t_eval, evaddr, evnw, evdeg, &
                                params, ne, ev_dir, ev_term, store, counts, &
                                dense_form, info, message)
        class(ode_system), intent(in) :: sys
        integer(c_int), intent(in) :: n
        real(c_double), intent(in) :: t_span(2), y0(n), rtol(n), atol(n)
        real(c_double), intent(in) :: first_step, max_step
        integer(c_int), intent(in) :: max_steps, dense, neval
        real(c_double), intent(in) :: t_eval(:)
        integer(c_int64_t), intent(in) :: evaddr
        integer(c_int), intent(in) :: evnw, evdeg, ne
        real(c_double), intent(in) :: params(:)
        integer(c_int), intent(in) :: ev_dir(:), ev_term(:)
        external :: store
        integer(c_int), intent(out) :: counts(6), dense_form, info
        character(len=*), intent(out) :: message
        type(ode_options) :: opt
        type(ode_result) :: res
        type(taylor_events), target :: ev
        type(taylor_stepper) :: stp
        type(c_funptr) :: fp

        counts = 0
        dense_form = 0
        info = CM_BAD_INPUT
        if (n < 1 .or. neval < 0 .or. ne < 1 .or. evnw < n + ne .or. evaddr == 0 .or. &
            evdeg < 2) then
            call copy_message("bad input: invalid compiled events", message)
            return
        end if
        call set_flat_options(opt, int(METHOD_TAYLOR, c_int), rtol, atol, first_step, &
                              max_step, max_steps, dense)
        fp = transfer(int(evaddr, c_intptr_t), c_null_funptr)
        call c_f_procpointer(fp, ev%series)
        ev%n = n
        ev%ne = ne
        ev%nw = evnw
        ev%degree = evdeg
        ev%p = params
        ev%direction = ev_dir(1:ne)
        ev%terminal = ev_term(1:ne) > 0
        ev%count = max(ev_term(1:ne), 1)
        ev%zero_at_t0 = .true.
        stp%ev => ev
        if (neval > 0) then
            call ode_solve(sys, t_span, y0, opt, res, t_eval=t_eval(1:neval), events=ev, &
                           stepper=stp)
        else
            call ode_solve(sys, t_span, y0, opt, res, events=ev, stepper=stp)
        end if
        counts = [res%stats%nfev, res%stats%njev, res%stats%nlu, res%stats%naccept, &
                  res%stats%nreject, ev%nsplit]
        info = res%status
        call copy_message(res%message, message)
        call store_result(res, n, opt%dense_output, store, dense_form)
    end subroutine run_taylor_solve

end module conmech_flat_taylor_support
