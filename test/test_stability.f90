!> Equilibria, Lagrange-Dirichlet, variational equations, shooting and continuation.
module stability_test_systems
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_system
    implicit none
    private
    public :: cart_pendulum_reduced, spinning_hoop

    !> Pendulum on a cart (M = m = l = 1), reduced dynamics (seed 000):
    !! (1 - cos^2/2) th'' + (1/2) cos sin th'^2 - g sin = 0. No analytic Jacobian (FD).
    type, extends(ode_system) :: cart_pendulum_reduced
        real(dp) :: g = 9.81_dp
    contains
        procedure :: rhs => cart_rhs
    end type cart_pendulum_reduced

    !> Bead on a hoop of radius R spinning at W: th'' = (W^2 cos th - g/R) sin th.
    type, extends(ode_system) :: spinning_hoop
        real(dp) :: w = 1.0_dp, g = 9.81_dp, r = 1.0_dp
    contains
        procedure :: rhs => hoop_rhs
    end type spinning_hoop

contains

    subroutine cart_rhs(self, t, y, dydt)
        class(cart_pendulum_reduced), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        dydt(1) = y(2)
        dydt(2) = (self%g*sin(y(1)) - 0.5_dp*cos(y(1))*sin(y(1))*y(2)**2) &
                  /(1.0_dp - 0.5_dp*cos(y(1))**2)
    end subroutine cart_rhs

    subroutine hoop_rhs(self, t, y, dydt)
        class(spinning_hoop), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        dydt(1) = y(2)
        dydt(2) = (self%w**2*cos(y(1)) - self%g/self%r)*sin(y(1))
    end subroutine hoop_rhs

end module stability_test_systems

program test_stability
    use conmech_kinds, only: dp, pi
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_integrate
    use conmech_systems_basic, only: pendulum_theta, harmonic_oscillator, kepler_2d, van_der_pol
    use conmech_hill, only: hill_problem, hill_equilibrium_x, hill_jacobi
    use conmech_hill_orbit
    use conmech_equilibria
    use conmech_variational
    use conmech_floquet
    use conmech_shooting
    use conmech_lapack, only: la_det
    use stability_test_systems
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    real(dp), parameter :: g = 9.81_dp
    real(dp) :: hill_m
    ts%name = "test_stability"
    hill_m = 0.080848933808312_dp

    call test_pendulum()
    call test_cart_pendulum()
    call test_hoop()
    call test_hill_equilibria()
    call test_lagrange_dirichlet()
    call test_stm()
    call test_vdp_limit_cycle()
    call test_hill_generic_shooting()
    call test_bad_input()
    call ts%finish()

