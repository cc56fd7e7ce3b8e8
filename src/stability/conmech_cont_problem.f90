!> The equations a continuation of periodic orbits follows (see conmech_continuation):
!! their evaluation, Newton corrector with one extra row, and the branch point made of a
!! corrected X (tangent, multipliers, test functions), for single shooting (general or
!! symmetric, dense Gauss-Newton by LAPACK dgelsd) or for the boundary-value discretisations
!! of conmech_orbit_bvp (multiple shooting, collocation: the structured solve of
!! conmech_block_chain). The problem's set-up and unknowns: conmech_cont_setup.
module conmech_cont_problem
    use conmech_kinds, only: dp
    use conmech_central_step, only: central_step
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_integrate
    use conmech_variational, only: integrate_stm
    use conmech_orbit_types, only: set_parameter_proc, ORBIT_SINGLE
    use conmech_block_chain, only: lstsq_solve
    use conmech_orbit_bvp
    use conmech_orbit_newton, only: bvp_evaluate, bvp_full_factors
    use conmech_multiple_shooting, only: segment_closure
    use conmech_periodic_multipliers, only: multiplier_set, product_multipliers
    use conmech_multiplier_tests, only: multiplier_tests
    use conmech_branch_types
    use conmech_cont_setup
    implicit none
    private

    public :: cproblem, cconstraint, branch_energy, CON_LINEAR, CON_ENERGY
    public :: cp_setup, cp_pack_start, cp_unpack, cp_set_reference, cp_correct
    public :: cp_make_point, cp_closure, cp_rdot, cp_rnorm, cp_energy_row, cp_evaluate

