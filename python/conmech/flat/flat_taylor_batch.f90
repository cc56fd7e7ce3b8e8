!> Flat f2py layer of Taylor ensembles in SIMD lanes (conventions:
!! python/conmech/flat/flat_ode.f90; Python API: conmech/ivp/ensemble.py).

!> Ensemble of m members of one symbolic ode system by its generated lane propagator at
!! address runaddr (conmech.symbolic.taylor_batch: n states, the parameters params shared
!! by every member), chunks of members over OpenMP threads (threads = 0: the default
!! number). Each member takes exactly the steps of its own solve_ivp run. Outputs per
!! member: y_final(:, j), t_final(j), status (conmech_status codes), nfev (its
!! expansions), naccept, nreject; info: the lowest status (0 when every member ended).
subroutine flat_taylor_batch_run(runaddr, np, params, n, m, y0, t_span, rtol, atol, &
                                 max_step, max_steps, threads, y_final, t_final, status, &
                                 nfev, naccept, nreject, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_intptr_t, c_funptr, &
                                           c_null_funptr, c_f_procpointer
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_taylor_batch, only: taylor_batch_run_fn, taylor_batch_run_members
    use conmech_flat_ode_support, only: copy_message
    implicit none
    integer(8), intent(in) :: runaddr
    integer(c_int), intent(in) :: np, n, m, max_steps, threads
    real(c_double), intent(in) :: params(max(np, 1)), y0(n, m), t_span(2), rtol(n), atol(n)
    real(c_double), intent(in) :: max_step
    real(c_double), intent(out) :: y_final(n, m), t_final(m)
    integer(c_int), intent(out) :: status(m), nfev(m), naccept(m), nreject(m), info
    character(len=256), intent(out) :: message
    procedure(taylor_batch_run_fn), pointer :: run
    type(c_funptr) :: fp
    info = CM_BAD_INPUT
    status = CM_BAD_INPUT
    nfev = 0
    naccept = 0
    nreject = 0
    y_final = y0
    t_final = t_span(1)
    if (runaddr == 0 .or. n < 1 .or. m < 1 .or. max_steps < 1 .or. threads < 0) then
        call copy_message("bad input: invalid lane propagator, sizes or counts", message)
        return
    end if
    fp = transfer(int(runaddr, c_intptr_t), c_null_funptr)
    call c_f_procpointer(fp, run)
    call taylor_batch_run_members(run, real(params(1:max(np, 1)), dp), n, m, y_final, &
                                  t_span(1), t_span(2), rtol, atol, max_step, max_steps, &
                                  threads, t_final, status, nfev, naccept, nreject)
    info = CM_SUCCESS
    if (any(status < 0)) info = minval(status)
    call copy_message("success", message)
end subroutine flat_taylor_batch_run
