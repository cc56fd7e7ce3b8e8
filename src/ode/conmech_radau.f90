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
!! This module holds the driver (input checks, set-up, the step loop, the outputs); the
!! parts: conmech_radau_coefficients (constants), conmech_radau_state (the state type and
!! its packing for the step-by-step use), conmech_radau_newton (Jacobian, LU, Newton),
!! conmech_radau_control (initial step, error estimate, step-size control),
!! conmech_radau_collocation (the collocation polynomial), conmech_radau_common (outputs).
module conmech_radau
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_is_nan
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system, ode_events
    use conmech_ode_solver, only: ode_options, ode_result
    use conmech_radau_common
    use conmech_radau_coefficients, only: NIT, THET
    use conmech_radau_state
    use conmech_radau_collocation, only: radau_collocation_basis, radau_collocation_update
    use conmech_radau_newton, only: radau_rhs, radau_jacobian, radau_decompose, radau_newton
    use conmech_radau_control
    implicit none
    private

    public :: radau_solve
    public :: RADAU_NR, RADAU_NI, RADAU_NW
    public :: RADAU_RT, RADAU_RTOLD, RADAU_RHOLD, RADAU_WY, RADAU_WFC, RADAU_IFEV

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

        type(radau_state) :: s
        type(step_output) :: o
        real(dp) :: t0, tf, quot, tstop
        integer :: n, lainfo
        logical :: stop_now, stepping, resume
        character(len=32) :: buf

        n = size(y0)
        t0 = t_span(1)
        tf = t_span(2)
        stop_now = .false.
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
            call radau_state_allocate(s, n, .true.)
            call radau_state_unpack(s, res%stats, r_state, i_state, w_state, res%status, &
                                    res%message)
            if (res%status /= CM_SUCCESS) return
        else
            call start()
            if (res%status /= CM_SUCCESS .or. stepping) return
            if (tf == t0) return
        end if
        ! ------------------------------------------------------------------ main loop
        do
            if (0.1_dp*abs(s%h) <= abs(s%t)*s%uround .or. abs(s%h) < tiny(1.0_dp)) then
                write (buf, '(es14.6)') s%t
                if (s%newton_failed) then
                    call finish(CM_STEP_TOO_SMALL, "step size too small at t ="//trim(buf)// &
                                " (the Newton iteration did not converge)")
                else
                    call finish(CM_STEP_TOO_SMALL, "step size too small at t ="//trim(buf))
                end if
                return
            end if
            if (s%nsteps >= opt%max_steps) then
                write (buf, '(es14.6)') s%t
                call finish(CM_TOO_MANY_STEPS, "too many steps: max_steps reached at t ="// &
                            trim(buf))
                return
            end if
            if (s%need_jac) then
                call radau_jacobian(s, sys, res%stats)
                if (.not. all(ieee_is_finite(s%jac))) then
                    write (buf, '(es14.6)') s%t
                    call finish(CM_NONFINITE, "non-finite Jacobian at t ="//trim(buf))
                    return
                end if
                s%caljac = .true.
                s%need_jac = .false.
                s%need_lu = .true.
            end if
            if (s%need_lu) then
                call radau_decompose(s, res%stats, lainfo, mass)
                if (lainfo /= 0) then
                    s%nsing = s%nsing + 1
                    if (s%nsing >= 5) then
                        write (buf, '(es14.6)') s%t
                        call finish(CM_SINGULAR, "singular iteration matrix (gamma/h I - J) "// &
                                    "five times in a row at t ="//trim(buf))
                        return
                    end if
                    s%h = 0.5_dp*s%h
                    s%reject = .true.
                    s%last = .false.
                    cycle
                end if
                s%need_lu = .false.
                s%nsing = 0
            end if
            s%nsteps = s%nsteps + 1
            s%scal = s%scal0
            if (present(index2)) then
                where (index2) s%scal = s%scal0/abs(s%h)
            end if

            call radau_newton(s, sys, res%stats, mass)
            if (.not. s%converged) then
                if (s%newton_failed) s%nfail = s%nfail + 1
                if (s%nfail > 60) then
                    write (buf, '(es14.6)') s%t
                    call finish(CM_STEP_TOO_SMALL, "step size too small at t ="//trim(buf)// &
                                " (the Newton iteration did not converge in 60 step reductions)")
                    return
                end if
                s%reject = .true.
                s%last = .false.
                s%need_lu = .true.
                if (.not. s%caljac) s%need_jac = .true.
                cycle
            end if
            s%newton_failed = .false.
            s%nfail = 0
            call radau_estimate_error(s, sys, res%stats, mass)

            quot = radau_propose_step(s)
            if (s%err < 1.0_dp) then
                ! ---------------------------------------------------- accepted step
                s%first = .false.
                res%stats%naccept = res%stats%naccept + 1
                call radau_predictive_step(s, quot, res%stats%naccept)
                call radau_collocation_update(s%pmat, s%y, s%z1, s%z2, s%z3, s%fc)
                s%have_cont = .true.
                s%ynew = s%y + s%z3
                if (.not. stepping) call out_step(o, res, s%t, s%h, s%fc, s%ynew, stop_now, &
                                                  tstop, s%ystop, t_eval, events)
                s%hold = s%h
                s%t_prev = s%t
                if (stop_now) then
                    s%t = tstop
                    s%y = s%ystop
                    call finish(CM_EVENT_STOP, "a termination event occurred")
                    return
                end if
                if (s%last) then
                    s%t = s%tf
                else
                    s%t = s%t + s%h
                end if
                s%y = s%ynew
                s%caljac = .false.
                if (s%last) exit
                call radau_rhs(sys, res%stats, s%t, s%y, s%f0)
                if (.not. all(ieee_is_finite(s%f0))) then
                    write (buf, '(es14.6)') s%t
                    call finish(CM_NONFINITE, "non-finite right-hand side at t ="//trim(buf))
                    return
                end if
                s%scal0 = s%atolv + s%rtolv*abs(s%y)
                call radau_next_step(s)
                if (stepping) exit       ! one accepted step per call
            else
                ! ---------------------------------------------------- rejected step
                s%reject = .true.
                s%last = .false.
                if (s%first) then
                    s%h = 0.1_dp*s%h
                else
                    s%h = s%hnew
                end if
                if (res%stats%naccept >= 1) res%stats%nreject = res%stats%nreject + 1
                s%need_lu = .true.
                ! (the Jacobian is kept: SciPy's rule; RADAU5 refreshes an old one here)
            end if
        end do
        call finish(CM_SUCCESS, "success")

    contains

        !> Validate the input and set up the integration at (t0, y0): the options, f0, the
        !! scale, the initial step and the flags (action 0 ends here, with the packed state).
        subroutine start()
            call validate()
            if (res%status /= CM_SUCCESS) return
            call radau_state_allocate(s, n, .false.)
            s%t0 = t0
            s%tf = tf
            s%h = 0.0_dp
            s%t_prev = t0
            s%y = y0
            s%jac = 0.0_dp
            s%e1 = 0.0_dp
            s%e2 = 0.0_dp
            s%ip1 = 0
            s%ip2 = 0
            s%t = t0
            if (.not. stepping) call out_init(o, res, opt, t0, tf, y0, 3, t_eval, events)
            if (tf == t0 .and. .not. stepping) then
                call finish(CM_SUCCESS, "success")
                return
            end if
            s%posneg = sign(1.0_dp, tf - t0)
            s%uround = epsilon(1.0_dp)
            s%hmax = min(abs(opt%max_step), abs(tf - t0))
            s%fnewt = max(10.0_dp*s%uround/minval(s%rtolv), min(0.03_dp, sqrt(minval(s%rtolv))))
            s%safe = 0.9_dp
            if (opt%safety > 0.0_dp) s%safe = opt%safety
            s%facl = 5.0_dp
            s%facr = 1.0_dp/8.0_dp
            if (opt%fac_min > 0.0_dp) s%facl = 1.0_dp/opt%fac_min
            if (opt%fac_max > 0.0_dp) s%facr = 1.0_dp/opt%fac_max
            s%cfac = s%safe*real(1 + 2*NIT, dp)
            call radau_collocation_basis(s%cvec, s%pmat)

            call radau_rhs(sys, res%stats, s%t, s%y, s%f0)
            if (.not. all(ieee_is_finite(s%f0))) then
                call finish(CM_NONFINITE, "the right-hand side is not finite at the initial point")
                return
            end if
            s%scal = s%atolv + s%rtolv*abs(s%y)
            s%scal0 = s%scal
            if (opt%first_step > 0.0_dp) then
                s%h = min(opt%first_step, s%hmax)*s%posneg
            else if (present(mass)) then
                s%h = min(1.0e-6_dp, s%hmax)*s%posneg     ! RADAU5's default for DAEs
            else
                s%h = radau_initial_step(s, sys, res%stats)
            end if
            s%last = (s%t + s%h - tf)*s%posneg >= 0.0_dp
            if (s%last) s%h = tf - s%t

            s%first = .true.
            s%reject = .false.
            s%caljac = .false.
            s%need_jac = .true.
            s%need_lu = .true.
            s%have_cont = .false.
            s%faccon = 1.0_dp
            s%theta = THET
            s%hold = s%h
            s%hacc = s%h
            s%erracc = 1.0_dp
            s%nsteps = 0
            s%nsing = 0
            s%nfail = 0
            s%newton_failed = .false.
            s%fc = 0.0_dp
            if (stepping) call finish(CM_SUCCESS, "success")   ! action 0: no step
        end subroutine start

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
            call tolerance_vectors(opt, n, s%rtolv, s%atolv, res%status, m2)
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

        !> End the run: status and message; the outputs (or the packed state when stepping).
        subroutine finish(code, text)
            integer, intent(in) :: code
            character(len=*), intent(in) :: text
            res%status = code
            res%message = text
            res%success = code >= 0
            res%stats%h_next = s%h
            if (stepping) then
                call radau_state_pack(s, res%stats, r_state, i_state, w_state)
            else if (allocated(o%g_old) .or. o%n > 0) then
                call out_finish(o, res, s%t, s%y)
            end if
        end subroutine finish

    end subroutine radau_solve
end module conmech_radau
