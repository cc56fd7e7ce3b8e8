!> Flat f2py layer of ensembles (conmech_ensemble): many initial states and/or parameter
!! sets of one built-in system integrated with OpenMP threads, results as arrays. The
!! Python API is conmech/ensemble.py. Conventions as in flat_ode.f90.

!> Ensemble of the built-in system `name` or of a compiled one (nspec, spec: see
!! conmech_flat_spec). params(np, mp): one column shared by every member (mp = 1) or one
!! per member (mp = m); y0(n, my0): likewise. Events: ne functions
!! g_j = y(ev_comp(j)) - ev_value(j) with direction ev_dir(j) (+1, -1, 0); the first k
!! events of each member are kept; terminal /= 0 stops a member at its k-th event.
!! threads = 0: the OpenMP default; chunk: members between progress calls (0 automatic);
!! use_progress /= 0 calls progress(done, total, cancel) between chunks (cancel /= 0
!! skips the rest). meval = m if neval > 0 else 1, mev = m if k > 0 and ne > 0 else 1
!! (sizes of the outputs). Member status: conmech's codes (0 end, 1 terminal event,
!! < 0 failure, -99 not run); info and message: the first failure (or bad input, or the
!! cancel).
subroutine flat_ensemble_builtin(name, np, mp, params, nspec, spec, n, m, my0, y0, t_span, &
                                 method, rtol, atol, first_step, max_step, max_steps, &
                                 neval, t_eval, ne, ev_comp, ev_value, ev_dir, k, terminal, &
                                 threads, chunk, use_progress, progress, meval, mev, &
                                 y_eval, t_final, y_final, status, nfev, naccept, nreject, &
                                 nev, ev_t, ev_y, ev_id, done, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options
    use conmech_flat_spec, only: spec_system_of_size
    use conmech_ensemble, only: ode_ensemble, ensemble_options, ensemble_result, &
        crossing_events
    use conmech_flat_ode_support, only: copy_message, set_flat_options
    use conmech_flat_ensemble_support, only: builtin_members, callback_progress
    implicit none
    character(len=*), intent(in) :: name
    integer(c_int), intent(in) :: np, mp, n, m, my0
    real(c_double), intent(in) :: params(max(np, 1), mp)
    integer(c_int), intent(in) :: nspec
    integer(8), intent(in) :: spec(max(nspec, 1))  ! c_int64_t (f2py: long_long)
    real(c_double), intent(in) :: y0(n, my0)
    real(c_double), intent(in) :: t_span(2)
    integer(c_int), intent(in) :: method
    real(c_double), intent(in) :: rtol(n), atol(n)
    real(c_double), intent(in) :: first_step, max_step
    integer(c_int), intent(in) :: max_steps, neval
    real(c_double), intent(in) :: t_eval(max(neval, 1))
    integer(c_int), intent(in) :: ne
    integer(c_int), intent(in) :: ev_comp(max(ne, 1))
    real(c_double), intent(in) :: ev_value(max(ne, 1))
    integer(c_int), intent(in) :: ev_dir(max(ne, 1))
    integer(c_int), intent(in) :: k, terminal, threads, chunk, use_progress, meval, mev
    real(c_double), intent(out) :: y_eval(n, max(neval, 1), meval)
    real(c_double), intent(out) :: t_final(m), y_final(n, m)
    integer(c_int), intent(out) :: status(m), nfev(m), naccept(m), nreject(m), nev(m)
    real(c_double), intent(out) :: ev_t(max(k, 1), mev), ev_y(n, max(k, 1), mev)
    integer(c_int), intent(out) :: ev_id(max(k, 1), mev)
    integer(c_int), intent(out) :: done, info
    character(len=256), intent(out) :: message
!f2py external progress
    interface
        subroutine progress(d, total, cancel)
            use, intrinsic :: iso_c_binding, only: c_int
            integer(c_int), intent(in) :: d, total
            integer(c_int), intent(out) :: cancel
        end subroutine progress
    end interface
    class(ode_system), allocatable :: sys
    type(builtin_members) :: members
    type(ode_options) :: opt
    type(ensemble_options) :: eo
    type(ensemble_result) :: res
    type(crossing_events) :: ev
    type(callback_progress) :: prog
    type(crossing_events), allocatable :: evs
    type(callback_progress), allocatable :: pg
    real(dp), allocatable :: te(:)
    character(len=:), allocatable :: msg
    logical :: with_events
    integer :: kk

    y_eval = 0.0_dp
    t_final = 0.0_dp
    y_final = 0.0_dp
    status = CM_BAD_INPUT
    nfev = 0
    naccept = 0
    nreject = 0
    nev = 0
    ev_t = 0.0_dp
    ev_y = 0.0_dp
    ev_id = 0
    done = 0
    info = CM_BAD_INPUT
    with_events = ne > 0 .and. k > 0
    if (n < 1 .or. m < 1 .or. neval < 0 .or. ne < 0 .or. k < 0 .or. np < 0) then
        call copy_message("bad input: array sizes must be positive", message)
        return
    end if
    if ((mp /= 1 .and. mp /= m) .or. (my0 /= 1 .and. my0 /= m)) then
        call copy_message("bad input: params and y0 need one column or one per member", &
                          message)
        return
    end if
    if ((neval > 0 .and. meval /= m) .or. (neval == 0 .and. meval /= 1) .or. &
        (with_events .and. mev /= m) .or. (.not. with_events .and. mev /= 1)) then
        call copy_message("bad input: meval or mev inconsistent with neval, ne and k", &
                          message)
        return
    end if
    call spec_system_of_size(name, real(params(1:np, 1), dp), nspec, spec, n, "", sys, info, &
                             msg)
    if (info /= CM_SUCCESS) then
        call copy_message(msg, message)
        return
    end if

    call set_flat_options(opt, method, rtol, atol, first_step, max_step, max_steps, 0)
    eo%threads = threads
    eo%chunk = chunk
    eo%terminal = terminal /= 0 .and. with_events
    kk = 1
    if (with_events) then
        kk = k
        ev%component = ev_comp(1:ne)
        ev%value = ev_value(1:ne)
        ev%direction = ev_dir(1:ne)
        allocate (ev%terminal(ne))
        ev%terminal = .false.
    end if
    eo%max_events = kk
    prog%f => progress

    ! unallocated allocatables passed to optional dummies are absent (Fortran 2008)
    if (neval > 0) te = t_eval(1:neval)
    if (with_events) allocate (evs, source=ev)
    if (use_progress /= 0) allocate (pg, source=prog)
    if (mp == 1) then
        ! one system for all: members differ in y0 (m columns, or one shared)
        if (my0 == m) then
            call ode_ensemble(sys, t_span, y0, opt, res, te, evs, eo, pg)
        else
            call ode_ensemble(sys, t_span, spread(y0(:, 1), 2, m), opt, res, te, evs, eo, pg)
        end if
    else
        members%name = name
        members%params = real(params(1:np, :), dp)
        members%spec = spec(1:max(nspec, 1))
        members%nspec = nspec
        call ode_ensemble(members, t_span, y0, opt, res, te, evs, eo, pg)
    end if

    info = res%status
    call copy_message(res%message, message)
    done = res%done
    if (.not. allocated(res%member_status)) return
    if (size(res%member_status) /= m) return
    t_final = res%t_final
    y_final = res%y_final
    status = res%member_status
    nfev = res%nfev
    naccept = res%naccept
    nreject = res%nreject
    nev = res%nev
    if (neval > 0) y_eval = res%y
    if (with_events) then
        ev_t = res%ev_t
        ev_y = res%ev_y
        ev_id = res%ev_id
    end if
end subroutine flat_ensemble_builtin
