!> The rolling rubber ball (seed 001) against its closed forms: on the plane the centre moves
!! on a straight line and the ball turns about a fixed horizontal axis; on an incline the
!! centre moves on a parabola with x'' = g sin(alpha)/(1 + I/(m R^2)) and the contact force
!! F_x = -I x''/R^2 is the multiplier. Constraints, energy, and the analytic acceleration
!! terms against the finite-difference defaults.
program test_systems_ball
    use conmech
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    class(constrained_system), allocatable :: cs
    type(constrained_options) :: copt
    type(constrained_result) :: cr
    real(dp) :: te(81), e
    integer :: info, i
    character(len=:), allocatable :: msg
    real(dp), parameter :: m = 1.3_dp, rr = 0.7_dp, ii = 0.2_dp, g = 9.81_dp

    ts%name = "test_systems_ball"
    copt%ode%rtol = 1.0e-12_dp
    copt%ode%atol = 1.0e-12_dp
    do i = 1, size(te)
        te(i) = (i - 1)*0.05_dp
    end do

    call make_constrained("rolling_ball", [m, rr, ii, g, 0.0_dp], cs, info, msg)
    call ts%check(info == CM_SUCCESS .and. cs%n == 6 .and. cs%n_hol == 1 .and. cs%n_nh == 3, &
                  "rolling_ball registered (6, 1, 3)")

    ! ---------------------------------------------------------------- flat plane
    block
        real(dp), parameter :: u = 0.8_dp, w = -0.5_dp
        real(dp) :: om(3), omn, eq(4), e0(4), v0(6)
        e0 = [0.6_dp, 0.0_dp, 0.8_dp, 0.0_dp]
        om = [-w/rr, u/rr, 0.0_dp]
        v0(1:2) = [u, w]
        v0(3:6) = 0.5_dp*qmul([0.0_dp, om], e0)
        call constrained_solve(cs, [0.0_dp, 4.0_dp], [0.1_dp, 0.2_dp, e0], v0, copt, cr, te)
        call ts%check(cr%success, "ball on the plane solves")
        call ts%check_less(cr%dq0 + cr%dv0, 1.0e-14_dp, "consistent initial state unchanged")
        omn = norm2(om)
        e = 0.0_dp
        do i = 1, cr%nt
            eq = qmul([cos(0.5_dp*omn*te(i)), sin(0.5_dp*omn*te(i))*om/omn], e0)
            e = max(e, abs(cr%q(1, i) - 0.1_dp - u*te(i)), abs(cr%q(2, i) - 0.2_dp - w*te(i)), &
                    maxval(abs(cr%q(3:6, i) - eq)))
        end do
        call ts%check_less(e, 1.0e-10_dp, "plane: straight line, rotation about a fixed axis")
        call ts%check_less(maxval(cr%res_pos) + maxval(cr%res_vel), 1.0e-12_dp, &
                           "plane: |e| = 1, no slip, no spin")
        call ts%check_less(maxval(abs(cr%lam(2:4, :))), 1.0e-10_dp, &
                           "plane: no contact force or torque needed")
        call ts%check_less(maxval(abs(cr%lam(1, :) + ii*omn**2)), 1.0e-10_dp, &
                           "plane: quaternion multiplier -4 I |e'|^2 = -I |w|^2")
        call ts%check_less(maxval(abs(cr%energy - cr%energy(1))), 1.0e-12_dp, &
                           "plane: energy conserved")
    end block

    ! ---------------------------------------------------------------- incline
    block
        real(dp), parameter :: alpha = 0.3_dp, u = 0.4_dp, w = 1.1_dp
        real(dp) :: acc, fx, e0(4), v0(6), om(3), en
        call make_constrained("rolling_ball", [m, rr, ii, g, alpha], cs, info, msg)
        e0 = [0.5_dp, 0.5_dp, -0.5_dp, 0.5_dp]
        om = [-w/rr, u/rr, 0.0_dp]
        v0(1:2) = [u, w]
        v0(3:6) = 0.5_dp*qmul([0.0_dp, om], e0)
        call constrained_solve(cs, [0.0_dp, 4.0_dp], [0.0_dp, 0.0_dp, e0], v0, copt, cr, te)
        call ts%check(cr%success, "ball on the incline solves")
        acc = g*sin(alpha)/(1.0_dp + ii/(m*rr**2))
        fx = -ii*acc/rr**2
        e = 0.0_dp
        do i = 1, cr%nt
            e = max(e, abs(cr%q(1, i) - u*te(i) - 0.5_dp*acc*te(i)**2), &
                    abs(cr%q(2, i) - w*te(i)))
        end do
        call ts%check_less(e, 1.0e-10_dp, "incline: parabola, x'' = g sin a/(1 + I/(m R^2))")
        call ts%check_less(maxval(abs(cr%lam(2, :) - fx)), 1.0e-9_dp, &
                           "incline: friction multiplier F_x = -I x''/R^2")
        call ts%check_less(maxval(abs(cr%lam(3:4, :))), 1.0e-9_dp, &
                           "incline: F_y = 0 and no spin torque (isotropic ball)")
        call ts%check_less(maxval(cr%res_pos) + maxval(cr%res_vel), 1.0e-12_dp, &
                           "incline: constraints hold")
        en = maxval(abs(cr%energy - cr%energy(1)))
        call ts%check_less(en, 1.0e-10_dp, "incline: energy conserved")
        call ts%check_less(maxval(abs(cr%power)), 1.0e-10_dp, "incline: reactions do no work")
    end block

    ! ---------------------------------------------------------------- analytic vs defaults
    block
        real(dp) :: q(6), v(6), ga(1), gf(1), na(3), nf(3), ja(1, 6), jf(1, 6)
        q = [0.3_dp, -0.2_dp, 0.4_dp, -0.3_dp, 0.7_dp, 0.5_dp]
        v = [0.5_dp, -1.0_dp, 0.3_dp, 0.8_dp, -0.2_dp, 0.6_dp]
        call cs%phi_gamma(0.0_dp, q, v, ga)
        call fd_phi_gamma(cs, 0.0_dp, q, v, gf)
        call ts%check_less(abs(ga(1) - gf(1)), 1.0e-8_dp, "gamma_h analytic = differences")
        call cs%nh_gamma(0.0_dp, q, v, na)
        call fd_nh_gamma(cs, 0.0_dp, q, v, nf)
        call ts%check_less(maxval(abs(na - nf)), 1.0e-9_dp, "gamma_n analytic = differences")
        call cs%phi_jac(0.0_dp, q, ja)
        call fd_phi_jac(cs, 0.0_dp, q, jf)
        call ts%check_less(maxval(abs(ja - jf)), 1.0e-9_dp, "G analytic = differences")
    end block

    ! ---------------------------------------------------------------- bad input
    block
        call make_constrained("rolling_bal", [m], cs, info, msg)
        call ts%check(info == CM_BAD_INPUT .and. index(msg, "rolling_ball") > 0, &
                      "unknown name: error lists rolling_ball")
    end block

    call ts%finish()
    if (allocated(msg)) deallocate (msg)   ! main-program variables are not freed at exit
    if (allocated(cs)) deallocate (cs)     ! (LeakSanitizer would report them)

contains

    !> Quaternion product a * b.
    pure function qmul(a, b) result(c)
        real(dp), intent(in) :: a(4), b(4)
        real(dp) :: c(4)
        c(1) = a(1)*b(1) - dot_product(a(2:4), b(2:4))
        c(2:4) = a(1)*b(2:4) + b(1)*a(2:4) + [a(3)*b(4) - a(4)*b(3), a(4)*b(2) - a(2)*b(4), &
                                                a(2)*b(3) - a(3)*b(2)]
    end function qmul

end program test_systems_ball
