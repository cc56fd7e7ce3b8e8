!> Flat f2py layer of Taylor's method (conventions: python/conmech/flat/flat_ode.f90).

!> Solve y' = f(t, y) by Taylor's method for a compiled system (spec with Taylor routines)
!! with compiled events: evaddr is the address of the events' series routine
!! (conmech.symbolic.taylor.event_source) with evnw work columns, evdeg the degree of the
!! series used to isolate their roots; ne events with directions ev_dir (+1 rising, -1
!! falling, 0 both) and terminal counts ev_term (> 0: the run stops at that occurrence,
!! 0: not terminal); an event exactly zero at t0 follows SciPy's rule, as in flat_solve.
!! Other arguments and `store` as in flat_solve; counts = [nfev, njev, nlu, naccept,
!! nreject, steps shortened to separate two roots of an event].
subroutine flat_solve_taylor(name, np, params, nspec, spec, store, n, t_span, y0, rtol, &
                             atol, first_step, max_step, max_steps, dense, neval, t_eval, &
                             evaddr, evnw, evdeg, ne, ev_dir, ev_term, counts, &
                             dense_form, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_flat_spec, only: spec_system_of_size
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
    integer(c_int), intent(in) :: ev_dir(max(ne, 1)), ev_term(max(ne, 1))
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
    call spec_system_of_size(name, real(params(1:np), dp), nspec, spec, n, &
                             "bad input: y0 does not match the system's dimension", sys, info, msg)
    if (info /= CM_SUCCESS) then
        call copy_message(msg, message)
        return
    end if
    call run_taylor_solve(sys, n, t_span, y0, rtol, atol, first_step, max_step, max_steps, &
                          dense, neval, t_eval, int(evaddr, c_int64_t), evnw, evdeg, &
                          real(params(1:max(np, 1)), dp), ne, ev_dir, ev_term, store, &
                          counts, dense_form, info, message)
end subroutine flat_solve_taylor

!> State and STM by Taylor's method on the variational system's own recurrences (a
!! compiled system whose spec has taylor_var); as flat_stm otherwise.
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

!> Ensemble of m members of one compiled system by Taylor's method in batches: the batch
!! routine at address fnaddr computes `width` members' coefficients at once (nw work
!! columns, shared parameters params); batches run in OpenMP threads (threads = 0: the
!! default number). Each member takes exactly the steps of its own integration. Outputs per
!! member: y_final(:, j), t_final(j), status (conmech_status codes), naccept, nreject;
!! nfev(j) counts the expansions of its batch.
subroutine flat_taylor_ensemble(fnaddr, width, nw, np, params, n, m, y0, t_span, rtol, atol, &
                                max_step, max_steps, threads, y_final, t_final, status, &
                                nfev, naccept, nreject, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t, c_intptr_t, &
                                           c_funptr, c_null_funptr, c_f_procpointer
    !$ use omp_lib, only: omp_get_max_threads
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_taylor_batch, only: taylor_batch_fn, taylor_batch_propagate
    use conmech_flat_ode_support, only: copy_message
    implicit none
    integer(8), intent(in) :: fnaddr
    integer(c_int), intent(in) :: width, nw, np, n, m, max_steps, threads
    real(c_double), intent(in) :: params(max(np, 1)), y0(n, m), t_span(2), rtol(n), atol(n)
    real(c_double), intent(in) :: max_step
    real(c_double), intent(out) :: y_final(n, m), t_final(m)
    integer(c_int), intent(out) :: status(m), nfev(m), naccept(m), nreject(m), info
    character(len=256), intent(out) :: message
    procedure(taylor_batch_fn), pointer :: fn
    type(c_funptr) :: fp
    integer :: b, nb, j0, nm, nthr, nfb
    integer :: st(width), na(width), nr(width)
    real(dp) :: te(width)
    info = CM_BAD_INPUT
    status = CM_BAD_INPUT
    nfev = 0
    naccept = 0
    nreject = 0
    y_final = y0
    t_final = t_span(1)
    if (fnaddr == 0 .or. width < 1 .or. nw < n .or. n < 1 .or. m < 1) then
        call copy_message("bad input: invalid batch Taylor routine or sizes", message)
        return
    end if
    fp = transfer(int(fnaddr, c_intptr_t), c_null_funptr)
    call c_f_procpointer(fp, fn)
    nb = (m + width - 1)/width
    nthr = 1
    !$ nthr = omp_get_max_threads()
    if (threads > 0) nthr = threads
    !$omp parallel do num_threads(nthr) schedule(dynamic, 1) default(shared) &
    !$omp private(b, j0, nm, st, na, nr, te, nfb)
    do b = 1, nb
        j0 = (b - 1)*width + 1
        nm = min(width, m - j0 + 1)
        call taylor_batch_propagate(fn, width, nw, real(params(1:max(np, 1)), dp), n, nm, &
                                    t_span(1), t_span(2), y_final(:, j0:j0 + nm - 1), rtol, &
                                    atol, max_step, max_steps, st(1:nm), te(1:nm), nfb, &
                                    na(1:nm), nr(1:nm))
        status(j0:j0 + nm - 1) = st(1:nm)
        t_final(j0:j0 + nm - 1) = te(1:nm)
        naccept(j0:j0 + nm - 1) = na(1:nm)
        nreject(j0:j0 + nm - 1) = nr(1:nm)
        nfev(j0:j0 + nm - 1) = nfb
    end do
    !$omp end parallel do
    info = CM_SUCCESS
    if (any(status < 0)) info = minval(status)
    call copy_message("success", message)
end subroutine flat_taylor_ensemble

!> Taylor's method in quadruple precision for a reference solution: the generated
!! real128 routine at fnaddr (nw work columns); y0, the parameters, t0, tf and tol as pairs
!! of doubles (hi, lo: the value hi + lo), the final state y1 likewise; nsteps accepted
!! steps at order `order`.
subroutine flat_taylor_quad(fnaddr, nw, np, params, n, y0, t_span, tol, max_steps, y1, &
                            nsteps, order, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT, status_message
    use conmech_taylor_quad, only: qp, taylor_qp_fn, taylor_propagate_qp
    use conmech_flat_quad_pairs, only: from_pairs, from_pair, to_pairs, quad_routine
    use conmech_flat_ode_support, only: copy_message
    implicit none
    integer(8), intent(in) :: fnaddr
    integer(c_int), intent(in) :: nw, np, n, max_steps
    real(c_double), intent(in) :: params(2, max(np, 1)), y0(2, n), t_span(2, 2), tol(2)
    real(c_double), intent(out) :: y1(2, n)
    integer(c_int), intent(out) :: nsteps, order, info
    character(len=256), intent(out) :: message
    procedure(taylor_qp_fn), pointer :: fn
    real(qp) :: y(n), p(max(np, 1))
    integer :: ns, ord, inf
    y1 = y0
    nsteps = 0
    order = 0
    if (fnaddr == 0 .or. nw < n .or. n < 1) then
        info = CM_BAD_INPUT
        call copy_message("bad input: invalid quadruple-precision Taylor routine", message)
        return
    end if
    call quad_routine(fnaddr, fn)
    y = from_pairs(y0)
    p = from_pairs(params)
    call taylor_propagate_qp(fn, n, nw, p, from_pair(t_span(:, 1)), from_pair(t_span(:, 2)), &
                             y, from_pair(tol), max_steps, inf, ns, ord)
    call to_pairs(y, y1)
    nsteps = ns
    order = ord
    info = inf
    call copy_message(status_message(inf), message)
end subroutine flat_taylor_quad
