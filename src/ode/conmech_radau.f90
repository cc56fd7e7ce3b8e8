!> Radau IIA of order 5 (three stages) for stiff systems y' = f(t, y): Hairer & Wanner's
!! RADAU5 (Solving ODEs II, section IV.8), written anew on conmech's interfaces.
!!
!! - Simplified Newton iteration on the transformed stage system: with the eigenvalues
!!   gamma and alpha +- i beta of the inverse Radau matrix, one real LU of
!!   (gamma/h I - J) and one complex LU of ((alpha + i beta)/h I - J), both of size n
!!   (LAPACK dgetrf/zgetrf). Convergence control by the contraction rate theta as
!!   RADAU5: at most 7 iterations, stop when theta/(1 - theta) |dW| <= fnewt, a step
!!   reduction when the predicted error after the remaining iterations is too large.
!! - Error estimate (I - h gamma0 J)^{-1}(f0 + (e1 z1 + e2 z2 + e3 z3)/h), refined by one
!!   more solve after a rejection or at the first step, as RADAU5.
!! - Step size: h_new = h / max(1/8, min(5, err^(1/4)/fac)), fac = min(0.9, 0.9 (2 nit
!!   + 1)/(newt + 2 nit)), then the predictive controller of Gustafsson. The Jacobian is
!!   re-evaluated after an accepted step only when the Newton iteration was slow (more
!!   than two iterations and theta > 0.001; RADAU5 uses theta alone, SciPy this rule),
!!   and after a Newton failure if it is not current; a step rejected by the error test
!!   keeps it (SciPy; RADAU5 refreshes it there);
!!   otherwise the step and the LU are kept when the proposed ratio is below 1.2 (SciPy's
!!   window; RADAU5's default is [1, 1.2]). With these two choices the counts of steps,
!!   Jacobians and LUs are within a few per cent of SciPy's Radau (bench/bench_radau.py).
!! - Tolerances are used as given (SciPy's convention; RADAU5 itself transforms rtol to
!!   0.1 rtol^(2/3)): error norm sqrt(mean((err_i/sk_i)^2)), sk_i = atol_i + rtol_i |y_i|
!!   at the start of the step; Newton tolerance fnewt = max(10 eps/rtol, min(0.03,
!!   rtol^(1/2))) as SciPy and RADAU5.
!! - Initial step: the heuristic of SciPy's select_initial_step for an error estimator of
!!   order 3, unless first_step is given.
!! - Jacobian: the system's analytic `jacobian` if `has_jacobian()`, else forward
!!   differences with Hairer's steps sqrt(eps max(1e-5, |y_j|)) (n evaluations, counted in
!!   nfev).
!! - Dense output and events on the collocation polynomial (degree 3, power basis).
!! - Failures: a Newton iteration that does not converge (or meets non-finite values)
!!   halves the step; 0.1 |h| <= eps |t| ends the run (CM_STEP_TOO_SMALL, with the time);
!!   a singular iteration matrix halves the step, five singular ones in a row end the run
!!   (CM_SINGULAR).
!! - Mass-matrix form M y' = f(t, y) with a constant, possibly singular M (differential-
!!   algebraic systems of index 1 and 2, RADAU5's IMAS = 1): optional arguments `mass`
!!   and `index2` (index-2 components get their error scaled by h, as RADAU5's NIND2);
!!   the initial step is then 1e-6 unless given. The constrained layer uses it through
!!   conmech_rattle_dae (the stabilised index-2 formulation).
!! Counters: nfev, njev, nlu (each LU counts once: two per factorisation, as SciPy counts).
module conmech_radau
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_is_nan
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_lapack, only: dgetrf, dgetrs
    use conmech_ode_system, only: ode_system, ode_events
    use conmech_ode_solver, only: ode_options, ode_result
    use conmech_radau_common
    implicit none
    private

    public :: radau_solve
    public :: RADAU_NR, RADAU_NI, RADAU_NW

    !> Sizes of the packed state of a step-by-step integration (radau_solve with r_state,
    !! i_state, w_state and action; conmech_radau_stepper): r(RADAU_NR) reals,
    !! iv(RADAU_NI + 2 n) integers (the last 2 n: LU pivots), w(n, RADAU_NW + 4 n) columns
    !! (y, f(t, y), scale, rtol, atol, the collocation polynomial of the last step
    !! fc(:, 0:3) in x = (s - t_old)/h_old, then J, the real LU, the complex LU's real and
    !! imaginary parts).
    integer, parameter :: RADAU_NR = 20, RADAU_NI = 20, RADAU_NW = 9
    !> Positions in the packed state read by the callers (r: t, t_old, h_old; w: y, fc).
    integer, parameter, public :: RADAU_RT = 3, RADAU_RTOLD = 18, RADAU_RHOLD = 13
    integer, parameter, public :: RADAU_WY = 1, RADAU_WFC = 6
    !> Positions of the counters in iv: nfev, njev, nlu, naccept, nreject.
    integer, parameter, public :: RADAU_IFEV = 5


    interface
        subroutine zgetrf(m, n, a, lda, ipiv, info)
            import :: dp
            integer, intent(in) :: m, n, lda
            complex(dp), intent(inout) :: a(lda, *)
            integer, intent(out) :: ipiv(*), info
        end subroutine zgetrf
        subroutine zgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
            import :: dp
            character(len=1), intent(in) :: trans
            integer, intent(in) :: n, nrhs, lda, ldb
            complex(dp), intent(in) :: a(lda, *)
            integer, intent(in) :: ipiv(*)
            complex(dp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine zgetrs
    end interface

    real(dp), parameter :: SQ6 = sqrt(6.0_dp)
    real(dp), parameter :: C1 = (4.0_dp - SQ6)/10.0_dp, C2 = (4.0_dp + SQ6)/10.0_dp
    real(dp), parameter :: DD1 = -(13.0_dp + 7.0_dp*SQ6)/3.0_dp
    real(dp), parameter :: DD2 = (-13.0_dp + 7.0_dp*SQ6)/3.0_dp
    real(dp), parameter :: DD3 = -1.0_dp/3.0_dp
    ! eigenvalues of the inverse Radau matrix: gamma (real), alpha +- i beta
    real(dp), parameter :: GAM0 = 3.6378342527444957322_dp
    real(dp), parameter :: ALPH = 2.6810828736277521339_dp
    real(dp), parameter :: BETA = 3.0504301992474105694_dp
    ! T^{-1} A^{-1} T = diag(gamma, [[alpha, -beta], [beta, alpha]]) (Hairer's T, TI)
    real(dp), parameter :: T11 = 9.1232394870892942792e-02_dp
    real(dp), parameter :: T12 = -0.14125529502095420843_dp
    real(dp), parameter :: T13 = -3.0029194105147424492e-02_dp
    real(dp), parameter :: T21 = 0.24171793270710701896_dp
    real(dp), parameter :: T22 = 0.20412935229379993199_dp
    real(dp), parameter :: T23 = 0.38294211275726193779_dp
    real(dp), parameter :: T31 = 0.96604818261509293619_dp
    real(dp), parameter :: TI11 = 4.3255798900631553510_dp
    real(dp), parameter :: TI12 = 0.33919925181580986954_dp
    real(dp), parameter :: TI13 = 0.54177053993587487119_dp
    real(dp), parameter :: TI21 = -4.1787185915519047273_dp
    real(dp), parameter :: TI22 = -0.32768282076106238708_dp
    real(dp), parameter :: TI23 = 0.47662355450055045196_dp
    real(dp), parameter :: TI31 = -0.50287263494578687595_dp
    real(dp), parameter :: TI32 = 2.5719269498556054292_dp
    real(dp), parameter :: TI33 = -0.59603920482822492497_dp
    integer, parameter :: NIT = 7                 !! Newton iterations per step at most
    real(dp), parameter :: THET = 0.001_dp        !! Jacobian reuse threshold
    !> after an accepted step, h and the LU are kept when the proposed ratio is below QUOT2
    !! and the Jacobian is not refreshed (SciPy's rule; RADAU5's default window is [1, 1.2])
    real(dp), parameter :: QUOT1 = 0.0_dp, QUOT2 = 1.2_dp

contains

    !> Solve y' = f(t, y) on t_span with Radau IIA (order 5); outputs as `ode_solve`
    !! (every accepted step, or t_eval interpolated on the collocation polynomial; dense
    !! output; events). res%stats counts nfev, njev, nlu, naccept, nreject.
    subroutine radau_solve(sys, t_span, y0, opt, res, t_eval, events, mass, index2, &
                           r_state, i_state, w_state, action)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: y0(:)
        type(ode_options), intent(in) :: opt
        type(ode_result), intent(inout) :: res
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        !> constant mass matrix M of M y' = f(t, y) (n x n, may be singular: a DAE)
        real(dp), intent(in), optional :: mass(:, :)
        !> the index-2 algebraic components (their error is scaled by h, as RADAU5)
        logical, intent(in), optional :: index2(:)
        !> step-by-step use (radau_stepper_*): the packed state and the action (0: start
        !! at (t_span(1), y0), 1: one accepted step); outputs in res are then not kept
        real(dp), intent(inout), optional :: r_state(:)
        integer, intent(inout), optional :: i_state(:)
        real(dp), intent(inout), optional :: w_state(:, :)
        integer, intent(in), optional :: action

        type(step_output) :: o
        real(dp), allocatable :: y(:), f0(:), jac(:, :), e1(:, :), z1(:), z2(:), z3(:)
        real(dp), allocatable :: w1(:), w2(:), w3(:), a1(:), a2(:), a3(:), scal(:), cont(:)
        real(dp), allocatable :: rtolv(:), atolv(:), fc(:, :), ynew(:), ystop(:), scal0(:)
        real(dp), allocatable :: b1(:), b2(:), b3(:)
        complex(dp), allocatable :: e2(:, :), zc(:)
        integer, allocatable :: ip1(:), ip2(:)
        real(dp) :: t0, tf, t, h, hmax, posneg, uround, fnewt, faccon, theta, thqold
        real(dp) :: dyno, dynold, thq, dyth, qnewt, hhfac, err, fac, quot, hnew, facgus
        real(dp) :: hacc, erracc, hold, safe, facl, facr, cfac, tstop, c3q, xi
        real(dp) :: pmat(3, 3), cvec(3)
        integer :: n, newt, nsteps, nsing, nfail, lainfo, i, j
        logical :: first, reject, last, caljac, need_jac, need_lu, converged, stop_now
        logical :: newton_failed, have_cont, stepping, resume
        real(dp) :: t_prev
        character(len=32) :: buf

        n = size(y0)
        t0 = t_span(1)
        tf = t_span(2)
        h = 0.0_dp
        stop_now = .false.
        t_prev = t0
        stepping = present(action) .and. present(r_state) .and. present(i_state) .and. &
                   present(w_state)
        resume = .false.
        if (stepping) resume = action == 1
        if (stepping) then
            if (present(mass) .or. present(t_eval) .or. present(events) .or. &
                size(r_state) < RADAU_NR .or. size(i_state) < RADAU_NI + 2*n .or. &
                size(w_state, 1) /= n .or. size(w_state, 2) < RADAU_NW + 4*n) then
                res%status = CM_BAD_INPUT
                res%message = "bad input: the packed Radau state has the wrong size (or "// &
                              "mass, t_eval, events given to a step-by-step integration)"
                return
            end if
        end if
        if (resume) then
            allocate (y(n), f0(n), jac(n, n), e1(n, n), z1(n), z2(n), z3(n), w1(n), w2(n), &
                      w3(n), a1(n), a2(n), a3(n), scal(n), cont(n), fc(n, 0:3), ynew(n), &
                      ystop(n), e2(n, n), zc(n), ip1(n), ip2(n), scal0(n), b1(n), b2(n), &
                      b3(n), rtolv(n), atolv(n))
            call load_state()
            if (res%status /= CM_SUCCESS) return
        else
        call validate()
        if (res%status /= CM_SUCCESS) return
        allocate (y(n), f0(n), jac(n, n), e1(n, n), z1(n), z2(n), z3(n), w1(n), w2(n), &
                  w3(n), a1(n), a2(n), a3(n), scal(n), cont(n), fc(n, 0:3), ynew(n), &
                  ystop(n), e2(n, n), zc(n), ip1(n), ip2(n), scal0(n), b1(n), b2(n), b3(n))
        y = y0
        jac = 0.0_dp
        e1 = 0.0_dp
        e2 = 0.0_dp
        ip1 = 0
        ip2 = 0
        t = t0
        if (.not. stepping) call out_init(o, res, opt, t0, tf, y0, 3, t_eval, events)
        if (tf == t0 .and. .not. stepping) then
            call finish(CM_SUCCESS, "success")
            return
        end if
        posneg = sign(1.0_dp, tf - t0)
        uround = epsilon(1.0_dp)
        hmax = min(abs(opt%max_step), abs(tf - t0))
        fnewt = max(10.0_dp*uround/minval(rtolv), min(0.03_dp, sqrt(minval(rtolv))))
        safe = 0.9_dp
        if (opt%safety > 0.0_dp) safe = opt%safety
        facl = 5.0_dp
        facr = 1.0_dp/8.0_dp
        if (opt%fac_min > 0.0_dp) facl = 1.0_dp/opt%fac_min
        if (opt%fac_max > 0.0_dp) facr = 1.0_dp/opt%fac_max
        cfac = safe*real(1 + 2*NIT, dp)
        cvec = [C1, C2, 1.0_dp]
        pmat = power_basis_matrix(cvec)

        call rhs(t, y, f0)
        if (.not. all(ieee_is_finite(f0))) then
            call finish(CM_NONFINITE, "the right-hand side is not finite at the initial point")
            return
        end if
        scal = atolv + rtolv*abs(y)
        scal0 = scal
        if (opt%first_step > 0.0_dp) then
            h = min(opt%first_step, hmax)*posneg
        else if (present(mass)) then
            h = min(1.0e-6_dp, hmax)*posneg     ! RADAU5's default for DAEs
        else
            h = initial_step()
        end if
        last = (t + h - tf)*posneg >= 0.0_dp
        if (last) h = tf - t

        first = .true.
        reject = .false.
        caljac = .false.
        need_jac = .true.
        need_lu = .true.
        have_cont = .false.
        faccon = 1.0_dp
        theta = THET
        hold = h
        hacc = h
        erracc = 1.0_dp
        nsteps = 0
        nsing = 0
        nfail = 0
        newton_failed = .false.
        fc = 0.0_dp
        if (stepping) then           ! action 0: the state at the start, no step
            call finish(CM_SUCCESS, "success")
            return
        end if
        end if
        ! ------------------------------------------------------------------ main loop
        do
            if (0.1_dp*abs(h) <= abs(t)*uround .or. abs(h) < tiny(1.0_dp)) then
                write (buf, '(es14.6)') t
                if (newton_failed) then
                    call finish(CM_STEP_TOO_SMALL, "step size too small at t ="//trim(buf)// &
                                " (the Newton iteration did not converge)")
                else
                    call finish(CM_STEP_TOO_SMALL, "step size too small at t ="//trim(buf))
                end if
                return
            end if
            if (nsteps >= opt%max_steps) then
                write (buf, '(es14.6)') t
                call finish(CM_TOO_MANY_STEPS, "too many steps: max_steps reached at t ="// &
                            trim(buf))
                return
            end if
            if (need_jac) then
                call jacobian()
                if (.not. all(ieee_is_finite(jac))) then
                    write (buf, '(es14.6)') t
                    call finish(CM_NONFINITE, "non-finite Jacobian at t ="//trim(buf))
                    return
                end if
                caljac = .true.
                need_jac = .false.
                need_lu = .true.
            end if
            if (need_lu) then
                call decompose(lainfo)
                if (lainfo /= 0) then
                    nsing = nsing + 1
                    if (nsing >= 5) then
                        write (buf, '(es14.6)') t
                        call finish(CM_SINGULAR, "singular iteration matrix (gamma/h I - J) "// &
                                    "five times in a row at t ="//trim(buf))
                        return
                    end if
                    h = 0.5_dp*h
                    reject = .true.
                    last = .false.
                    cycle
                end if
                need_lu = .false.
                nsing = 0
            end if
            nsteps = nsteps + 1
            scal = scal0
            if (present(index2)) then
                where (index2) scal = scal0/abs(h)
            end if

            call newton()
            if (.not. converged) then
                if (newton_failed) nfail = nfail + 1
                if (nfail > 60) then
                    write (buf, '(es14.6)') t
                    call finish(CM_STEP_TOO_SMALL, "step size too small at t ="//trim(buf)// &
                                " (the Newton iteration did not converge in 60 step reductions)")
                    return
                end if
                reject = .true.
                last = .false.
                need_lu = .true.
                if (.not. caljac) need_jac = .true.
                cycle
            end if
            newton_failed = .false.
            nfail = 0
            call estimate_error()

            fac = min(safe, cfac/real(newt + 2*NIT, dp))
            quot = max(facr, min(facl, err**0.25_dp/fac))
            hnew = h/quot
            if (err < 1.0_dp) then
                ! ---------------------------------------------------- accepted step
                first = .false.
                res%stats%naccept = res%stats%naccept + 1
                if (res%stats%naccept > 1) then
                    facgus = (hacc/h)*(err**2/erracc)**0.25_dp/safe
                    facgus = max(facr, min(facl, facgus))
                    quot = max(quot, facgus)
                    hnew = h/quot
                end if
                hacc = h
                erracc = max(1.0e-2_dp, err)
                ! collocation polynomial in the power basis of x = (s - t)/h
                fc(:, 0) = y
                do j = 1, 3
                    fc(:, j) = pmat(j, 1)*z1 + pmat(j, 2)*z2 + pmat(j, 3)*z3
                end do
                have_cont = .true.
                ynew = y + z3
                if (.not. stepping) call out_step(o, res, t, h, fc, ynew, stop_now, tstop, &
                                                  ystop, t_eval, events)
                hold = h
                t_prev = t
                if (stop_now) then
                    t = tstop
                    y = ystop
                    call finish(CM_EVENT_STOP, "a termination event occurred")
                    return
                end if
                if (last) then
                    t = tf
                else
                    t = t + h
                end if
                y = ynew
                caljac = .false.
                if (last) exit
                call rhs(t, y, f0)
                if (.not. all(ieee_is_finite(f0))) then
                    write (buf, '(es14.6)') t
                    call finish(CM_NONFINITE, "non-finite right-hand side at t ="//trim(buf))
                    return
                end if
                scal0 = atolv + rtolv*abs(y)
                hnew = posneg*min(abs(hnew), hmax)
                if (reject) hnew = posneg*min(abs(hnew), abs(h))
                reject = .false.
                need_jac = newt > 2 .and. theta > THET
                if ((t + hnew - tf)*posneg >= 0.0_dp) then
                    h = tf - t
                    last = .true.
                    need_lu = .true.
                else
                    if (.not. need_jac .and. hnew/h >= QUOT1 .and. hnew/h <= QUOT2) then
                        need_lu = .false.
                    else
                        h = hnew
                        need_lu = .true.
                    end if
                end if
                if (stepping) exit       ! one accepted step per call
            else
                ! ---------------------------------------------------- rejected step
                reject = .true.
                last = .false.
                if (first) then
                    h = 0.1_dp*h
                else
                    h = hnew
                end if
                if (res%stats%naccept >= 1) res%stats%nreject = res%stats%nreject + 1
                need_lu = .true.
                ! (the Jacobian is kept: SciPy's rule; RADAU5 refreshes an old one here)
            end if
        end do
        call finish(CM_SUCCESS, "success")

    contains

        subroutine validate()
            character(len=:), allocatable :: m2
            res%status = CM_BAD_INPUT
            if (n < 1) then
                res%message = "bad input: y0 is empty"
            else if (.not. all(ieee_is_finite(y0))) then
                res%message = "bad input: y0 contains NaN or Inf"
            else if (.not. ieee_is_finite(t0) .or. ieee_is_nan(tf) .or. &
                     (.not. ieee_is_finite(tf) .and. .not. stepping)) then
                ! (a step-by-step integration may run towards t_bound = +-inf)
                res%message = "bad input: t_span must be finite"
            else if (.not. opt%max_step > 0.0_dp) then
                res%message = "bad input: max_step must be positive"
            else if (.not. opt%first_step >= 0.0_dp) then
                res%message = "bad input: first_step must be positive"
            else if (opt%first_step > abs(tf - t0) .and. tf /= t0) then
                res%message = "bad input: first_step exceeds the length of t_span"
            else if (opt%max_steps < 1) then
                res%message = "bad input: max_steps must be positive"
            else if (present(mass)) then
                if (size(mass, 1) /= n .or. size(mass, 2) /= n) then
                    res%message = "bad input: the mass matrix must be n x n"
                else if (.not. all(ieee_is_finite(mass))) then
                    res%message = "bad input: the mass matrix contains NaN or Inf"
                else
                    res%status = CM_SUCCESS
                end if
            else
                res%status = CM_SUCCESS
            end if
            if (res%status == CM_SUCCESS .and. present(index2)) then
                if (size(index2) /= n) then
                    res%status = CM_BAD_INPUT
                    res%message = "bad input: index2 must have n elements"
                end if
            end if
            if (res%status /= CM_SUCCESS) return
            call tolerance_vectors(opt, n, rtolv, atolv, res%status, m2)
            if (res%status /= CM_SUCCESS) then
                res%message = m2
                return
            end if
            if (present(t_eval)) then
                call check_t_eval(t_span, t_eval, res%status, m2)
                if (res%status /= CM_SUCCESS) then
                    res%message = m2
                    return
                end if
            end if
            if (present(events)) then
                if (events%n_events() > 0) then
                    if (.not. allocated(events%terminal)) then
                        res%status = CM_BAD_INPUT
                        res%message = "bad input: events%terminal must be allocated"
                    else if (size(events%terminal) /= size(events%direction)) then
                        res%status = CM_BAD_INPUT
                        res%message = "bad input: events%terminal and events%direction " &
                                      //"differ in size"
                    end if
                end if
            end if
        end subroutine validate

        subroutine finish(code, text)
            integer, intent(in) :: code
            character(len=*), intent(in) :: text
            res%status = code
            res%message = text
            res%success = code >= 0
            res%stats%h_next = h
            if (stepping) then
                call save_state()
            else if (allocated(o%g_old) .or. o%n > 0) then
                call out_finish(o, res, t, y)
            end if
        end subroutine finish

        !> Pack the state of the integration into (r_state, i_state, w_state).
        subroutine save_state()
            r_state = 0.0_dp
            r_state(1:RADAU_NR) = [t0, tf, t, h, hmax, posneg, uround, fnewt, faccon, &
                                   theta, hacc, erracc, hold, safe, facl, facr, cfac, &
                                   t_prev, 0.0_dp, 0.0_dp]
            i_state(1:RADAU_NI) = [n, nsteps, nsing, nfail, res%stats%nfev, &
                                   res%stats%njev, res%stats%nlu, res%stats%naccept, &
                                   res%stats%nreject, l2i(first), l2i(reject), l2i(last), &
                                   l2i(caljac), l2i(need_jac), l2i(need_lu), &
                                   l2i(have_cont), l2i(newton_failed), 1, 0, 0]
            i_state(RADAU_NI + 1:RADAU_NI + n) = ip1
            i_state(RADAU_NI + n + 1:RADAU_NI + 2*n) = ip2
            w_state(:, 1) = y
            w_state(:, 2) = f0
            w_state(:, 3) = scal0
            w_state(:, 4) = rtolv
            w_state(:, 5) = atolv
            w_state(:, 6:9) = fc
            w_state(:, RADAU_NW + 1:RADAU_NW + n) = jac
            w_state(:, RADAU_NW + n + 1:RADAU_NW + 2*n) = e1
            w_state(:, RADAU_NW + 2*n + 1:RADAU_NW + 3*n) = real(e2, dp)
            w_state(:, RADAU_NW + 3*n + 1:RADAU_NW + 4*n) = aimag(e2)
        end subroutine save_state

        !> Unpack the state written by save_state (action 1).
        subroutine load_state()
            if (i_state(1) /= n .or. i_state(18) /= 1) then
                res%status = CM_BAD_INPUT
                res%message = "bad input: the Radau state was not started (action 0 first)"
                return
            end if
            res%status = CM_SUCCESS
            t0 = r_state(1); tf = r_state(2); t = r_state(3); h = r_state(4)
            hmax = r_state(5); posneg = r_state(6); uround = r_state(7); fnewt = r_state(8)
            faccon = r_state(9); theta = r_state(10); hacc = r_state(11)
            erracc = r_state(12); hold = r_state(13); safe = r_state(14); facl = r_state(15)
            facr = r_state(16); cfac = r_state(17); t_prev = r_state(18)
            nsteps = i_state(2); nsing = i_state(3); nfail = i_state(4)
            res%stats%nfev = i_state(5); res%stats%njev = i_state(6)
            res%stats%nlu = i_state(7); res%stats%naccept = i_state(8)
            res%stats%nreject = i_state(9)
            first = i_state(10) /= 0; reject = i_state(11) /= 0; last = i_state(12) /= 0
            caljac = i_state(13) /= 0; need_jac = i_state(14) /= 0
            need_lu = i_state(15) /= 0; have_cont = i_state(16) /= 0
            newton_failed = i_state(17) /= 0
            ip1 = i_state(RADAU_NI + 1:RADAU_NI + n)
            ip2 = i_state(RADAU_NI + n + 1:RADAU_NI + 2*n)
            y = w_state(:, 1)
            f0 = w_state(:, 2)
            scal0 = w_state(:, 3)
            rtolv = w_state(:, 4)
            atolv = w_state(:, 5)
            fc = w_state(:, 6:9)
            jac = w_state(:, RADAU_NW + 1:RADAU_NW + n)
            e1 = w_state(:, RADAU_NW + n + 1:RADAU_NW + 2*n)
            e2 = cmplx(w_state(:, RADAU_NW + 2*n + 1:RADAU_NW + 3*n), &
                       w_state(:, RADAU_NW + 3*n + 1:RADAU_NW + 4*n), kind=dp)
            cvec = [C1, C2, 1.0_dp]
            pmat = power_basis_matrix(cvec)
        end subroutine load_state

        integer function l2i(l)
            logical, intent(in) :: l
            l2i = merge(1, 0, l)
        end function l2i

        subroutine rhs(tt, yy, ff)
            real(dp), intent(in) :: tt, yy(:)
            real(dp), intent(out) :: ff(:)
            call sys%rhs(tt, yy, ff)
            res%stats%nfev = res%stats%nfev + 1
        end subroutine rhs

        !> Initial step of SciPy's select_initial_step (error estimator order 3).
        function initial_step() result(hh)
            real(dp) :: hh, d0, d1, d2, h1
            d0 = sqrt(sum((y/scal)**2)/n)
            d1 = sqrt(sum((f0/scal)**2)/n)
            if (d0 < 1.0e-5_dp .or. d1 < 1.0e-5_dp) then
                hh = 1.0e-6_dp
            else
                hh = 0.01_dp*d0/d1
            end if
            hh = min(hh, hmax)
            a1 = y + hh*posneg*f0
            call rhs(t + hh*posneg, a1, a2)
            d2 = sqrt(sum(((a2 - f0)/scal)**2)/n)/hh
            if (.not. ieee_is_finite(d2)) d2 = huge(1.0_dp)
            if (d1 <= 1.0e-15_dp .and. d2 <= 1.0e-15_dp) then
                h1 = max(1.0e-6_dp, hh*1.0e-3_dp)
            else
                h1 = (0.01_dp/max(d1, d2))**0.25_dp
            end if
            hh = min(100.0_dp*hh, h1, hmax)*posneg
        end function initial_step

        subroutine jacobian()
            real(dp) :: delt, ysafe
            integer :: jj
            res%stats%njev = res%stats%njev + 1
            if (sys%has_jacobian()) then
                call sys%jacobian(t, y, jac)
                return
            end if
            do jj = 1, n
                ysafe = y(jj)
                delt = sqrt(uround*max(1.0e-5_dp, abs(ysafe)))
                y(jj) = ysafe + delt
                call rhs(t, y, a1)
                y(jj) = ysafe
                jac(:, jj) = (a1 - f0)/delt
            end do
        end subroutine jacobian

        !> LU of gamma/h I - J (real) and (alpha + i beta)/h I - J (complex).
        subroutine decompose(linfo)
            integer, intent(out) :: linfo
            real(dp) :: fac1
            complex(dp) :: sig
            integer :: ii
            fac1 = GAM0/h
            sig = cmplx(ALPH/h, BETA/h, kind=dp)
            if (present(mass)) then
                e1 = fac1*mass - jac
                e2 = sig*mass - jac
            else
                e1 = -jac
                e2 = cmplx(-jac, 0.0_dp, kind=dp)
                do ii = 1, n
                    e1(ii, ii) = e1(ii, ii) + fac1
                    e2(ii, ii) = e2(ii, ii) + sig
                end do
            end if
            call dgetrf(n, n, e1, n, ip1, linfo)
            res%stats%nlu = res%stats%nlu + 1
            if (linfo /= 0) return
            call zgetrf(n, n, e2, n, ip2, linfo)
            res%stats%nlu = res%stats%nlu + 1
        end subroutine decompose

        !> Simplified Newton iteration for the stage increments z1..z3 (RADAU5's control).
        subroutine newton()
            real(dp) :: fac1, alphn, betan, s2, s3
            integer :: linfo
            converged = .false.
            fac1 = GAM0/h
            alphn = ALPH/h
            betan = BETA/h
            ! starting values: the previous collocation polynomial, extrapolated
            if (first .or. .not. have_cont) then
                z1 = 0.0_dp; z2 = 0.0_dp; z3 = 0.0_dp
                w1 = 0.0_dp; w2 = 0.0_dp; w3 = 0.0_dp
            else
                c3q = h/hold
                do i = 1, 3
                    xi = 1.0_dp + cvec(i)*c3q
                    ! u(xi) - u(1) = sum_j fc_j (xi^j - 1)
                    a2 = fc(:, 1)*(xi - 1.0_dp) + fc(:, 2)*(xi**2 - 1.0_dp) &
                         + fc(:, 3)*(xi**3 - 1.0_dp)
                    select case (i)
                    case (1)
                        z1 = a2
                    case (2)
                        z2 = a2
                    case default
                        z3 = a2
                    end select
                end do
                w1 = TI11*z1 + TI12*z2 + TI13*z3
                w2 = TI21*z1 + TI22*z2 + TI23*z3
                w3 = TI31*z1 + TI32*z2 + TI33*z3
            end if
            newt = 0
            faccon = max(faccon, uround)**0.8_dp
            theta = abs(THET)
            dynold = 0.0_dp
            thqold = 0.0_dp
            do
                if (newt >= NIT) exit
                call rhs(t + C1*h, y + z1, a1)
                call rhs(t + C2*h, y + z2, a2)
                call rhs(t + h, y + z3, a3)
                if (.not. (all(ieee_is_finite(a1)) .and. all(ieee_is_finite(a2)) .and. &
                           all(ieee_is_finite(a3)))) exit
                if (present(mass)) then
                    b1 = matmul(mass, w1)
                    b2 = matmul(mass, w2)
                    b3 = matmul(mass, w3)
                else
                    b1 = w1
                    b2 = w2
                    b3 = w3
                end if
                z1 = TI11*a1 + TI12*a2 + TI13*a3 - fac1*b1
                do i = 1, n
                    s2 = TI21*a1(i) + TI22*a2(i) + TI23*a3(i)
                    s3 = TI31*a1(i) + TI32*a2(i) + TI33*a3(i)
                    zc(i) = cmplx(s2 - alphn*b2(i) + betan*b3(i), &
                                  s3 - alphn*b3(i) - betan*b2(i), kind=dp)
                end do
                call dgetrs('N', n, 1, e1, n, ip1, z1, n, linfo)
                call zgetrs('N', n, 1, e2, n, ip2, zc, n, linfo)
                z2 = real(zc, dp)
                z3 = aimag(zc)
                newt = newt + 1
                dyno = sqrt(sum((z1/scal)**2 + (z2/scal)**2 + (z3/scal)**2)/real(3*n, dp))
                if (.not. ieee_is_finite(dyno)) exit
                if (newt > 1 .and. newt < NIT) then
                    thq = dyno/dynold
                    if (newt == 2) then
                        theta = thq
                    else
                        theta = sqrt(thq*thqold)
                    end if
                    thqold = thq
                    if (theta < 0.99_dp) then
                        faccon = theta/(1.0_dp - theta)
                        dyth = faccon*dyno*theta**(NIT - 1 - newt)/fnewt
                        if (dyth >= 1.0_dp) then
                            ! slow convergence: a smaller step
                            qnewt = max(1.0e-4_dp, min(20.0_dp, dyth))
                            hhfac = 0.8_dp*qnewt**(-1.0_dp/real(4 + NIT - 1 - newt, dp))
                            h = hhfac*h
                            return
                        end if
                    else
                        exit
                    end if
                end if
                dynold = max(dyno, uround)
                w1 = w1 + z1
                w2 = w2 + z2
                w3 = w3 + z3
                z1 = T11*w1 + T12*w2 + T13*w3
                z2 = T21*w1 + T22*w2 + T23*w3
                z3 = T31*w1 + w2
                if (faccon*dyno <= fnewt) then
                    converged = .true.
                    return
                end if
            end do
            ! divergence, too many iterations or non-finite values: halve the step
            newton_failed = .true.
            h = 0.5_dp*h
        end subroutine newton

        !> RADAU5's error estimate (estrad).
        subroutine estimate_error()
            real(dp) :: hee1, hee2, hee3
            integer :: linfo
            hee1 = DD1/h
            hee2 = DD2/h
            hee3 = DD3/h
            a2 = hee1*z1 + hee2*z2 + hee3*z3
            if (present(mass)) a2 = matmul(mass, a2)
            cont = a2 + f0
            call dgetrs('N', n, 1, e1, n, ip1, cont, n, linfo)
            err = max(sqrt(sum((cont/scal)**2)/real(n, dp)), 1.0e-10_dp)
            if (err < 1.0_dp) return
            if (first .or. reject) then
                a1 = y + cont
                call rhs(t, a1, a3)
                cont = a3 + a2
                call dgetrs('N', n, 1, e1, n, ip1, cont, n, linfo)
                err = max(sqrt(sum((cont/scal)**2)/real(n, dp)), 1.0e-10_dp)
            end if
            if (.not. ieee_is_finite(err)) err = 1.0e10_dp
        end subroutine estimate_error

    end subroutine radau_solve
end module conmech_radau
