!> Closed forms and conservation laws of the built-in seed systems: Atwood machine, knife
!! edge on an incline, rolling disk, pendulum on a cart (seed 000), yo-yo and moving
!! suspension (rheonomic, excessive vs generalized), rod with a non-holonomic constraint,
!! bead on a spinning hoop, spring systems and the polar particle.
program test_mechanics_systems
    use conmech
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    class(constrained_system), allocatable :: cs
    class(generalized_system), allocatable :: gs
    type(constrained_options) :: copt
    type(ode_options) :: gopt
    type(constrained_result) :: cr
    type(ode_result) :: gr
    real(dp) :: te(101), e, ref
    integer :: info, i
    character(len=:), allocatable :: msg

    ts%name = "test_mechanics_systems"
    copt%ode%rtol = 1.0e-12_dp
    copt%ode%atol = 1.0e-12_dp
    gopt%rtol = 1.0e-12_dp
    gopt%atol = 1.0e-12_dp
    do i = 1, size(te)
        te(i) = (i - 1)*0.05_dp
    end do

    ! ---------------------------------------------------------------- Atwood machine
    block
        real(dp), parameter :: m1 = 3.0_dp, m2 = 1.0_dp, g = 9.81_dp
        real(dp) :: acc, tension
        acc = (m1 - m2)*g/(m1 + m2)
        tension = 2.0_dp*m1*m2*g/(m1 + m2)
        call make_constrained("atwood_xy", [m1, m2, g, 2.0_dp], cs, info, msg)
        call constrained_solve(cs, [0.0_dp, 5.0_dp], [1.0_dp, 1.0_dp], [0.0_dp, 0.0_dp], &
                               copt, cr, te)
        call ts%check(cr%success, "atwood_xy solves")
        e = 0.0_dp
        do i = 1, cr%nt
            e = max(e, abs(cr%q(1, i) - (1.0_dp + 0.5_dp*acc*te(i)**2)), &
                    abs(cr%q(2, i) - (1.0_dp - 0.5_dp*acc*te(i)**2)))
        end do
        call ts%check_less(e, 1.0e-10_dp, "Atwood: y1 = y0 + a t^2/2, a = (m1-m2) g/(m1+m2)")
        call ts%check_less(maxval(abs(cr%lam(1, :) - tension)), 1.0e-10_dp, &
                           "Atwood: multiplier = tension 2 m1 m2 g/(m1+m2)")
        call make_generalized("atwood", [m1, m2, g], gs, info, msg)
        call generalized_solve(gs, [0.0_dp, 5.0_dp], [0.0_dp], [0.0_dp], gopt, gr, te)
        call ts%check_less(maxval(abs(gr%y(1, :) - (cr%q(1, :) - 1.0_dp))), 1.0e-10_dp, &
                           "Atwood: generalized coordinate agrees with excessive")
    end block

    ! ---------------------------------------------------------------- knife edge on incline
    block
        real(dp), parameter :: alpha = 0.4_dp, w = 1.7_dp, g = 9.81_dp
        real(dp) :: c, x, y
        call make_constrained("skate", [2.0_dp, 0.5_dp, g, alpha], cs, info, msg)
        call constrained_solve(cs, [0.0_dp, 5.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], &
                               [0.0_dp, 0.0_dp, w], copt, cr, te)
        call ts%check(cr%success, "skate solves")
        c = g*sin(alpha)/(2.0_dp*w**2)
        e = 0.0_dp
        do i = 1, cr%nt
            x = c*sin(w*te(i))**2
            y = c*(w*te(i) - 0.5_dp*sin(2.0_dp*w*te(i)))
            e = max(e, abs(cr%q(1, i) - x), abs(cr%q(2, i) - y), abs(cr%q(3, i) - w*te(i)))
        end do
        call ts%check_less(e, 1.0e-10_dp, "knife edge: x = c sin^2 wt, y = c (wt - sin 2wt/2)")
        call ts%check_less(maxval(cr%res_vel), 1.0e-12_dp, "knife edge: no side slip")
        call ts%check_less(maxval(abs(cr%power)), 1.0e-11_dp, "knife edge: reaction power 0")
        call ts%check_less(maxval(abs(cr%energy - cr%energy(1))), 1.0e-10_dp, &
                           "knife edge: energy conserved")
    end block

    ! ---------------------------------------------------------------- knife edge, flat plane
    block
        real(dp), parameter :: w = 0.8_dp, u = 1.5_dp
        real(dp) :: rad
        call make_constrained("skate", [1.0_dp, 1.0_dp, 9.81_dp, 0.0_dp], cs, info, msg)
        call constrained_solve(cs, [0.0_dp, 5.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], &
                               [u, 0.0_dp, w], copt, cr, te)
        rad = u/w
        e = maxval(abs(sqrt(cr%q(1, :)**2 + (cr%q(2, :) - rad)**2) - rad))
        call ts%check_less(e, 1.0e-10_dp, "knife edge on a flat plane: circle of radius v/omega")
    end block

    ! ---------------------------------------------------------------- rolling disk
    block
        real(dp), parameter :: rr = 0.7_dp, om = 0.9_dp, ph = 2.5_dp
        real(dp) :: rho
        call make_constrained("rolling_disk", [1.3_dp, rr, 0.4_dp, 0.2_dp], cs, info, msg)
        call constrained_solve(cs, [0.0_dp, 5.0_dp], [0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp], &
                               [rr*ph, 0.0_dp, om, ph], copt, cr, te)
        call ts%check(cr%success, "rolling disk solves")
        call ts%check_less(maxval(abs(cr%v(3, :) - om)) + maxval(abs(cr%v(4, :) - ph)), &
                           1.0e-11_dp, "rolling disk: theta'' = phi'' = 0")
        rho = rr*ph/om
        e = maxval(abs(sqrt(cr%q(1, :)**2 + (cr%q(2, :) - rho)**2) - rho))
        call ts%check_less(e, 1.0e-10_dp, "rolling disk: centre on a circle of radius R w/W")
        call ts%check_less(maxval(cr%res_vel), 1.0e-12_dp, "rolling disk: rolls without slip")
    end block

    ! ---------------------------------------------------------------- cart pendulum (seed 000)
    block
        real(dp) :: p0, xf, x0, th0
        type(ode_result) :: r
        call make_generalized("cart_pendulum", [1.0_dp, 1.0_dp, 1.0_dp, 9.81_dp], gs, info, msg)
        x0 = 0.3_dp
        th0 = 2.5_dp
        call generalized_solve(gs, [0.0_dp, 5.0_dp], [x0, th0], [0.4_dp, 1.0_dp], gopt, r, te)
        call ts%check(r%success, "cart pendulum solves")
        p0 = 2.0_dp*0.4_dp + cos(th0)*1.0_dp
        e = 0.0_dp
        ref = 0.0_dp
        do i = 1, r%nt
            e = max(e, abs(2.0_dp*r%y(3, i) + cos(r%y(2, i))*r%y(4, i) - p0))
            xf = x0 + 0.5_dp*sin(th0) - 0.5_dp*sin(r%y(2, i)) + 0.5_dp*p0*te(i)
            ref = max(ref, abs(r%y(1, i) - xf))
        end do
        call ts%check_less(e, 1.0e-10_dp, "cart pendulum: momentum P = 2 xd + cos(th) thd")
        call ts%check_less(ref, 1.0e-10_dp, "cart pendulum: x(t) = -sin(th)/2 + C0 + C1 t")
        e = 0.0_dp
        do i = 1, r%nt
            e = max(e, abs(gs%energy(0.0_dp, r%y(1:2, i), r%y(3:4, i)) &
                           - gs%energy(0.0_dp, r%y(1:2, 1), r%y(3:4, 1))))
        end do
        call ts%check_less(e, 1.0e-9_dp, "cart pendulum: energy conserved")
        ! the seed's equations hold along the solution: 2 x'' + cos th'' - sin thd^2 = 0
        block
            real(dp) :: a(2)
            call generalized_accel(gs, 0.0_dp, r%y(1:2, 50), r%y(3:4, 50), a, info, msg)
            call ts%check_less(abs(2.0_dp*a(1) + cos(r%y(2, 50))*a(2) - sin(r%y(2, 50)) &
                                   *r%y(4, 50)**2) + abs(cos(r%y(2, 50))*a(1) + a(2) &
                                   - 9.81_dp*sin(r%y(2, 50))), 1.0e-12_dp, &
                               "cart pendulum: seed 000 equations")
        end block
    end block

    ! ---------------------------------------------------------------- yo-yo (rheonomic)
    block
        real(dp), parameter :: m = 0.2_dp, r = 0.03_dp, ii = 1.0e-4_dp, g = 9.81_dp
        real(dp), parameter :: ah = 1.5_dp, vh = 0.2_dp
        real(dp) :: tension, ydd
        tension = (ah + g)/(1.0_dp/m + r**2/ii)
        ydd = -g + tension/m
        call make_constrained("yoyo", [m, r, ii, g, ah, vh, 0.0_dp], cs, info, msg)
        call constrained_solve(cs, [0.0_dp, 5.0_dp], [0.0_dp, 0.0_dp], [vh, 0.0_dp], copt, &
                               cr, te)
        call ts%check(cr%success, "yo-yo solves")
        call ts%check_less(maxval(abs(cr%lam(1, :) - tension)), 1.0e-10_dp, &
                           "yo-yo: tension = (ah + g)/(1/m + r^2/I)")
        call ts%check_less(maxval(abs(cr%q(1, :) - (vh*te + 0.5_dp*ydd*te**2))), 1.0e-9_dp, &
                           "yo-yo: y = vh t + y'' t^2/2")
        call make_generalized("yoyo_angle", [m, r, ii, g, ah, vh, 0.0_dp], gs, info, msg)
        call generalized_solve(gs, [0.0_dp, 5.0_dp], [0.0_dp], [vh], gopt, gr, te)
        call ts%check_less(maxval(abs(gr%y(1, :) - cr%q(1, :))), 1.0e-9_dp, &
                           "yo-yo: excessive vs generalized")
    end block

    ! ---------------------------------------------------------------- moving suspension
    block
        real(dp), parameter :: p(6) = [1.0_dp, 9.81_dp, 0.9_dp, 0.5_dp, 0.2_dp, 4.0_dp]
        real(dp) :: s, th0
        th0 = 0.6_dp
        call make_constrained("pendulum_moving_xy", p, cs, info, msg)
        call constrained_solve(cs, [0.0_dp, 5.0_dp], [p(3)*sin(th0), -p(3)*cos(th0)], &
                               [p(5)*p(6), 0.0_dp], copt, cr, te)
        call ts%check(cr%success, "pendulum with moving support solves: "//cr%message)
        call make_generalized("pendulum_moving", p, gs, info, msg)
        call generalized_solve(gs, [0.0_dp, 5.0_dp], [th0], [0.0_dp], gopt, gr, te)
        e = 0.0_dp
        do i = 1, cr%nt
            s = 0.5_dp*p(4)*te(i)**2 + p(5)*sin(p(6)*te(i))
            e = max(e, abs(cr%q(1, i) - s - p(3)*sin(gr%y(1, i))), &
                    abs(cr%q(2, i) + p(3)*cos(gr%y(1, i))))
        end do
        call ts%check_less(e, 1.0e-9_dp, "moving suspension: excessive vs generalized")
        call ts%check_less(maxval(cr%res_pos) + maxval(cr%res_vel), 1.0e-12_dp, &
                           "moving suspension: rheonomic residuals")
        ! the reaction does work on a rheonomic system: power is not zero
        call ts%check(maxval(abs(cr%power)) > 1.0e-3_dp, "moving suspension: reaction works")
    end block

    ! ---------------------------------------------------------------- rod with NH constraint
    block
        real(dp), allocatable :: q0(:), v0(:)
        real(dp) :: c(2), d(2), cv(2)
        call make_constrained("rod_two_masses", [9.81_dp, 1.0_dp], cs, info, msg)
        call mech_initial_state("rod_two_masses", [9.81_dp, 1.0_dp], q0, v0, info)
        call constrained_solve(cs, [0.0_dp, 5.0_dp], q0, v0, copt, cr, te)
        call ts%check(cr%success, "rod with non-holonomic constraint solves")
        call ts%check(cr%dq0 == 0.0_dp .and. cr%dv0 < 1.0e-15_dp, "rod: default state consistent")
        e = 0.0_dp
        do i = 1, cr%nt
            d = cr%q(3:4, i) - cr%q(1:2, i)
            cv = 0.5_dp*(cr%v(1:2, i) + cr%v(3:4, i))
            c = [-d(2), d(1)]
            e = max(e, abs(dot_product(c, cv)), abs(norm2(d) - 1.0_dp))
        end do
        call ts%check_less(e, 1.0e-12_dp, "rod: length kept, centre velocity along the rod")
        call ts%check_less(maxval(abs(cr%energy - cr%energy(1))), 5.0e-10_dp, &
                           "rod: energy conserved (ideal constraints)")
        call ts%check_less(maxval(abs(cr%power)), 1.0e-11_dp, "rod: reaction power zero")
        ! integrable: the rod turns at a constant rate (no torque about the centre)
        e = 0.0_dp
        do i = 1, cr%nt
            d = cr%q(3:4, i) - cr%q(1:2, i)
            cv = cr%v(3:4, i) - cr%v(1:2, i)
            e = max(e, abs((d(1)*cv(2) - d(2)*cv(1)) - 0.6_dp))
        end do
        call ts%check_less(e, 1.0e-10_dp, "rod: constant angular velocity (integrable motion)")
        ! the centre speed along the rod: u' = -g sin(psi), psi = psi0 + w t, so
        ! u(t) = u0 + (g/w)(cos psi - cos psi0)
        e = 0.0_dp
        do i = 1, cr%nt
            d = cr%q(3:4, i) - cr%q(1:2, i)
            cv = 0.5_dp*(cr%v(1:2, i) + cr%v(3:4, i))
            ref = 1.0_dp + 9.81_dp/0.6_dp*(cos(0.5_dp + 0.6_dp*te(i)) - cos(0.5_dp))
            e = max(e, abs(dot_product(cv, d) - ref))
        end do
        call ts%check_less(e, 1.0e-9_dp, "rod: centre speed u = u0 + (g/w)(cos psi - cos psi0)")
    end block

    ! ---------------------------------------------------------------- cart pendulum equilibria
    block
        class(ode_system), allocatable :: os
        real(dp) :: jac(4, 4), wr(4), wi(4), g
        g = 9.81_dp
        call make_system("cart_pendulum", [1.0_dp, 1.0_dp, 1.0_dp, g], os, info, msg)
        call os%jacobian(0.0_dp, [0.3_dp, 0.0_dp, 0.0_dp, 0.0_dp], jac)
        call la_eig(jac, wr, wi, info)
        call ts%check_close(maxval(wr), sqrt(2.0_dp*g), 1.0e-6_dp, &
                            "cart pendulum upright: z'' = 2 g z (saddle, rate sqrt(2 g))")
        call os%jacobian(0.0_dp, [0.3_dp, acos(-1.0_dp), 0.0_dp, 0.0_dp], jac)
        call la_eig(jac, wr, wi, info)
        call ts%check_close(maxval(wi), sqrt(2.0_dp*g), 1.0e-6_dp, &
                            "cart pendulum hanging: z'' = -2 g z (centre, frequency sqrt(2 g))")
        call ts%check_less(maxval(abs(wr)), 1.0e-6_dp, "cart pendulum hanging: no growth")
    end block

    ! ---------------------------------------------------------------- bead on a spinning hoop
    block
        real(dp), parameter :: rr = 0.5_dp, om = 6.0_dp, g = 9.81_dp, eps = 1.0e-5_dp
        real(dp) :: ths, wsmall, tt(3), a(1)
        type(ode_result) :: r
        call make_generalized("bead_hoop", [1.0_dp, rr, om, g], gs, info, msg)
        ths = acos(g/(rr*om**2))
        call generalized_accel(gs, 0.0_dp, [ths], [0.0_dp], a, info, msg)
        call ts%check_less(abs(a(1)), 1.0e-12_dp, "bead: cos th* = g/(R W^2) is an equilibrium")
        wsmall = om*sin(ths)
        tt = [0.0_dp, acos(-1.0_dp)/wsmall, 2.0_dp*acos(-1.0_dp)/wsmall]
        call generalized_solve(gs, [0.0_dp, tt(3)], [ths + eps], [0.0_dp], gopt, r, tt)
        call ts%check_less(abs(r%y(1, 2) - (ths - eps)), 1.0e-3_dp*eps, &
                           "bead: oscillation about th* at W sin th* (half period)")
        call ts%check_less(abs(r%y(1, 3) - (ths + eps)), 1.0e-3_dp*eps, &
                           "bead: oscillation about th* at W sin th* (full period)")
        call generalized_accel(gs, 0.0_dp, [0.1_dp], [0.0_dp], a, info, msg)
        call ts%check(a(1) > 0.0_dp, "bead: th = 0 unstable when W^2 > g/R (pushed away)")
        call make_generalized("bead_hoop", [1.0_dp, rr, 0.5_dp*sqrt(g/rr), g], gs, info, msg)
        call generalized_accel(gs, 0.0_dp, [0.1_dp], [0.0_dp], a, info, msg)
        call ts%check(a(1) < 0.0_dp, "bead: th = 0 restoring when W^2 < g/R")
        ! and then th = 0 oscillates at sqrt(g/R - W^2)
        wsmall = sqrt(g/rr - 0.25_dp*g/rr)
        tt = [0.0_dp, acos(-1.0_dp)/wsmall, 2.0_dp*acos(-1.0_dp)/wsmall]
        call generalized_solve(gs, [0.0_dp, tt(3)], [eps], [0.0_dp], gopt, r, tt)
        call ts%check_less(abs(r%y(1, 2) + eps), 1.0e-3_dp*eps, &
                           "bead: small oscillation about 0 at sqrt(g/R - W^2)")
    end block

    ! ---------------------------------------------------------------- energies and momenta
    call conserve("spring_pendulum")
    call conserve("double_spring_pendulum")
    call conserve("three_springs")
    call conserve("polar_particle")
    call conserve("double_pendulum")
    call conserve("bead_hoop")
    block
        real(dp), allocatable :: q0(:), v0(:)
        type(ode_result) :: r
        real(dp) :: p0(2), l0
        call make_generalized("three_springs", [real(dp) ::], gs, info, msg)
        call mech_initial_state("three_springs", [real(dp) ::], q0, v0, info)
        call generalized_solve(gs, [0.0_dp, 5.0_dp], q0, v0, gopt, r, te)
        p0 = [sum(v0(1::2)), sum(v0(2::2))]
        e = 0.0_dp
        do i = 1, r%nt
            e = max(e, abs(sum(r%y(7::2, i)) - p0(1)), abs(sum(r%y(8::2, i)) - p0(2)))
        end do
        call ts%check_less(e, 1.0e-11_dp, "three springs: linear momentum conserved")
        call make_generalized("polar_particle", [real(dp) ::], gs, info, msg)
        call mech_initial_state("polar_particle", [real(dp) ::], q0, v0, info)
        call generalized_solve(gs, [0.0_dp, 5.0_dp], q0, v0, gopt, r, te)
        l0 = q0(1)**2*v0(2)
        call ts%check_less(maxval(abs(r%y(1, :)**2*r%y(4, :) - l0)), 1.0e-10_dp, &
                           "polar particle: angular momentum m r^2 thd conserved")
    end block

    ! ---------------------------------------------------------------- first-order registry
    block
        class(ode_system), allocatable :: os
        call make_system("cart_pendulum", [1.0_dp, 1.0_dp, 1.0_dp, 9.81_dp], os, info, msg)
        call ts%check(info == CM_SUCCESS .and. system_dimension("cart_pendulum") == 4, &
                      "make_system knows the generalized seed systems")
    end block

    ! gfortran keeps a deferred-length character of the main program on its stack, not in
    ! static storage: free it, or LeakSanitizer reports its last value as leaked
    if (allocated(msg)) deallocate (msg)
    call ts%finish()

contains

    subroutine conserve(name)
        character(len=*), intent(in) :: name
        real(dp), allocatable :: q0(:), v0(:)
        type(ode_result) :: r
        real(dp) :: e0, emax
        integer :: j, nd
        call make_generalized(name, [real(dp) ::], gs, info, msg)
        call mech_initial_state(name, [real(dp) ::], q0, v0, info)
        call generalized_solve(gs, [0.0_dp, 5.0_dp], q0, v0, gopt, r, te)
        nd = size(q0)
        e0 = gs%energy(0.0_dp, q0, v0)
        emax = 0.0_dp
        do j = 1, r%nt
            emax = max(emax, abs(gs%energy(0.0_dp, r%y(1:nd, j), r%y(nd + 1:, j)) - e0))
        end do
        call ts%check(r%success .and. gs%has_energy(), name//" solves")
        call ts%check_less(emax, 1.0e-9_dp*max(1.0_dp, abs(e0)), name//": energy conserved")
    end subroutine conserve

end program test_mechanics_systems