contains

    subroutine test_pendulum()
        type(pendulum_theta) :: p
        type(equilibrium_result) :: e
        call analyze_equilibrium(p, [0.0_dp, 0.0_dp], e)
        call ts%check(e%info == CM_SUCCESS .and. e%analytic, "pendulum: analytic Jacobian used")
        call ts%check(e%kind == EQ_CENTRE, "pendulum at 0: centre")
        call ts%check_close(maxval(abs(e%wi)), sqrt(g), 1.0e-12_dp, "pendulum at 0: omega")
        call analyze_equilibrium(p, [pi, 0.0_dp], e)
        call ts%check(e%kind == EQ_UNSTABLE .and. e%saddle, "pendulum at pi: saddle")
        call ts%check_close(maxval(e%wr), sqrt(g), 1.0e-12_dp, "pendulum at pi: rate")
    end subroutine test_pendulum

    subroutine test_cart_pendulum()
        type(cart_pendulum_reduced) :: c
        type(equilibrium_result) :: e
        call analyze_equilibrium(c, [0.0_dp, 0.0_dp], e)
        call ts%check(.not. e%analytic, "cart pendulum: finite-difference Jacobian")
        call ts%check(e%kind == EQ_UNSTABLE .and. e%saddle, "cart pendulum upright: saddle")
        ! z'' - 2 g z = 0: eigenvalues +-sqrt(2 g)
        call ts%check_close(maxval(e%wr), sqrt(2.0_dp*g), 1.0e-8_dp, &
                            "cart pendulum upright: z'' - 2 g z = 0")
        call ts%check_close(e%jacobian(2, 1), 2.0_dp*g, 1.0e-7_dp, "upright: A21 = 2 g")
        call analyze_equilibrium(c, [pi, 0.0_dp], e)
        call ts%check(e%kind == EQ_CENTRE, "cart pendulum hanging: centre")
        call ts%check_close(maxval(e%wi), sqrt(2.0_dp*g), 1.0e-8_dp, &
                            "cart pendulum hanging: z'' + 2 g z = 0")
    end subroutine test_cart_pendulum

    subroutine test_hoop()
        type(spinning_hoop) :: h
        type(equilibrium_result) :: e
        real(dp) :: y(2), ths
        integer :: info
        character(len=:), allocatable :: msg
        h%w = 0.5_dp*sqrt(g)       ! below the critical spin W^2 = g/R
        call analyze_equilibrium(h, [0.0_dp, 0.0_dp], e)
        call ts%check(e%kind == EQ_CENTRE, "hoop below critical spin: bottom is a centre")
        call ts%check_close(maxval(e%wi), sqrt(g - h%w**2), 1.0e-8_dp, &
                            "hoop below critical: frequency sqrt(g/R - W^2)")
        h%w = 2.0_dp*sqrt(g)       ! above
        call analyze_equilibrium(h, [0.0_dp, 0.0_dp], e)
        call ts%check(e%kind == EQ_UNSTABLE, "hoop above critical spin: bottom unstable")
        y = [0.8_dp, 0.0_dp]
        call find_equilibrium(h, y, info, msg)
        ths = acos(g/(h%r*h%w**2))
        call ts%check(info == CM_SUCCESS, "hoop: off-axis equilibrium found by Newton")
        call ts%check_close(cos(y(1)), cos(ths), 1.0e-12_dp, "hoop: cos th* = g/(R W^2)")
        call analyze_equilibrium(h, y, e)
        call ts%check(e%kind == EQ_CENTRE, "hoop: off-axis equilibrium is a centre")
        call ts%check_close(maxval(e%wi), h%w*sin(ths), 1.0e-7_dp, &
                            "hoop: off-axis frequency W sin th*")
    end subroutine test_hoop

    subroutine test_hill_equilibria()
        type(hill_problem) :: hp
        type(equilibrium_result) :: e
        real(dp) :: y(4), xe
        integer :: info, nr, nc
        character(len=:), allocatable :: msg
        hp%m = hill_m
        xe = hill_equilibrium_x(hp%m, hp%kappa)
        y = [1.1_dp*xe, 0.01_dp, 0.0_dp, 0.0_dp]
        call find_equilibrium(hp, y, info, msg)
        call ts%check(info == CM_SUCCESS, "Hill: Newton finds the libration point")
        call ts%check_close(y(1), xe, 1.0e-12_dp, "Hill: x_e = (kappa/(3 m^2))^(1/3)")
        call analyze_equilibrium(hp, y, e)
        nr = count(abs(e%wi) < 1.0e-10_dp .and. abs(e%wr) > 1.0e-6_dp)
        nc = count(abs(e%wr) < 1.0e-10_dp .and. abs(e%wi) > 1.0e-6_dp)
        call ts%check(e%kind == EQ_UNSTABLE .and. e%saddle .and. nr == 2 .and. nc == 2, &
                      "Hill: libration point is saddle x centre")
        call analyze_equilibrium(hp, [-xe, 0.0_dp, 0.0_dp, 0.0_dp], e)
        call ts%check(e%kind == EQ_UNSTABLE .and. e%residual < 1.0e-12_dp, &
                      "Hill: (-x_e, 0) is an unstable equilibrium too")
    end subroutine test_hill_equilibria

    subroutine test_lagrange_dirichlet()
        real(dp) :: hs(2, 2), w(2)
        logical :: stable
        integer :: info
        call potential_hessian(pot2, [0.0_dp, 0.0_dp], hs)
        call ts%check_close(hs(1, 1), 2.0_dp, 1.0e-6_dp, "FD Hessian of the potential (1,1)")
        call ts%check_close(hs(1, 2), 0.5_dp, 1.0e-6_dp, "FD Hessian of the potential (1,2)")
        call lagrange_dirichlet(hs, stable, w, info)
        call ts%check(info == CM_SUCCESS .and. stable, "Lagrange-Dirichlet: minimum is stable")
        call potential_hessian(pot2, [pi, 0.0_dp], hs)
        call lagrange_dirichlet(hs, stable, w, info)
        call ts%check(info == CM_SUCCESS .and. .not. stable, &
                      "Lagrange-Dirichlet: saddle of the potential is not a minimum")
        call lagrange_dirichlet(reshape([1.0_dp, 0.0_dp, 1.0_dp, 1.0_dp], [2, 2]), stable, &
                                w, info)
        call ts%check(info == CM_BAD_INPUT, "Lagrange-Dirichlet: non-symmetric -> bad input")
    end subroutine test_lagrange_dirichlet

    !> V = 2 (1 - cos q1) + q2^2/2 ... with a coupling q1 q2 / 2 (pendulum-like in q1).
    function pot2(q) result(v)
        real(dp), intent(in) :: q(:)
        real(dp) :: v
        v = 2.0_dp*(1.0_dp - cos(q(1))) + 0.5_dp*q(2)**2 + 0.5_dp*sin(q(1))*q(2)
    end function pot2

    subroutine test_stm()
        type(kepler_2d) :: k
        type(harmonic_oscillator) :: ho
        type(ode_options) :: opt
        real(dp) :: y(4), phi(4, 4), yp(4), ym(4), fd(4, 4), h, y2(2), p2(2, 2)
        integer :: info, j
        opt%rtol = 1.0e-12_dp
        opt%atol = 1.0e-12_dp
        ! harmonic oscillator: the STM is the rotation [cos, sin/w; -w sin, cos]
        ho%omega = 2.0_dp
        y2 = [1.0_dp, 0.0_dp]
        p2 = reshape([1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2])
        call integrate_stm(ho, 0.0_dp, 1.3_dp, y2, p2, opt, info)
        call ts%check_close(p2(1, 2), sin(2.6_dp)/2.0_dp, 1.0e-10_dp, "STM harmonic (1,2)")
        call ts%check_close(p2(2, 1), -2.0_dp*sin(2.6_dp), 1.0e-10_dp, "STM harmonic (2,1)")
        ! Kepler ellipse: STM against central differences of the flow
        y = [1.0_dp, 0.0_dp, 0.0_dp, 1.2_dp]
        phi = 0.0_dp
        do j = 1, 4
            phi(j, j) = 1.0_dp
        end do
        call integrate_stm(k, 0.0_dp, 3.0_dp, y, phi, opt, info)
        call ts%check(info == CM_SUCCESS, "integrate_stm Kepler succeeds")
        do j = 1, 4
            h = 1.0e-5_dp
            yp = [1.0_dp, 0.0_dp, 0.0_dp, 1.2_dp]
            ym = yp
            yp(j) = yp(j) + h
            ym(j) = ym(j) - h
            call ode_integrate(k, 0.0_dp, 3.0_dp, yp, opt, info)
            call ode_integrate(k, 0.0_dp, 3.0_dp, ym, opt, info)
            fd(:, j) = (yp - ym)/(2.0_dp*h)
        end do
        call ts%check_less(maxval(abs(fd - phi))/maxval(abs(phi)), 1.0e-7_dp, &
                           "STM = d flow / d y0 (Kepler, central differences)")
        call ts%check_close(la_det(phi), 1.0_dp, 1.0e-9_dp, "det STM = 1 (Liouville)")
        ! control on the state only: same state, STM still accurate
        y = [1.0_dp, 0.0_dp, 0.0_dp, 1.2_dp]
        fd = phi
        phi = 0.0_dp
        do j = 1, 4
            phi(j, j) = 1.0_dp
        end do
        call integrate_stm(k, 0.0_dp, 3.0_dp, y, phi, opt, info, state_only=.true.)
        call ts%check(info == CM_SUCCESS, "integrate_stm state_only succeeds")
        call ts%check_less(maxval(abs(fd - phi))/maxval(abs(phi)), 1.0e-8_dp, &
                           "STM with error control on the state only")
    end subroutine test_stm

    subroutine test_vdp_limit_cycle()
        type(van_der_pol) :: v
        type(periodic_orbit) :: o
        real(dp) :: mu1
        integer :: i
        v%mu = 1.0_dp
        call find_periodic_orbit(v, [2.0_dp, 0.0_dp], 6.5_dp, o)
        call ts%check(o%info == CM_SUCCESS, "Van der Pol limit cycle: shooting converges")
        call ts%check_close(o%period, 6.663286859323130_dp, 1.0e-9_dp, &
                            "Van der Pol mu = 1 period")
        ! multipliers: 1 (trivial) and exp(int div f) < 1
        mu1 = minval(o%floquet%abs_mult)
        call ts%check_close(maxval(o%floquet%abs_mult), 1.0_dp, 1.0e-8_dp, &
                            "Van der Pol: trivial multiplier 1")
        call ts%check(mu1 < 0.01_dp .and. o%floquet%stable, &
                      "Van der Pol: limit cycle is orbitally stable")
        call ts%check_close(o%floquet%det, mu1*maxval(o%floquet%abs_mult), 1.0e-12_dp, &
                            "det M = product of the multipliers")
        i = 0
        call test_vdp_continuation()
    end subroutine test_vdp_limit_cycle

    !> Continuation of the limit cycle in mu (general shooting, free period).
    subroutine test_vdp_continuation()
        type(van_der_pol) :: v
        type(periodic_orbit) :: fam(6), o
        real(dp) :: mus(6)
        integer :: i
        logical :: ok
        mus = [0.5_dp, 0.6_dp, 0.7_dp, 0.8_dp, 0.9_dp, 1.0_dp]
        v%mu = mus(1)
        call continue_periodic_family(v, set_mu, mus, [2.0_dp, 0.0_dp], 6.4_dp, fam)
        ok = all(fam%info == CM_SUCCESS)
        call ts%check(ok, "Van der Pol continuation in mu converges")
        call ts%check_close(fam(6)%period, 6.663286859323130_dp, 1.0e-9_dp, &
                            "continued period at mu = 1")
        ok = .true.
        do i = 2, 6
            ok = ok .and. fam(i)%period > fam(i - 1)%period
        end do
        call ts%check(ok, "the period grows with mu")
        v%mu = 0.7_dp
        call find_periodic_orbit(v, [2.0_dp, 0.0_dp], 6.4_dp, o)
        call ts%check_close(fam(3)%period, o%period, 1.0e-9_dp, "continued = cold start")
    end subroutine test_vdp_continuation

    subroutine set_mu(sys, p)
        class(ode_system), intent(inout) :: sys
        real(dp), intent(in) :: p
        select type (sys)
        type is (van_der_pol)
            sys%mu = p
        end select
    end subroutine set_mu

    subroutine test_hill_generic_shooting()
        type(hill_problem) :: hp
        type(periodic_orbit) :: o, oe
        type(periodic_orbit) :: fam(5)
        type(hill_orbit) :: fast
        type(shooting_options) :: so
        real(dp) :: ms(5), s
        integer :: i
        logical :: ok
        hp%m = hill_m
        call hill_variation_orbit(hill_m, 1.0_dp, fast)
        so%rtol = 1.0e-13_dp
        so%atol = 1.0e-13_dp
        call find_symmetric_orbit(hp, [0.95_dp, 0.0_dp, 0.0_dp, 0.95_dp], [1, 4], 0.5_dp*pi, &
                                  [1, 4], o, so, period_factor=4.0_dp)
        call ts%check(o%info == CM_SUCCESS, "generic symmetric shooting (quarter period)")
        call ts%check_less(maxval(abs(o%y0 - fast%y0)), 1.0e-11_dp, &
                           "generic symmetric orbit = fast variation orbit")
        s = 0.5_dp*(o%floquet%trace - 2.0_dp)
        call ts%check_close(hill_perigee_c(s), 1.0715832774160_dp, 1.0e-10_dp, &
                            "c from the generic DOP853 monodromy")
        ! fixed energy general shooting: the Jacobi constant of the variation orbit
        call find_periodic_orbit(hp, fast%y0 + [1.0e-4_dp, 0.0_dp, 0.0_dp, -1.0e-4_dp], &
                                 2.0_dp*pi + 1.0e-3_dp, oe, PO_FIXED_ENERGY, so, jac_energy, &
                                 fast%jacobi)
        call ts%check(oe%info == CM_SUCCESS, "fixed-energy shooting converges")
        call ts%check_close(oe%period, 2.0_dp*pi, 1.0e-9_dp, &
                            "fixed-energy shooting recovers the period 2 pi")
        ! continuation over m
        ms = [0.06_dp, 0.065_dp, 0.07_dp, 0.075_dp, 0.08_dp]
        call continue_symmetric_family(hp, set_m, ms, [0.95_dp, 0.0_dp, 0.0_dp, 0.95_dp], &
                                       [1, 4], 0.5_dp*pi, [1, 4], fam, so, &
                                       period_factor=4.0_dp)
        ok = all(fam%info == CM_SUCCESS)
        do i = 1, 5
            call hill_variation_orbit(ms(i), 1.0_dp, fast)
            ok = ok .and. maxval(abs(fam(i)%y0 - fast%y0)) < 1.0e-11_dp
            ok = ok .and. fam(i)%iterations <= 4
        end do
        call ts%check(ok, "continuation of the symmetric family = fast family")
    end subroutine test_hill_generic_shooting

    function jac_energy(y) result(e)
        real(dp), intent(in) :: y(:)
        real(dp) :: e
        e = hill_jacobi(hill_m, 1.0_dp, y(1:4))
    end function jac_energy

    subroutine set_m(sys, p)
        class(ode_system), intent(inout) :: sys
        real(dp), intent(in) :: p
        select type (sys)
        type is (hill_problem)
            sys%m = p
        end select
    end subroutine set_m

    subroutine test_bad_input()
        type(harmonic_oscillator) :: ho
        type(pendulum_theta) :: p
        type(periodic_orbit) :: o
        type(hill_orbit) :: ho2
        type(hill_orbit_options) :: hopt
        type(shooting_options) :: so
        ! isochronous: every orbit has period 2 pi -> no isolated orbit
        call find_periodic_orbit(ho, [1.0_dp, 0.0_dp], 2.0_dp*pi, o, PO_FIXED_PERIOD)
        call ts%check(o%info == CM_SINGULAR, "harmonic, fixed period: singular Newton ("// &
                      o%message//")")
        ! free period in a conservative system: a family, not isolated
        p%g = 1.0_dp
        call find_periodic_orbit(p, [1.0_dp, 0.0_dp], 6.7_dp, o, PO_FREE_PERIOD)
        call ts%check(o%info == CM_SINGULAR, "pendulum, free period: singular Newton")
        ! a rotation of the pendulum is not periodic in theta
        so%max_iter = 15
        call find_periodic_orbit(p, [0.0_dp, 3.0_dp], 2.0_dp, o, PO_FIXED_ENERGY, so, &
                                 pend_energy, 4.5_dp - 1.0_dp)
        call ts%check(o%info == CM_NO_CONVERGENCE .or. o%info == CM_SINGULAR, &
                      "non-periodic guess (pendulum rotation): failure status ("// &
                      o%message//")")
        call ts%check(o%info < 0 .and. len(o%message) > 10, "... with a message")
        call find_periodic_orbit(p, [1.0_dp, 0.0_dp], -1.0_dp, o)
        call ts%check(o%info == CM_BAD_INPUT, "negative period: bad input")
        call find_symmetric_orbit(p, [1.0_dp, 0.0_dp], [5], 1.0_dp, [2], o)
        call ts%check(o%info == CM_BAD_INPUT, "free index out of range: bad input")
        call hill_variation_orbit(-0.1_dp, 1.0_dp, ho2)
        call ts%check(ho2%info == CM_BAD_INPUT, "Hill: m < 0 is bad input")
        hopt%max_iter = 1
        call hill_variation_orbit(hill_m, 1.0_dp, ho2, hopt)
        call ts%check(ho2%info == CM_NO_CONVERGENCE, "Hill: one Newton step -> no convergence")
        ! far from any periodic orbit
        call hill_variation_orbit(hill_m, 1.0_dp, ho2, guess=[5.0_dp, 5.0_dp])
        call ts%check(ho2%info == CM_NO_CONVERGENCE, &
                      "Hill: non-periodic guess fails cleanly ("//ho2%message//")")
        ! a retrograde guess converges to a retrograde orbit: refused as the variation orbit
        call hill_variation_orbit(hill_m, 1.0_dp, ho2, guess=[0.95_dp, -0.95_dp])
        call ts%check(ho2%info == CM_NO_CONVERGENCE .and. index(ho2%message, "another") > 0, &
                      "Hill: retrograde orbit is not taken for the variation orbit")
    end subroutine test_bad_input

    function pend_energy(y) result(e)
        real(dp), intent(in) :: y(:)
        real(dp) :: e
        e = 0.5_dp*y(2)**2 - cos(y(1))
    end function pend_energy

end program test_stability
