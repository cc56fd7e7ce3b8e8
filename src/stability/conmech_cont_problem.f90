!> The equations a continuation of periodic orbits follows (see conmech_continuation):
!! their unknowns X, evaluation, Newton corrector with one extra row, and the branch point
!! made of a corrected X (tangent, multipliers, test functions), for single shooting
!! (general or symmetric, dense Gauss-Newton by LAPACK dgelsd) or for the boundary-value
!! discretisations of conmech_orbit_bvp (multiple shooting, collocation: the structured
!! solve of conmech_block_chain).
!!
!! The reduced unknowns: single shooting, all of X; multiple shooting and collocation,
!! the first node z_1 and the border unknowns (S, p) only. Tangents are normalised and the
!! pseudo-arclength equation written in them, so that a step `ds` means the same for every
!! discretisation.
module conmech_cont_problem
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_integrate
    use conmech_variational, only: integrate_stm
    use conmech_orbit_types, only: set_parameter_proc, ORBIT_SINGLE, ORBIT_COLLOCATION
    use conmech_block_chain, only: lstsq_solve
    use conmech_orbit_bvp
    use conmech_orbit_newton, only: bvp_evaluate, bvp_full_factors
    use conmech_multiple_shooting, only: ms_guess, segment_closure
    use conmech_collocation, only: co_guess
    use conmech_periodic_multipliers, only: multiplier_set, product_multipliers
    use conmech_multiplier_tests, only: multiplier_tests
    use conmech_branch_types
    implicit none
    private

    public :: cproblem, cconstraint, branch_energy, CON_LINEAR, CON_ENERGY
    public :: cp_setup, cp_pack_start, cp_unpack, cp_set_reference, cp_correct
    public :: cp_make_point, cp_closure, cp_rdot, cp_rnorm, cp_energy_row, cp_evaluate

    integer, parameter :: CON_LINEAR = 1  !! a . X = b
    integer, parameter :: CON_ENERGY = 2  !! E(y0(X), p(X)) = b

    !> The continued problem.
    type :: cproblem
        integer :: n = 0, nx = 0, neq = 0
        logical :: sym = .false., tfree = .true.
        integer, allocatable :: free(:), targets(:)
        real(dp) :: pf = 2.0_dp, tfix = 0.0_dp
        real(dp), allocatable :: ybase(:), yref(:), fref(:)
        type(cont_options) :: o
        integer :: ntriv = 0
        type(orbit_bvp) :: bvp                    !! multiple shooting / collocation
        ! the last single-shooting evaluation
        real(dp), allocatable :: g(:), dg(:, :), phi(:, :)
    end type cproblem

    !> The extra row of the corrector.
    type :: cconstraint
        integer :: kind = CON_LINEAR
        real(dp), allocatable :: a(:)
        real(dp) :: b = 0.0_dp
    end type cconstraint

    !> An energy (first integral) E(y, p) along a branch: extend it and implement `value`.
    type, abstract :: branch_energy
    contains
        procedure(energy_value), deferred :: value
    end type branch_energy

    abstract interface
        function energy_value(self, y, p) result(e)
            import :: dp, branch_energy
            class(branch_energy), intent(in) :: self
            real(dp), intent(in) :: y(:), p
            real(dp) :: e
        end function energy_value
    end interface

