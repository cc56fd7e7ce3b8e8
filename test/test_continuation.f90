!> Pseudo-arclength continuation of periodic orbits and their special points, against
!! closed forms (normal forms whose multipliers are known exactly) and Hill's problem.
module continuation_test_systems
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use conmech
    implicit none
    private
    public :: nf_cycles, fold_cycle, set_p

    !> 7-dim system with the cycle x = cos t, y = sin t (period 2 pi, every p) and, along
    !! it, the exact multipliers 1, exp(-4 pi) (radial), -exp(2 pi (p - 1)) and
    !! -exp(-2 pi) (a Moebius band: (u, w) turns by half the angle, xi' = diag(p - 1, -1) xi
    !! - |xi|^2 xi in the half-angle frame), exp(2 pi (p - 2)) (z' = (p - 2) z - z^3) and
    !! exp(2 pi (p - 3)) exp(+-2 pi i alpha) (v' = (p - 3 + i alpha) v - |v|^2 v):
    !! period doubling at p = 1 (the doubled orbit has |xi|^2 = p - 1), a pitchfork branch
    !! point at p = 2, Neimark-Sacker at p = 3 (closed forms by construction).
    type, extends(ode_system) :: nf_cycles
        real(dp) :: p = 0.0_dp
        real(dp) :: alpha = 0.4472135954999579_dp
    contains
        procedure :: rhs => nf_rhs
    end type nf_cycles

    !> r' = r (p + r^2 - r^4), theta' = 1 + r^2: a fold of cycles at p = -1/4, r^2 = 1/2,
    !! period 2 pi/(1 + r^2) = 4 pi/3 there (closed form).
    type, extends(ode_system) :: fold_cycle
        real(dp) :: p = 0.0_dp
        real(dp) :: p_break = -huge(1.0_dp)   !! below it the model returns NaN (a test)
    contains
        procedure :: rhs => fold_rhs
    end type fold_cycle

contains

    subroutine set_p(sys, p)
        class(ode_system), intent(inout) :: sys
        real(dp), intent(in) :: p
        select type (sys)
        type is (nf_cycles)
            sys%p = p
        type is (fold_cycle)
            sys%p = p
        end select
    end subroutine set_p

    subroutine nf_rhs(self, t, y, dydt)
        class(nf_cycles), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: r2, r, c, s, a, b, q2, v2
        r2 = y(1)**2 + y(2)**2
        r = sqrt(r2)
        c = y(1)/r
        s = y(2)/r
        dydt(1) = y(1)*(1.0_dp - r2) - y(2)
        dydt(2) = y(2)*(1.0_dp - r2) + y(1)
        a = self%p - 1.0_dp
        b = -1.0_dp
        q2 = y(3)**2 + y(4)**2
        dydt(3) = -0.5_dp*y(4) + 0.5_dp*(a + b)*y(3) + 0.5_dp*(a - b)*(c*y(3) + s*y(4)) &
                  - q2*y(3)
        dydt(4) = 0.5_dp*y(3) + 0.5_dp*(a + b)*y(4) + 0.5_dp*(a - b)*(s*y(3) - c*y(4)) &
                  - q2*y(4)
        dydt(5) = (self%p - 2.0_dp)*y(5) - y(5)**3
        v2 = y(6)**2 + y(7)**2
        dydt(6) = (self%p - 3.0_dp)*y(6) - self%alpha*y(7) - v2*y(6)
        dydt(7) = (self%p - 3.0_dp)*y(7) + self%alpha*y(6) - v2*y(7)
    end subroutine nf_rhs

    subroutine fold_rhs(self, t, y, dydt)
        class(fold_cycle), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: r2, g
        r2 = y(1)**2 + y(2)**2
        g = self%p + r2 - r2*r2
        dydt(1) = y(1)*g - y(2)*(1.0_dp + r2)
        dydt(2) = y(2)*g + y(1)*(1.0_dp + r2)
        if (self%p < self%p_break) dydt = ieee_value(1.0_dp, ieee_quiet_nan)
    end subroutine fold_rhs

end module continuation_test_systems

program test_continuation
    use conmech
    use conmech_testing
    use continuation_test_systems
    implicit none
    type(test_suite) :: ts

    ts%name = "test_continuation"
    call test_pd_bp_ns()
    call test_fold()
    call test_bad_input()
    call ts%finish()

contains

    subroutine test_pd_bp_ns()
        type(nf_cycles) :: sys
        type(branch) :: br
        type(cont_options) :: o
        integer :: k, nfound(4)
        real(dp) :: found(4)
        o%ds = 0.05_dp
        o%ds_max = 0.25_dp
        o%p_max = 3.6_dp
        o%max_points = 100
        call continue_orbits(sys, set_p, 0.0_dp, [1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, &
                             0.0_dp, 0.0_dp], 6.0_dp, br, o)
        call ts%check(br%info == CM_SUCCESS, "branch of the normal-form cycle: "//br%message)
        nfound = 0
        found = 0.0_dp
        do k = 1, br%nspecial
            nfound(br%special(k)%kind) = nfound(br%special(k)%kind) + 1
            found(br%special(k)%kind) = br%special(k)%point%p
            write (*, '(2a, f20.15)') "  ", special_name(br%special(k)%kind), &
                br%special(k)%point%p
        end do
        call ts%check(all(nfound == [0, 1, 1, 1]), "one each of BP, PD, NS and no fold")
        call check_honest(br)
        ! closed forms: PD at p = 1, BP at p = 2, NS at p = 3
        call ts%check_close(found(SP_PD), 1.0_dp, 1.0e-8_dp, "period doubling at p = 1")
        call ts%check_close(found(SP_BP), 2.0_dp, 1.0e-8_dp, "branch point at p = 2")
        call ts%check_close(found(SP_NS), 3.0_dp, 1.0e-8_dp, "Neimark-Sacker at p = 3")
        call ts%check_close(br%points(br%npoints)%period, 8.0_dp*atan(1.0_dp), 1.0e-9_dp, &
                            "the period stays 2 pi")
        call same_by_multiple_shooting(sys, found)
        ! branch switching at the period doubling: the doubled orbit has period 4 pi and
        ! u^2 + w^2 = |xi|^2 = p - 1 (closed form), p > 1 (supercritical)
        do k = 1, br%nspecial
            if (br%special(k)%kind == SP_PD) call check_doubled(sys, br%special(k))
            if (br%special(k)%kind == SP_BP) call check_pitchfork(sys, br, k)
        end do
    end subroutine test_pd_bp_ns

    !> Every special point located, its orbit's independent closure below 1e-8, and (fold,
    !! branch point, period doubling) its test function below 1e-6; the Neimark-Sacker
    !! test is a product over all pairs of multipliers, not normalised.
    subroutine check_honest(br)
        type(branch), intent(in) :: br
        integer :: k
        logical :: ok
        ok = br%nspecial > 0
        do k = 1, br%nspecial
            ok = ok .and. br%special(k)%located .and. br%special(k)%closure < 1.0e-8_dp
            if (br%special(k)%kind /= SP_NS) ok = ok .and. abs(br%special(k)%test) < 1.0e-6_dp
        end do
        call ts%check(ok, "every special point located, closure < 1e-8, test ~ 0")
    end subroutine check_honest

    !> The same branch by multiple shooting (4 segments) and by collocation (24 intervals
    !! of degree 5): the same special points, located to 1e-8.
    subroutine same_by_multiple_shooting(sys, found)
        type(nf_cycles), intent(inout) :: sys
        real(dp), intent(in) :: found(4)
        type(branch) :: br
        type(cont_options) :: o
        integer :: k, d
        logical :: ok
        do d = ORBIT_MULTIPLE, ORBIT_COLLOCATION
            o%ds = 0.05_dp
            o%ds_max = 0.25_dp
            o%p_max = 3.6_dp
            o%max_points = 100
            o%discretisation = d
            o%segments = 4
            o%intervals = 24
            o%degree = 5
            call continue_orbits(sys, set_p, 0.0_dp, [1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, &
                                 0.0_dp, 0.0_dp, 0.0_dp], 6.0_dp, br, o)
            ok = br%info == CM_SUCCESS .and. br%nspecial == 3
            do k = 1, br%nspecial
                ok = ok .and. abs(br%special(k)%point%p - found(br%special(k)%kind)) &
                     < 1.0e-8_dp .and. br%special(k)%located
            end do
            call ts%check(ok, orbit_method_name(d)//": the same located BP, PD, NS: "// &
                          br%message)
            call ts%check(abs(br%points(br%npoints)%p - 3.6_dp) < 1.0e-13_dp, &
                          orbit_method_name(d)//": the branch ends at p_max")
        end do
    end subroutine same_by_multiple_shooting

    !> Branch switching at the pitchfork p = 2 of z' = (p - 2) z - z^3 (the symmetry
    !! z -> -z broken): the new orbits have z^2 = p - 2 (closed form by construction), the
    !! rest of the state on the old cycle, period 2 pi; each checked by an independent
    !! integration over its period (true closure error).
    subroutine check_pitchfork(sys, br, k)
        type(nf_cycles), intent(inout) :: sys
        type(branch), intent(in) :: br
        integer, intent(in) :: k
        type(branch) :: b2
        type(cont_options) :: o
        type(ode_options) :: oo
        real(dp) :: err, clos, ratio, y(7)
        integer :: j, i, info
        logical :: newb
        i = br%special(k)%index
        o%ds = 0.05_dp
        o%ds_max = 0.1_dp
        o%max_points = 8
        call switch_branch_point(sys, set_p, br%special(k), &
                                 branch_secant(br%points(i), br%points(i + 1), .true.), b2, &
                                 o, ratio)
        call ts%check(b2%info == CM_SUCCESS .and. b2%npoints == 8, &
                      "pitchfork branch: "//b2%message)
        call ts%check_less(ratio, 1.0e-4_dp, "two-dimensional kernel at the branch point")
        err = 0.0_dp
        clos = 0.0_dp
        newb = .true.
        oo%rtol = 1.0e-12_dp
        oo%atol = 1.0e-12_dp
        do j = 2, b2%npoints
            err = max(err, abs(b2%points(j)%y0(5)**2 - (b2%points(j)%p - 2.0_dp)), &
                      abs(b2%points(j)%period - 8.0_dp*atan(1.0_dp)))
            sys%p = b2%points(j)%p
            y = b2%points(j)%y0
            call ode_integrate(sys, 0.0_dp, b2%points(j)%period, y, oo, info)
            clos = max(clos, maxval(abs(y - b2%points(j)%y0)))
            newb = newb .and. b2%points(j)%p > 2.0_dp .and. &
                   b2%points(j)%y0(5) > 0.5_dp*sqrt(max(b2%points(j)%p - 2.0_dp, 0.0_dp))
        end do
        call ts%check(newb, "new orbits: p > 2, z > 0 (not the old branch z = 0)")
        call ts%check_less(err, 1.0e-8_dp, "pitchfork orbits: z^2 = p - 2, period 2 pi")
        call ts%check_less(clos, 1.0e-8_dp, "pitchfork orbits close (true closure error)")
        ! the other side of the pitchfork: z < 0 (direction -1)
        o%direction = -1
        o%max_points = 3
        call switch_branch_point(sys, set_p, br%special(k), &
                                 branch_secant(br%points(i), br%points(i + 1), .true.), b2, o)
        call ts%check(b2%info == CM_SUCCESS .and. b2%points(b2%npoints)%y0(5) < -0.05_dp, &
                      "direction -1: the mirror branch z < 0")
        ! not a branch point
        call switch_branch_point(sys, set_p, br%special(1 + mod(k, br%nspecial)), &
                                 [1.0_dp], b2, o)
        call ts%check(b2%info == CM_BAD_INPUT, "switch at a non-BP rejected: "//b2%message)
    end subroutine check_pitchfork

    subroutine check_doubled(sys, sp)
        type(nf_cycles), intent(inout) :: sys
        type(special_point), intent(in) :: sp
        type(branch) :: b2
        type(cont_options) :: o
        real(dp) :: err
        integer :: k
        o%ds = 0.05_dp
        o%ds_max = 0.1_dp
        o%max_points = 8
        call switch_period_doubling(sys, set_p, sp, b2, o)
        call ts%check(b2%info == CM_SUCCESS .and. b2%npoints == 8, &
                      "doubled branch: "//b2%message)
        err = 0.0_dp
        do k = 2, b2%npoints
            err = max(err, abs(b2%points(k)%period - 16.0_dp*atan(1.0_dp)), &
                      abs(b2%points(k)%y0(3)**2 + b2%points(k)%y0(4)**2 - &
                          (b2%points(k)%p - 1.0_dp)))
        end do
        call ts%check(b2%npoints >= 2 .and. all(b2%points(2:b2%npoints)%p > 1.0_dp), &
                      "doubled orbits for p > 1")
        call ts%check_less(err, 1.0e-8_dp, "doubled orbit: period 4 pi, u^2 + w^2 = p - 1")
    end subroutine check_doubled

    subroutine test_fold()
        type(fold_cycle) :: sys
        type(branch) :: br
        type(cont_options) :: o
        integer :: k, nf
        real(dp) :: r2
        o%ds = 0.05_dp
        o%direction = -1
        o%max_points = 40
        o%p_max = 1.0_dp
        o%max_points = 25
        call continue_orbits(sys, set_p, 0.0_dp, [1.0_dp, 0.0_dp], 3.0_dp, br, o)
        call ts%check(br%info == CM_SUCCESS, "fold branch: "//br%message)
        do k = 1, br%nspecial
            write (*, '(2a, f20.15)') "  ", special_name(br%special(k)%kind), &
                br%special(k)%point%p
        end do
        call check_honest(br)
        nf = 0
        do k = 1, br%nspecial
            if (br%special(k)%kind == SP_FOLD) then
                nf = nf + 1
                r2 = sum(br%special(k)%point%y0**2)
                ! closed form: p = -1/4, r^2 = 1/2, T = 4 pi/3
                call ts%check_close(br%special(k)%point%p, -0.25_dp, 1.0e-9_dp, &
                                    "fold at p = -1/4")
                call ts%check_close(r2, 0.5_dp, 1.0e-5_dp, "fold at r^2 = 1/2")
                call ts%check_close(br%special(k)%point%period, 16.0_dp*atan(1.0_dp)/3.0_dp, &
                                    1.0e-5_dp, "fold period 4 pi/3")
            end if
        end do
        call ts%check(nf == 1 .and. br%nspecial == 1, "exactly one special point: the fold")
        ! after the fold the branch comes back (inner, unstable cycles: p increases)
        call ts%check(br%points(br%npoints)%p > -0.25_dp .and. &
                      sum(br%points(br%npoints)%y0**2) < 0.5_dp, "the branch turns at the fold")
    end subroutine test_fold

    subroutine test_bad_input()
        type(fold_cycle) :: sys
        type(branch) :: br
        type(cont_options) :: o
        ! not a periodic orbit of this system: the start fails with a clear status
        o%max_points = 5
        call continue_orbits(sys, set_p, 0.0_dp, [0.0_dp, 0.0_dp], 3.0_dp, br, o)
        call ts%check(br%info /= CM_SUCCESS .and. index(br%message, "start") > 0, &
                      "an equilibrium start is rejected: "//br%message)
        ! a corrector that cannot converge (tolerance below the integration error): the
        ! continuation stops with the branch so far and a message naming the parameter value
        o = cont_options()
        o%ds = 0.05_dp
        o%max_points = 20
        o%tol = 1.0e-15_dp
        o%res_tol = 1.0e-16_dp
        call continue_orbits(sys, set_p, 0.0_dp, [1.0_dp, 0.0_dp], 3.0_dp, br, o)
        call ts%check(br%info /= CM_SUCCESS .and. index(br%message, "converge") > 0, &
                      "unreachable tolerance at the start: "//br%message)
        ! the model breaks down (NaN) below p = -0.1: the branch stops there with the points
        ! so far and a message naming the last parameter value reached
        o = cont_options()
        o%ds = 0.05_dp
        o%direction = -1
        o%max_points = 50
        sys%p_break = -0.1_dp
        call continue_orbits(sys, set_p, 0.0_dp, [1.0_dp, 0.0_dp], 3.0_dp, br, o)
        call ts%check(br%info == CM_NO_CONVERGENCE .and. br%npoints >= 2 .and. &
                      index(br%message, "stopped at p = -") > 0 .and. &
                      br%points(br%npoints)%p >= -0.1_dp - 1.0e-6_dp .and. &
                      br%points(br%npoints)%p < -0.09_dp, "failure names p: "//br%message)
    end subroutine test_bad_input

end program test_continuation
