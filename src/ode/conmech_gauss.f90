!> Gauss-Legendre collocation (implicit Runge-Kutta) with s = 2 and s = 3 stages, of
!! orders 4 and 6: symplectic and symmetric, it keeps quadratic invariants (angular
!! momentum) exactly and the energy error of Hamiltonian systems bounded over long times.
!!
!! - Fixed step: h = (tf - t0)/N with N = ceil(|tf - t0|/first_step).
!! - Stage equations Z_i = h sum_j a_ij f(t + c_j h, y + Z_j) solved by fixed-point
!!   iteration to round-off (Hairer-Lubich-Wanner, GNI VIII.6): iterate until the
!!   correction vanishes or stops decreasing at the round-off level; starting
!!   values from the collocation polynomial of the previous step. At most 50 iterations:
!!   otherwise (h too large for the iteration to contract, e.g. a stiff system) the run
!!   stops with CM_NO_CONVERGENCE and the time.
!! - Compensated (Kahan) summation of y_{n+1} = y_n + h sum_i b_i f_i, so that round-off
!!   does not random-walk the invariants.
!! - Outputs: every step, or t_eval on the collocation polynomial (degree s); dense
!!   output and events on the same polynomial (power basis).
!! - Step by step (SciPy's OdeSolver use, conmech.Gauss4 / Gauss6): `gauss_solve` with the
!!   packed state (r_state(GAUSS_NR), i_state(GAUSS_NI), w_state(n, GAUSS_NW)) and
!!   action 0 (start) or 1 (one step): the steps of the whole run, bit for bit.
module conmech_gauss
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system, ode_events
    use conmech_ode_solver, only: ode_options, ode_result
    use conmech_radau_common
    implicit none
    private

    public :: gauss_solve, gauss_tableau

    integer, parameter :: MAX_ITER = 50
    !> Sizes of the packed state of a step-by-step run: reals (t0, tf, t, h, t_old),
    !! integers (n, s, steps done, steps, nfev, naccept, polynomial known, started),
    !! columns (y, the compensation of the summation, the polynomial fc(:, 0:s) of the
    !! last step in x = (t - t_old)/h).
    integer, parameter, public :: GAUSS_NR = 8, GAUSS_NI = 8, GAUSS_NW = 6

contains

    !> Butcher tableau (a, b, c) of the s-stage Gauss-Legendre method, s = 2 or 3.
    pure subroutine gauss_tableau(s, a, b, c)
        integer, intent(in) :: s
        real(dp), intent(out) :: a(s, s), b(s), c(s)
        real(dp) :: r3, r15
        if (s == 2) then
            r3 = sqrt(3.0_dp)
            c = [0.5_dp - r3/6.0_dp, 0.5_dp + r3/6.0_dp]
            b = [0.5_dp, 0.5_dp]
            a(1, :) = [0.25_dp, 0.25_dp - r3/6.0_dp]
            a(2, :) = [0.25_dp + r3/6.0_dp, 0.25_dp]
        else
            r15 = sqrt(15.0_dp)
            c = [0.5_dp - r15/10.0_dp, 0.5_dp, 0.5_dp + r15/10.0_dp]
            b = [5.0_dp/18.0_dp, 4.0_dp/9.0_dp, 5.0_dp/18.0_dp]
            a(1, :) = [5.0_dp/36.0_dp, 2.0_dp/9.0_dp - r15/15.0_dp, 5.0_dp/36.0_dp - r15/30.0_dp]
            a(2, :) = [5.0_dp/36.0_dp + r15/24.0_dp, 2.0_dp/9.0_dp, 5.0_dp/36.0_dp - r15/24.0_dp]
            a(3, :) = [5.0_dp/36.0_dp + r15/30.0_dp, 2.0_dp/9.0_dp + r15/15.0_dp, 5.0_dp/36.0_dp]
        end if
    end subroutine gauss_tableau

    !> Solve y' = f(t, y) on t_span with the s-stage Gauss method (s = 2: opt%method =
    !! METHOD_GAUSS4, s = 3: METHOD_GAUSS6), fixed step opt%first_step; outputs as
    !! `ode_solve`.
    subroutine gauss_solve(sys, s, t_span, y0, opt, res, t_eval, events, r_state, i_state, &
                           w_state, action)
        class(ode_system), intent(in) :: sys
        integer, intent(in) :: s
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: y0(:)
        type(ode_options), intent(in) :: opt
        type(ode_result), intent(inout) :: res
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        !> step-by-step use: the packed state and the action (0: start, 1: one step)
        real(dp), intent(inout), optional :: r_state(:)
        integer, intent(inout), optional :: i_state(:)
        real(dp), intent(inout), optional :: w_state(:, :)
        integer, intent(in), optional :: action

        type(step_output) :: o
        real(dp) :: a(s, s), b(s), c(s), pmat(s, s), h, t0, tf, t, tnew, tstop, xi
        real(dp), allocatable :: y(:), comp(:), z(:, :), znew(:, :), f(:, :), fc(:, :)
        real(dp), allocatable :: ynew(:), ystop(:), incr(:), tmp(:)
        real(dp) :: dyno, dynold, scale
        integer :: n, nsteps, k, i, j, it, kstart, kdone
        logical :: converged, stop_now, have_poly, stepping, resume
        real(dp) :: t_prev
        character(len=:), allocatable :: m2
        character(len=32) :: buf

        n = size(y0)
        t0 = t_span(1)
        tf = t_span(2)
        h = 0.0_dp
        res%status = CM_BAD_INPUT
        if (s /= 2 .and. s /= 3) then
            res%message = "bad input: Gauss methods have s = 2 or 3 stages"
        else if (n < 1) then
            res%message = "bad input: y0 is empty"
        else if (.not. all(ieee_is_finite(y0))) then
            res%message = "bad input: y0 contains NaN or Inf"
        else if (.not. (ieee_is_finite(t0) .and. ieee_is_finite(tf))) then
            res%message = "bad input: t_span must be finite"
        else if (.not. (opt%first_step > 0.0_dp .and. opt%first_step < huge(1.0_dp))) then
            res%message = "bad input: Gauss methods are fixed-step methods and need a " &
                          //"step (first_step > 0)"
        else
            res%status = CM_SUCCESS
        end if
        if (res%status == CM_SUCCESS .and. present(t_eval)) then
            call check_t_eval(t_span, t_eval, res%status, m2)
            if (res%status /= CM_SUCCESS) res%message = m2
        end if
        stepping = present(action) .and. present(r_state) .and. present(i_state) .and. &
                   present(w_state)
        resume = .false.
        if (stepping) resume = action == 1
        if (res%status == CM_SUCCESS .and. stepping) then
            if (present(t_eval) .or. present(events) .or. size(r_state) < GAUSS_NR .or. &
                size(i_state) < GAUSS_NI .or. size(w_state, 1) /= n .or. &
                size(w_state, 2) < GAUSS_NW) then
                res%status = CM_BAD_INPUT
                res%message = "bad input: the packed Gauss state has the wrong size (or "// &
                              "t_eval, events given to a step-by-step integration)"
            else if (resume .and. (i_state(1) /= n .or. i_state(2) /= s .or. &
                                   i_state(8) /= 1)) then
                res%status = CM_BAD_INPUT
                res%message = "bad input: the Gauss state was not started (action 0 first)"
            end if
        end if
        if (res%status /= CM_SUCCESS) return

        call gauss_tableau(s, a, b, c)
        pmat = power_basis_matrix(c)
        allocate (y(n), comp(n), z(n, s), znew(n, s), f(n, s), fc(n, 0:s), ynew(n), &
                  ystop(n), incr(n), tmp(n))
        y = y0
        comp = 0.0_dp
        t = t0
        t_prev = t0
        kdone = 0
        fc = 0.0_dp
        if (.not. stepping) call out_init(o, res, opt, t0, tf, y0, s, t_eval, events)
        nsteps = 0
        if (tf /= t0) nsteps = max(1, ceiling(abs(tf - t0)/opt%first_step*(1.0_dp - 1.0e-12_dp)))
        if (nsteps > opt%max_steps) then
            write (buf, '(i0)') nsteps
            call finish(CM_TOO_MANY_STEPS, "too many steps: the run needs "//trim(buf)// &
                        " steps of first_step, more than max_steps")
            return
        end if
        h = 0.0_dp
        if (nsteps > 0) h = (tf - t0)/real(nsteps, dp)
        have_poly = .false.
        z = 0.0_dp
        kstart = 1
        if (resume) then
            call load_state()
            kstart = kdone + 1
        else if (stepping) then
            call finish(CM_SUCCESS, "success")
            return
        end if

        do k = kstart, nsteps
            ! starting values: the previous collocation polynomial, u(1 + c_i) - u(1)
            if (have_poly) then
                do i = 1, s
                    xi = 1.0_dp + c(i)
                    z(:, i) = 0.0_dp
                    do j = 1, s
                        z(:, i) = z(:, i) + fc(:, j)*(xi**j - 1.0_dp)
                    end do
                end do
            end if
            scale = max(maxval(abs(y)), tiny(1.0_dp))
            dynold = huge(1.0_dp)
            converged = .false.
            do it = 1, MAX_ITER
                do i = 1, s
                    call sys%rhs(t + c(i)*h, y + z(:, i), f(:, i))
                end do
                res%stats%nfev = res%stats%nfev + s
                if (.not. all(ieee_is_finite(f))) exit
                znew = h*matmul(f, transpose(a))
                dyno = maxval(abs(znew - z))
                z = znew
                ! converged when the correction vanishes or stops decreasing at the
                ! round-off level (GNI's criterion)
                if (dyno == 0.0_dp) then
                    converged = .true.
                    exit
                end if
                if (it >= 2 .and. dyno >= dynold .and. dyno <= 1.0e3_dp*epsilon(1.0_dp)*scale) &
                    then
                    converged = .true.
                    exit
                end if
                dynold = dyno
            end do
            if (.not. converged) then
                write (buf, '(es14.6)') t
                call finish(CM_NO_CONVERGENCE, "the fixed-point iteration of the Gauss " &
                            //"stages did not converge at t ="//trim(buf)// &
                            " (step too large, or a stiff or non-finite right-hand side)")
                return
            end if
            ! compensated summation of y + h sum b_i f_i
            incr = h*matmul(f, b)
            tmp = incr + comp
            ynew = y + tmp
            comp = (y - ynew) + tmp
            ! collocation polynomial: u(0) = y, u(c_i) = y + z_i
            fc(:, 0) = y
            do j = 1, s
                fc(:, j) = matmul(z, pmat(j, :))
            end do
            have_poly = .true.
            if (k == nsteps) then
                tnew = tf
            else
                tnew = t0 + real(k, dp)*h
            end if
            stop_now = .false.
            if (.not. stepping) call out_step(o, res, t, tnew - t, fc, ynew, stop_now, &
                                              tstop, ystop, t_eval, events)
            res%stats%naccept = res%stats%naccept + 1
            kdone = k
            t_prev = t
            if (stop_now) then
                t = tstop
                y = ystop
                call finish(CM_EVENT_STOP, "a termination event occurred")
                return
            end if
            y = ynew
            t = tnew
            if (stepping) exit           ! one step per call
        end do
        call finish(CM_SUCCESS, "success")

    contains

        subroutine finish(code, text)
            integer, intent(in) :: code
            character(len=*), intent(in) :: text
            res%status = code
            res%message = text
            res%success = code >= 0
            res%stats%h_next = h
            if (stepping) then
                r_state(1:GAUSS_NR) = [t0, tf, t, h, t_prev, 0.0_dp, 0.0_dp, 0.0_dp]
                i_state(1:GAUSS_NI) = [n, s, kdone, nsteps, res%stats%nfev, &
                                       res%stats%naccept, merge(1, 0, have_poly), 1]
                w_state(:, 1) = y
                w_state(:, 2) = comp
                w_state(:, 3:3 + s) = fc
            else
                call out_finish(o, res, t, y)
            end if
        end subroutine finish

        subroutine load_state()
            t = r_state(3)
            t_prev = r_state(5)
            kdone = i_state(3)
            res%stats%nfev = i_state(5)
            res%stats%naccept = i_state(6)
            have_poly = i_state(7) /= 0
            y = w_state(:, 1)
            comp = w_state(:, 2)
            fc = w_state(:, 3:3 + s)
        end subroutine load_state

    end subroutine gauss_solve

end module conmech_gauss
