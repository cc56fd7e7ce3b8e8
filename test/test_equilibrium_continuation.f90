!> Continuation of equilibria: folds and Hopf points against closed forms, the first
!! Lyapunov coefficient against the normal form, a degenerate Hopf point, p_range and a
!! start that is not an equilibrium.
module eqc_test_systems
    use conmech
    implicit none
    private
    public :: brusselator, cubic_fold, hopf_nf, set_p

    !> The Brusselator x' = a - (b + 1) x + x^2 y, y' = b x - x^2 y (parameter b): the
    !! equilibrium (a, b/a) has the eigenvalue pair with trace b - 1 - a^2 and
    !! determinant a^2, so a Hopf point at b = 1 + a^2 with omega = a (Kuznetsov 2004,
    !! Example 3.1). Analytic Jacobian.
    type, extends(ode_system) :: brusselator
        real(dp) :: a = 2.0_dp
        real(dp) :: b = 1.0_dp
    contains
        procedure :: rhs => br_rhs
        procedure :: jacobian => br_jac
        procedure :: has_jacobian => br_has
    end type brusselator

    !> x' = p + x - x^3/3, y' = -y: folds at (x, p) = (1, -2/3) and (-1, 2/3).
    type, extends(ode_system) :: cubic_fold
        real(dp) :: p = 0.0_dp
    contains
        procedure :: rhs => cf_rhs
    end type cubic_fold

    !> The Hopf normal form in Cartesian coordinates, z = x + i y:
    !! z' = (p + i) z + c z |z|^2 - z |z|^4 (finite-difference Jacobian). With <q, q> = 1
    !! (z = sqrt 2 times the normal-form coordinate) the first Lyapunov coefficient is
    !! l1 = 2 c; c = 0 is a degenerate (Bautin) point.
    type, extends(ode_system) :: hopf_nf
        real(dp) :: p = -0.5_dp
        real(dp) :: c = -1.0_dp
    contains
        procedure :: rhs => nf_rhs
    end type hopf_nf

contains

    subroutine set_p(sys, p)
        class(ode_system), intent(inout) :: sys
        real(dp), intent(in) :: p
        select type (sys)
        type is (brusselator)
            sys%b = p
        type is (cubic_fold)
            sys%p = p
        type is (hopf_nf)
            sys%p = p
        end select
    end subroutine set_p

    subroutine br_rhs(self, t, y, dydt)
        class(brusselator), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        dydt(1) = self%a - (self%b + 1.0_dp)*y(1) + y(1)**2*y(2)
        dydt(2) = self%b*y(1) - y(1)**2*y(2)
    end subroutine br_rhs

    subroutine br_jac(self, t, y, dfdy)
        class(brusselator), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        dfdy(1, 1) = -(self%b + 1.0_dp) + 2.0_dp*y(1)*y(2)
        dfdy(1, 2) = y(1)**2
        dfdy(2, 1) = self%b - 2.0_dp*y(1)*y(2)
        dfdy(2, 2) = -y(1)**2
    end subroutine br_jac

    logical function br_has(self)
        class(brusselator), intent(in) :: self
        br_has = .true.
    end function br_has

    subroutine cf_rhs(self, t, y, dydt)
        class(cubic_fold), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        dydt(1) = self%p + y(1) - y(1)**3/3.0_dp
        dydt(2) = -y(2)
    end subroutine cf_rhs

    subroutine nf_rhs(self, t, y, dydt)
        class(hopf_nf), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: r2, g
        r2 = y(1)**2 + y(2)**2
        g = self%p + self%c*r2 - r2*r2
        dydt(1) = g*y(1) - y(2)
        dydt(2) = g*y(2) + y(1)
    end subroutine nf_rhs

end module eqc_test_systems

program test_equilibrium_continuation
    use conmech
    use conmech_testing
    use eqc_test_systems
    implicit none
    type(test_suite) :: ts
    ts%name = "test_equilibrium_continuation"
    call test_brusselator(ts)
    call test_folds(ts)
    call test_normal_form(ts)
    call test_bad_start(ts)
    call ts%finish()

