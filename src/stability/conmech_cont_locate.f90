!> Special points of a continuation: detection by a sign change of a test function
!! between consecutive points, location by Illinois' regula falsi on the arclength sigma
!! of the step, and the honest record of the result.
!!
!! Each trial point at sigma is a corrected orbit on the hyperplane t0 . (X - X0) = sigma,
!! started from the cubic Hermite interpolant of the current bracket ends (their X and
!! tangents), so that near a branch point, where a second branch crosses and Newton could
!! reach it instead, the start lies on this branch to O(bracket^4). A trial whose
!! correction from that start exceeds a hundredth of the bracket (it left the branch), or
!! whose corrector fails, ends the location. At a branch point itself Newton's matrix is
!! singular and the iteration cannot meet its step tolerance; the trial is then the
!! interpolant only if a fresh evaluation there meets the corrector's residual tolerance
!! (a checked orbit; its tangent is the interpolant's derivative).
!!
!! The special point is `located` when the bracket in sigma shrank below locate_tol (or
!! a test function vanished exactly), or when the trials stopped with the bracket's
!! parameter interval already below 10 locate_tol max(1, |p|). Otherwise it is "not
!! located": its orbit is the bracket end with the smaller test function (a checked
!! orbit, never an unchecked interpolated state) and the message says why. Every special
!! point carries its test-function value and the closure of its orbit by an independent
!! integration. A sign change of the branch-point test at a fold is the fold itself and
!! is not reported twice; a Neimark-Sacker test that vanishes for a real pair mu, 1/mu (a
!! neutral saddle) is not reported.
module conmech_cont_locate
    use conmech_kinds, only: dp
    use conmech_illinois, only: illinois_bracket
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_orbit_types, only: set_parameter_proc
    use conmech_multiplier_tests, only: ns_is_complex
    use conmech_branch_types
    use conmech_cont_problem
    implicit none
    private

    public :: detect_special, record_special

