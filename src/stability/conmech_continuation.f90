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
!!   G = y(tau)(targets), the period is `period_factor` * tau; the unknowns other than p
!!   must be as many as the targets.
!! - `discretisation` ORBIT_MULTIPLE / ORBIT_COLLOCATION: the same equations by multiple
!!   shooting or collocation (conmech_orbit_bvp: X holds every node and stage, the
!!   structured solve of conmech_block_chain; the arclength and the tangent's norm use
!!   the first node and (T, p) only, so that ds means the same as for single shooting).
!! The Jacobian comes from the state transition matrices (variational equations) and, for
!! the parameter, from central differences (step `fd_step` max(1, |p|)). The parameter is
!! set through the callback `set_param(sys, p)`. With `in_period` (conservative systems,
!! no parameter) the period itself is the continued quantity (X = [y0, T], or
!! [y0(free), tau] for symmetric shooting), so the branch is the family of orbits through
!! the energy levels.
!!
!! Predictor: X + ds t (t the unit tangent, the null vector of DG, oriented by the previous
!! one); corrector: Newton on [G(X); t . (X - X_pred)] = 0. Step length: grown by 1.5 after
!! a corrector of <= 3 iterations, shrunk by 0.7 after >= 6, halved on failure (the branch
!! stops, with a message naming the parameter value, below `ds_min`). The first direction:
!! `direction` +1/-1, or 0 (the default): towards larger p unless the amplitude of the orbit
!! (|f(y0)|, zero at an equilibrium) shrinks that way fast enough to reach zero within the
!! branch's reach, max_points ds_max (a family born at an equilibrium is followed away
!! from it, not into it).
!!
!! Collocation: the mesh is adapted (equidistribution, conmech_collocation_mesh) every
!! third point, solution and tangent carried over; every point's nodes are checked by
!! independent integrations, and the branch stops with a message where the mesh no longer
!! resolves the orbit.
!!
!! Ranges: p_range (p_min, p_max), and the period and the energy (an `energy(y, p)`
!! function) ranges. A step that leaves a range is replaced by the orbit exactly on the
!! bound (Newton with the bound as the extra equation, from the interpolation of the two
!! points); if that fails the branch ends at the last point inside, with a message.
!!
!! Special points: see conmech_cont_locate (fold: the parameter component of the tangent;
!! branch point: a real multiplier through +1, for a conservative planar orbit S through
!! +1; period doubling: through -1; Neimark-Sacker: a complex pair through the unit circle,
!! not for conservative systems; test functions in conmech_multiplier_tests).
module conmech_continuation
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_orbit_types, only: set_parameter_proc, ORBIT_COLLOCATION
    use conmech_orbit_newton, only: bvp_closure_tol
    use conmech_collocation_mesh, only: co_new_mesh, co_remesh
    use conmech_branch_types
    use conmech_cont_problem
    use conmech_cont_locate, only: detect_special
    implicit none
    private

    public :: SP_FOLD, SP_BP, SP_PD, SP_NS
    public :: cont_options, cont_point, special_point, branch, continue_orbits, special_name
    public :: branch_energy

