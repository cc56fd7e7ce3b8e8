!> Branch switching at a period-doubling point: from the located point (p*, y*, T*) of a
!! branch, onto the branch of orbits of period 2 T* that bifurcates there.
!!
!! At the point, the monodromy M has the multiplier -1 with eigenvector v (found by inverse
!! iteration on M + I, LAPACK dgesv). For the doubled period the shooting Jacobian has the
!! two-dimensional kernel {old tangent, (v, 0, 0)}: the continuation of the problem with
!! period 2 T* starts at (y*, 2 T*, p*) with the tangent (v, 0, 0), so its first
!! pseudo-arclength step leaves the old branch (which the hyperplane t . (X - X*) = ds
!! excludes) for the new one; `direction` (+1/-1) picks the sign of v.
!!
!! Branch switching at a branch point (a real multiplier through +1: a transcritical or a
!! symmetry-breaking pitchfork bifurcation of periodic orbits in a parameter, or in a
!! conservative family continued in the period, S through +1):
!! at the point X* = (y*, T*, p*) the Jacobian DG of the general shooting equations (see
!! conmech_continuation: [Phi - I, f(y(T)), dy(T)/dp; f(y*)^T, 0, 0]) has a two-dimensional
!! kernel, spanned by the right singular vectors of its two smallest singular values (LAPACK
!! dgesvd). It holds the old branch's tangent t_old; the direction in it orthogonal to t_old
!! is the tangent of the second branch (exactly for a pitchfork, and a direction whose
!! pseudo-arclength hyperplane excludes the old branch to first order in general), and the
!! continuation of the same problem starts there. The ratio of the two smallest singular
!! values to the third is reported: a genuine branch point has both far below it.
module conmech_branch_switch
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_integrate
    use conmech_variational, only: integrate_stm
    use conmech_lapack, only: dgesv, dgesvd
    use conmech_shooting, only: set_parameter_proc
    use conmech_continuation, only: cont_options, branch, special_point, continue_orbits, &
                                    SP_PD, SP_BP, cont_point
    implicit none
    private
    public :: switch_period_doubling, switch_branch_point, branch_secant