contains

    !> Sign changes between the points k-1 (X0, tangent t0) and k (X1, tangent t1) of the
    !! branch: locate and record each.
    subroutine detect_special(sys, set_param, pb, br, x0, t0, x1, t1, ds, k)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(inout) :: pb
        type(branch), intent(inout) :: br
        real(dp), intent(in) :: x0(:), t0(:), x1(:), t1(:), ds
        integer, intent(in) :: k
        type(special_point) :: sp
        real(dp) :: a, b, xs(size(x0))
        integer :: kind
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
            call locate(sys, set_param, pb, x0, t0, x1, t1, ds, kind, br%points(k - 1), &
                        br%points(k), sp, xs)
            if (kind == SP_NS) then
                if (.not. ns_is_complex(sp%point%mr, sp%point%mi, pb%ntriv)) cycle
            end if
            sp%kind = kind
            sp%index = k - 1
            call record_special(sys, set_param, pb, sp, xs)
            br%nspecial = br%nspecial + 1
            br%special(br%nspecial) = sp
        end do
    end subroutine detect_special

    !> The closure of the special point's orbit (X = xs) and its test-function value.
    subroutine record_special(sys, set_param, pb, sp, xs)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(in) :: pb
        type(special_point), intent(inout) :: sp
        real(dp), intent(in) :: xs(:)
        integer :: info
        sp%test = sp%point%psi(sp%kind)
        call cp_closure(sys, set_param, pb, xs, sp%closure, info)
        if (info < 0) sp%closure = huge(1.0_dp)
    end subroutine record_special

    !> Cubic Hermite interpolation in sigma of the branch between (sa, xa, da) and
    !! (sb, xb, db), d the derivative dX/dsigma.
    pure function hermite(sa, xa, da, sb, xb, db, s) result(x)
        real(dp), intent(in) :: sa, xa(:), da(:), sb, xb(:), db(:), s
        real(dp) :: x(size(xa)), h, u, h00, h10, h01, h11
        h = sb - sa
        u = (s - sa)/h
        h00 = (1.0_dp + 2.0_dp*u)*(1.0_dp - u)**2
        h10 = u*(1.0_dp - u)**2
        h01 = u*u*(3.0_dp - 2.0_dp*u)
        h11 = u*u*(u - 1.0_dp)
        x = h00*xa + h10*h*da + h01*xb + h11*h*db
    end function hermite

    !> The derivative in sigma of the cubic Hermite interpolant (see `hermite`).
    pure function hermite_slope(sa, xa, da, sb, xb, db, s) result(d)
        real(dp), intent(in) :: sa, xa(:), da(:), sb, xb(:), db(:), s
        real(dp) :: d(size(xa)), h, u
        h = sb - sa
        u = (s - sa)/h
        d = (6.0_dp*u*u - 6.0_dp*u)*(xa - xb)/h + (3.0_dp*u*u - 4.0_dp*u + 1.0_dp)*da + &
            (3.0_dp*u*u - 2.0_dp*u)*db
    end function hermite_slope

    !> Illinois on sigma in [0, ds] (see the module notes). sp receives the point, located,
    !! p_bracket and message; xs the X of its orbit.
    subroutine locate(sys, set_param, pb, x0, t0, x1, t1, ds, kind, p0, p1, sp, xs)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(inout) :: pb
        real(dp), intent(in) :: x0(:), t0(:), x1(:), t1(:), ds
        integer, intent(in) :: kind
        type(cont_point), intent(in) :: p0, p1
        type(special_point), intent(out) :: sp
        real(dp), intent(out) :: xs(:)
        real(dp) :: sc, fc, x(size(x0)), t(size(x0)), xh(size(x0))
        real(dp) :: xa(size(x0)), xb(size(x0)), da(size(x0)), db(size(x0)), pscale, res
        integer :: iter, it, info
        type(illinois_bracket) :: br
        logical :: moved
        type(cont_point) :: trial, qa, qb
        type(cconstraint) :: con
        character(len=:), allocatable :: msg, why
        character(len=40) :: buf
        br%a = 0.0_dp
        br%b = ds
        qa = p0
        qb = p1
        xa = x0
        xb = x1
        da = t0/cp_rdot(pb, t0, t0)
        db = t1/cp_rdot(pb, t0, t1)
        br%fa = qa%psi(kind)
        br%fb = qb%psi(kind)
        con%kind = CON_LINEAR
        con%a = t0
        if (pb%o%discretisation /= 1) call zero_unreduced(con%a)
        why = "the iteration limit"
        sp%reason = SPR_LIMIT
        do iter = 1, 60
            sc = br%trial()
            if (br%a < br%b) then
                xh = hermite(br%a, xa, da, br%b, xb, db, sc)
            else
                xh = hermite(br%b, xb, db, br%a, xa, da, sc)
            end if
            x = xh
            con%b = dot_product(con%a, x0) + sc
            call cp_correct(sys, set_param, pb, x, con, .false., it, info, msg)
            if (info /= CM_SUCCESS) then
                ! at a branch point Newton's matrix is singular and the iteration cannot
                ! meet its step tolerance: the interpolant itself is accepted when its own
                ! residual (a fresh evaluation) meets the corrector's residual tolerance
                x = xh
                it = 0
                call cp_evaluate(sys, set_param, pb, x, res, info, msg)
                if (info == CM_SUCCESS .and. .not. (res <= pb%o%res_tol)) then
                    info = CM_NO_CONVERGENCE
                    msg = "Newton did not converge"
                end if
            end if
            if (info == CM_SUCCESS) then
                t = t0
                call cp_make_point(sys, set_param, pb, x, t, it, sc, trial, info)
                if (info == CM_SINGULAR) then
                    ! no unique tangent at the branch point: this branch's is the limit of
                    ! its tangents, the derivative of the interpolant
                    if (br%a < br%b) then
                        t = hermite_slope(br%a, xa, da, br%b, xb, db, sc)
                    else
                        t = hermite_slope(br%b, xb, db, br%a, xa, da, sc)
                    end if
                    t = t/cp_rnorm(pb, t)
                    call cp_make_point(sys, set_param, pb, x, t, it, sc, trial, info, &
                                       keep_t=.true.)
                end if
                if (info /= CM_SUCCESS) msg = "the tangent or the multipliers failed"
            end if
            if (info /= CM_SUCCESS) then
                write (buf, '(es10.3)') sc
                why = "the corrector failed at sigma = "//trim(adjustl(buf))//" ("//msg//")"
                sp%reason = SPR_CORRECTOR
                exit
            end if
            if (cp_rnorm(pb, x - xh) > 0.01_dp*abs(br%b - br%a) .and. &
                cp_rnorm(pb, x - xh) > 1.0e3_dp*pb%o%tol*max(1.0_dp, maxval(abs(x)))) then
                write (buf, '(es10.3)') sc
                sp%reason = SPR_LEFT_BRANCH
                why = "the trial at sigma = "//trim(adjustl(buf))//" left the branch "// &
                      "(another branch crosses here)"
                exit
            end if
            fc = trial%psi(kind)
            if (fc == 0.0_dp .or. abs(br%b - br%a) <= pb%o%locate_tol) then
                sp%point = trial
                sp%located = .true.
                sp%reason = SPR_LOCATED
                sp%p_bracket = [min(qa%p, qb%p), max(qa%p, qb%p)]
                sp%message = "located"
                xs = x
                return
            end if
            call br%update(sc, fc, moved)
            if (moved) then
                qa = qb
                xa = xb
                da = db
            end if
            qb = trial
            xb = x
            db = t/cp_rdot(pb, t0, t)
        end do
        ! the trials stopped: the bracket end nearer the sign change (a corrected orbit)
        sp%p_bracket = [min(qa%p, qb%p), max(qa%p, qb%p)]
        if (abs(qa%psi(kind)) <= abs(qb%psi(kind))) then
            sp%point = qa
            xs = xa
        else
            sp%point = qb
            xs = xb
        end if
        pscale = 10.0_dp*pb%o%locate_tol*max(1.0_dp, abs(sp%point%p))
        write (buf, '(2es12.4)') sp%p_bracket
        if (sp%p_bracket(2) - sp%p_bracket(1) <= pscale) then
            sp%located = .true.
            sp%message = "located to the bracket p in ["//trim(adjustl(buf))//"] ("// &
                         why//")"
        else
            sp%located = .false.
            sp%message = "not located: "//why//"; the orbit given is the computed one "// &
                         "nearest the sign change, p in ["//trim(adjustl(buf))//"]"
        end if
    contains
        subroutine zero_unreduced(a)
            real(dp), intent(inout) :: a(:)
            a(pb%n + 1:pb%nx - pb%bvp%nw) = 0.0_dp
        end subroutine zero_unreduced
    end subroutine locate

end module conmech_cont_locate
