!> Pseudo-arclength continuation of periodic orbits in a parameter of the system, with the
!! detection and location of their bifurcations (special points).
!!
!! Unknowns X and equations G(X) = 0 (one equation fewer than unknowns: a curve):
!! - general shooting: X = [y0, T, p] (T dropped with `fixed_period`), G = [y(T; y0, p) - y0;
!!   f(y_ref) . (y0 - y_ref)] (the phase condition only for `autonomous` systems; y_ref is
!!   the previous point of the branch). A conservative system with a fixed period (e.g.
!!   Hill's variation orbit, T = 2 pi) has n + 1 equations of rank n: Gauss-Newton in the
!!   least-squares sense (LAPACK dgelsd) handles it.
!! - symmetric shooting (`free` given): X = [y0(free), tau (if `free_time`), p],
!!   G = y(tau)(targets), the period is `period_factor` * tau.
!! The Jacobian comes from the state transition matrix (variational equations) and, for the
!! parameter, from a central difference of two state integrations (step `fd_step` max(1,
!! |p|)). The parameter is set through the callback `set_param(sys, p)`. With `in_period`
!! (conservative systems, no parameter) the period itself is the continued quantity:
!! X = [y0, T], G = [y(T) - y0; phase] (rank n), so the branch is the family of orbits
!! through the energy levels (the energy is a function of the point; folds in T, where the
!! period is extremal along the family, are passed by the arclength).
!!
!! Predictor: X + ds t (t the unit tangent, the null vector of DG, oriented by the previous
!! one); corrector: Newton on [G(X); t . (X - X_pred)] = 0. Step length: grown by 1.5 after
!! a corrector of <= 3 iterations, shrunk by 0.7 after >= 6, halved on failure (the branch
!! stops, with a message naming the parameter value, below `ds_min`).
!!
!! Special points, from sign changes between consecutive points of the test functions: a
!! fold (the parameter component of the tangent), a branch point (a real multiplier through
!! +1; for a conservative planar orbit S through +1), a period doubling (through -1), a
!! Neimark-Sacker point (a complex pair through the unit circle; not for conservative
!! systems). See `conmech_multiplier_tests`. Each is located by Illinois' regula falsi on
!! the arclength sigma of the step (the corrected point at sigma, the test function there)
!! to |sigma bracket| <= `locate_tol`. A sign change of the branch-point test at a fold is
!! the fold itself and is not reported twice.
module conmech_continuation
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_integrate
    use conmech_variational, only: integrate_stm
    use conmech_shooting, only: lstsq_solve, set_parameter_proc
    use conmech_multiplier_tests, only: multiplier_tests, ns_is_complex
    use conmech_branch_types
    implicit none
    private

    public :: SP_FOLD, SP_BP, SP_PD, SP_NS
    public :: cont_options, cont_point, special_point, branch, continue_orbits, special_name

    !> The problem being continued (internal).
    type :: cproblem
        integer :: n = 0, nx = 0, neq = 0
        logical :: sym = .false., tfree = .true.
        integer, allocatable :: free(:), targets(:)
        real(dp) :: pf = 2.0_dp, tfix = 0.0_dp
        real(dp), allocatable :: ybase(:), yref(:), fref(:)
        type(cont_options) :: o
        integer :: ntriv = 0
    end type cproblem

contains

    !> Continue the periodic orbit through y0 (period guess `period`) of `sys` at the
    !! parameter p0 (set by `set_param`). General shooting, or symmetric shooting when
    !! `free` and `targets` are given (see the module notes). Returns the branch; its info is
    !! CM_SUCCESS when it ended normally (max_points or the p range), CM_NO_CONVERGENCE
    !! when the corrector failed below ds_min (the branch so far is kept; the message names
    !! the parameter value), CM_SINGULAR / CM_NO_CONVERGENCE / CM_BAD_INPUT for a bad start.
    subroutine continue_orbits(sys, set_param, p0, y0, period, br, options, free, targets, &
                               free_time, period_factor, tangent0)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        real(dp), intent(in) :: p0
        real(dp), intent(in) :: y0(:)
        real(dp), intent(in) :: period
        type(branch), intent(out) :: br
        type(cont_options), intent(in), optional :: options
        integer, intent(in), optional :: free(:), targets(:)
        logical, intent(in), optional :: free_time
        real(dp), intent(in), optional :: period_factor
        real(dp), intent(in), optional :: tangent0(:)  !! first tangent (branch switching)
        type(cproblem) :: pb
        real(dp), allocatable :: x(:), t(:), xn(:), tn(:), xp(:), gl(:), dgl(:, :), phil(:, :)
        type(cont_point) :: pt
        real(dp) :: ds
        integer :: info, it, k
        character(len=:), allocatable :: msg
        character(len=32) :: buf
        if (present(options)) pb%o = options
        call setup(pb, y0, period, p0, free, targets, free_time, period_factor, info, msg)
        if (info /= CM_SUCCESS) then
            br%info = info
            br%message = msg
            return
        end if
        allocate (br%points(pb%o%max_points), br%special(64))
        allocate (x(pb%nx), t(pb%nx), xn(pb%nx), tn(pb%nx), xp(pb%nx))
        allocate (gl(pb%neq), dgl(pb%neq, pb%nx), phil(pb%n, pb%n))
        ! the first point: Newton at fixed p
        call pack_start(pb, y0, period, p0, x)
        ! a given tangent0 starts at a bifurcation point (already a solution, not isolated)
        it = 0
        info = CM_SUCCESS
        if (present(tangent0)) then
            call set_reference(sys, set_param, pb, x)
        else
            call correct(sys, set_param, pb, x, t, .true., it, info, msg)
        end if
        if (info /= CM_SUCCESS) then
            br%info = info
            br%message = "continuation: the start is not a periodic orbit: "//msg
            return
        end if
        ! the first tangent: the null vector of DG with t_p of sign `direction`
        t = 0.0_dp
        t(pb%nx) = real(sign(1, pb%o%direction), dp)
        if (present(tangent0)) then
            if (size(tangent0) /= pb%nx .or. .not. (norm2(tangent0) > 0.0_dp)) then
                br%info = CM_BAD_INPUT
                br%message = "continuation: tangent0 must have one entry per unknown"
                return
            end if
            t = tangent0/norm2(tangent0)
        end if
        call make_point(sys, set_param, pb, x, t, it, 0.0_dp, br%points(1), info, &
                        keep_t=present(tangent0))
        if (info /= CM_SUCCESS) then
            br%info = CM_SINGULAR
            br%message = "continuation: degenerate start (no unique tangent: the orbit is "// &
                         "not isolated, or already at a fold)"
            return
        end if
        br%npoints = 1
        br%info = CM_SUCCESS
        br%message = "success: max_points reached"
        ds = pb%o%ds
        do while (br%npoints < pb%o%max_points)
            call set_reference(sys, set_param, pb, x)
            xn = x + ds*t
            xp = xn
            call correct(sys, set_param, pb, xn, t, .false., it, info, msg, xp, gl, dgl, phil)
            tn = t
            if (info == CM_SUCCESS) call make_point(sys, set_param, pb, xn, tn, it, ds, pt, &
                                                     info, gl, dgl, phil)
            if (info /= CM_SUCCESS) then
                ds = 0.5_dp*ds
                if (ds < pb%o%ds_min) then
                    write (buf, '(es23.15)') x(pb%nx)
                    br%info = CM_NO_CONVERGENCE
                    br%message = "continuation stopped at p = "//trim(adjustl(buf))// &
                                 ": the corrector did not converge with ds >= ds_min ("// &
                                 msg//")"
                    exit
                end if
                cycle
            end if
            br%npoints = br%npoints + 1
            br%points(br%npoints) = pt
            k = br%npoints
            ! (from a bifurcation point, the test functions of the first point are ~0)
            if (pb%o%locate .and. .not. (present(tangent0) .and. k == 2)) &
                call detect(sys, set_param, pb, br, x, t, ds, k)
            x = xn
            t = tn
            if (it <= 3) ds = min(pb%o%ds_max, 1.5_dp*ds)
            if (it >= 6) ds = max(pb%o%ds_min, 0.7_dp*ds)
            if (x(pb%nx) < pb%o%p_min .or. x(pb%nx) > pb%o%p_max) then
                br%message = "success: the parameter left [p_min, p_max]"
                exit
            end if
        end do
    end subroutine continue_orbits

    subroutine setup(pb, y0, period, p0, free, targets, free_time, period_factor, info, msg)
        type(cproblem), intent(inout) :: pb
        real(dp), intent(in) :: y0(:), period, p0
        integer, intent(in), optional :: free(:), targets(:)
        logical, intent(in), optional :: free_time
        real(dp), intent(in), optional :: period_factor
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        pb%n = size(y0)
        info = CM_BAD_INPUT
        if (pb%n < 1 .or. .not. all(ieee_is_finite(y0)) .or. .not. (period > 0.0_dp) .or. &
            .not. ieee_is_finite(p0) .or. pb%o%max_points < 1 .or. &
            .not. (pb%o%ds > 0.0_dp) .or. .not. (pb%o%ds_min > 0.0_dp)) then
            msg = "continuation: bad input (empty or non-finite y0 or p0, period <= 0, "// &
                  "max_points < 1, ds <= 0)"
            return
        end if
        pb%sym = present(free)
        if (pb%o%in_period .and. (pb%sym .or. .not. pb%o%autonomous)) then
            msg = "continuation: in_period is for general shooting of autonomous systems"
            return
        end if
        if (pb%sym .neqv. present(targets)) then
            msg = "continuation: symmetric shooting needs both free and targets"
            return
        end if
        pb%ybase = y0
        if (pb%sym) then
            if (size(free) < 1 .or. size(targets) < 1 .or. any(free < 1) .or. &
                any(free > pb%n) .or. any(targets < 1) .or. any(targets > pb%n)) then
                msg = "continuation: free and targets must be state indices"
                return
            end if
            pb%free = free
            pb%targets = targets
            pb%tfree = .false.
            if (present(free_time)) pb%tfree = free_time
            if (present(period_factor)) pb%pf = period_factor
            if (.not. (pb%pf > 0.0_dp)) then
                msg = "continuation: period_factor must be positive"
                return
            end if
            pb%tfix = period/pb%pf
            pb%nx = size(free) + 1
            if (pb%tfree) pb%nx = pb%nx + 1
            pb%neq = size(targets)
            pb%ntriv = 0
            if (pb%o%autonomous) pb%ntriv = 1
        else
            pb%tfree = pb%o%autonomous .and. .not. pb%o%fixed_period .and. &
                       .not. pb%o%in_period
            pb%tfix = period
            pb%nx = pb%n + 1
            if (pb%tfree) pb%nx = pb%nx + 1
            pb%neq = pb%n
            if (pb%o%autonomous) pb%neq = pb%n + 1
            pb%ntriv = 0
            if (pb%o%autonomous) pb%ntriv = 1
        end if
        if (pb%o%conservative) pb%ntriv = pb%ntriv + 1
        allocate (pb%yref(pb%n), pb%fref(pb%n))
        pb%yref = y0
        pb%fref = 0.0_dp
        info = CM_SUCCESS
        msg = "success"
    end subroutine setup

    pure subroutine pack_start(pb, y0, period, p0, x)
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: y0(:), period, p0
        real(dp), intent(out) :: x(:)
        integer :: nf
        if (pb%sym) then
            nf = size(pb%free)
            x(1:nf) = y0(pb%free)
            if (pb%tfree) x(nf + 1) = period/pb%pf
        else
            x(1:pb%n) = y0
            if (pb%tfree) x(pb%n + 1) = period
        end if
        x(pb%nx) = p0
        if (pb%o%in_period) x(pb%nx) = period
    end subroutine pack_start

    !> (full initial state, integration time, period) of X.
    pure subroutine unpack(pb, x, y, tend, per)
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: y(:), tend, per
        integer :: nf
        if (pb%sym) then
            nf = size(pb%free)
            y = pb%ybase
            y(pb%free) = x(1:nf)
            tend = pb%tfix
            if (pb%tfree) tend = x(nf + 1)
            per = pb%pf*tend
        else
            y = x(1:pb%n)
            tend = pb%tfix
            if (pb%tfree) tend = x(pb%n + 1)
            if (pb%o%in_period) tend = x(pb%nx)
            per = tend
        end if
    end subroutine unpack

    !> The phase condition's reference: the current point and its vector field.
    subroutine set_reference(sys, set_param, pb, x)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(inout) :: pb
        real(dp), intent(in) :: x(:)
        real(dp) :: tend, per
        if (pb%sym .or. .not. pb%o%autonomous) return
        call unpack(pb, x, pb%yref, tend, per)
        if (.not. pb%o%in_period) call set_param(sys, x(pb%nx))
        call sys%rhs(0.0_dp, pb%yref, pb%fref)
    end subroutine set_reference

    !> G(X), DG(X) and the STM over the integration time.
    subroutine evaluate(sys, set_param, pb, x, g, dg, phi, info, msg)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: g(:), dg(:, :), phi(:, :)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(ode_options) :: oo
        real(dp) :: y(pb%n), y0(pb%n), yp(pb%n), ym(pb%n), f(pb%n), tend, per, p, h
        integer :: j, n, nf
        n = pb%n
        oo%rtol = pb%o%rtol
        oo%atol = pb%o%atol
        p = x(pb%nx)
        ! the parameter's difference step (used below when the parameter is not the period)
        h = pb%o%fd_step*max(1.0_dp, abs(p))
        call unpack(pb, x, y0, tend, per)
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
        phi = 0.0_dp
        do j = 1, n
            phi(j, j) = 1.0_dp
        end do
        call integrate_stm(sys, 0.0_dp, tend, y, phi, oo, info, msg)
        if (info < 0) return
        call sys%rhs(tend, y, f)
        dg = 0.0_dp
        if (pb%sym) then
            nf = size(pb%free)
            g = y(pb%targets)
            do j = 1, nf
                dg(:, j) = phi(pb%targets, pb%free(j))
            end do
            if (pb%tfree) dg(:, nf + 1) = f(pb%targets)
            dg(:, pb%nx) = (yp(pb%targets) - ym(pb%targets))/(2.0_dp*h)
        else
            g(1:n) = y - y0
            dg(1:n, 1:n) = phi
            do j = 1, n
                dg(j, j) = dg(j, j) - 1.0_dp
            end do
            if (pb%tfree) dg(1:n, n + 1) = f
            if (pb%o%in_period) then
                dg(1:n, pb%nx) = f                  ! d y(T)/dT
            else
                dg(1:n, pb%nx) = (yp - ym)/(2.0_dp*h)
            end if
            if (pb%o%autonomous) then
                g(n + 1) = dot_product(pb%fref, y0 - pb%yref)
                dg(n + 1, 1:n) = pb%fref
            end if
        end if
        info = CM_SUCCESS
        if (.not. (all(ieee_is_finite(g)) .and. all(ieee_is_finite(dg)))) then
            info = CM_NONFINITE
            msg = "non-finite values"
        end if
    end subroutine evaluate

    !> Newton corrector. first: at fixed p (the start); else with the arclength equation
    !! t . (X - xp) = 0 about the predicted point xp.
    subroutine correct(sys, set_param, pb, x, t, first, it, info, msg, xp, gl, dgl, phil)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(inout) :: pb
        real(dp), intent(inout) :: x(:)
        real(dp), intent(in) :: t(:)
        logical, intent(in) :: first
        integer, intent(out) :: it, info
        character(len=:), allocatable, intent(out) :: msg
        real(dp), intent(in), optional :: xp(:)
        real(dp), intent(out), optional :: gl(:), dgl(:, :), phil(:, :)  !! last evaluation
        real(dp) :: g(pb%neq), dg(pb%neq, pb%nx), phi(pb%n, pb%n), a(pb%neq + 1, pb%nx)
        real(dp) :: r(pb%neq + 1), dx(pb%nx), res
        integer :: rank, nun
        if (first) call set_reference(sys, set_param, pb, x)
        msg = "Newton did not converge"
        info = CM_NO_CONVERGENCE
        do it = 1, pb%o%max_iter
            call evaluate(sys, set_param, pb, x, g, dg, phi, info, msg)
            if (info /= CM_SUCCESS) return
            if (present(gl)) gl = g
            if (present(dgl)) dgl = dg
            if (present(phil)) phil = phi
            res = maxval(abs(g))
            if (first) then
                nun = pb%nx - 1
                call lstsq_solve(dg(:, 1:nun), -g, dx(1:nun), rank, info, pb%o%rcond)
                dx(pb%nx) = 0.0_dp
                if (info == CM_SUCCESS .and. rank < min(nun, pb%neq)) info = CM_SINGULAR
            else
                a(1:pb%neq, :) = dg
                a(pb%neq + 1, :) = t
                r(1:pb%neq) = -g
                r(pb%neq + 1) = -dot_product(t, x - xp)
                call lstsq_solve(a, r, dx, rank, info, pb%o%rcond)
                if (info == CM_SUCCESS .and. rank < pb%nx) info = CM_SINGULAR
            end if
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
    end subroutine correct

    !> The point of the branch at X: the unit tangent (solving [DG; t_old] t = [0; 1]; t is
    !! the old tangent on entry, the new one on exit), period, state, monodromy, multipliers,
    !! test functions.
    subroutine make_point(sys, set_param, pb, x, t, it, ds, pt, info, g0, dg0, phi0, keep_t)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: x(:), ds
        real(dp), intent(inout) :: t(:)
        integer, intent(in) :: it
        type(cont_point), intent(out) :: pt
        integer, intent(out) :: info
        real(dp), intent(in), optional :: g0(:), dg0(:, :), phi0(:, :)  !! the corrector's last
        logical, intent(in), optional :: keep_t   !! keep t (a bifurcation point: no unique one)
        real(dp) :: y(pb%n), tend, per, phi(pb%n, pb%n), psi(3), g(pb%neq)
        real(dp) :: dg(pb%neq, pb%nx), a(pb%neq + 1, pb%nx), r(pb%neq + 1), tn(pb%nx)
        real(dp) :: f(pb%n)
        type(ode_options) :: oo
        character(len=:), allocatable :: msg
        integer :: j, rank
        call unpack(pb, x, y, tend, per)
        pt%p = x(pb%nx)
        pt%period = per
        pt%y0 = y
        pt%iterations = it
        pt%ds = ds
        if (present(g0) .and. present(dg0) .and. present(phi0)) then
            ! the corrector's last evaluation, one Newton step (<= tol) from x
            g = g0
            dg = dg0
            phi = phi0
            info = CM_SUCCESS
        else
            call evaluate(sys, set_param, pb, x, g, dg, phi, info, msg)
            if (info /= CM_SUCCESS) return
        end if
        pt%residual = maxval(abs(g))
        a(1:pb%neq, :) = dg
        a(pb%neq + 1, :) = t
        r = 0.0_dp
        r(pb%neq + 1) = 1.0_dp
        call lstsq_solve(a, r, tn, rank, info, pb%o%rcond)
        if (info /= CM_SUCCESS) return
        if (present(keep_t)) then
            if (keep_t) then
                rank = pb%nx
                tn = t
            end if
        end if
        if (rank < pb%nx .or. .not. (norm2(tn) > 0.0_dp)) then
            info = CM_SINGULAR
            return
        end if
        t = tn/norm2(tn)
        if (.not. pb%o%in_period) call set_param(sys, pt%p)
        call sys%rhs(0.0_dp, y, f)
        if (pb%sym) then
            ! the monodromy over the full period
            oo%rtol = pb%o%rtol
            oo%atol = pb%o%atol
            phi = 0.0_dp
            do j = 1, pb%n
                phi(j, j) = 1.0_dp
            end do
            call integrate_stm(sys, 0.0_dp, per, y, phi, oo, info, msg)
            if (info < 0) return
        end if
        allocate (pt%mr(pb%n), pt%mi(pb%n))
        if (pb%o%autonomous) then
            call multiplier_tests(phi, pb%ntriv, pb%o%conservative, pt%mr, pt%mi, psi, &
                                  pt%stability_index, info, f)
        else
            call multiplier_tests(phi, pb%ntriv, pb%o%conservative, pt%mr, pt%mi, psi, &
                                  pt%stability_index, info)
        end if
        if (info /= CM_SUCCESS) return
        pt%psi(1) = t(pb%nx)
        pt%psi(2:4) = psi
    end subroutine make_point

    !> Sign changes between the last two points; locate and record.
    subroutine detect(sys, set_param, pb, br, x0, t0, ds, k)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(inout) :: pb
        type(branch), intent(inout) :: br
        real(dp), intent(in) :: x0(:), t0(:), ds
        integer, intent(in) :: k
        real(dp) :: a, b
        integer :: kind, info
        logical :: fold
        fold = .false.
        do kind = SP_FOLD, SP_NS
            a = br%points(k - 1)%psi(kind)
            b = br%points(k)%psi(kind)
            if (.not. (a*b < 0.0_dp)) cycle
            if (kind == SP_FOLD) fold = .true.
            if (kind == SP_BP .and. fold) cycle
            if (kind == SP_NS .and. pb%o%conservative) cycle
            if (br%nspecial >= size(br%special)) return
            call locate(sys, set_param, pb, x0, t0, ds, kind, br%points(k - 1), &
                        br%points(k), br%special(br%nspecial + 1)%point, fold, info)
            if (info /= CM_SUCCESS) cycle
            if (kind == SP_NS) then
                if (.not. ns_is_complex(br%special(br%nspecial + 1)%point%mr, &
                                        br%special(br%nspecial + 1)%point%mi, pb%ntriv)) cycle
            end if
            br%nspecial = br%nspecial + 1
            br%special(br%nspecial)%kind = kind
            br%special(br%nspecial)%index = k - 1
        end do
    end subroutine detect

    !> Illinois on sigma in [0, ds]: the corrected point at arclength sigma from x0 along t0
    !! and the test function `kind` there, from the bracket (p0 at 0, p1 at ds). Near a
    !! branch point the corrector loses accuracy in the singular direction as the bracket
    !! shrinks (round-off amplified by 1/distance): when it fails, the point is the linear
    !! interpolation of the bracket ends at the secant root of the test function (error
    !! O(bracket^2) in the parameter).
    subroutine locate(sys, set_param, pb, x0, t0, ds, kind, p0, p1, pt, fold, info)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(inout) :: pb
        real(dp), intent(in) :: x0(:), t0(:), ds
        integer, intent(in) :: kind
        type(cont_point), intent(in) :: p0, p1
        type(cont_point), intent(out) :: pt
        logical, intent(inout) :: fold
        integer, intent(out) :: info
        real(dp) :: sa, sb, fa, fb, sc, fc, x(size(x0)), t(size(x0)), w
        integer :: iter, side, it
        type(cont_point) :: trial, qa, qb
        character(len=:), allocatable :: msg
        real(dp) :: gl(pb%neq), dgl(pb%neq, pb%nx), phil(pb%n, pb%n)
        if (kind == SP_FOLD) fold = .true.
        sa = 0.0_dp
        sb = ds
        qa = p0
        qb = p1
        fa = qa%psi(kind)
        fb = qb%psi(kind)
        side = 0
        do iter = 1, 60
            sc = (sa*fb - sb*fa)/(fb - fa)
            if (.not. (sc > min(sa, sb) .and. sc < max(sa, sb))) sc = 0.5_dp*(sa + sb)
            x = x0 + sc*t0
            call correct(sys, set_param, pb, x, t0, .false., it, info, msg, x0 + sc*t0, gl, &
                         dgl, phil)
            if (info == CM_SUCCESS) then
                t = t0
                call make_point(sys, set_param, pb, x, t, it, sc, trial, info, gl, dgl, phil)
            end if
            if (info /= CM_SUCCESS) exit
            fc = trial%psi(kind)
            if (fc == 0.0_dp .or. abs(sb - sa) <= pb%o%locate_tol) then
                pt = trial
                return
            end if
            if (fc*fb < 0.0_dp) then
                sa = sb
                fa = fb
                qa = qb
                side = 0
            else
                if (side == 1) fa = 0.5_dp*fa
                side = 1
            end if
            sb = sc
            fb = fc
            qb = trial
        end do
        ! interpolate between the bracket ends (true test-function values at both)
        fa = qa%psi(kind)
        fb = qb%psi(kind)
        w = fa/(fa - fb)
        pt = qb
        if (abs(w) < 0.5_dp) pt = qa
        pt%p = (1.0_dp - w)*qa%p + w*qb%p
        pt%period = (1.0_dp - w)*qa%period + w*qb%period
        pt%y0 = (1.0_dp - w)*qa%y0 + w*qb%y0
        pt%psi = (1.0_dp - w)*qa%psi + w*qb%psi
        info = CM_SUCCESS
    end subroutine locate

end module conmech_continuation
