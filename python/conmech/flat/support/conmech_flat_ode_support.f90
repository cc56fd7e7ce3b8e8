!> Support of the flat f2py layer for the integrators (compiled into the extension, not
!! wrapped by f2py: it holds derived types).
!!
!! `callback_system` and `callback_events` (from conmech_flat_adapters, re-exported) adapt
!! f2py callbacks into Python to conmech's `ode_system` and `ode_events`; `run_solve` runs
!! `ode_solve` from plain arguments and hands the whole result to a `store` procedure,
!! so that output sizes need not be known in advance and nothing is saved between calls
!! (thread-safe).
!!
!! Calling conventions of the external procedures (all arguments by reference):
!!
!!     fun(t, y, dydt, n)                real(c_double) t, y(n), dydt(n); integer(c_int) n
!!     events(t, y, g, n, ne)            real(c_double) t, y(n), g(ne); integer(c_int) n, ne
!!     store(t, y, ev_t, ev_y, ev_id, ts, hs, coef, n, nt, nev, nseg, nf1)
!!         real(c_double) t(nt), y(n,nt), ev_t(nev), ev_y(n,nev), ts(nseg), hs(nseg),
!!         coef(n,nf1,nseg); integer(c_int) ev_id(nev), n, nt, nev, nseg, nf1
module conmech_flat_ode_support
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system, ode_events
    use conmech_ode_solver, only: ode_options, ode_result, ode_solve, METHOD_DOPRI5, &
        ode_stepper
    use conmech_ode_methods, only: new_stepper
    use conmech_radau_stepper, only: radau_stepper
    use conmech_flat_adapters, only: callback_system, callback_jac_system, &
                                      callback_events
    implicit none
    private
    public :: callback_system, callback_jac_system, callback_events, run_solve, copy_message
    public :: solve_into, store_result, set_flat_options
    public :: scipy_first_step, set_jacobian_structure

    !> Method code of the flat layer for SciPy's RK45: DOPRI5 with SciPy's step control
    !! (no Lund stabilisation) and SciPy's initial step (select_initial_step).
    integer(c_int), parameter, public :: METHOD_RK45_SCIPY = 12

