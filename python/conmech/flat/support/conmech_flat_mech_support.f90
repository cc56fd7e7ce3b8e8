!> Support of the flat f2py layer for constrained mechanical systems (compiled into the
!! extension, not wrapped: it holds derived types).
!!
!! `callback_constrained` (conmech_flat_adapters, re-exported) adapts f2py callbacks into
!! Python to `constrained_system`; `run_constrained` runs `constrained_solve` from plain arguments
!! and hands the whole result to a `store` procedure. Calling conventions (by reference):
!!
!!     mass(t, q, mm, n)            real(c_double) t, q(n), mm(n, n)
!!     forces(t, q, v, f, n)        real(c_double) t, q(n), v(n), f(n)
!!     phi(t, q, c, n, mh)          c(mh): holonomic constraints
!!     jac(t, q, g, n, mh)          g(mh, n): d phi / d q       (if has_jac, else FD)
!!     gamma(t, q, v, gam, n, mh)   G q'' = gam                 (if has_gamma, else FD)
!!     nh(t, q, a, b, n, mn)        a(mn, n), b(mn): A q' + b = 0
!!     nhgamma(t, q, v, gam, n, mn) A q'' = gam                 (if has_nh_gamma, else FD)
!!     store(t, q, v, acc, lam, reac, cm, rp, rv, en, pw, n, mm, nt)  the result, once, at
!!         the end (acc (n, nt) the accelerations; lam is (mm, nt), mm = max(n_hol + n_nh,
!!         1); cm (mm, n, nt) the constraint matrix C = [G; A] at every output, from which
!!         the caller forms the generalized force C_i^T lam_i of each constraint; zero rows
!!         when there is no constraint)
module conmech_flat_mech_support
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_constrained_system
    use conmech_constrained_solver
    use conmech_ode_system, only: ode_events
    use conmech_flat_ode_support, only: copy_message
    use conmech_flat_adapters, only: callback_constrained, callback_events
    implicit none
    private
    public :: callback_constrained, run_constrained

contains

    !> Run `constrained_solve` from plain arguments; the result goes to `store`.
    !! first_step 0: automatic; neval 0: output at every accepted step. iopt(1:5) =
    !! [projection, every, proj_max_iter, max_steps, dae_index]; ropt(1:5) = [first_step, max_step,
    !! alpha, beta, proj_tol]. stats(1:7) = [nfev, naccept, nreject, nproj, proj_iter, rank,
    !! proj_iter_max];
    !! moved(1:2) = [dq0, dv0]. Optional events (every method): ne functions of
    !! (t, [q; v]) by events(t, y, g, 2n, ne), ev_dir (+1, -1, 0), ev_term (/= 0:
    !! terminal); the events found go to evstore(ev_t, ev_q, ev_v, ev_id, n, nev).
    subroutine run_constrained(sys, n, t_span, q0, v0, method, rtol, atol, iopt, ropt, &
                               neval, t_eval, store, stats, moved, info, message, ne, &
                               ev_dir, ev_term, events, evstore)
        class(constrained_system), intent(in) :: sys
        include "../flat_constrained_args.inc"
        external :: store
        character(len=*), intent(out) :: message
        integer(c_int), intent(in), optional :: ne
        integer(c_int), intent(in), optional :: ev_dir(:), ev_term(:)
        external :: events, evstore
        optional :: events, evstore
        type(constrained_options) :: opt
        type(callback_events), allocatable :: ev
        real(dp), allocatable :: te(:)
        integer(c_int) :: nev_fun
        type(constrained_result) :: r
        real(dp), allocatable :: lam(:, :), cm(:, :, :)
        real(dp), allocatable :: c0(:)
        integer(c_int) :: m, mm, nt, nn, j

        stats = 0
        moved = 0.0_dp
        if (sys%n /= n) then
            info = CM_BAD_INPUT
            call copy_message("bad input: q0 and v0 must have the system's n elements", message)
            return
        end if
        opt%ode%method = method
        opt%ode%rtol = rtol
        opt%ode%atol = atol
        opt%ode%first_step = ropt(1)
        opt%ode%max_step = ropt(2)
        opt%ode%max_steps = iopt(4)
        opt%projection = iopt(1)
        opt%every = iopt(2)
        opt%proj_max_iter = iopt(3)
        opt%dae_index = iopt(5)
        opt%alpha = ropt(3)
        opt%beta = ropt(4)
        opt%proj_tol = ropt(5)
        nev_fun = 0
        if (present(ne)) nev_fun = ne
        if (nev_fun > 0) then
            allocate (ev)
            ev%g => events
            ev%n = 2*n
            ev%ne = nev_fun
            ev%direction = ev_dir(1:nev_fun)
            ev%terminal = ev_term(1:nev_fun) /= 0
        end if
        if (neval > 0) te = t_eval(1:neval)
        ! the optional arguments once: an unallocated actual argument is an absent one
        call constrained_solve(sys, t_span, q0, v0, opt, r, te, events=ev)
        info = r%status
        call copy_message(r%message, message)
        stats = [r%nfev, r%naccept, r%nreject, r%nproj, r%proj_iter, r%rank, r%proj_iter_max]
        moved = [r%dq0, r%dv0]
        m = sys%n_hol + sys%n_nh
        mm = max(m, 1)
        nt = r%nt
        nn = n
        allocate (lam(mm, max(nt, 1)))
        lam = 0.0_dp
        if (m > 0 .and. nt > 0) lam(1:m, 1:nt) = r%lam
        allocate (cm(mm, n, max(nt, 1)), c0(mm))
        cm = 0.0_dp
        if (m > 0) then
            do j = 1, nt
                call constraint_matrix(sys, r%t(j), r%q(:, j), cm(1:m, :, j), c0(1:m))
            end do
        end if
        if (nt > 0) call store(r%t, r%q, r%v, r%acc, lam, r%reaction, cm, r%res_pos, &
                               r%res_vel, r%energy, r%power, nn, mm, nt)
        if (nev_fun > 0 .and. r%nev > 0) call evstore(r%ev_t, r%ev_q, r%ev_v, r%ev_id, nn, &
                                                      int(r%nev, c_int))
    end subroutine run_constrained

end module conmech_flat_mech_support
