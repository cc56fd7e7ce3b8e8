!> Pseudo-arclength continuation of equilibria f(t, y; p) = 0 in a parameter p, with folds
!! and Hopf points detected and located, and the first Lyapunov coefficient at each Hopf
!! point (conmech_hopf).
!!
!! Unknowns X = [y, p] (n + 1), equations f = 0 (n): a curve. The Jacobian [df/dy, df/dp]
!! comes from the system's df/dy (analytic or its finite-difference default) and a central
!! difference in p (step fd_step max(1, |p|)) through `set_param`. Predictor X + ds t (t
!! the unit tangent, the null vector of [df/dy, df/dp] oriented by the previous one);
!! corrector: Newton on [f(X); t . (X - X_pred)] = 0 until |dX| <= tol max(1, |X|) and the
!! residual max |f| at the returned point is <= res_tol. Step length: grown by 1.5 after a
!! corrector of <= 3 iterations, shrunk by 0.7 after >= 6, halved on failure (below
!! `ds_min` the branch stops, keeping its points, with a message naming the parameter).
!! A step that leaves [p_min, p_max] is cut at the bound: the last point is the
!! equilibrium at p = p_min or p_max, located like a special point.
!!
!! Test functions at every point (eigenvalues of df/dy by LAPACK's dgeev):
!! - fold: the parameter component t_p of the tangent (a sign change: p turns back);
!! - Hopf: the sign of prod_{i<j} (lambda_i + lambda_j), the determinant of the
!!   bialternate product 2 A (.) I (Kuznetsov 2004, sec. 10.2), computed from the
!!   eigenvalues; it changes sign when a complex pair crosses the imaginary axis, and also
!!   at a neutral saddle (real lambda, -lambda), which is not a bifurcation and is not
!!   reported: a Hopf point needs, in addition, the real part of the complex pair nearest
!!   the imaginary axis to change sign across the step.
!! Each sign change is located by Illinois' regula falsi on the arclength sigma of the step:
!! at each trial the corrector finds the equilibrium at sigma (to the same tolerances as the
!! branch points), and the test (t_p, or that real part) is evaluated there, until
!! |test| <= test_tol (Hopf: relative to max(1, |lambda|)) or the bracket is below
!! locate_tol. A point is `located` only then; a corrector that fails inside the bracket, or
!! iterations that run out, leave `located` false and return the best corrected equilibrium
!! of the bracket (never an interpolated state), with its own test value and residual.
module conmech_equilibrium_continuation
    use conmech_kinds, only: dp
    use conmech_illinois, only: illinois_bracket
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_lapack, only: la_eig
    use conmech_shooting, only: lstsq_solve, set_parameter_proc
    use conmech_hopf, only: hopf_normal_form, first_lyapunov_coefficient
    use conmech_eq_branch_types
    implicit none
    private

    public :: EQ_FOLD, EQ_HOPF, eq_options, eq_point, eq_special, eq_branch
    public :: continue_equilibria, eq_tests

    integer, parameter :: TEST_BOUND = 0   !! locate p = bound (the end of the range)
    integer, parameter :: MAX_SPECIAL = 64

contains

    !> Continue the equilibrium near y0 of `sys` at p0 (set by `set_param`). Returns the
    !! branch; its info is CM_SUCCESS when it ended normally (max_points, or the bound of
    !! the p range reached), CM_NO_CONVERGENCE when the corrector failed below ds_min (the
    !! points so far are kept; the message names the parameter), CM_BAD_INPUT /
    !! CM_NO_CONVERGENCE / CM_SINGULAR for a bad start (not an equilibrium, or at a fold).
    subroutine continue_equilibria(sys, set_param, p0, y0, br, options)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        real(dp), intent(in) :: p0
        real(dp), intent(in) :: y0(:)
        type(eq_branch), intent(out) :: br
        type(eq_options), intent(in), optional :: options
        type(eq_options) :: o
        real(dp), allocatable :: x(:), t(:), xn(:), tn(:), xp(:)
        type(eq_point) :: pt
        type(eq_special) :: last
        real(dp) :: ds, bound
        integer :: n, info, it, k
        character(len=:), allocatable :: msg
        character(len=32) :: buf
        if (present(options)) o = options
        n = size(y0)
        br%info = CM_BAD_INPUT
        if (n < 1 .or. .not. all(abs(y0) <= huge(1.0_dp)) .or. &
            .not. (abs(p0) <= huge(1.0_dp)) .or. &
            o%max_points < 1 .or. .not. (o%ds > 0.0_dp) .or. .not. (o%ds_min > 0.0_dp) .or. &
            .not. (o%ds_max >= o%ds_min) .or. .not. (o%tol > 0.0_dp) .or. &
            .not. (o%res_tol > 0.0_dp) .or. o%max_iter < 1) then
            br%message = "equilibrium continuation: bad input (empty or non-finite y0 or "// &
                         "p0, max_points or max_iter < 1, ds, ds_min, tol or res_tol <= 0, "// &
                         "ds_max < ds_min)"
            return
        end if
        if (p0 < o%p_min .or. p0 > o%p_max) then
            br%message = "equilibrium continuation: p0 is outside [p_min, p_max]"
            return
        end if
        allocate (br%points(o%max_points), br%special(MAX_SPECIAL))
        allocate (x(n + 1), t(n + 1), xn(n + 1), tn(n + 1), xp(n + 1))
        x(1:n) = y0
        x(n + 1) = p0
        call correct(sys, set_param, o, x, t, .true., x, it, info, msg)
        if (info /= CM_SUCCESS) then
            call br%fail(info, "equilibrium continuation: the start is not an equilibrium "// &
                               "(Newton at fixed p from y0: "//msg//")")
            return
        end if
        t = 0.0_dp
        t(n + 1) = real(sign(1, o%direction), dp)
        call make_point(sys, set_param, o, x, t, it, 0.0_dp, br%points(1), info)
        if (info /= CM_SUCCESS) then
            call br%fail(CM_SINGULAR, "equilibrium continuation: degenerate start (no unique "// &
                                      "tangent: a fold or a branch point at p0)")
            return
        end if
        br%npoints = 1
        br%info = CM_SUCCESS
        br%message = "success: max_points reached"
        ds = o%ds
        do while (br%npoints < o%max_points)
            xp = x + ds*t
            xn = xp
            call correct(sys, set_param, o, xn, t, .false., xp, it, info, msg)
            tn = t
            if (info == CM_SUCCESS) call make_point(sys, set_param, o, xn, tn, it, ds, pt, info)
            if (info /= CM_SUCCESS) then
                ds = 0.5_dp*ds
                if (ds < o%ds_min) then
                    call br%corrector_stalled("equilibrium continuation", x(n + 1), msg)
                    exit
                end if
                cycle
            end if
            br%npoints = br%npoints + 1
            k = br%npoints
            br%points(k) = pt
            if (pt%p < o%p_min .or. pt%p > o%p_max) then
                ! cut the step at the bound: the last point is the equilibrium there
                bound = o%p_max
                if (pt%p < o%p_min) bound = o%p_min
                call locate(sys, set_param, o, x, t, ds, TEST_BOUND, br%points(k - 1), pt, &
                            bound, last)
                br%points(k) = last%point
                if (o%locate) call detect(sys, set_param, o, br, x, t, &
                                          br%points(k)%ds, k)
                write (buf, '(es23.15)') bound
                br%message = "success: the branch reached the end of the p range, p = "// &
                             trim(adjustl(buf))
                if (.not. last%located) then
                    call br%fail(CM_NO_CONVERGENCE, "equilibrium continuation: the end of the "// &
                                                    "p range, p = "//trim(adjustl(buf))// &
                                                    ", was not located")
                end if
                exit
            end if
            if (o%locate) call detect(sys, set_param, o, br, x, t, ds, k)
            x = xn
            t = tn
            if (it <= 3) ds = min(o%ds_max, 1.5_dp*ds)
            if (it >= 6) ds = max(o%ds_min, 0.7_dp*ds)
        end do
    end subroutine continue_equilibria

    !> f and [df/dy, df/dp] at X = [y, p].
    subroutine evaluate(sys, set_param, o, x, f, dfx)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(eq_options), intent(in) :: o
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: f(:), dfx(:, :)
        real(dp) :: fp(size(f)), fm(size(f)), p, h
        integer :: n
        n = size(f)
        p = x(n + 1)
        h = o%fd_step*max(1.0_dp, abs(p))
        call set_param(sys, p + h)
        call sys%rhs(o%t, x(1:n), fp)
        call set_param(sys, p - h)
        call sys%rhs(o%t, x(1:n), fm)
        call set_param(sys, p)
        call sys%rhs(o%t, x(1:n), f)
        call sys%jacobian(o%t, x(1:n), dfx(:, 1:n))
        dfx(:, n + 1) = (fp - fm)/(2.0_dp*h)
    end subroutine evaluate

    !> Newton's method: at fixed p (`fixed_p`, the start) or with the arclength equation
    !! t . (X - xp) = 0. Success when |dX| <= tol max(1, |X|) and max |f| <= res_tol at the
    !! returned X.
    subroutine correct(sys, set_param, o, x, t, fixed_p, xp, it, info, msg)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(eq_options), intent(in) :: o
        real(dp), intent(inout) :: x(:)
        real(dp), intent(in) :: t(:), xp(:)
        logical, intent(in) :: fixed_p
        integer, intent(out) :: it, info
        character(len=:), allocatable, intent(out) :: msg
        real(dp) :: f(size(x) - 1), dfx(size(x) - 1, size(x)), a(size(x), size(x))
        real(dp) :: r(size(x)), dx(size(x)), res
        integer :: n, rank
        n = size(x) - 1
        msg = "Newton did not converge"
        info = CM_NO_CONVERGENCE
        do it = 1, o%max_iter
            call evaluate(sys, set_param, o, x, f, dfx)
            if (.not. (all(abs(f) <= huge(1.0_dp)) .and. all(abs(dfx) <= huge(1.0_dp)))) then
                info = CM_NONFINITE
                msg = "f or its Jacobian is not finite"
                return
            end if
            if (fixed_p) then
                call lstsq_solve(dfx(:, 1:n), -f, dx(1:n), rank, info, o%rcond)
                dx(n + 1) = 0.0_dp
                if (info == CM_SUCCESS .and. rank < n) info = CM_SINGULAR
            else
                a(1:n, :) = dfx
                a(n + 1, :) = t
                r(1:n) = -f
                r(n + 1) = -dot_product(t, x - xp)
                call lstsq_solve(a, r, dx, rank, info, o%rcond)
                if (info == CM_SUCCESS .and. rank < n + 1) info = CM_SINGULAR
            end if
            if (info /= CM_SUCCESS) then
                msg = "singular Newton matrix"
                return
            end if
            x = x + dx
            if (maxval(abs(dx)) <= o%tol*max(1.0_dp, maxval(abs(x)))) then
                call set_param(sys, x(n + 1))
                call sys%rhs(o%t, x(1:n), f)
                res = maxval(abs(f))
                if (res <= o%res_tol) then
                    info = CM_SUCCESS
                    msg = "success"
                    return
                end if
            end if
            info = CM_NO_CONVERGENCE
            if (maxval(abs(dx)) > 1.0e3_dp*max(1.0_dp, maxval(abs(x)))) exit
        end do
        msg = "Newton did not converge"
    end subroutine correct

    !> The point of the branch at X: the unit tangent (from [df/dy, df/dp; t_old] t =
    !! [0; 1]; t is the old tangent on entry, the new one on exit), eigenvalues, tests.
    subroutine make_point(sys, set_param, o, x, t, it, ds, pt, info)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(eq_options), intent(in) :: o
        real(dp), intent(in) :: x(:), ds
        real(dp), intent(inout) :: t(:)
        integer, intent(in) :: it
        type(eq_point), intent(out) :: pt
        integer, intent(out) :: info
        real(dp) :: f(size(x) - 1), dfx(size(x) - 1, size(x)), a(size(x), size(x))
        real(dp) :: r(size(x)), tn(size(x))
        integer :: n, rank
        n = size(x) - 1
        call evaluate(sys, set_param, o, x, f, dfx)
        pt%p = x(n + 1)
        pt%y = x(1:n)
        pt%residual = maxval(abs(f))
        pt%iterations = it
        pt%ds = ds
        a(1:n, :) = dfx
        a(n + 1, :) = t
        r = 0.0_dp
        r(n + 1) = 1.0_dp
        call lstsq_solve(a, r, tn, rank, info, o%rcond)
        if (info /= CM_SUCCESS) return
        if (rank < n + 1 .or. .not. (norm2(tn) > 0.0_dp)) then
            info = CM_SINGULAR
            return
        end if
        t = tn/norm2(tn)
        allocate (pt%wr(n), pt%wi(n))
        call la_eig(dfx(:, 1:n), pt%wr, pt%wi, info)
        if (info /= CM_SUCCESS) return
        call eq_tests(pt%wr, pt%wi, pt%psi(2:3), pt%n_unstable)
        pt%psi(1) = t(n + 1)
    end subroutine make_point

    !> The Hopf tests from the eigenvalues: psi(1) the real part of the complex pair nearest
    !! the imaginary axis (0 if there is none), psi(2) the sign (+1, -1, or 0) of
    !! prod_{i<j} (lambda_i + lambda_j); n_unstable the eigenvalues with Re > 1e-12
    !! max(1, |lambda|).
    pure subroutine eq_tests(wr, wi, psi, n_unstable)
        real(dp), intent(in) :: wr(:), wi(:)
        real(dp), intent(out) :: psi(2)
        integer, intent(out) :: n_unstable
        real(dp) :: best, d, sgn, scale
        integer :: i, j
        scale = max(1.0_dp, maxval(hypot(wr, wi)))
        n_unstable = count(wr > 1.0e-12_dp*scale)
        psi(1) = 0.0_dp
        best = huge(1.0_dp)
        sgn = 1.0_dp
        do i = 1, size(wr)
            if (wi(i) > 0.0_dp) then
                ! the factor lambda + conj(lambda) = 2 Re lambda of the pair
                sgn = sgn*sign(1.0_dp, wr(i))
                if (wr(i) == 0.0_dp) sgn = 0.0_dp
                d = abs(wr(i))/hypot(wr(i), wi(i))
                if (d < best) then
                    best = d
                    psi(1) = wr(i)
                end if
            else if (wi(i) == 0.0_dp) then
                do j = i + 1, size(wr)
                    if (wi(j) /= 0.0_dp) cycle
                    if (wr(i) + wr(j) == 0.0_dp) then
                        sgn = 0.0_dp
                    else
                        sgn = sgn*sign(1.0_dp, wr(i) + wr(j))
                    end if
                end do
            end if
        end do
        psi(2) = sgn
    end subroutine eq_tests

    !> Sign changes between points k - 1 and k (the step from x0 along t0 of length ds);
    !! locate and record.
    subroutine detect(sys, set_param, o, br, x0, t0, ds, k)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(eq_options), intent(in) :: o
        type(eq_branch), intent(inout) :: br
        real(dp), intent(in) :: x0(:), t0(:), ds
        integer, intent(in) :: k
        type(eq_point) :: a, b
        integer :: kind, info, m
        type(hopf_normal_form) :: hf
        character(len=:), allocatable :: msg
        a = br%points(k - 1)
        b = br%points(k)
        do kind = EQ_FOLD, EQ_HOPF
            if (kind == EQ_FOLD .and. .not. (a%psi(1)*b%psi(1) < 0.0_dp)) cycle
            if (kind == EQ_HOPF .and. .not. (a%psi(3)*b%psi(3) < 0.0_dp .and. &
                                             a%psi(2)*b%psi(2) < 0.0_dp)) cycle
            if (br%nspecial >= size(br%special)) return
            m = br%nspecial + 1
            call locate(sys, set_param, o, x0, t0, ds, kind, a, b, 0.0_dp, br%special(m))
            br%special(m)%kind = kind
            br%special(m)%index = k - 1
            if (kind == EQ_HOPF) then
                call set_param(sys, br%special(m)%point%p)
                call first_lyapunov_coefficient(sys, o%t, br%special(m)%point%y, hf, info, &
                                                msg, o%l1_tol)
                if (info == CM_SUCCESS) then
                    br%special(m)%omega = hf%omega
                    br%special(m)%l1 = hf%l1
                    br%special(m)%l1_scale = hf%scale
                    br%special(m)%l1_error = hf%l1_error
                    br%special(m)%criticality = hf%criticality
                    br%special(m)%q = hf%q
                    br%special(m)%adj = hf%p
                end if
            end if
            br%nspecial = m
        end do
    end subroutine detect

    !> The test function `kind` at a point (TEST_BOUND: p - bound).
    pure real(dp) function test_of(kind, pt, bound) result(v)
        integer, intent(in) :: kind
        type(eq_point), intent(in) :: pt
        real(dp), intent(in) :: bound
        select case (kind)
        case (EQ_FOLD)
            v = pt%psi(1)
        case (EQ_HOPF)
            v = pt%psi(2)
        case default
            v = pt%p - bound
        end select
    end function test_of

    !> The tolerance of |test| at which a trial point counts as the special point.
    pure real(dp) function test_tolerance(o, kind, pt) result(tol)
        type(eq_options), intent(in) :: o
        integer, intent(in) :: kind
        type(eq_point), intent(in) :: pt
        select case (kind)
        case (EQ_HOPF)
            tol = o%test_tol*max(1.0_dp, maxval(hypot(pt%wr, pt%wi)))
        case (TEST_BOUND)
            tol = o%test_tol*max(1.0_dp, abs(pt%p))
        case default
            tol = o%test_tol
        end select
    end function test_tolerance

    !> Illinois' regula falsi on sigma in [0, ds]: the corrected equilibrium at arclength
    !! sigma from x0 along t0 and the test there, from the bracket (pa at 0, pb at ds).
    subroutine locate(sys, set_param, o, x0, t0, ds, kind, pa, pb, bound, sp)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(eq_options), intent(in) :: o
        real(dp), intent(in) :: x0(:), t0(:), ds, bound
        integer, intent(in) :: kind
        type(eq_point), intent(in) :: pa, pb
        type(eq_special), intent(out) :: sp
        real(dp) :: sc, fc, x(size(x0)), t(size(x0))
        integer :: iter, it, info
        type(illinois_bracket) :: br
        logical :: moved
        type(eq_point) :: trial
        character(len=:), allocatable :: msg
        br%a = 0.0_dp
        br%b = ds
        br%fa = test_of(kind, pa, bound)
        br%fb = test_of(kind, pb, bound)
        ! the best corrected point so far (smallest |test|)
        sp%point = pa
        sp%test = br%fa
        if (abs(br%fb) < abs(br%fa)) then
            sp%point = pb
            sp%test = br%fb
        end if
        sp%bracket = ds
        sp%located = .false.
        sp%reason = EQ_NOT_RESOLVED
        do iter = 1, 100
            sc = br%trial()
            x = x0 + sc*t0
            call correct(sys, set_param, o, x, t0, .false., x0 + sc*t0, it, info, msg)
            if (info == CM_SUCCESS) then
                t = t0
                call make_point(sys, set_param, o, x, t, it, sc, trial, info)
            end if
            if (info /= CM_SUCCESS) then
                sp%reason = EQ_CORRECTOR_FAILED
                return
            end if
            fc = test_of(kind, trial, bound)
            if (abs(fc) < abs(sp%test)) then
                sp%point = trial
                sp%test = fc
            end if
            sp%bracket = abs(br%b - br%a)
            if (abs(fc) <= test_tolerance(o, kind, trial) .or. &
                abs(br%b - br%a) <= o%locate_tol) then
                sp%point = trial
                sp%test = fc
                sp%located = .true.
                sp%reason = EQ_LOCATED
                return
            end if
            call br%update(sc, fc, moved)
        end do
    end subroutine locate

end module conmech_equilibrium_continuation