contains

    subroutine test_brusselator(ts)
        type(test_suite), intent(inout) :: ts
        type(brusselator) :: sys
        type(eq_branch) :: br
        type(eq_options) :: o
        type(eq_special) :: h
        integer :: k, nh
        sys%a = 2.0_dp
        sys%b = 1.0_dp
        o%ds = 0.1_dp
        o%ds_max = 0.5_dp
        o%p_max = 8.0_dp
        call continue_equilibria(sys, set_p, 1.0_dp, [2.0_dp, 0.5_dp], br, o)
        call ts%check(br%info == CM_SUCCESS, "Brusselator: branch ends normally")
        call ts%check_close(br%points(br%npoints)%p, 8.0_dp, 1.0e-12_dp, &
                            "Brusselator: the last point is on p_max")
        ! every point is the equilibrium (a, b/a)
        do k = 1, br%npoints
            call ts%check_less(abs(br%points(k)%y(1) - 2.0_dp) + &
                               abs(br%points(k)%y(2) - br%points(k)%p/2.0_dp), 1.0e-12_dp, &
                               "Brusselator: equilibrium (a, b/a)")
        end do
        nh = 0
        do k = 1, br%nspecial
            if (br%special(k)%kind /= EQ_HOPF) cycle
            nh = nh + 1
            h = br%special(k)
        end do
        call ts%check(nh == 1 .and. br%nspecial == 1, "Brusselator: one special point, Hopf")
        if (nh /= 1) return
        call ts%check(h%located, "Brusselator: the Hopf point is located")
        call ts%check_close(h%point%p, 5.0_dp, 1.0e-10_dp, "Brusselator: Hopf at b = 1 + a^2")
        call ts%check_close(h%omega, 2.0_dp, 1.0e-10_dp, "Brusselator: omega = a")
        call ts%check_less(abs(h%test), 1.0e-12_dp, "Brusselator: test value at the point")
        call ts%check_less(h%point%residual, 1.0e-12_dp, "Brusselator: residual")
        call ts%check(h%criticality == HOPF_SUPERCRITICAL .and. h%l1 < 0.0_dp, &
                      "Brusselator: supercritical (l1 < 0)")
        ! stable before, unstable after
        call ts%check(br%points(1)%n_unstable == 0 .and. &
                      br%points(br%npoints)%n_unstable == 2, "Brusselator: stability change")
    end subroutine test_brusselator

    subroutine test_folds(ts)
        type(test_suite), intent(inout) :: ts
        type(cubic_fold) :: sys
        type(eq_branch) :: br
        type(eq_options) :: o
        integer :: k, nf
        real(dp) :: pf(2)
        o%ds = 0.05_dp
        o%ds_max = 0.2_dp
        o%direction = -1
        o%max_points = 80
        o%p_min = -3.0_dp
        o%p_max = 3.0_dp
        call continue_equilibria(sys, set_p, 0.0_dp, [sqrt(3.0_dp), 0.0_dp], br, o)
        call ts%check(br%info == CM_SUCCESS, "cubic: branch ends normally")
        nf = 0
        do k = 1, br%nspecial
            if (br%special(k)%kind /= EQ_FOLD) cycle
            nf = nf + 1
            if (nf <= 2) pf(nf) = br%special(k)%point%p
            call ts%check(br%special(k)%located, "cubic: fold located")
            call ts%check_close(abs(br%special(k)%point%y(1)), 1.0_dp, 1.0e-6_dp, &
                                "cubic: fold at |x| = 1")
            call ts%check_less(br%special(k)%point%residual, 1.0e-12_dp, "cubic: residual")
        end do
        call ts%check(nf == 2, "cubic: two folds")
        if (nf /= 2) return
        call ts%check_close(pf(1), -2.0_dp/3.0_dp, 1.0e-10_dp, "cubic: fold at p = -2/3")
        call ts%check_close(pf(2), 2.0_dp/3.0_dp, 1.0e-10_dp, "cubic: fold at p = 2/3")
        call ts%check(abs(br%points(br%npoints)%p) >= 3.0_dp - 1.0e-12_dp, &
                      "cubic: ends on the p range")
    end subroutine test_folds

    subroutine test_normal_form(ts)
        type(test_suite), intent(inout) :: ts
        type(hopf_nf) :: sys
        type(eq_branch) :: br
        type(eq_options) :: o
        real(dp) :: cs(3)
        integer :: i
        character(len=8) :: lab
        cs = [-1.0_dp, 0.5_dp, 0.0_dp]
        o%ds = 0.05_dp
        o%p_max = 0.5_dp
        do i = 1, 3
            sys%c = cs(i)
            write (lab, '(f5.2)') cs(i)
            call continue_equilibria(sys, set_p, -0.5_dp, [0.0_dp, 0.0_dp], br, o)
            call ts%check(br%info == CM_SUCCESS .and. br%nspecial == 1, &
                          "normal form c ="//lab//": one special point")
            if (br%nspecial /= 1) cycle
            call ts%check(br%special(1)%kind == EQ_HOPF .and. br%special(1)%located, &
                          "normal form: Hopf located")
            ! (the finite-difference Jacobian carries ~eps^(2/3) ~ 4e-11)
            call ts%check_less(abs(br%special(1)%point%p), 1.0e-9_dp, "normal form: p = 0")
            if (i == 3) then
                call ts%check(br%special(1)%criticality == HOPF_DEGENERATE, &
                              "normal form c = 0: degenerate Hopf point")
                call ts%check_less(abs(br%special(1)%l1), max(1.0e-6_dp*br%special(1)%l1_scale, &
                                   br%special(1)%l1_error), "normal form c = 0: l1 ~ 0")
            else
                call ts%check_close(br%special(1)%l1, 2.0_dp*cs(i), 1.0e-7_dp, &
                                    "normal form: l1 = 2 c ("//lab//")")
                if (cs(i) < 0.0_dp) then
                    call ts%check(br%special(1)%criticality == HOPF_SUPERCRITICAL, &
                                  "normal form: supercritical")
                else
                    call ts%check(br%special(1)%criticality == HOPF_SUBCRITICAL, &
                                  "normal form: subcritical")
                end if
            end if
        end do
    end subroutine test_normal_form

    subroutine test_bad_start(ts)
        type(test_suite), intent(inout) :: ts
        type(cubic_fold) :: sys
        type(eq_branch) :: br
        type(eq_options) :: o
        o%max_iter = 3
        ! y' = -y has no equilibrium at y = 5 reachable... (x far, 3 iterations)
        call continue_equilibria(sys, set_p, 0.0_dp, [40.0_dp, 5.0_dp], br, o)
        call ts%check(br%info /= CM_SUCCESS .and. br%npoints == 0, &
                      "bad start: not an equilibrium is an error")
        call ts%check(index(br%message, "not an equilibrium") > 0, "bad start: message")
        o = eq_options()
        o%p_max = -1.0_dp
        call continue_equilibria(sys, set_p, 0.0_dp, [sqrt(3.0_dp), 0.0_dp], br, o)
        call ts%check(br%info == CM_BAD_INPUT, "bad start: p0 outside the p range")
    end subroutine test_bad_start

end program test_equilibrium_continuation