contains

    !> Copy a message into a fixed-length output (truncated, blank padded).
    subroutine copy_message(src, dst)
        character(len=*), intent(in) :: src
        character(len=*), intent(out) :: dst
        dst = src
    end subroutine copy_message

    !> The integration options every flat integrator routine takes from its plain arguments:
    !! the method code, the tolerances per component, the first and largest step (0: none),
    !! the step limit and dense output (dense /= 0), written into opt in place (no copy of
    !! the tolerance vectors, as the assignment of a function's result makes). SciPy's RK45
    !! code is left to the caller.
    subroutine set_flat_options(opt, method, rtol, atol, first_step, max_step, max_steps, &
                                dense)
        type(ode_options), intent(out) :: opt
        integer(c_int), intent(in) :: method, max_steps, dense
        real(c_double), intent(in) :: rtol(:), atol(:), first_step, max_step
        opt%method = method
        opt%rtol_vec = rtol
        opt%atol_vec = atol
        opt%first_step = first_step
        opt%max_step = max_step
        opt%max_steps = max_steps
        opt%dense_output = dense /= 0
    end subroutine set_flat_options

    !> What the caller knows of df/dy, on a fresh stepper of a method that uses it (Radau):
    !! constant (jac_const /= 0: read once, never re-evaluated, not counted in njev), and
    !! the sparsity pattern (nnz >= 0: column pointers sp_ptr(1:n + 1), rows sp_idx(1:nnz),
    !! 1-based) for differences by groups of columns. Other methods ignore both.
    subroutine set_jacobian_structure(s, n, jac_const, nnz, sp_ptr, sp_idx, info, msg)
        class(ode_stepper), intent(inout) :: s
        integer(c_int), intent(in) :: n, jac_const, nnz, sp_ptr(:), sp_idx(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(inout) :: msg
        info = CM_SUCCESS
        select type (s)
        type is (radau_stepper)
            s%jstruct%constant = jac_const /= 0
            if (nnz >= 0) then
                if (size(sp_ptr) < n + 1 .or. size(sp_idx) < nnz) then
                    info = CM_BAD_INPUT
                    msg = "bad input: jac_sparsity: arrays too short"
                    return
                end if
                call s%jstruct%set_pattern(n, sp_ptr(1:n + 1), sp_idx(1:nnz), info, msg)
            end if
        end select
    end subroutine set_jacobian_structure

    !> Solve with `ode_solve` (any method of the table) from plain arguments and pass the
    !! result to `store`; counts = [nfev, njev, nlu, naccept, nreject].
    !! Tolerances are per component; first_step 0 means automatic; ne = 0: no events;
    !! neval = 0: output at every step. `events` is not called when ne = 0. The arrays
    !! t_eval, ev_dir, ev_term, ev_res have at least one element (f2py cannot pass empty
    !! ones). ev_term: an event's terminal count (> 0: the run stops at that occurrence;
    !! 0: not terminal). ev_res: each event's resolution (0: SciPy's rule, the step's ends
    !! only). jac_const, nnz, sp_ptr, sp_idx: `set_jacobian_structure`. zero_at_t0
    !! (default .false.): SciPy's rule for an event zero at t0 (ode_events%zero_at_t0).
    !! dense_form: the polynomial form of the dense coefficients (dense_solution%form of
    !! conmech_ode_solver: 1 Hairer's, 2 power basis; 0 without dense output).
    subroutine run_solve(sys, n, t_span, y0, method, rtol, atol, first_step, max_step, &
                         max_steps, dense, neval, t_eval, ne, ev_dir, ev_term, ev_res, &
                         jac_const, nnz, sp_ptr, sp_idx, events, store, counts, dense_form, &
                         info, message, zero_at_t0)
        class(ode_system), intent(in) :: sys
        include "../flat_solve_args.inc"
        integer(c_int), intent(in) :: jac_const, nnz, sp_ptr(:), sp_idx(:)
        external :: events, store
        integer(c_int), intent(out) :: counts(5), dense_form, info
        character(len=*), intent(out) :: message
        logical, intent(in), optional :: zero_at_t0
        type(ode_result) :: res

        dense_form = 0
        call solve_into(sys, n, t_span, y0, method, rtol, atol, first_step, max_step, &
                        max_steps, dense, neval, t_eval, ne, ev_dir, ev_term, ev_res, &
                        jac_const, nnz, sp_ptr, sp_idx, res, counts, info, message, events, &
                        zero_at_t0)
        if (.not. allocated(res%t)) return          ! refused before any integration
        call store_result(res, n, dense /= 0, store, dense_form)
    end subroutine run_solve

    !> The integration of `run_solve` without the transfer of its outputs: `ode_solve` from
    !! plain arguments (arguments as there) into res; counts = [nfev, njev, nlu, naccept,
    !! nreject]; info and message the run's status (res%t unallocated when the arguments
    !! were refused before the run). `events` may be absent when ne = 0.
    subroutine solve_into(sys, n, t_span, y0, method, rtol, atol, first_step, max_step, &
                          max_steps, dense, neval, t_eval, ne, ev_dir, ev_term, ev_res, &
                          jac_const, nnz, sp_ptr, sp_idx, res, counts, info, message, events, &
                          zero_at_t0)
        class(ode_system), intent(in) :: sys
        include "../flat_solve_args.inc"
        integer(c_int), intent(in) :: jac_const, nnz, sp_ptr(:), sp_idx(:)
        type(ode_result), intent(out) :: res
        integer(c_int), intent(out) :: counts(5), info
        character(len=*), intent(out) :: message
        external :: events
        optional :: events
        logical, intent(in), optional :: zero_at_t0

        type(ode_options) :: opt
        type(callback_events), allocatable :: ev
        real(dp), allocatable :: te(:)
        class(ode_stepper), allocatable :: stp
        character(len=:), allocatable :: msg
        integer :: sinfo
        integer(c_int) :: nfev

        nfev = 0
        counts = 0
        if (n < 1 .or. neval < 0 .or. ne < 0 .or. (ne > 0 .and. .not. present(events))) then
            info = CM_BAD_INPUT
            call copy_message("bad input: array sizes must be positive", message)
            return
        end if
        call set_flat_options(opt, method, rtol, atol, first_step, max_step, max_steps, dense)
        ! both callers read the points up to res%nt: no final copy to cut the arrays
        opt%trim_outputs = .false.
        if (method == METHOD_RK45_SCIPY) then
            opt%method = METHOD_DOPRI5
            opt%beta = 0.0_dp
            opt%stretch = 0.0_dp
        end if
        call new_stepper(opt%method, stp, sinfo, msg)
        if (sinfo == CM_SUCCESS) call set_jacobian_structure(stp, n, jac_const, nnz, sp_ptr, &
                                                             sp_idx, sinfo, msg)
        if (sinfo /= CM_SUCCESS) then
            info = sinfo
            call copy_message(msg, message)
            return
        end if
        if (method == METHOD_RK45_SCIPY .and. .not. first_step > 0.0_c_double) then
            call scipy_first_step(sys, t_span, y0, max(rtol, 100.0_dp*epsilon(1.0_dp)), &
                                  atol, max_step, 4, opt%first_step, nfev)
        end if
        if (ne > 0) then
            allocate (ev)
            ev%g => events
            ev%n = n
            ev%ne = ne
            ev%direction = ev_dir(1:ne)
            ev%terminal = ev_term(1:ne) > 0
            ev%count = max(ev_term(1:ne), 1)
            ev%resolution = ev_res(1:ne)
            if (present(zero_at_t0)) ev%zero_at_t0 = zero_at_t0
        end if
        if (neval > 0) te = t_eval(1:neval)
        ! the optional arguments once: an unallocated actual argument is an absent one
        call ode_solve(sys, t_span, y0, opt, res, t_eval=te, events=ev, stepper=stp)

        counts = [nfev + res%stats%nfev, res%stats%njev, res%stats%nlu, res%stats%naccept, &
                  res%stats%nreject]
        info = res%status
        call copy_message(res%message, message)
    end subroutine solve_into

    !> Hand the whole result of a run to `store` (conventions of `run_solve`); dense_form
    !! as there.
    subroutine store_result(res, n, dense, store, dense_form)
        type(ode_result), intent(in) :: res
        integer(c_int), intent(in) :: n
        logical, intent(in) :: dense
        external :: store
        integer(c_int), intent(out) :: dense_form
        real(c_double) :: empty1(0), empty3(n, 1, 0)
        integer :: nseg, nf1
        nseg = 0
        nf1 = 1
        dense_form = 0
        if (dense .and. allocated(res%sol%ts)) then
            nseg = res%sol%nseg
            nf1 = res%sol%nf + 1
            dense_form = res%sol%form
        end if
        if (nseg > 0) then
            call store(res%t(1:res%nt), res%y(:, 1:res%nt), res%ev_t(1:res%nev), &
                       res%ev_y(:, 1:res%nev), res%ev_id(1:res%nev), res%sol%ts(1:nseg), &
                       res%sol%hs(1:nseg), res%sol%coef(:, :, 1:nseg), &
                       n, res%nt, res%nev, nseg, nf1)
        else
            call store(res%t(1:res%nt), res%y(:, 1:res%nt), res%ev_t(1:res%nev), &
                       res%ev_y(:, 1:res%nev), res%ev_id(1:res%nev), empty1, empty1, &
                       empty3, n, res%nt, res%nev, 0, 1)
        end if
    end subroutine store_result

    !> SciPy's initial step (scipy.integrate._ivp.common.select_initial_step, Hairer's
    !! heuristic with RMS norms): two right-hand side evaluations, counted in nfev.
    subroutine scipy_first_step(sys, t_span, y0, rtol, atol, max_step, err_order, h, nfev)
        class(ode_system), intent(in) :: sys
        real(c_double), intent(in) :: t_span(2), y0(:), rtol(:), atol(:), max_step
        integer, intent(in) :: err_order
        real(dp), intent(out) :: h
        integer(c_int), intent(inout) :: nfev
        real(dp) :: f0(size(y0)), f1(size(y0)), y1(size(y0)), sc(size(y0))
        real(dp) :: d0, d1, d2, h0, h1, span, dir
        integer :: n
        n = size(y0)
        h = 0.0_dp
        span = abs(t_span(2) - t_span(1))
        if (span == 0.0_dp) return
        dir = sign(1.0_dp, t_span(2) - t_span(1))
        call sys%rhs(t_span(1), y0, f0)
        nfev = nfev + 1
        sc = atol + abs(y0)*rtol
        d0 = sqrt(sum((y0/sc)**2)/n)
        d1 = sqrt(sum((f0/sc)**2)/n)
        if (.not. (d0 == d0 .and. d1 == d1)) return    ! non-finite: the solver reports it
        if (d0 < 1.0e-5_dp .or. d1 < 1.0e-5_dp) then
            h0 = 1.0e-6_dp
        else
            h0 = 0.01_dp*d0/d1
        end if
        h0 = min(h0, span)
        y1 = y0 + h0*dir*f0
        call sys%rhs(t_span(1) + h0*dir, y1, f1)
        nfev = nfev + 1
        d2 = sqrt(sum(((f1 - f0)/sc)**2)/n)/h0
        if (.not. (d2 == d2)) return
        if (d1 <= 1.0e-15_dp .and. d2 <= 1.0e-15_dp) then
            h1 = max(1.0e-6_dp, h0*1.0e-3_dp)
        else
            h1 = (0.01_dp/max(d1, d2))**(1.0_dp/real(err_order + 1, dp))
        end if
        h = min(100.0_dp*h0, h1, span, max_step)
        if (.not. (h > 0.0_dp .and. h <= span)) h = 0.0_dp
    end subroutine scipy_first_step

end module conmech_flat_ode_support