contains

    !> Continue the periodic orbit through y0 (period guess `period`) of `sys` at the
    !! parameter p0 (set by `set_param`). General shooting, or symmetric shooting when
    !! `free` and `targets` are given (see the module notes). Returns the branch; its info is
    !! CM_SUCCESS when it ended normally (max_points or a range bound), CM_NO_CONVERGENCE
    !! when the corrector failed below ds_min (the branch so far is kept; the message names
    !! the parameter value), CM_SINGULAR / CM_NO_CONVERGENCE / CM_BAD_INPUT for a bad start.
    !! `energy` (E(y, p), an extension of branch_energy): for the energy range (options
    !! energy_min/energy_max).
    subroutine continue_orbits(sys, set_param, p0, y0, period, br, options, free, targets, &
                               free_time, period_factor, tangent0, energy)
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
        class(branch_energy), intent(in), optional :: energy
        type(cproblem) :: pb
        real(dp), allocatable :: x(:), t(:), xn(:), tn(:)
        type(cont_point) :: pt
        type(cconstraint) :: con
        real(dp) :: ds, f(size(y0)), fx(size(y0)), tend, per, p, clos, ratio
        real(dp), allocatable :: newmesh(:)
        integer :: info, it, k, dir
        logical :: ended
        character(len=:), allocatable :: msg
        character(len=32) :: buf
        character(len=64) :: b2
        if (present(options)) pb%o = options
        call cp_setup(pb, y0, period, p0, free, targets, free_time, period_factor, info, msg)
        if (info /= CM_SUCCESS) then
            call br%fail(info, msg)
            return
        end if
        if (pb%o%autonomous .and. .not. present(tangent0)) then
            if (.not. pb%o%in_period) call set_param(sys, p0)
            call sys%rhs(0.0_dp, y0, f)
            if (norm2(f)*period <= 1.0e-10_dp*max(1.0_dp, maxval(abs(y0)))) then
                br%info = CM_BAD_INPUT
                write (buf, '(es9.2)') norm2(f)
                br%message = "continuation: the start y0 is an equilibrium (|f(y0)| = "// &
                             trim(adjustl(buf))//"): start from a small periodic orbit "// &
                             "near it"
                return
            end if
        end if
        allocate (br%points(pb%o%max_points), br%special(64))
        allocate (x(pb%nx), t(pb%nx), xn(pb%nx), tn(pb%nx))
        if (pb%o%discretisation == ORBIT_COLLOCATION) allocate (newmesh(pb%bvp%k + 1))
        if (.not. pb%o%in_period) call set_param(sys, p0)
        call cp_pack_start(sys, pb, y0, period, p0, x, info, msg)
        if (info /= CM_SUCCESS) then
            call br%fail(info, "continuation: "//msg)
            return
        end if
        ! the first point: Newton at fixed p (a given tangent0 starts at a bifurcation
        ! point: already a solution, not isolated; the equations are only evaluated)
        it = 0
        if (present(tangent0)) then
            call cp_set_reference(sys, set_param, pb, x)
            con = fixed_last(pb, x)
            con%kind = -1
        else
            con = fixed_last(pb, x)
        end if
        call first_point(sys, set_param, pb, x, con, it, info, msg)
        if (info /= CM_SUCCESS) then
            call br%fail(info, "continuation: the start is not a periodic orbit: "//msg)
            return
        end if
        if (pb%o%autonomous .and. .not. present(tangent0)) then
            ! Newton at a fixed period can end on an equilibrium (periodic with any period)
            call cp_unpack(pb, x, f, tend, per, p)
            call sys%rhs(0.0_dp, f, fx)
            if (norm2(fx)*per <= 1.0e-10_dp*max(1.0_dp, maxval(abs(f)))) then
                call br%fail(CM_BAD_INPUT, "continuation: the start converged to an "// &
                                           "equilibrium (a periodic solution of any period): "// &
                                           "start from the orbit's own period, e.g. found by "// &
                                           "symmetric_orbit with the time free")
                return
            end if
        end if
        ! the first tangent: the null vector of DG with t_p of sign `direction`
        dir = pb%o%direction
        t = 0.0_dp
        t(pb%nx) = 1.0_dp
        if (dir < 0) t(pb%nx) = -1.0_dp
        if (present(tangent0)) then
            call start_tangent(pb, tangent0, t, info)
            if (info /= CM_SUCCESS) then
                call br%fail(CM_BAD_INPUT, "continuation: tangent0 must have one entry per "// &
                                           "unknown [y0, T, p] of single shooting (T only if "// &
                                           "free)")
                return
            end if
        end if
        call cp_make_point(sys, set_param, pb, x, t, it, 0.0_dp, br%points(1), info, &
                           keep_t=present(tangent0))
        if (info /= CM_SUCCESS) then
            call br%fail(CM_SINGULAR, "continuation: degenerate start (no unique tangent: the "// &
                                      "orbit is not isolated, or already at a fold)")
            return
        end if
        if (dir == 0 .and. .not. present(tangent0)) then
            if (walks_into_equilibrium(sys, set_param, pb, x, t)) t = -t
            br%points(1)%psi(SP_FOLD) = t(pb%nx)
        end if
        br%direction = merge(1, -1, t(pb%nx) >= 0.0_dp)
        br%npoints = 1
        br%info = CM_SUCCESS
        br%message = "success: max_points reached"
        ds = pb%o%ds
        do while (br%npoints < pb%o%max_points)
            call cp_set_reference(sys, set_param, pb, x)
            xn = x + ds*t
            con%kind = CON_LINEAR
            con%a = reduced(pb, t)
            con%b = dot_product(con%a, xn)
            call cp_correct(sys, set_param, pb, xn, con, .false., it, info, msg)
            tn = t
            if (info == CM_SUCCESS) then
                call cp_make_point(sys, set_param, pb, xn, tn, it, ds, pt, info)
                if (info /= CM_SUCCESS) msg = "the tangent or the multipliers failed"
            end if
            if (info /= CM_SUCCESS) then
                ds = 0.5_dp*ds
                if (ds < pb%o%ds_min) then
                    call br%corrector_stalled("continuation", br%points(br%npoints)%p, msg)
                    exit
                end if
                cycle
            end if
            call range_end(sys, set_param, pb, x, xn, tn, pt, ended, msg, energy)
            if (ended .and. .not. allocated(pt%y0)) then
                br%message = msg
                exit
            end if
            if (pb%o%discretisation == ORBIT_COLLOCATION) then
                ! the discrete orbit must still be the orbit: independent integrations
                call cp_closure(sys, set_param, pb, xn, clos, info)
                if (info < 0 .or. .not. (clos <= bvp_closure_tol(pb%bvp, xn))) then
                    write (buf, '(es23.15)') pt%p
                    write (b2, '(i0,a,i0,a,es9.2)') pb%bvp%k, " intervals of degree ", &
                        pb%bvp%m, "; closure ", clos
                    call br%fail(CM_NO_CONVERGENCE, "continuation stopped at p = "// &
                                                    trim(adjustl(buf))//": the collocation "// &
                                                    "mesh ("//trim(b2)//") does not resolve "// &
                                                    "the orbit there (use more intervals or "// &
                                                    "a higher degree)")
                    exit
                end if
            end if
            br%npoints = br%npoints + 1
            br%points(br%npoints) = pt
            k = br%npoints
            ! (from a bifurcation point, the test functions of the first point are ~0)
            if (pb%o%locate .and. .not. (present(tangent0) .and. k == 2)) &
                call detect_special(sys, set_param, pb, br, x, t, xn, tn, &
                                    cp_rdot(pb, reduced(pb, t), xn - x), k)
            x = xn
            t = tn
            if (pb%o%discretisation == ORBIT_COLLOCATION .and. mod(br%npoints, 3) == 0) then
                ! the mesh follows the orbit (equidistribution, as AUTO every 3 steps)
                call co_new_mesh(pb%bvp, pb%bvp%tab, x, newmesh, ratio)
                call co_remesh(pb%bvp, pb%bvp%tab, newmesh, x, xn)
                call co_remesh(pb%bvp, pb%bvp%tab, newmesh, t, tn)
                pb%bvp%mesh = newmesh
                x = xn
                t = tn/cp_rnorm(pb, tn)
            end if
            if (ended) then
                br%message = msg
                exit
            end if
            if (it <= 3) ds = min(pb%o%ds_max, 1.5_dp*ds)
            if (it >= 6) ds = max(pb%o%ds_min, 0.7_dp*ds)
        end do
    end subroutine continue_orbits

    !> t with the components outside the reduced unknowns set to zero.
    pure function reduced(pb, t) result(r)
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: t(:)
        real(dp) :: r(size(t))
        r = t
        if (pb%o%discretisation /= 1) r(pb%n + 1:pb%nx - pb%bvp%nw) = 0.0_dp
    end function reduced

    !> The constraint fixing the continued quantity (the last unknown) at its value in x.
    pure function fixed_last(pb, x) result(con)
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: x(:)
        type(cconstraint) :: con
        con%kind = CON_LINEAR
        allocate (con%a(pb%nx))
        con%a = 0.0_dp
        con%a(pb%nx) = 1.0_dp
        con%b = x(pb%nx)
    end function fixed_last

    !> The start: corrected at fixed p, or (con%kind < 0, a given tangent) only evaluated
    !! (a bifurcation point: Newton is singular there, and X is already a solution).
    subroutine first_point(sys, set_param, pb, x, con, it, info, msg)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(inout) :: pb
        real(dp), intent(inout) :: x(:)
        type(cconstraint), intent(inout) :: con
        integer, intent(out) :: it, info
        character(len=:), allocatable, intent(out) :: msg
        real(dp) :: res
        if (con%kind >= 0) then
            call cp_correct(sys, set_param, pb, x, con, .true., it, info, msg)
            return
        end if
        con%kind = CON_LINEAR
        it = 0
        call cp_evaluate(sys, set_param, pb, x, res, info, msg)
    end subroutine first_point

    !> The tangent of a branch switch in this problem's unknowns from tangent0 given in
    !! single shooting's [y0, T, p] (or [y0, T] / [y0, p] as the problem's period is free
    !! or not): the reduced part; the rest follows from DG t = 0 in cp_make_point.
    subroutine start_tangent(pb, tangent0, t, info)
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: tangent0(:)
        real(dp), intent(out) :: t(:)
        integer, intent(out) :: info
        integer :: nw
        info = CM_BAD_INPUT
        t = 0.0_dp
        if (pb%o%discretisation == 1) then
            if (size(tangent0) /= pb%nx .or. .not. (norm2(tangent0) > 0.0_dp)) return
            t = tangent0/norm2(tangent0)
        else
            nw = pb%bvp%nw
            if (size(tangent0) /= pb%n + nw .or. .not. (norm2(tangent0) > 0.0_dp)) return
            t(1:pb%n) = tangent0(1:pb%n)
            t(pb%nx - nw + 1:) = tangent0(pb%n + 1:)
            t = t/norm2(tangent0)
        end if
        info = CM_SUCCESS
    end subroutine start_tangent

    !> True if the step along t (towards larger p) shrinks the orbit's amplitude |f(y0)|
    !! fast enough to reach zero (an equilibrium) within max_points ds_max.
    logical function walks_into_equilibrium(sys, set_param, pb, x, t) result(into)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: x(:), t(:)
        real(dp) :: y(pb%n), f0(pb%n), f1(pb%n), tend, per, p, h, a0, a1, reach
        into = .false.
        if (.not. pb%o%autonomous) return
        h = 1.0e-4_dp*max(1.0_dp, maxval(abs(x)))
        call cp_unpack(pb, x, y, tend, per, p)
        if (.not. pb%o%in_period) call set_param(sys, p)
        call sys%rhs(0.0_dp, y, f0)
        call cp_unpack(pb, x + h*t, y, tend, per, p)
        if (.not. pb%o%in_period) call set_param(sys, p)
        call sys%rhs(0.0_dp, y, f1)
        call cp_unpack(pb, x, y, tend, per, p)
        if (.not. pb%o%in_period) call set_param(sys, p)
        a0 = norm2(f0)
        a1 = norm2(f1)
        reach = pb%o%max_points*pb%o%ds_max
        if (.not. (a1 < a0)) return
        into = a0/((a0 - a1)/h) < reach
    end function walks_into_equilibrium

    !> If the new point xn leaves the p, period or energy range, replace it by the orbit on
    !! the bound (pt, xn, tn updated; ended with a message). If that orbit cannot be
    !! computed, pt%y0 is deallocated (the branch ends at x) and the message says so.
    subroutine range_end(sys, set_param, pb, x, xn, tn, pt, ended, msg, energy)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(inout) :: pb
        real(dp), intent(in) :: x(:)
        real(dp), intent(inout) :: xn(:), tn(:)
        type(cont_point), intent(inout) :: pt
        logical, intent(out) :: ended
        character(len=:), allocatable, intent(out) :: msg
        class(branch_energy), intent(in), optional :: energy
        real(dp) :: m0(3), m1(3), lo(3), hi(3), bound, w, xb(size(x)), tb(size(x)), y(pb%n)
        real(dp) :: tend, per, p
        type(cconstraint) :: con
        type(cont_point) :: pe
        integer :: which, info, it, iw
        character(len=*), parameter :: names(3) = ["p     ", "period", "energy"]
        character(len=32) :: buf
        ended = .false.
        msg = ""
        call monitors(x, m0)
        call monitors(xn, m1)
        lo = [pb%o%p_min, pb%o%period_min, pb%o%energy_min]
        hi = [pb%o%p_max, pb%o%period_max, pb%o%energy_max]
        if (.not. present(energy)) then
            lo(3) = -huge(1.0_dp)
            hi(3) = huge(1.0_dp)
        end if
        do which = 1, 3
            if (m1(which) > hi(which) .and. m0(which) <= hi(which)) then
                bound = hi(which)
            else if (m1(which) < lo(which) .and. m0(which) >= lo(which)) then
                bound = lo(which)
            else
                cycle
            end if
            ended = .true.
            write (buf, '(es23.15)') bound
            w = (bound - m0(which))/(m1(which) - m0(which))
            xb = x + w*(xn - x)
            con%kind = CON_LINEAR
            allocate (con%a(pb%nx))
            con%a = 0.0_dp
            iw = period_index(which)
            if (which == 3) then
                con%kind = CON_ENERGY
                con%b = bound
            else if (iw > 0) then
                ! p itself, or the unknown time: the period over period_factor
                con%a(iw) = 1.0_dp
                con%b = bound
                if (which == 2 .or. pb%o%in_period) con%b = bound/pb%pf
            else
                ended = .false.
                deallocate (con%a)
                cycle
            end if
            call cp_correct(sys, set_param, pb, xb, con, .false., it, info, msg, energy)
            tb = tn
            if (info == CM_SUCCESS) call cp_make_point(sys, set_param, pb, xb, tb, it, &
                                                        pt%ds, pe, info)
            if (info == CM_SUCCESS) then
                pt = pe
                xn = xb
                tn = tb
                msg = "success: the branch reached "//trim(names(which))//" = "// &
                      trim(adjustl(buf))
            else
                if (allocated(pt%y0)) deallocate (pt%y0)
                msg = "the branch ends at the last point before "//trim(names(which))// &
                      " = "//trim(adjustl(buf))//": the orbit on the bound could not "// &
                      "be computed ("//msg//")"
            end if
            return
        end do
    contains
        subroutine monitors(xx, m)
            real(dp), intent(in) :: xx(:)
            real(dp), intent(out) :: m(3)
            call cp_unpack(pb, xx, y, tend, per, p)
            m(1) = p
            m(2) = per
            m(3) = 0.0_dp
            if (present(energy)) m(3) = energy%value(y, p)
        end subroutine monitors
        !> The unknown carrying p (which = 1) or the period (2); 0 if it is not one.
        integer function period_index(wh) result(i)
            integer, intent(in) :: wh
            i = 0
            if (wh == 1 .or. (wh == 2 .and. pb%o%in_period)) then
                i = pb%nx
            else if (wh == 2) then
                if (pb%o%discretisation /= 1) then
                    if (pb%bvp%tfree) i = pb%nx - pb%bvp%nw + 1
                else if (pb%tfree) then
                    i = merge(size(pb%free) + 1, pb%n + 1, pb%sym)
                end if
            end if
        end function period_index
    end subroutine range_end

end module conmech_continuation
