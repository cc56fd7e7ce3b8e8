!> Periodic orbits by multiple shooting or orthogonal collocation (conmech_orbit_bvp):
!! Newton's method with the structured solve of conmech_block_chain, mesh adaptation for
!! collocation, the closure checked by independent integrations, and the multipliers from
!! the segment (or interval) transfer matrices by the periodic eigenvalue method.
!!
!! `find_orbit_bvp` is what `find_periodic_orbit` and `find_symmetric_orbit` call when
!! shooting_options%discretisation is ORBIT_MULTIPLE or ORBIT_COLLOCATION. Its Newton
!! iteration stops when |dX| <= tol max(1, |X|) and the residual (before the step) <=
!! sqrt(tol), as single shooting's; the problem is then evaluated once more at the result,
!! whose residual and transfer matrices are those reported. A collocation solution is
!! accepted only if independent integrations (DOP853 at the options' tolerances) from each
!! mesh node reach the next node to max(1e-8, 1e3 max(rtol, atol)) max(1, |y|):
!! otherwise the mesh does not resolve the orbit and the message says so.
module conmech_orbit_newton
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options
    use conmech_variational, only: integrate_stm
    use conmech_orbit_types
    use conmech_orbit_bvp
    use conmech_multiple_shooting, only: ms_evaluate, ms_guess, segment_closure, &
                                         bvp_ode_options
    use conmech_collocation, only: co_evaluate, co_guess
    use conmech_collocation_mesh, only: co_adapt
    use conmech_periodic_multipliers, only: product_multipliers
    use conmech_floquet, only: floquet_from_multipliers
    implicit none
    private

    public :: bvp_evaluate, bvp_newton, find_orbit_bvp, bvp_full_factors, bvp_closure_tol

contains

    !> Residuals, linearisation and boundary rows of the problem at X.
    subroutine bvp_evaluate(bvp, sys, set_param, x, info, msg, energy)
        type(orbit_bvp), intent(inout) :: bvp
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        real(dp), intent(in) :: x(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        procedure(energy_fun), optional :: energy
        if (bvp%method == ORBIT_COLLOCATION) then
            call co_evaluate(bvp, sys, set_param, x, info, msg)
        else
            call ms_evaluate(bvp, sys, set_param, x, info, msg)
        end if
        if (info /= CM_SUCCESS) return
        call bvp_boundary(bvp, x, energy)
        if (.not. (all(abs(bvp%gres) <= huge(1.0_dp)) .and. &
                   all(abs(bvp%bres) <= huge(1.0_dp)))) then
            info = CM_NONFINITE
            msg = "non-finite residuals (a bad guess?)"
        end if
    end subroutine bvp_evaluate

    !> Newton's method on the problem from X (no extra rows): on success the last
    !! evaluation is at the returned X. `residual`: its max |residual|.
    subroutine bvp_newton(bvp, sys, set_param, x, max_iter, tol, rcond, it, residual, info, &
                          msg, energy)
        type(orbit_bvp), intent(inout) :: bvp
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        real(dp), intent(inout) :: x(:)
        integer, intent(in) :: max_iter
        real(dp), intent(in) :: tol, rcond
        integer, intent(out) :: it, info
        real(dp), intent(out) :: residual
        character(len=:), allocatable, intent(out) :: msg
        procedure(energy_fun), optional :: energy
        real(dp) :: dx(size(x)), e0(0, bvp%n), ew(0, bvp%nw), er(0)
        integer :: rank, iter
        logical :: done
        done = .false.
        residual = huge(1.0_dp)
        it = 0
        do iter = 1, max_iter + 1
            call bvp_evaluate(bvp, sys, set_param, x, info, msg, energy)
            if (info /= CM_SUCCESS) return
            residual = bvp_residual(bvp)
            if (done) then
                info = CM_SUCCESS
                msg = "success"
                return
            end if
            if (iter > max_iter) exit
            it = iter
            call bvp_solve(bvp, e0, ew, er, 1.0_dp, dx, rank, info, rcond)
            if (info /= CM_SUCCESS .or. rank < 2*bvp%n + bvp%nw) then
                info = CM_SINGULAR
                msg = "singular Newton matrix (the orbit is not isolated: fix the energy "// &
                      "or the period?)"
                return
            end if
            x = x + dx
            if (bvp%tfree) then
                if (.not. (bvp_span(bvp, x) > 0.0_dp)) then
                    info = CM_NO_CONVERGENCE
                    msg = "the period became non-positive"
                    return
                end if
            end if
            done = maxval(abs(dx)) <= tol*max(1.0_dp, maxval(abs(x))) .and. &
                   residual <= sqrt(tol)
        end do
        info = CM_NO_CONVERGENCE
        msg = "Newton did not converge"
    end subroutine bvp_newton

    !> The closure tolerance of the independent check: max(1e-8, 1e3 max(rtol, atol))
    !! max(1, |y|).
    pure real(dp) function bvp_closure_tol(bvp, x) result(tl)
        type(orbit_bvp), intent(in) :: bvp
        real(dp), intent(in) :: x(:)
        tl = max(1.0e-8_dp, 1.0e3_dp*max(bvp%rtol, bvp%atol))*bvp_state_scale(bvp, x)
    end function bvp_closure_tol

    !> The transfer matrices over the whole period (the last evaluation's for a periodic
    !! problem; for a symmetric one, those of [0, tau] followed by STMs integrated over
    !! the rest of the period, period_factor tau, in as many segments per tau) and the
    !! vector field at their ends.
    subroutine bvp_full_factors(bvp, sys, x, period_factor, phi, fs, fe, info, msg)
        type(orbit_bvp), intent(in) :: bvp
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: x(:), period_factor
        real(dp), allocatable, intent(out) :: phi(:, :, :), fs(:, :), fe(:, :)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(ode_options) :: oo
        real(dp) :: y(bvp%n), tau, t0, t1, dt
        integer :: n, k, kr, j, i
        n = bvp%n
        k = bvp%k
        info = CM_SUCCESS
        msg = "success"
        if (bvp%periodic) then
            phi = bvp%a
            fs = bvp%fstart
            fe = bvp%fend
            return
        end if
        kr = max(1, nint((period_factor - 1.0_dp)*k))
        allocate (phi(n, n, k + kr), fs(n, k + kr), fe(n, k + kr))
        phi(:, :, 1:k) = bvp%a
        fs(:, 1:k) = bvp%fstart
        fe(:, 1:k) = bvp%fend
        oo = bvp_ode_options(bvp)
        tau = bvp_span(bvp, x)
        dt = (period_factor - 1.0_dp)*tau/kr
        y = bvp_z(bvp, x, k + 1)
        do j = 1, kr
            t0 = tau + (j - 1)*dt
            t1 = tau + j*dt
            phi(:, :, k + j) = 0.0_dp
            do i = 1, n
                phi(i, i, k + j) = 1.0_dp
            end do
            call sys%rhs(t0, y, fs(:, k + j))
            call integrate_stm(sys, t0, t1, y, phi(:, :, k + j), oo, info, msg)
            if (info < 0) then
                msg = "the rest of the symmetric orbit: "//msg
                return
            end if
            call sys%rhs(t1, y, fe(:, k + j))
        end do
        info = CM_SUCCESS
    end subroutine bvp_full_factors

    !> A periodic orbit by multiple shooting or collocation (opt%discretisation), general
    !! (mode PO_FREE_PERIOD, PO_FIXED_PERIOD, PO_FIXED_ENERGY with energy/energy_value) or,
    !! with free and targets, symmetric (tau = period/period_factor, free if free_time).
    subroutine find_orbit_bvp(sys, y0, period, orbit, opt, mode, energy, energy_value, &
                              free, targets, free_time, period_factor)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: y0(:), period
        type(periodic_orbit), intent(out) :: orbit
        type(shooting_options), intent(in) :: opt
        integer, intent(in), optional :: mode
        procedure(energy_fun), optional :: energy
        real(dp), intent(in), optional :: energy_value
        integer, intent(in), optional :: free(:), targets(:)
        logical, intent(in), optional :: free_time
        real(dp), intent(in), optional :: period_factor
        class(ode_system), allocatable :: s
        type(orbit_bvp) :: bvp
        real(dp), allocatable :: x(:), xn(:), phi(:, :, :), fs(:, :), fe(:, :)
        real(dp) :: span, pf, closure, ratio, tl, res
        integer :: n, k, md, info, it, pass, j, itot
        logical :: sym, tfree
        character(len=:), allocatable :: msg, what
        character(len=32) :: b1, b2
        n = size(y0)
        sym = present(free) .and. present(targets)
        md = PO_FREE_PERIOD
        if (present(mode)) md = mode
        pf = 1.0_dp
        if (sym) pf = 2.0_dp
        if (present(period_factor)) pf = period_factor
        tfree = md /= PO_FIXED_PERIOD
        if (sym) then
            tfree = .false.
            if (present(free_time)) tfree = free_time
        end if
        span = period/pf
        k = opt%segments
        if (opt%discretisation == ORBIT_COLLOCATION) k = opt%intervals
        what = orbit_method_name(opt%discretisation)
        if (sym) then
            call bvp_setup(bvp, opt%discretisation, n, k, opt%degree, .false., tfree, &
                           .false., span, 0.0_dp, info, msg, free, targets, y0)
        else
            call bvp_setup(bvp, opt%discretisation, n, k, opt%degree, .true., tfree, &
                           .false., span, 0.0_dp, info, msg)
        end if
        orbit%discretisation = opt%discretisation
        orbit%iterations = 0
        if (info /= CM_SUCCESS) then
            call orbit%fail(info, what//": "//msg)
            return
        end if
        bvp%rtol = opt%rtol
        bvp%atol = opt%atol
        bvp%max_steps = opt%max_steps
        bvp%integrator = opt%method
        if (.not. sym .and. md == PO_FIXED_ENERGY) then
            bvp%energy_row = .true.
            bvp%energy_value = energy_value
        end if
        allocate (s, source=sys)
        bvp%yref = y0
        call s%rhs(0.0_dp, y0, bvp%fref)
        allocate (x(bvp%nx), xn(bvp%nx))
        x = 0.0_dp
        if (bvp%tfree) x(bvp_index_w(bvp, 1)) = span
        if (bvp%method == ORBIT_COLLOCATION) then
            call co_guess(bvp, s, y0, span, x, info, msg)
        else
            call ms_guess(bvp, s, y0, span, x, info, msg)
        end if
        if (info /= CM_SUCCESS) then
            call orbit%fail(info, what//": "//msg)
            return
        end if
        itot = 0
        do pass = 0, merge(max(0, opt%adapt), 0, bvp%method == ORBIT_COLLOCATION)
            if (pass > 0) then
                call co_adapt(bvp, bvp%tab, x, xn, ratio)
                x = xn
            end if
            call bvp_newton(bvp, s, no_parameter, x, opt%max_iter, opt%tol, opt%rcond, it, &
                            res, info, msg, energy)
            itot = itot + it
            if (info /= CM_SUCCESS) exit
        end do
        orbit%iterations = itot
        orbit%residual = res
        if (info /= CM_SUCCESS) then
            orbit%info = info
            write (b1, '(i0)') k
            if (bvp%method == ORBIT_COLLOCATION) then
                orbit%message = "collocation ("//trim(b1)//" intervals): "//msg
            else
                orbit%message = "multiple shooting ("//trim(b1)//" segments): "//msg
            end if
            return
        end if
        ! the closure by independent integrations from the nodes
        call segment_closure(bvp, s, x, closure, info, msg)
        tl = bvp_closure_tol(bvp, x)
        if (info < 0 .or. .not. (closure <= tl)) then
            orbit%info = CM_NO_CONVERGENCE
            write (b1, '(es9.2)') closure
            write (b2, '(es9.2)') tl
            if (bvp%method == ORBIT_COLLOCATION) then
                write (b1, '(i0,a,i0)') k, " intervals of degree ", bvp%m
                write (b2, '(es9.2)') closure
                orbit%message = "the collocation mesh ("//trim(b1)//") does not resolve "// &
                                "the orbit: independent integrations miss the next mesh "// &
                                "node by "//trim(adjustl(b2))//" (use more intervals or "// &
                                "a higher degree)"
            else
                orbit%message = "multiple shooting: the segments do not close under "// &
                                "independent integration ("//trim(adjustl(b1))//" > "// &
                                trim(adjustl(b2))//")"
            end if
            return
        end if
        orbit%y0 = bvp_z(bvp, x, 1)
        orbit%period = pf*bvp_span(bvp, x)
        orbit%degree = bvp%m
        allocate (orbit%nodes(n, k + 1), orbit%node_times(k + 1))
        do j = 1, k + 1
            orbit%nodes(:, j) = bvp_z(bvp, x, j)
        end do
        orbit%node_times = bvp%mesh*bvp_span(bvp, x)
        call bvp_full_factors(bvp, s, x, pf, phi, fs, fe, info, msg)
        if (info < 0) then
            call orbit%fail(info, msg)
            return
        end if
        call product_multipliers(phi, orbit%multipliers, fs, fe, max(opt%rtol, opt%atol))
        orbit%monodromy = phi(:, :, 1)
        do j = 2, size(phi, 3)
            orbit%monodromy = matmul(phi(:, :, j), orbit%monodromy)
        end do
        call floquet_from_multipliers(orbit%multipliers, orbit%monodromy, orbit%period, &
                                      orbit%floquet)
        if (orbit%multipliers%info /= CM_SUCCESS) then
            call orbit%fail(orbit%multipliers%info, "the periodic eigenvalue iteration failed")
            return
        end if
        orbit%info = CM_SUCCESS
        orbit%message = "success"
    end subroutine find_orbit_bvp

end module conmech_orbit_newton