contains

    logical function is_bvp(pb)
        type(cproblem), intent(in) :: pb
        is_bvp = pb%o%discretisation /= ORBIT_SINGLE
    end function is_bvp

    !> Set up the problem (see continue_orbits); a message names what is wrong.
    subroutine cp_setup(pb, y0, period, p0, free, targets, free_time, period_factor, info, &
                        msg)
        type(cproblem), intent(inout) :: pb
        real(dp), intent(in) :: y0(:), period, p0
        integer, intent(in), optional :: free(:), targets(:)
        logical, intent(in), optional :: free_time
        real(dp), intent(in), optional :: period_factor
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: nf, ntg, k
        character(len=64) :: b1
        pb%n = size(y0)
        info = CM_BAD_INPUT
        if (pb%n < 1 .or. .not. all(ieee_is_finite(y0)) .or. .not. (period > 0.0_dp) .or. &
            .not. ieee_is_finite(p0) .or. pb%o%max_points < 1 .or. &
            .not. (pb%o%ds > 0.0_dp) .or. .not. (pb%o%ds_min > 0.0_dp)) then
            msg = "continuation: bad input (empty or non-finite y0 or p0, period <= 0, "// &
                  "max_points < 1, ds <= 0)"
            return
        end if
        if (pb%o%discretisation < 1 .or. pb%o%discretisation > 3) then
            msg = "continuation: unknown discretisation"
            return
        end if
        pb%sym = present(free)
        if (pb%o%in_period .and. .not. pb%o%autonomous) then
            msg = "continuation: in_period is for autonomous systems"
            return
        end if
        if (pb%sym .neqv. present(targets)) then
            msg = "continuation: symmetric shooting needs both free and targets"
            return
        end if
        pb%ybase = y0
        if (present(period_factor)) pb%pf = period_factor
        if (pb%sym) then
            nf = size(free)
            ntg = size(targets)
            if (nf < 1 .or. ntg < 1 .or. any(free < 1) .or. &
                any(free > pb%n) .or. any(targets < 1) .or. any(targets > pb%n)) then
                msg = "continuation: free and targets must be state indices"
                return
            end if
            pb%free = free
            pb%targets = targets
            pb%tfree = .false.
            if (present(free_time)) pb%tfree = free_time
            if (pb%o%in_period .and. pb%tfree) then
                msg = "continuation: in_period continues in the time itself (free_time "// &
                    "must be false)"
                return
            end if
            if (.not. (pb%pf > 0.0_dp)) then
                msg = "continuation: period_factor must be positive"
                return
            end if
            if (nf + merge(1, 0, pb%tfree) /= ntg) then
                write (b1, '(i0,a,i0,a)') nf + merge(1, 0, pb%tfree), " unknowns (", nf, &
                    " free components"
                if (pb%tfree) b1 = trim(b1)//" + the time"
                msg = "continuation: "//trim(b1)//") for "// &
                      trim(adjustl(itoa(ntg)))//" targets: symmetric shooting needs as "// &
                      "many unknowns (free components, and the time if free) as targets "// &
                      "(the parameter is the one extra unknown of the branch)"
                return
            end if
            pb%tfix = period/pb%pf
            pb%nx = nf + 1
            if (pb%tfree) pb%nx = pb%nx + 1
            pb%neq = ntg
        else
            pb%pf = 1.0_dp
            pb%tfree = pb%o%autonomous .and. .not. pb%o%fixed_period .and. &
                       .not. pb%o%in_period
            pb%tfix = period
            pb%nx = pb%n + 1
            if (pb%tfree) pb%nx = pb%nx + 1
            pb%neq = pb%n
            if (pb%o%autonomous) pb%neq = pb%n + 1
        end if
        pb%ntriv = 0
        if (pb%o%autonomous) pb%ntriv = 1
        if (pb%o%conservative) pb%ntriv = pb%ntriv + 1
        allocate (pb%yref(pb%n), pb%fref(pb%n))
        pb%yref = y0
        pb%fref = 0.0_dp
        if (is_bvp(pb)) then
            k = pb%o%segments
            if (pb%o%discretisation == ORBIT_COLLOCATION) k = pb%o%intervals
            ! X = [nodes, stages, S (if free or continued), p (unless in_period)]
            if (pb%sym) then
                call bvp_setup(pb%bvp, pb%o%discretisation, pb%n, k, pb%o%degree, .false., &
                               pb%tfree .or. pb%o%in_period, .not. pb%o%in_period, &
                               pb%tfix, p0, info, msg, free, targets, y0)
            else
                call bvp_setup(pb%bvp, pb%o%discretisation, pb%n, k, pb%o%degree, .true., &
                               pb%tfree .or. pb%o%in_period, .not. pb%o%in_period, &
                               pb%tfix, p0, info, msg)
            end if
            if (info /= CM_SUCCESS) then
                msg = "continuation: "//msg
                return
            end if
            pb%bvp%autonomous = pb%o%autonomous
            pb%bvp%rtol = pb%o%rtol
            pb%bvp%atol = pb%o%atol
            pb%bvp%fd_step = pb%o%fd_step
            pb%nx = pb%bvp%nx
        end if
        info = CM_SUCCESS
        msg = "success"
    end subroutine cp_setup

    pure function itoa(k) result(s)
        integer, intent(in) :: k
        character(len=16) :: s
        write (s, '(i0)') k
    end function itoa

    !> X of the start (y0, period, p0); multiple shooting and collocation integrate y0
    !! over the period for the other nodes (info from that integration).
    subroutine cp_pack_start(sys, pb, y0, period, p0, x, info, msg)
        class(ode_system), intent(in) :: sys
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: y0(:), period, p0
        real(dp), intent(out) :: x(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: nf
        info = CM_SUCCESS
        msg = "success"
        x = 0.0_dp
        if (is_bvp(pb)) then
            if (pb%bvp%tfree) x(bvp_index_w(pb%bvp, 1)) = period/pb%pf
            if (pb%bvp%pfree) x(pb%nx) = p0
            if (pb%bvp%method == ORBIT_COLLOCATION) then
                call co_guess(pb%bvp, sys, y0, period/pb%pf, x, info, msg)
            else
                call ms_guess(pb%bvp, sys, y0, period/pb%pf, x, info, msg)
            end if
            return
        end if
        if (pb%sym) then
            nf = size(pb%free)
            x(1:nf) = y0(pb%free)
            if (pb%tfree) x(nf + 1) = period/pb%pf
        else
            x(1:pb%n) = y0
            if (pb%tfree) x(pb%n + 1) = period
        end if
        x(pb%nx) = p0
        if (pb%o%in_period) x(pb%nx) = period/pb%pf
    end subroutine cp_pack_start

    !> (full initial state, integration time, period, parameter) of X. With in_period
    !! the parameter is the period.
    pure subroutine cp_unpack(pb, x, y, tend, per, p)
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: y(:), tend, per, p
        integer :: nf
        if (pb%o%discretisation /= ORBIT_SINGLE) then
            y = bvp_z(pb%bvp, x, 1)
            tend = bvp_span(pb%bvp, x)
            per = pb%pf*tend
            p = bvp_param(pb%bvp, x)
            if (pb%o%in_period) p = per
            return
        end if
        if (pb%sym) then
            nf = size(pb%free)
            y = pb%ybase
            y(pb%free) = x(1:nf)
            tend = pb%tfix
            if (pb%tfree) tend = x(nf + 1)
        else
            y = x(1:pb%n)
            tend = pb%tfix
            if (pb%tfree) tend = x(pb%n + 1)
        end if
        if (pb%o%in_period) tend = x(pb%nx)
        per = pb%pf*tend
        p = x(pb%nx)
        if (pb%o%in_period) p = per
    end subroutine cp_unpack

    !> The phase condition's reference: the current point and its vector field.
    subroutine cp_set_reference(sys, set_param, pb, x)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(inout) :: pb
        real(dp), intent(in) :: x(:)
        real(dp) :: tend, per, p
        if (pb%sym .or. .not. pb%o%autonomous) return
        call cp_unpack(pb, x, pb%yref, tend, per, p)
        if (.not. pb%o%in_period) call set_param(sys, p)
        call sys%rhs(0.0_dp, pb%yref, pb%fref)
        if (is_bvp(pb)) then
            pb%bvp%yref = pb%yref
            pb%bvp%fref = pb%fref
        end if
    end subroutine cp_set_reference

    !> Dot product and norm over the reduced unknowns.
    pure real(dp) function cp_rdot(pb, a, b) result(d)
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: a(:), b(:)
        integer :: nw
        if (pb%o%discretisation == ORBIT_SINGLE) then
            d = dot_product(a, b)
        else
            nw = pb%bvp%nw
            d = dot_product(a(1:pb%n), b(1:pb%n)) + &
                dot_product(a(pb%nx - nw + 1:), b(pb%nx - nw + 1:))
        end if
    end function cp_rdot

    pure real(dp) function cp_rnorm(pb, a) result(r)
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: a(:)
        r = sqrt(max(cp_rdot(pb, a, a), 0.0_dp))
    end function cp_rnorm

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
        if (.not. (all(ieee_is_finite(pb%g)) .and. all(ieee_is_finite(pb%dg)))) then
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
            h = epsilon(1.0_dp)**(1.0_dp/3.0_dp)*max(abs(x(j)), 1.0_dp)
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
        y1 = y
        call ode_integrate(sys, 0.0_dp, per, y1, oo, info, message=msg)
        if (info < 0) return
        closure = maxval(abs(y1 - y))
    end subroutine cp_closure

end module conmech_cont_problem
