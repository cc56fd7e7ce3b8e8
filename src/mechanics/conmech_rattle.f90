!> RATTLE for mechanical systems with holonomic constraints in excessive coordinates,
!! M q'' = Q(t, q, q') + G(t, q)^T lambda, phi(t, q) = 0: fixed step h, second order,
!! symmetric, and symplectic for a constant mass matrix and forces Q(q) from a potential.
!! This module is the driver of a run: input checks, the grid, outputs, events and
!! diagnostics. The step and its constraint solves: `conmech_rattle_step`; event
!! location on the side step: `conmech_rattle_events`.
!!
!! - Output times: the trajectory runs on the grid t_k = t0 + k h (h = (tf - t0)/N, N =
!!   ceil(|tf - t0|/first_step)); a t_eval point between grid points is reached by one
!!   RATTLE side step of the remaining length from the grid point before it (so every
!!   output is on the constraint manifold to round-off; the trajectory itself is not
!!   altered). Without t_eval every grid point is an output (or only the ends, without
!!   save_steps).
!! - Events (`events`, functions g(t, y) of y = [q; v], `ode_events`): located by Brent's
!!   method on the RATTLE side step from the grid point before the sign change (event
!!   times of the method's second order). Events of one step are reported in time order;
!!   a terminal one ends the run there (status CM_EVENT_STOP), its state the last output
!!   (without t_eval).
!! Multipliers, reactions, residuals, energy and power at the outputs come from the
!! acceleration-level KKT system, as in `constrained_solve`; only holonomic constraints
!! (n_nh = 0).
module conmech_rattle
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_constrained_system, only: constrained_system, constrained_accel, &
        constraint_matrix, constraint_residuals
    use conmech_constrained_solver, only: constrained_options, constrained_result, &
        consistent_initial
    use conmech_ode_system, only: ode_events
    use conmech_rattle_step, only: rattle_state, rattle_work, rattle_work_init, &
        rattle_prepare, rattle_step
    use conmech_rattle_events, only: rattle_event_log, rattle_events_ok, &
        rattle_events_init, rattle_find_events
    implicit none
    private

    public :: rattle_solve

contains

    !> Integrate a holonomic constrained system from (q0, v0) over t_span with RATTLE,
    !! fixed step options%ode%first_step (see the module documentation). Result and
    !! options as `constrained_solve` (projection, rtol, atol are not used; proj_tol and
    !! proj_max_iter control the position solve; max_steps bounds the number of steps).
    subroutine rattle_solve(sys, t_span, q0, v0, options, res, t_eval, events)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: q0(:), v0(:)
        type(constrained_options), intent(in) :: options
        type(constrained_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)
        !> event functions of (t, [q; v]) (see the module documentation)
        class(ode_events), intent(in), optional :: events

        type(rattle_state) :: st(2), side
        type(rattle_work) :: wk
        type(rattle_event_log) :: evl
        integer :: cur, ne, nev
        real(dp) :: tk
        real(dp), allocatable :: tout(:), qout(:, :), vout(:, :), q(:), v(:), acc(:), lam(:)
        real(dp) :: h, t0, tf, posneg
        integer :: n, m, nsteps, k, nout, n_eval, i_eval, info, iters, j
        character(len=:), allocatable :: msg
        character(len=32) :: buf

        n = sys%n
        m = sys%n_hol
        t0 = t_span(1)
        tf = t_span(2)
        n_eval = 0
        if (present(t_eval)) n_eval = size(t_eval)
        ne = 0
        if (present(events)) ne = events%n_events()
        nev = 0
        res%message = "bad input"
        res%status = CM_BAD_INPUT
        if (n < 1 .or. sys%n_hol < 0) then
            res%message = "bad input: the system needs n >= 1 coordinates and n_hol >= 0"
        else if (sys%n_nh /= 0) then
            res%message = "bad input: RATTLE handles holonomic constraints only (n_nh = 0)"
        else if (size(q0) /= n .or. size(v0) /= n) then
            write (buf, '(i0)') n
            res%message = "bad input: q0 and v0 must have n = "//trim(buf)//" elements"
        else if (.not. (all(ieee_is_finite(q0)) .and. all(ieee_is_finite(v0)))) then
            res%message = "bad input: q0 or v0 contains NaN or Inf"
        else if (.not. (ieee_is_finite(t0) .and. ieee_is_finite(tf))) then
            res%message = "bad input: t_span must be finite"
        else if (.not. (options%ode%first_step > 0.0_dp .and. &
                        options%ode%first_step < huge(1.0_dp))) then
            res%message = "bad input: RATTLE is a fixed-step method and needs the step " &
                          //"first_step > 0"
        else if (options%proj_max_iter < 1 .or. .not. options%proj_tol > 0.0_dp) then
            res%message = "bad input: proj_max_iter and proj_tol must be positive"
        else if (.not. rattle_events_ok(events, ne)) then
            res%message = "bad input: the events need direction and terminal arrays of " &
                          //"n_events elements"
        else if (.not. t_eval_ok()) then
            res%message = "bad input: t_eval must lie in t_span, sorted in the direction " &
                          //"of integration"
        else
            res%status = CM_SUCCESS
        end if
        if (res%status /= CM_SUCCESS) then
            call allocate_outputs(0)
            allocate (res%ev_t(0), res%ev_q(max(n, 0), 0), res%ev_v(max(n, 0), 0), &
                      res%ev_id(0))
            return
        end if
        posneg = sign(1.0_dp, tf - t0)
        nsteps = 0
        if (tf /= t0) nsteps = max(1, ceiling(abs(tf - t0)/options%ode%first_step &
                                              *(1.0_dp - 1.0e-12_dp)))
        if (nsteps > options%ode%max_steps) then
            write (buf, '(i0)') nsteps
            call fail(CM_TOO_MANY_STEPS, "too many steps: the run needs "//trim(buf)// &
                      " steps of first_step, more than max_steps")
            return
        end if
        h = 0.0_dp
        if (nsteps > 0) h = (tf - t0)/real(nsteps, dp)

        allocate (q(n), v(n), acc(n), lam(m))
        q = q0
        v = v0
        if (options%project_initial) then
            call consistent_initial(sys, t0, q, v, options%proj_tol, options%proj_max_iter, &
                                    res%dq0, res%dv0, iters, info, msg)
            res%proj_iter = iters
            res%proj_iter_max = iters
            if (info /= CM_SUCCESS) then
                call fail(info, msg)
                return
            end if
        end if
        call constrained_accel(sys, t0, q, v, acc, lam, info, msg, rank=res%rank)
        if (info /= CM_SUCCESS) then
            call fail(info, msg)
            return
        end if
        call rattle_work_init(wk, sys, t0, q, options%proj_tol, options%proj_max_iter, &
                              info, msg)
        if (info /= CM_SUCCESS) then
            call fail(info, msg)
            return
        end if
        cur = 1
        call rattle_prepare(sys, wk, st(1), t0, q, v, info, msg)
        if (info /= CM_SUCCESS) then
            call fail(info, msg)
            return
        end if

        call rattle_events_init(evl, events, ne, n, t0, tf, q, v)

        ! ------------------------------------------------------------ outputs at t0
        allocate (tout(16), qout(n, 16), vout(n, 16))
        nout = 0
        i_eval = 1
        if (n_eval == 0) then
            call push(t0, q, v)
        else
            do while (i_eval <= n_eval)
                if (t_eval(i_eval) /= t0) exit
                call push(t0, q, v)
                i_eval = i_eval + 1
            end do
        end if

        ! ------------------------------------------------------------ the grid
        do k = 1, nsteps
            call rattle_step(sys, wk, st(cur), h, st(3 - cur), info, msg)
            if (info /= CM_SUCCESS) exit
            tk = t0 + k*h
            if (k == nsteps) tk = tf
            st(3 - cur)%t = tk
            if (ne > 0) then
                call rattle_find_events(evl, events, sys, wk, st(cur), st(3 - cur), h, &
                                        posneg, side, info, msg)
                if (info /= CM_SUCCESS) exit
            end if
            ! t_eval points strictly inside (t_{k-1}, t_k) (up to t_stop after a terminal
            ! event): a side step from t_{k-1}
            do while (i_eval <= n_eval)
                if (evl%stopped) then
                    if ((t_eval(i_eval) - evl%t_stop)*posneg > 0.0_dp) exit
                else
                    if ((t_eval(i_eval) - tk)*posneg >= 0.0_dp) exit
                end if
                call rattle_step(sys, wk, st(cur), t_eval(i_eval) - st(cur)%t, side, info, &
                                 msg)
                if (info /= CM_SUCCESS) exit
                call push(t_eval(i_eval), side%q, side%v)
                i_eval = i_eval + 1
            end do
            if (info /= CM_SUCCESS) exit
            res%naccept = res%naccept + 1
            if (evl%stopped) then
                ! the state at the terminal event is the last output without t_eval
                nev = evl%nev
                if (n_eval == 0) call push(evl%t_stop, evl%evq(:, nev), evl%evv(:, nev))
                cur = 3 - cur
                exit
            end if
            cur = 3 - cur
            if (n_eval == 0) then
                if (options%save_steps .or. k == nsteps) &
                    call push(st(cur)%t, st(cur)%q, st(cur)%v)
            else
                ! points on this grid point (at the end: every remaining point, = tf)
                do while (i_eval <= n_eval)
                    if (k < nsteps .and. t_eval(i_eval) /= st(cur)%t) exit
                    call push(t_eval(i_eval), st(cur)%q, st(cur)%v)
                    i_eval = i_eval + 1
                end do
            end if
        end do
        if (info /= CM_SUCCESS) then
            write (buf, '(es14.6)') st(cur)%t
            res%status = info
            res%message = msg//" (RATTLE step from t ="//trim(buf)//")"
        else if (evl%stopped) then
            res%status = CM_EVENT_STOP
            res%message = "a terminal event occurred"
        else
            res%status = CM_SUCCESS
            res%message = "success"
        end if

        ! ------------------------------------------------------------ diagnostics
        call take_counts()
        nev = evl%nev
        res%nev = nev
        res%ev_t = evl%evt(1:nev)
        res%ev_q = evl%evq(:, 1:nev)
        res%ev_v = evl%evv(:, 1:nev)
        res%ev_id = evl%evid(1:nev)
        call allocate_outputs(nout)
        do j = 1, nout
            call store(j)
        end do
        res%success = res%status >= 0

    contains

        logical function t_eval_ok()
            integer :: i
            t_eval_ok = .true.
            if (n_eval == 0) return
            if (.not. all(ieee_is_finite(t_eval))) t_eval_ok = .false.
            do i = 1, n_eval
                if ((t_eval(i) - t0)*(tf - t_eval(i)) < 0.0_dp) t_eval_ok = .false.
                ! max(i - 1, 1): at i = 1 the difference is 0 (nothing to compare)
                if ((t_eval(i) - t_eval(max(i - 1, 1)))*(tf - t0) < 0.0_dp) t_eval_ok = .false.
            end do
        end function t_eval_ok

        subroutine fail(code, text)
            integer, intent(in) :: code
            character(len=*), intent(in) :: text
            res%status = code
            res%message = text
            res%success = .false.
            call take_counts()
            call allocate_outputs(0)
            allocate (res%ev_t(0), res%ev_q(n, 0), res%ev_v(n, 0), res%ev_id(0))
        end subroutine fail

        subroutine allocate_outputs(nt)
            integer, intent(in) :: nt
            res%nt = nt
            allocate (res%t(nt), res%q(n, nt), res%v(n, nt), res%lam(m, nt), &
                      res%reaction(n, nt), res%res_pos(nt), res%res_vel(nt), &
                      res%energy(nt), res%power(nt))
        end subroutine allocate_outputs

        subroutine push(tt, qq, vv)
            real(dp), intent(in) :: tt, qq(:), vv(:)
            real(dp), allocatable :: t2(:), q2(:, :), v2(:, :)
            integer :: cap
            cap = size(tout)
            if (nout >= cap) then
                allocate (t2(2*cap), q2(n, 2*cap), v2(n, 2*cap))
                t2(1:nout) = tout(1:nout)
                q2(:, 1:nout) = qout(:, 1:nout)
                v2(:, 1:nout) = vout(:, 1:nout)
                call move_alloc(t2, tout)
                call move_alloc(q2, qout)
                call move_alloc(v2, vout)
            end if
            nout = nout + 1
            tout(nout) = tt
            qout(:, nout) = qq
            vout(:, nout) = vv
        end subroutine push

        subroutine store(jj)
            integer, intent(in) :: jj
            integer :: inf2
            real(dp) :: c(m, n), c0(m), tt
            character(len=:), allocatable :: m2
            tt = tout(jj)
            res%t(jj) = tt
            res%q(:, jj) = qout(:, jj)
            res%v(:, jj) = vout(:, jj)
            call constrained_accel(sys, tt, qout(:, jj), vout(:, jj), acc, lam, inf2, m2)
            if (inf2 /= CM_SUCCESS .and. res%status >= 0) then
                res%status = inf2
                res%message = m2
            end if
            res%lam(:, jj) = lam
            res%reaction(:, jj) = 0.0_dp
            if (m > 0) then
                call constraint_matrix(sys, tt, qout(:, jj), c, c0)
                res%reaction(:, jj) = matmul(lam, c)
            end if
            call constraint_residuals(sys, tt, qout(:, jj), vout(:, jj), res%res_pos(jj), &
                                      res%res_vel(jj))
            res%energy(jj) = 0.0_dp
            if (sys%has_energy()) res%energy(jj) = sys%energy(tt, qout(:, jj), vout(:, jj))
            res%power(jj) = dot_product(res%reaction(:, jj), vout(:, jj))
        end subroutine store

        !> The counters of the steps (after those of the initial projection).
        subroutine take_counts()
            res%nfev = res%nfev + wk%nfev
            res%nproj = res%nproj + wk%nproj
            res%proj_iter = res%proj_iter + wk%proj_iter
            res%proj_iter_max = max(res%proj_iter_max, wk%proj_iter_max)
        end subroutine take_counts

    end subroutine rattle_solve

end module conmech_rattle