contains

    !> Single shooting: G(X), DG(X) and the STM over the integration time into pb.
    subroutine evaluate_single(sys, set_param, pb, x, info, msg)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(inout) :: pb
        real(dp), intent(in) :: x(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(ode_options) :: oo
        real(dp) :: y(pb%n), y0(pb%n), yp(pb%n), ym(pb%n), f(pb%n), tend, per, p, h
        integer :: j, n, nf
        n = pb%n
        if (.not. allocated(pb%g)) allocate (pb%g(pb%neq), pb%dg(pb%neq, pb%nx), &
                                             pb%phi(n, n))
        oo%rtol = pb%o%rtol
        oo%atol = pb%o%atol
        oo%method = pb%o%integrator
        call cp_unpack(pb, x, y0, tend, per, p)
        h = pb%o%fd_step*max(1.0_dp, abs(p))
        if (.not. (tend > 0.0_dp)) then
            info = CM_NO_CONVERGENCE
            msg = "the period became non-positive"
            return
        end if
        if (.not. pb%o%in_period) then
            call set_param(sys, p + h)
            yp = y0
            call ode_integrate(sys, 0.0_dp, tend, yp, oo, info, message=msg)
            if (info < 0) return
            call set_param(sys, p - h)
            ym = y0
            call ode_integrate(sys, 0.0_dp, tend, ym, oo, info, message=msg)
            if (info < 0) return
            call set_param(sys, p)
        end if
        y = y0
        pb%phi = 0.0_dp
        do j = 1, n
            pb%phi(j, j) = 1.0_dp
        end do
        call integrate_stm(sys, 0.0_dp, tend, y, pb%phi, oo, info, msg)
        if (info < 0) return
        call sys%rhs(tend, y, f)
        pb%dg = 0.0_dp
        if (pb%sym) then
            nf = size(pb%free)
            pb%g = y(pb%targets)
            do j = 1, nf
                pb%dg(:, j) = pb%phi(pb%targets, pb%free(j))
            end do
            if (pb%tfree) pb%dg(:, nf + 1) = f(pb%targets)
            if (pb%o%in_period) then
                pb%dg(:, pb%nx) = f(pb%targets)
            else
                pb%dg(:, pb%nx) = (yp(pb%targets) - ym(pb%targets))/(2.0_dp*h)
            end if
        else
            pb%g(1:n) = y - y0
            pb%dg(1:n, 1:n) = pb%phi
            do j = 1, n
                pb%dg(j, j) = pb%dg(j, j) - 1.0_dp
            end do
            if (pb%tfree) pb%dg(1:n, n + 1) = f
            if (pb%o%in_period) then
                pb%dg(1:n, pb%nx) = f                  ! d y(T)/dT
            else
                pb%dg(1:n, pb%nx) = (yp - ym)/(2.0_dp*h)
            end if
            if (pb%o%autonomous) then
                pb%g(n + 1) = dot_product(pb%fref, y0 - pb%yref)
                pb%dg(n + 1, 1:n) = pb%fref
            end if
        end if
        info = CM_SUCCESS
        if (.not. (all(abs(pb%g) <= huge(1.0_dp)) .and. all(abs(pb%dg) <= huge(1.0_dp)))) then
            info = CM_NONFINITE
            msg = "non-finite values"
        end if
    end subroutine evaluate_single

    !> Evaluate the equations at X (kept in pb for the solves and cp_make_point) and
    !! return max |G|.
    subroutine cp_evaluate(sys, set_param, pb, x, res, info, msg)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(inout) :: pb
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: res
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        res = huge(1.0_dp)
        if (is_bvp(pb)) then
            call bvp_evaluate(pb%bvp, sys, set_param, x, info, msg)
            if (info == CM_SUCCESS) res = bvp_residual(pb%bvp)
            if (pb%bvp%pfree) call set_param(sys, bvp_param(pb%bvp, x))
        else
            call evaluate_single(sys, set_param, pb, x, info, msg)
            if (info == CM_SUCCESS) res = maxval(abs(pb%g))
        end if
    end subroutine cp_evaluate

    !> The linear system of the last evaluation bordered by `nr` rows (rows(nr, nx), rhs):
    !! dx = the least-squares solution of [DG; rows] dx = [-scale G; rhs]. rank: full is nx
    !! (single) or 2n + nw (the reduced system of the structured solve).
    subroutine solve_bordered(pb, rows, rhs, scale, dx, rank, full, info)
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: rows(:, :), rhs(:), scale
        real(dp), intent(out) :: dx(:)
        integer, intent(out) :: rank, full, info
        real(dp), allocatable :: a(:, :), r(:), ez(:, :), ew(:, :)
        integer :: nr, nw
        nr = size(rhs)
        if (is_bvp(pb)) then
            nw = pb%bvp%nw
            ez = rows(:, 1:pb%n)
            ew = rows(:, pb%nx - nw + 1:pb%nx)
            call bvp_solve(pb%bvp, ez, ew, rhs, scale, dx, rank, info, pb%o%rcond)
            full = 2*pb%n + nw
            return
        end if
        allocate (a(pb%neq + nr, pb%nx), r(pb%neq + nr))
        a(1:pb%neq, :) = pb%dg
        a(pb%neq + 1:, :) = rows
        r(1:pb%neq) = -scale*pb%g
        r(pb%neq + 1:) = rhs
        call lstsq_solve(a, r, dx, rank, info, pb%o%rcond)
        full = pb%nx
    end subroutine solve_bordered

    !> The row and residual of the energy constraint E(y0(X), p(X)) = b (gradient by central
    !! differences in the reduced unknowns that carry y0 and p).
    subroutine cp_energy_row(pb, x, energy, b, row, r)
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: x(:), b
        class(branch_energy), intent(in) :: energy
        real(dp), intent(out) :: row(:), r
        real(dp) :: y(pb%n), tend, per, p, xp(size(x)), h, ep, em
        integer :: j, ny
        call cp_unpack(pb, x, y, tend, per, p)
        r = energy%value(y, p) - b
        row = 0.0_dp
        ny = pb%n
        if (pb%sym .and. .not. is_bvp(pb)) ny = size(pb%free)
        do j = 1, pb%nx
            if (j > ny .and. j /= pb%nx) cycle
            if (j == pb%nx .and. pb%o%in_period) cycle
            h = central_step(x(j))
            xp = x
            xp(j) = x(j) + h
            call cp_unpack(pb, xp, y, tend, per, p)
            ep = energy%value(y, p)
            xp(j) = x(j) - h
            call cp_unpack(pb, xp, y, tend, per, p)
            em = energy%value(y, p)
            row(j) = (ep - em)/(2.0_dp*h)
        end do
    end subroutine cp_energy_row

    !> Newton corrector with the extra row `con` (a . X = b, or the energy). first: the
    !! start, at fixed p (single shooting: without the p column, as Gauss-Newton in the
    !! remaining unknowns). On success the last evaluation (kept in pb) is one step (<= tol)
    !! before X.
    subroutine cp_correct(sys, set_param, pb, x, con, first, it, info, msg, energy)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(inout) :: pb
        real(dp), intent(inout) :: x(:)
        type(cconstraint), intent(in) :: con
        logical, intent(in) :: first
        integer, intent(out) :: it, info
        character(len=:), allocatable, intent(out) :: msg
        class(branch_energy), intent(in), optional :: energy
        real(dp) :: dx(pb%nx), res, row(1, pb%nx), rr(1), cres
        integer :: rank, full, nun
        if (first) call cp_set_reference(sys, set_param, pb, x)
        msg = "Newton did not converge"
        info = CM_NO_CONVERGENCE
        do it = 1, pb%o%max_iter
            call cp_evaluate(sys, set_param, pb, x, res, info, msg)
            if (info /= CM_SUCCESS) return
            if (con%kind == CON_ENERGY .and. present(energy)) then
                call cp_energy_row(pb, x, energy, con%b, row(1, :), cres)
            else
                row(1, :) = con%a
                cres = dot_product(con%a, x) - con%b
            end if
            rr(1) = -cres
            if (first .and. .not. is_bvp(pb)) then
                nun = pb%nx - 1
                call lstsq_solve(pb%dg(:, 1:nun), -pb%g, dx(1:nun), rank, info, pb%o%rcond)
                dx(pb%nx) = 0.0_dp
                full = min(nun, pb%neq)
            else
                call solve_bordered(pb, row, rr, 1.0_dp, dx, rank, full, info)
            end if
            if (info == CM_SUCCESS .and. rank < full) info = CM_SINGULAR
            if (info /= CM_SUCCESS) then
                msg = "singular Newton matrix (the orbit is not isolated?)"
                return
            end if
            x = x + dx
            if (maxval(abs(dx)) <= pb%o%tol*max(1.0_dp, maxval(abs(x))) .and. &
                res <= pb%o%res_tol) then
                info = CM_SUCCESS
                msg = "success"
                return
            end if
            info = CM_NO_CONVERGENCE
            if (maxval(abs(dx)) > 1.0e3_dp*max(1.0_dp, maxval(abs(x)))) exit
        end do
        msg = "Newton did not converge"
    end subroutine cp_correct

    !> The branch point at X from the last evaluation: the unit tangent (solving
    !! [DG; t_old] t = [0; 1] in the reduced norm; t is the old tangent on entry, the new
    !! one on exit; kept as given with keep_t), period, state, multipliers (periodic
    !! eigenvalues of the segment factors, with their errors), test functions.
    subroutine cp_make_point(sys, set_param, pb, x, t, it, ds, pt, info, keep_t)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(inout) :: pb
        real(dp), intent(in) :: x(:), ds
        real(dp), intent(inout) :: t(:)
        integer, intent(in) :: it
        type(cont_point), intent(out) :: pt
        integer, intent(out) :: info
        logical, intent(in), optional :: keep_t
        real(dp) :: y(pb%n), tend, per, psi(3), tn(pb%nx), row(1, pb%nx), rr(1), trace
        real(dp), allocatable :: phi(:, :, :), fs(:, :), fe(:, :), rows(:, :), rhs(:)
        type(ode_options) :: oo
        type(multiplier_set) :: ms
        character(len=:), allocatable :: msg
        integer :: j, rank, full, nw
        logical :: keep
        keep = .false.
        if (present(keep_t)) keep = keep_t
        call cp_unpack(pb, x, y, tend, per, pt%p)
        pt%period = per
        pt%y0 = y
        pt%iterations = it
        pt%ds = ds
        if (is_bvp(pb)) then
            pt%residual = bvp_residual(pb%bvp)
        else
            pt%residual = maxval(abs(pb%g))
        end if
        if (keep .and. is_bvp(pb)) then
            ! the full tangent with its reduced part as given (consistent: DG t = 0)
            nw = pb%bvp%nw
            allocate (rows(pb%n + nw, pb%nx), rhs(pb%n + nw))
            rows = 0.0_dp
            do j = 1, pb%n
                rows(j, j) = 1.0_dp
                rhs(j) = t(j)
            end do
            do j = 1, nw
                rows(pb%n + j, pb%nx - nw + j) = 1.0_dp
                rhs(pb%n + j) = t(pb%nx - nw + j)
            end do
            call solve_bordered(pb, rows, rhs, 0.0_dp, tn, rank, full, info)
            if (info /= CM_SUCCESS) return
            t = tn/cp_rnorm(pb, tn)
        else if (.not. keep) then
            row(1, :) = t
            if (is_bvp(pb)) then
                nw = pb%bvp%nw
                row(1, pb%n + 1:pb%nx - nw) = 0.0_dp
            end if
            rr(1) = 1.0_dp
            call solve_bordered(pb, row, rr, 0.0_dp, tn, rank, full, info)
            if (info /= CM_SUCCESS) return
            if (rank < full .or. .not. (cp_rnorm(pb, tn) > 0.0_dp)) then
                info = CM_SINGULAR
                return
            end if
            t = tn/cp_rnorm(pb, tn)
        end if
        if (.not. pb%o%in_period) call set_param(sys, pt%p)
        ! the transfer matrices over the full period and the vector field at their ends
        if (is_bvp(pb)) then
            call bvp_full_factors(pb%bvp, sys, x, pb%pf, phi, fs, fe, info, msg)
            if (info < 0) return
        else
            allocate (phi(pb%n, pb%n, 1), fs(pb%n, 1), fe(pb%n, 1))
            call sys%rhs(0.0_dp, y, fs(:, 1))
            if (pb%sym) then
                oo%rtol = pb%o%rtol
                oo%atol = pb%o%atol
                oo%method = pb%o%integrator
                phi(:, :, 1) = 0.0_dp
                do j = 1, pb%n
                    phi(j, j, 1) = 1.0_dp
                end do
                call integrate_stm(sys, 0.0_dp, per, y, phi(:, :, 1), oo, info, msg)
                if (info < 0) return
            else
                phi(:, :, 1) = pb%phi
                y = y + pb%g(1:pb%n)
            end if
            call sys%rhs(per, y, fe(:, 1))
        end if
        call product_multipliers(phi, ms, fs, fe, max(pb%o%rtol, pb%o%atol))
        if (ms%info /= CM_SUCCESS) then
            info = ms%info
            return
        end if
        if (is_bvp(pb)) then
            trace = sum(ms%mr)
        else
            trace = 0.0_dp
            do j = 1, pb%n
                trace = trace + phi(j, j, 1)
            end do
        end if
        call multiplier_tests(ms, pb%ntriv, &
                              pb%o%conservative, trace, psi, pt%stability_index, info)
        if (info /= CM_SUCCESS) return
        pt%mr = ms%mr
        pt%mi = ms%mi
        pt%merr = ms%err
        pt%accuracy = ms%accuracy
        pt%psi(1) = t(pb%nx)
        pt%psi(2:4) = psi
    end subroutine cp_make_point

    !> The true closure of the orbit of X by independent integrations of the state alone
    !! (DOP853 at the continuation's tolerances): |y(T) - y0| over the full period for
    !! single shooting, the largest miss of a node for multiple shooting and collocation
    !! (for a symmetric orbit also the targets at tau).
    subroutine cp_closure(sys, set_param, pb, x, closure, info)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: closure
        integer, intent(out) :: info
        type(ode_options) :: oo
        real(dp) :: y(pb%n), y1(pb%n), tend, per, p
        character(len=:), allocatable :: msg
        closure = huge(1.0_dp)
        call cp_unpack(pb, x, y, tend, per, p)
        if (.not. pb%o%in_period) call set_param(sys, p)
        if (is_bvp(pb)) then
            call segment_closure(pb%bvp, sys, x, closure, info, msg)
            if (pb%sym .and. info >= 0) then
                y1 = bvp_z(pb%bvp, x, pb%bvp%k + 1)
                closure = max(closure, maxval(abs(y1(pb%targets))))
            end if
            return
        end if
        oo%rtol = pb%o%rtol
        oo%atol = pb%o%atol
        oo%method = pb%o%integrator
        y1 = y
        call ode_integrate(sys, 0.0_dp, per, y1, oo, info, message=msg)
        if (info < 0) return
        closure = maxval(abs(y1 - y))
    end subroutine cp_closure

end module conmech_cont_problem