contains

    !> The doubled-period branch from the period-doubling point `sp` (general shooting of an
    !! autonomous system, period free). `options` as for continue_orbits (its `direction`
    !! chooses the side of v).
    subroutine switch_period_doubling(sys, set_param, sp, br, options)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(special_point), intent(in) :: sp
        type(branch), intent(out) :: br
        type(cont_options), intent(in), optional :: options
        type(cont_options) :: o
        type(ode_options) :: oo
        real(dp), allocatable :: y(:), phi(:, :), a(:, :), v(:, :), t0(:)
        integer, allocatable :: ipiv(:)
        integer :: n, j, it, info
        character(len=:), allocatable :: msg
        if (present(options)) o = options
        if (sp%kind /= SP_PD .or. .not. allocated(sp%point%y0)) then
            call br%fail(CM_BAD_INPUT, "switch_period_doubling: not a located period-doubling "// &
                                       "point")
            return
        end if
        n = size(sp%point%y0)
        allocate (y(n), phi(n, n), a(n, n), v(n, 1), ipiv(n), t0(n + 2))
        oo%rtol = o%rtol
        oo%atol = o%atol
        oo%method = o%integrator
        call set_param(sys, sp%point%p)
        y = sp%point%y0
        phi = 0.0_dp
        do j = 1, n
            phi(j, j) = 1.0_dp
        end do
        call integrate_stm(sys, 0.0_dp, sp%point%period, y, phi, oo, info, msg)
        if (info < 0) then
            call br%fail(info, "switch_period_doubling: "//msg)
            return
        end if
        ! inverse iteration on M + I for the eigenvector of the multiplier -1
        v(:, 1) = 1.0_dp/sqrt(real(n, dp))
        do it = 1, 3
            a = phi
            do j = 1, n
                a(j, j) = a(j, j) + 1.0_dp
            end do
            call dgesv(n, 1, a, n, ipiv, v, n, info)
            if (info < 0 .or. .not. (norm2(v(:, 1)) > 0.0_dp)) then
                call br%fail(CM_SINGULAR, "switch_period_doubling: no eigenvector for the "// &
                                          "multiplier -1")
                return
            end if
            v(:, 1) = v(:, 1)/norm2(v(:, 1))
        end do
        t0 = 0.0_dp
        t0(1:n) = real(sign(1, o%direction), dp)*v(:, 1)
        call continue_orbits(sys, set_param, sp%point%p, sp%point%y0, 2.0_dp*sp%point%period, &
                             br, o, tangent0=t0)
    end subroutine switch_period_doubling

    !> The unit secant (X(b) - X(a))/|X(b) - X(a)| between two points of a branch of general
    !! shooting, X = [y0, T, p] (T left out with `with_period` false): an approximation of
    !! the tangent there, e.g. the old branch's at a branch point between them.
    pure function branch_secant(a, b, with_period) result(t)
        type(cont_point), intent(in) :: a, b
        logical, intent(in) :: with_period
        real(dp), allocatable :: t(:)
        if (with_period) then
            t = [b%y0 - a%y0, b%period - a%period, b%p - a%p]
        else
            t = [b%y0 - a%y0, b%p - a%p]
        end if
        if (norm2(t) > 0.0_dp) t = t/norm2(t)
    end function branch_secant

    !> The second branch through the branch point `sp` (kind SP_BP, general shooting: the
    !! period an unknown for autonomous systems, fixed otherwise, or the continued quantity
    !! of a conservative family with `in_period`; not symmetric shooting, whose equations
    !! exclude the asymmetric branch of a symmetry-breaking pitchfork). `t_old`: the old
    !! branch's tangent at the point in the unknowns [y0, T, p] (T absent for a fixed
    !! period; [y0, T] with `in_period`), e.g. `branch_secant` of the points around it.
    !! `options` as for continue_orbits (`direction` picks the side of the new branch).
    !! `ratio` (optional): the second smallest singular value of DG over the third (small
    !! at a branch point).
    subroutine switch_branch_point(sys, set_param, sp, t_old, br, options, ratio)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(special_point), intent(in) :: sp
        real(dp), intent(in) :: t_old(:)
        type(branch), intent(out) :: br
        type(cont_options), intent(in), optional :: options
        real(dp), intent(out), optional :: ratio
        type(cont_options) :: o
        real(dp), allocatable :: dg(:, :), sv(:), vt(:, :), tn(:), k1(:), k2(:)
        real(dp) :: a1, a2, rat
        integer :: n, nx, neq, info
        logical :: tfree
        character(len=:), allocatable :: msg
        if (present(options)) o = options
        if (present(ratio)) ratio = huge(1.0_dp)
        if (sp%kind /= SP_BP .or. .not. allocated(sp%point%y0)) then
            call br%fail(CM_BAD_INPUT, "switch_branch_point: not a located branch point")
            return
        end if
        n = size(sp%point%y0)
        tfree = o%autonomous .and. .not. o%fixed_period .and. .not. o%in_period
        nx = n + 1
        if (tfree) nx = n + 2
        neq = n
        if (o%autonomous) neq = n + 1
        if ((o%conservative .and. .not. o%in_period) .or. &
            (o%autonomous .and. o%fixed_period)) then
            call br%fail(CM_BAD_INPUT, "switch_branch_point: for the general shooting of a "// &
                                       "family in a parameter, or of a conservative family in "// &
                                       "the period (in_period)")
            return
        end if
        if (size(t_old) /= nx .or. .not. (norm2(t_old) > 0.0_dp)) then
            call br%fail(CM_BAD_INPUT, "switch_branch_point: t_old must be a non-zero vector "// &
                                       "with one entry per unknown [y0, T, p]")
            return
        end if
        allocate (dg(neq, nx), sv(min(neq, nx)), vt(nx, nx), tn(nx), k1(nx), k2(nx))
        call shooting_jacobian(sys, set_param, sp%point, o, tfree, dg, info, msg)
        if (info /= CM_SUCCESS) then
            call br%fail(info, "switch_branch_point: "//msg)
            return
        end if
        call svd_vt(dg, sv, vt, info)
        if (info /= CM_SUCCESS .or. size(sv) < 3) then
            call br%fail(CM_SINGULAR, "switch_branch_point: SVD of the shooting Jacobian failed")
            return
        end if
        ! kernel of DG (neq = nx - 1 rows, or nx with in_period where the energy integral
        ! makes one row dependent): the last two right singular vectors
        k1 = vt(nx - 1, :)
        k2 = vt(nx, :)
        rat = sv(nx - 1)/max(sv(nx - 2), tiny(1.0_dp))
        if (present(ratio)) ratio = rat
        a1 = dot_product(t_old, k1)
        a2 = dot_product(t_old, k2)
        if (.not. (hypot(a1, a2) > 0.5_dp*norm2(t_old))) then
            call br%fail(CM_SINGULAR, "switch_branch_point: t_old is not in the kernel of the "// &
                                      "shooting Jacobian (not the tangent of this branch at "// &
                                      "this point?)")
            return
        end if
        tn = -a2*k1 + a1*k2
        tn = tn/norm2(tn)
        ! a sign convention independent of the SVD: the largest component positive
        if (tn(maxloc(abs(tn), 1)) < 0.0_dp) tn = -tn
        tn = real(sign(1, o%direction), dp)*tn
        call continue_orbits(sys, set_param, sp%point%p, sp%point%y0, sp%point%period, br, o, &
                             tangent0=tn)
    end subroutine switch_branch_point

    !> DG of the general shooting equations at the point (phase condition about itself).
    subroutine shooting_jacobian(sys, set_param, pt, o, tfree, dg, info, msg)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cont_point), intent(in) :: pt
        type(cont_options), intent(in) :: o
        logical, intent(in) :: tfree
        real(dp), intent(out) :: dg(:, :)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(ode_options) :: oo
        real(dp) :: y(size(pt%y0)), phi(size(pt%y0), size(pt%y0)), yp(size(pt%y0))
        real(dp) :: ym(size(pt%y0)), f(size(pt%y0)), h
        integer :: n, j, nx
        n = size(pt%y0)
        nx = size(dg, 2)
        oo%rtol = o%rtol
        oo%atol = o%atol
        oo%method = o%integrator
        h = o%fd_step*max(1.0_dp, abs(pt%p))
        if (.not. o%in_period) then
            call set_param(sys, pt%p + h)
            yp = pt%y0
            call ode_integrate(sys, 0.0_dp, pt%period, yp, oo, info, message=msg)
            if (info < 0) return
            call set_param(sys, pt%p - h)
            ym = pt%y0
            call ode_integrate(sys, 0.0_dp, pt%period, ym, oo, info, message=msg)
            if (info < 0) return
            call set_param(sys, pt%p)
        end if
        y = pt%y0
        phi = 0.0_dp
        do j = 1, n
            phi(j, j) = 1.0_dp
        end do
        call integrate_stm(sys, 0.0_dp, pt%period, y, phi, oo, info, msg)
        if (info < 0) return
        dg = 0.0_dp
        dg(1:n, 1:n) = phi
        do j = 1, n
            dg(j, j) = dg(j, j) - 1.0_dp
        end do
        call sys%rhs(pt%period, y, f)
        if (tfree) dg(1:n, n + 1) = f
        if (o%in_period) then
            dg(1:n, nx) = f                      ! the period is the continued quantity
        else
            dg(1:n, nx) = (yp - ym)/(2.0_dp*h)
        end if
        if (size(dg, 1) > n) then
            call sys%rhs(0.0_dp, pt%y0, f)
            dg(n + 1, 1:n) = f
        end if
        info = CM_SUCCESS
        msg = "success"
        if (.not. all(abs(dg) <= huge(1.0_dp))) then
            info = CM_NONFINITE
            msg = "the shooting Jacobian is not finite"
        end if
    end subroutine shooting_jacobian

    !> Singular values and the full V^T of a (dgesvd, workspace query first).
    subroutine svd_vt(a, s, vt, info)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(out) :: s(:), vt(:, :)
        integer, intent(out) :: info
        real(dp), allocatable :: aa(:, :), work(:)
        real(dp) :: u(1, 1), wq(1)
        integer :: m, n
        m = size(a, 1)
        n = size(a, 2)
        aa = a
        call dgesvd('N', 'A', m, n, aa, m, s, u, 1, vt, n, wq, -1, info)
        if (info /= 0) then
            info = CM_SINGULAR
            return
        end if
        allocate (work(max(1, int(wq(1)))))
        call dgesvd('N', 'A', m, n, aa, m, s, u, 1, vt, n, work, size(work), info)
        info = merge(CM_SUCCESS, CM_SINGULAR, info == 0)
    end subroutine svd_vt

end module conmech_branch_switch
