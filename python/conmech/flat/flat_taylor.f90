!> Flat f2py layer of Taylor's method (conventions: python/conmech/flat/flat_ode.f90).

!> Solve y' = f(t, y) by Taylor's method for a compiled system (spec with Taylor routines)
!! with compiled events: evaddr is the address of the events' series routine
!! (conmech.symbolic.taylor.event_source) with evnw work columns, evdeg the degree of the
!! series used to isolate their roots; ne events with directions ev_dir (+1 rising, -1
!! falling, 0 both) and terminal flags ev_term; ev_zero /= 0: the event is taken as zero
!! at t0 (a run continued from its root). Other arguments and `store` as in
!! flat_solve_builtin; counts = [nfev, njev, nlu, naccept, nreject, steps shortened to
!! separate two roots of an event].
subroutine flat_solve_taylor(name, np, params, nspec, spec, store, n, t_span, y0, rtol, &
                             atol, first_step, max_step, max_steps, dense, neval, t_eval, &
                             evaddr, evnw, evdeg, ne, ev_dir, ev_term, ev_zero, counts, &
                             dense_form, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_flat_spec, only: spec_system, spec_dimension
    use conmech_flat_ode_support, only: copy_message
    use conmech_flat_taylor_support, only: run_taylor_solve
    implicit none
    character(len=*), intent(in) :: name
    integer(c_int), intent(in) :: np
    real(c_double), intent(in) :: params(max(np, 1))
    integer(c_int), intent(in) :: nspec
    integer(8), intent(in) :: spec(max(nspec, 1))  ! c_int64_t (f2py: long_long)
    integer(c_int), intent(in) :: n
    real(c_double), intent(in) :: t_span(2)
    real(c_double), intent(in) :: y0(n)
    real(c_double), intent(in) :: rtol(n), atol(n)
    real(c_double), intent(in) :: first_step, max_step
    integer(c_int), intent(in) :: max_steps, dense, neval
    real(c_double), intent(in) :: t_eval(max(neval, 1))
    integer(8), intent(in) :: evaddr
    integer(c_int), intent(in) :: evnw, evdeg, ne
    integer(c_int), intent(in) :: ev_dir(max(ne, 1)), ev_term(max(ne, 1)), ev_zero(max(ne, 1))
    integer(c_int), intent(out) :: counts(6), dense_form, info
    character(len=256), intent(out) :: message
!f2py external store
    interface
        subroutine store(t, y, ev_t, ev_y, ev_id, ts, hs, coef, n, nt, nev, nseg, nf1)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n, nt, nev, nseg, nf1
            real(c_double), intent(in) :: t(nt)
            real(c_double), intent(in) :: y(n, nt)
            real(c_double), intent(in) :: ev_t(nev)
            real(c_double), intent(in) :: ev_y(n, nev)
            integer(c_int), intent(in) :: ev_id(nev)
            real(c_double), intent(in) :: ts(nseg)
            real(c_double), intent(in) :: hs(nseg)
            real(c_double), intent(in) :: coef(n, nf1, nseg)
        end subroutine store
    end interface
    class(ode_system), allocatable :: sys
    character(len=:), allocatable :: msg

    counts = 0
    dense_form = 0
    call spec_system(name, real(params(1:np), dp), nspec, spec, sys, info, msg)
    if (info /= CM_SUCCESS) then
        call copy_message(msg, message)
        return
    end if
    if (spec_dimension(name, nspec, spec) /= n) then
        info = CM_BAD_INPUT
        call copy_message("bad input: y0 does not match the system's dimension", message)
        return
    end if
    call run_taylor_solve(sys, n, t_span, y0, rtol, atol, first_step, max_step, max_steps, &
                          dense, neval, t_eval, int(evaddr, c_int64_t), evnw, evdeg, &
                          real(params(1:max(np, 1)), dp), ne, ev_dir, ev_term, ev_zero, store, &
                          counts, dense_form, info, message)
end subroutine flat_solve_taylor

!> State and STM by Taylor's method on the variational system's own recurrences (a
!! compiled system whose spec has taylor_var); as flat_stm_builtin otherwise.
subroutine flat_stm_taylor(name, np, params, nspec, spec, n, y0, t0, t1, rtol, atol, y1, phi, &
                           nfev, naccept, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: METHOD_TAYLOR
    use conmech_ode_solver, only: ode_options, ode_stats
    use conmech_flat_spec, only: spec_system
    use conmech_flat_ode_support, only: copy_message
    use conmech_variational, only: integrate_stm
    implicit none
    character(len=*), intent(in) :: name
    integer(c_int), intent(in) :: np, n
    integer(c_int), intent(in) :: nspec
    integer(8), intent(in) :: spec(max(nspec, 1))  ! c_int64_t (f2py: long_long)
    real(c_double), intent(in) :: params(max(np, 1)), y0(n), t0, t1, rtol, atol
    real(c_double), intent(out) :: y1(n), phi(n, n)
    integer(c_int), intent(out) :: nfev, naccept, info
    character(len=256), intent(out) :: message
    class(ode_system), allocatable :: sys
    character(len=:), allocatable :: msg
    type(ode_options) :: opt
    type(ode_stats) :: st
    integer :: i
    nfev = 0
    naccept = 0
    y1 = y0
    phi = 0.0_c_double
    do i = 1, n
        phi(i, i) = 1.0_c_double
    end do
    call spec_system(name, params(1:np), nspec, spec, sys, info, msg)
    if (info /= 0) then
        call copy_message(msg, message)
        return
    end if
    opt%method = METHOD_TAYLOR
    opt%rtol = rtol
    opt%atol = atol
    call integrate_stm(sys, t0, t1, y1, phi, opt, info, msg, st)
    nfev = st%nfev
    naccept = st%naccept
    call copy_message(msg, message)
end subroutine flat_stm_taylor
