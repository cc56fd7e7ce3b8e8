!> RATTLE (Andersen 1983; Hairer-Lubich-Wanner, Geometric Numerical Integration, VII.1)
!! for mechanical systems with holonomic constraints in excessive coordinates,
!! M q'' = Q(t, q, q') + G(t, q)^T lambda, phi(t, q) = 0: fixed step h, second order,
!! symmetric, and symplectic for a constant mass matrix and forces Q(q) from a potential.
!!
!! One step from (q_n, v_n):
!!
!!     v_{1/2} = v_n + h/2 M_n^{-1} (Q_n + G_n^T lambda)
!!     q_{n+1} = q_n + h v_{1/2},          phi(t_{n+1}, q_{n+1}) = 0
!!     v_{n+1} = v_{1/2} + h/2 M_{n+1}^{-1} (Q_{n+1} + G_{n+1}^T mu),
!!                                         G_{n+1} v_{n+1} + phi_t(t_{n+1}, q_{n+1}) = 0
!!
!! - Position constraints: simplified Newton in the scaled multiplier (h^2/2) lambda with
!!   the matrix G(q~) M_n^{-1} G_n^T (q~ the unconstrained predictor, so the contraction
!!   factor is O(h^2)), factorised once per step (LAPACK dgetrf), iterated until
!!   max|phi| <= proj_tol or the correction is below the round-off of q.
!! - Velocity constraints: one linear solve with G_{n+1} M_{n+1}^{-1} G_{n+1}^T.
!! - Mass matrix: M(q_n) in the first half kick and the position solve, M(q_{n+1}) in
!!   the second (the standard variant). A `diagonal_mass` system costs a division per
!!   coordinate, a `constant_mass` one is inverted once per run; otherwise M is
!!   factorised (Cholesky) and inverted at every grid point. One constraint (n_hol = 1)
!!   needs no factorisation at all (a scalar division). For a constant mass matrix this is RATTLE
!!   exactly; for a configuration-dependent one the method stays symmetric and of order
!!   2, but is not symplectic.
!! - Velocity-dependent forces: Q_{n+1} = Q(t_{n+1}, q_{n+1}, v_{n+1}) makes the second
!!   kick implicit; it is solved by fixed-point iteration (two force evaluations per step
!!   when Q does not depend on v: the second one confirms the first).
!! - Output times: the trajectory runs on the grid t_k = t0 + k h (h = (tf - t0)/N, N =
!!   ceil(|tf - t0|/first_step)); a t_eval point between grid points is reached by one
!!   RATTLE side step of the remaining length from the grid point before it (so every
!!   output is on the constraint manifold to round-off; the trajectory itself is not
!!   altered). Without t_eval every grid point is an output (or only the ends, without
!!   save_steps).
!! - Events (`events`, functions g(t, y) of y = [q; v], `ode_events`): a sign change of g
!!   between grid points (with the event's direction) is located by Brent's method on the
!!   RATTLE side step of length tau from the grid point before it (a continuous extension
!!   of the step whose states are on the constraint manifold to round-off; its local
!!   error is O(h^3), so event times have the method's second order). Events of one step
!!   are reported in time order; a terminal one ends the run there (status
!!   CM_EVENT_STOP), its state the last output (without t_eval).
!! Multipliers, reactions, residuals, energy and power at the outputs come from the
!! acceleration-level KKT system, as in `constrained_solve`; only holonomic constraints
!! (n_nh = 0).
module conmech_rattle
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_lapack, only: dgetrs
    use conmech_generalized, only: mass_cholesky
    use conmech_constrained_system, only: constrained_system, constrained_accel, &
        constraint_matrix, constraint_residuals
    use conmech_constrained_solver, only: constrained_options, constrained_result, &
        consistent_initial
    use conmech_ode_system, only: ode_events
    use conmech_brent, only: brent_state, brent_init, brent_step, brent_take
    implicit none
    private

    public :: rattle_solve

    integer, parameter :: MASS_GENERAL = 0, MASS_DIAGONAL = 1, MASS_CONSTANT = 2

    interface
        !> Unblocked LU (no block-size query: fast for the small constraint matrices).
        subroutine dgetf2(m, n, a, lda, ipiv, info)
            import :: dp
            integer, intent(in) :: m, n, lda
            real(dp), intent(inout) :: a(lda, *)
            integer, intent(out) :: ipiv(*), info
        end subroutine dgetf2
        !> Inverse from the Cholesky factor (upper triangle).
        subroutine dpotri(uplo, n, a, lda, info)
            import :: dp
            character(len=1), intent(in) :: uplo
            integer, intent(in) :: n, lda
            real(dp), intent(inout) :: a(lda, *)
            integer, intent(out) :: info
        end subroutine dpotri
    end interface

    !> The state at one grid point with what the next step reuses.
    type :: rattle_state
        real(dp) :: t = 0.0_dp
        real(dp), allocatable :: q(:), v(:)
        real(dp), allocatable :: f(:)       !! Q(t, q, v)
        real(dp), allocatable :: mc(:, :)   !! M(t, q)^{-1} (general mass only)
        real(dp), allocatable :: d(:)       !! 1 / diag M(t, q) (diagonal mass only)
        real(dp), allocatable :: x(:, :)    !! M^{-1} G^T (n x n_hol)
        real(dp), allocatable :: g(:, :)    !! G (n_hol x n)
    end type rattle_state

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
        integer :: cur, mkind
        real(dp), allocatable :: minv(:, :)
        ! work arrays of the step (allocated once: gfortran puts automatic arrays on the heap)
        real(dp), allocatable :: afree(:), vhalf(:), ph(:), gt(:, :), dq(:), dqsum(:), w(:)
        real(dp), allocatable :: r(:), vprev(:), pt(:, :), sm(:, :), cv(:)
        integer, allocatable :: ipiv(:)
        ! events: g at the current grid point, the events found, their states
        real(dp), allocatable :: g_old(:), g_new(:), yev(:), gv(:), evt(:), evq(:, :)
        real(dp), allocatable :: evv(:, :)
        integer, allocatable :: evid(:)
        integer :: ne, nev
        logical :: stopped
        real(dp) :: t_stop, tk
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
        else if (.not. events_ok()) then
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
        allocate (afree(n), vhalf(n), ph(m), gt(m, n), dq(n), dqsum(n), w(n), r(m), &
                  vprev(n), pt(m, n), sm(m, m), cv(m), ipiv(m))
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
        mkind = MASS_GENERAL
        if (sys%diagonal_mass) then
            mkind = MASS_DIAGONAL
        else if (sys%constant_mass) then
            ! M^{-1} once, kept for the run
            allocate (minv(n, n))
            call sys%mass(t0, q, minv)
            call mass_cholesky(minv, info, msg)
            if (info /= CM_SUCCESS) then
                call fail(info, msg)
                return
            end if
            call dpotri('U', n, minv, n, info)
            do j = 1, n - 1
                minv(j + 1:n, j) = minv(j, j + 1:n)
            end do
            mkind = MASS_CONSTANT
        end if
        cur = 1
        call prepare(st(1), t0, q, v, info, msg)
        if (info /= CM_SUCCESS) then
            call fail(info, msg)
            return
        end if

        allocate (g_old(ne), g_new(ne), yev(2*n), gv(ne), evt(8), evq(n, 8), evv(n, 8), evid(8))
        if (ne > 0) call events%eval(t0, [q, v], g_old)

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
        stopped = .false.
        t_stop = tf
        do k = 1, nsteps
            call step(st(cur), h, st(3 - cur), info, msg)
            if (info /= CM_SUCCESS) exit
            tk = t0 + k*h
            if (k == nsteps) tk = tf
            st(3 - cur)%t = tk
            if (ne > 0) then
                call find_events(st(cur), st(3 - cur), h, info, msg)
                if (info /= CM_SUCCESS) exit
            end if
            ! t_eval points strictly inside (t_{k-1}, t_k) (up to t_stop after a terminal
            ! event): a side step from t_{k-1}
            do while (i_eval <= n_eval)
                if (stopped) then
                    if ((t_eval(i_eval) - t_stop)*posneg > 0.0_dp) exit
                else
                    if ((t_eval(i_eval) - tk)*posneg >= 0.0_dp) exit
                end if
                call step(st(cur), t_eval(i_eval) - st(cur)%t, side, info, msg)
                if (info /= CM_SUCCESS) exit
                call push(t_eval(i_eval), side%q, side%v)
                i_eval = i_eval + 1
            end do
            if (info /= CM_SUCCESS) exit
            res%naccept = res%naccept + 1
            if (stopped) then
                ! the state at the terminal event is the last output without t_eval
                if (n_eval == 0) call push(t_stop, evq(:, nev), evv(:, nev))
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
        else if (stopped) then
            res%status = CM_EVENT_STOP
            res%message = "a terminal event occurred"
        else
            res%status = CM_SUCCESS
            res%message = "success"
        end if

        ! ------------------------------------------------------------ diagnostics
        res%nev = nev
        res%ev_t = evt(1:nev)
        res%ev_q = evq(:, 1:nev)
        res%ev_v = evv(:, 1:nev)
        res%ev_id = evid(1:nev)
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

        logical function events_ok()
            events_ok = .true.
            if (ne == 0) return
            if (.not. (allocated(events%direction) .and. allocated(events%terminal))) then
                events_ok = .false.
            else
                events_ok = size(events%direction) == ne .and. size(events%terminal) == ne
            end if
        end function events_ok

        !> Sign changes of the event functions between s0 and s1 (a step of length hs),
        !! each root by Brent's method on the side step from s0; events recorded in time
        !! order up to the first terminal one (then stopped, t_stop).
        subroutine find_events(s0, s1, hs, inf, mg)
            type(rattle_state), intent(in) :: s0, s1
            real(dp), intent(in) :: hs
            integer, intent(out) :: inf
            character(len=:), allocatable, intent(out) :: mg
            real(dp) :: times(ne)
            integer :: ids(ne), nf, i, j, jj, it
            logical :: cross, done
            type(brent_state) :: bs
            inf = CM_SUCCESS
            yev(1:n) = s1%q
            yev(n + 1:) = s1%v
            call events%eval(s1%t, yev, g_new)
            nf = 0
            do i = 1, ne
                cross = (g_old(i) < 0.0_dp .and. g_new(i) >= 0.0_dp .and. &
                         events%direction(i) >= 0) .or. &
                        (g_old(i) > 0.0_dp .and. g_new(i) <= 0.0_dp .and. &
                         events%direction(i) <= 0)
                if (.not. cross) cycle
                nf = nf + 1
                ids(nf) = i
                times(nf) = s1%t
                if (g_new(i) == 0.0_dp) cycle
                call brent_init(bs, g_old(i), g_new(i), s0%t, hs)
                do it = 1, 200
                    call brent_step(bs, done)
                    if (done) exit
                    call step(s0, bs%b*hs, side, inf, mg)
                    if (inf /= CM_SUCCESS) return
                    yev(1:n) = side%q
                    yev(n + 1:) = side%v
                    call events%eval(side%t, yev, gv)
                    call brent_take(bs, gv(i))
                end do
                times(nf) = s0%t + bs%b*hs
            end do
            g_old = g_new
            ! time order (insertion sort, few events)
            do i = 2, nf
                j = i
                do while (j > 1)
                    if ((times(j) - times(j - 1))*posneg >= 0.0_dp) exit
                    times(j - 1:j) = [times(j), times(j - 1)]
                    ids(j - 1:j) = [ids(j), ids(j - 1)]
                    j = j - 1
                end do
            end do
            do jj = 1, nf
                if (stopped .and. (times(jj) - t_stop)*posneg > 0.0_dp) exit
                if (times(jj) == s1%t) then
                    call push_event(times(jj), s1%q, s1%v, ids(jj))
                else
                    call step(s0, times(jj) - s0%t, side, inf, mg)
                    if (inf /= CM_SUCCESS) return
                    call push_event(times(jj), side%q, side%v, ids(jj))
                end if
                if (events%terminal(ids(jj)) .and. .not. stopped) then
                    stopped = .true.
                    t_stop = times(jj)
                end if
            end do
        end subroutine find_events

        subroutine push_event(tt, qq, vv, id)
            real(dp), intent(in) :: tt, qq(:), vv(:)
            integer, intent(in) :: id
            real(dp), allocatable :: t2(:), q2(:, :), v2(:, :)
            integer, allocatable :: i2(:)
            integer :: cap
            cap = size(evt)
            if (nev >= cap) then
                allocate (t2(2*cap), q2(n, 2*cap), v2(n, 2*cap), i2(2*cap))
                t2(1:nev) = evt(1:nev)
                q2(:, 1:nev) = evq(:, 1:nev)
                v2(:, 1:nev) = evv(:, 1:nev)
                i2(1:nev) = evid(1:nev)
                call move_alloc(t2, evt)
                call move_alloc(q2, evq)
                call move_alloc(v2, evv)
                call move_alloc(i2, evid)
            end if
            nev = nev + 1
            evt(nev) = tt
            evq(:, nev) = qq
            evv(:, nev) = vv
            evid(nev) = id
        end subroutine push_event

        subroutine allocate_state(st)
            type(rattle_state), intent(inout) :: st
            allocate (st%q(n), st%v(n), st%f(n), st%x(n, m), st%g(m, n))
            if (mkind == MASS_GENERAL) allocate (st%mc(n, n))
            if (mkind == MASS_DIAGONAL) allocate (st%d(n))
        end subroutine allocate_state

        !> Fill a state at (tt, qq, vv): forces, Cholesky of M, G and M^{-1} G^T.
        subroutine prepare(st, tt, qq, vv, inf, mg)
            type(rattle_state), intent(inout) :: st
            real(dp), intent(in) :: tt, qq(:), vv(:)
            integer, intent(out) :: inf
            character(len=:), allocatable, intent(out) :: mg
            if (.not. allocated(st%f)) call allocate_state(st)
            st%t = tt
            st%q = qq
            st%v = vv
            call sys%forces(tt, qq, vv, st%f)
            res%nfev = res%nfev + 1
            call factor_mass(st, inf, mg)
        end subroutine prepare

        !> M^{-1} (or 1/diag M) and M^{-1} G^T at st%t, st%q.
        subroutine factor_mass(st, inf, mg)
            type(rattle_state), intent(inout) :: st
            integer, intent(out) :: inf
            character(len=:), allocatable, intent(out) :: mg
            integer :: lainfo, jj
            inf = CM_SUCCESS
            select case (mkind)
            case (MASS_DIAGONAL)
                call sys%mass_diagonal(st%t, st%q, st%d)
                if (.not. all(st%d > 0.0_dp .and. st%d < huge(1.0_dp))) then
                    inf = CM_SINGULAR
                    mg = "the diagonal mass matrix has a non-positive or non-finite entry"
                    return
                end if
                st%d = 1.0_dp/st%d
            case (MASS_GENERAL)
                call sys%mass(st%t, st%q, st%mc)
                call mass_cholesky(st%mc, inf, mg)
                if (inf /= CM_SUCCESS) return
                ! the explicit inverse (small matrices: one LAPACK call per step instead
                ! of a triangular solve per right-hand side)
                call dpotri('U', n, st%mc, n, lainfo)
                do jj = 1, n - 1
                    st%mc(jj + 1:n, jj) = st%mc(jj, jj + 1:n)
                end do
            end select
            if (m > 0) then
                call sys%phi_jac(st%t, st%q, st%g)
                select case (mkind)
                case (MASS_DIAGONAL)
                    do jj = 1, m
                        st%x(:, jj) = st%d*st%g(jj, :)
                    end do
                case (MASS_CONSTANT)
                    st%x = matmul(minv, transpose(st%g))
                case default
                    st%x = matmul(st%mc, transpose(st%g))
                end select
            end if
        end subroutine factor_mass

        !> M(st)^{-1} f.
        subroutine minv_times(st, f, y)
            type(rattle_state), intent(in) :: st
            real(dp), intent(in) :: f(:)
            real(dp), intent(out) :: y(:)
            select case (mkind)
            case (MASS_DIAGONAL)
                y = st%d*f
            case (MASS_CONSTANT)
                y = matmul(minv, f)
            case default
                y = matmul(st%mc, f)
            end select
        end subroutine minv_times

        !> pt = S^{-T} X^T (m x n) for S = gg X (m x m, LU by dgetf2; one constraint: a
        !! division). inf = CM_SINGULAR when S is singular.
        subroutine schur_rows(gg, xx, pt, inf)
            real(dp), intent(in) :: gg(:, :), xx(:, :)
            real(dp), intent(out) :: pt(:, :)
            integer, intent(out) :: inf
            real(dp) :: s1
            integer :: lainfo, i2, j2
            inf = CM_SUCCESS
            if (m == 1) then
                s1 = dot_product(gg(1, :), xx(:, 1))
                if (.not. (abs(s1) > 0.0_dp .and. abs(s1) < huge(1.0_dp))) then
                    inf = CM_SINGULAR
                    return
                end if
                pt(1, :) = xx(:, 1)/s1
                return
            end if
            ! (loops: the library matmul costs more than the product of tiny matrices)
            do j2 = 1, m
                do i2 = 1, m
                    sm(i2, j2) = dot_product(gg(i2, :), xx(:, j2))
                end do
            end do
            call dgetf2(m, m, sm, m, ipiv, lainfo)
            if (lainfo /= 0) then
                inf = CM_SINGULAR
                return
            end if
            pt = transpose(xx)
            call dgetrs('T', m, n, sm, m, ipiv, pt, m, lainfo)
        end subroutine schur_rows

        !> One RATTLE step of length hs from st to s2 (s2 prepared for the next step).
        subroutine step(st, hs, s2, inf, mg)
            type(rattle_state), intent(in) :: st
            real(dp), intent(in) :: hs
            type(rattle_state), intent(inout) :: s2
            integer, intent(out) :: inf
            character(len=:), allocatable, intent(out) :: mg
            real(dp) :: t1, rnorm
            integer :: it, kk, i
            character(len=32) :: b2
            t1 = st%t + hs
            if (.not. allocated(s2%f)) call allocate_state(s2)
            ! first half kick without the constraint force, unconstrained predictor
            call minv_times(st, st%f, afree)
            s2%q = st%q + hs*st%v + (0.5_dp*hs*hs)*afree
            dqsum = 0.0_dp
            if (m > 0) then
                call sys%phi_jac(t1, s2%q, gt)
                ! pk = X S^{-1} (n x m) from S^T pk^T = X^T, S = G(q~) X
                call schur_rows(gt, st%x, pt, inf)
                if (inf /= CM_SUCCESS) then
                    mg = "singular constraint matrix G M^-1 G^T in the position solve " &
                         //"(redundant constraints?)"
                    return
                end if
                inf = CM_NO_CONVERGENCE
                do it = 1, options%proj_max_iter + 1
                    call sys%phi(t1, s2%q, ph)
                    rnorm = maxval(abs(ph))
                    if (.not. rnorm < huge(1.0_dp)) exit
                    if (rnorm <= options%proj_tol) then
                        inf = CM_SUCCESS
                        exit
                    end if
                    if (it > options%proj_max_iter) exit
                    dq = 0.0_dp
                    do i = 1, m
                        dq = dq + ph(i)*pt(i, :)
                    end do
                    dqsum = dqsum + dq
                    s2%q = s2%q - dq
                    if (maxval(abs(dq)) <= 4.0_dp*epsilon(1.0_dp)*maxval(abs(s2%q))) then
                        inf = CM_SUCCESS
                        exit
                    end if
                end do
                res%proj_iter = res%proj_iter + it
                res%proj_iter_max = max(res%proj_iter_max, it)
                res%nproj = res%nproj + 1
                if (inf /= CM_SUCCESS) then
                    write (b2, '(es10.3)') rnorm
                    mg = "position constraints not solved: |phi| ="//trim(b2)// &
                         " after proj_max_iter simplified Newton iterations"
                    return
                end if
            end if
            ! v_{1/2} = (q_{n+1} - q_n)/h without the cancellation
            vhalf = st%v + (0.5_dp*hs)*afree - dqsum/hs
            ! second half kick at q_{n+1}, velocity constraints
            s2%t = t1
            call factor_mass(s2, inf, mg)
            if (inf /= CM_SUCCESS) return
            if (m > 0) then
                call schur_rows(s2%g, s2%x, pt, inf)
                if (inf /= CM_SUCCESS) then
                    mg = "singular constraint matrix G M^-1 G^T in the velocity solve"
                    return
                end if
            end if
            r = 0.0_dp
            if (m > 0) call sys%phi_t(t1, s2%q, r)
            s2%v = 2.0_dp*vhalf - st%v
            inf = CM_NO_CONVERGENCE
            do kk = 1, 50
                call sys%forces(t1, s2%q, s2%v, s2%f)
                res%nfev = res%nfev + 1
                if (.not. all(ieee_is_finite(s2%f))) exit
                call minv_times(s2, s2%f, w)
                w = vhalf + (0.5_dp*hs)*w
                ! w - (G w + phi_t) S^{-1} G M^{-1} (all rows from the same w)
                do i = 1, m
                    cv(i) = dot_product(s2%g(i, :), w) + r(i)
                end do
                do i = 1, m
                    w = w - cv(i)*pt(i, :)
                end do
                vprev = s2%v
                s2%v = w
                if (kk > 1 .and. maxval(abs(s2%v - vprev)) <= 4.0_dp*epsilon(1.0_dp)* &
                    max(maxval(abs(s2%v)), tiny(1.0_dp))) then
                    ! converged: Q(t1, q1, v1) equals s2%f to round-off
                    inf = CM_SUCCESS
                    exit
                end if
            end do
            if (inf /= CM_SUCCESS) then
                mg = "the velocity-dependent forces of the second half kick did not " &
                     //"converge (or are not finite)"
            end if
        end subroutine step

    end subroutine rattle_solve

end module conmech_rattle
