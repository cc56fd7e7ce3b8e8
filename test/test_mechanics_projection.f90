!> Projected integrators: residuals over a long run (1e6 RK4 steps), the drift of the plain
!! index-1 form and its removal by projection, Baumgarte, convergence orders of the
!! projected methods, projection every k steps, consistent initial values.
program test_mechanics_projection
    use conmech
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    class(constrained_system), allocatable :: cs, dp2
    class(generalized_system), allocatable :: gs
    type(constrained_options) :: opt
    type(constrained_result) :: r, rn, rb
    type(ode_options) :: gopt
    type(ode_result) :: gr
    real(dp), parameter :: g = 9.81_dp, l = 1.0_dp, th0 = 1.0_dp
    real(dp) :: te(1001), q0(2), v0(2), drift_early, ord
    integer :: info, i
    character(len=:), allocatable :: msg
    character(len=16) :: buf

    ts%name = "test_mechanics_projection"
    call make_constrained("pendulum_xy", [1.0_dp, g, l], cs, info, msg)
    call make_generalized("pendulum_angle", [1.0_dp, g, l], gs, info, msg)
    q0 = [l*sin(th0), -l*cos(th0)]
    v0 = [0.0_dp, 0.0_dp]

    ! ---------------------------------------------------------------- 1e6 RK4 steps
    do i = 1, size(te)
        te(i) = (i - 1)*1.0_dp
    end do
    opt%ode%method = METHOD_RK4
    opt%ode%first_step = 1.0e-3_dp
    opt%ode%max_steps = 2000000
    opt%projection = PROJ_POSITION_VELOCITY
    call constrained_solve(cs, [0.0_dp, 1000.0_dp], q0, v0, opt, r, te)
    call ts%check(r%success, "projected RK4, 1e6 steps: "//r%message)
    write (buf, '(i0)') r%naccept
    call ts%check(r%naccept >= 1000000 .and. r%nproj == r%naccept, &
                  "1e6 steps, each one projected ("//trim(buf)//")")
    call ts%check_less(maxval(r%res_pos), 1.0e-12_dp, "projected: max |phi| over 1e6 steps")
    call ts%check_less(maxval(r%res_vel), 1.0e-12_dp, "projected: max |G v| over 1e6 steps")
    call ts%check(r%proj_iter_max >= 1 .and. r%proj_iter_max <= 3, &
                  "simplified Newton converges in at most 3 iterations")

    ! the other stabilisations over 1e5 steps (t = 100) to keep the test short
    opt%projection = PROJ_NONE
    call constrained_solve(cs, [0.0_dp, 100.0_dp], q0, v0, opt, rn, te(1:101))
    call ts%check(rn%success .and. rn%nproj == 0, "index-1 RK4, 1e5 steps, no projection")
    drift_early = rn%res_pos(2)
    call ts%check(rn%res_pos(rn%nt) > 1.0e-10_dp, "index-1 form drifts: |phi(100)| > 1e-10")
    call ts%check(rn%res_pos(rn%nt) > 10.0_dp*drift_early, &
                  "index-1 drift grows with t (|phi(100)| > 10 |phi(1)|)")
    call ts%check(rn%res_pos(rn%nt) > 1.0e3_dp*maxval(r%res_pos), &
                  "projection removes the drift (>1000x smaller)")

    opt%projection = PROJ_BAUMGARTE
    opt%alpha = 10.0_dp
    opt%beta = 10.0_dp
    call constrained_solve(cs, [0.0_dp, 100.0_dp], q0, v0, opt, rb, te(1:101))
    call ts%check(rb%success, "Baumgarte RK4 succeeds")
    call ts%check_less(rb%res_pos(rb%nt), 0.1_dp*rn%res_pos(rn%nt), &
                       "Baumgarte keeps |phi| below the plain index-1 drift")

    opt%projection = PROJ_VELOCITY
    call constrained_solve(cs, [0.0_dp, 100.0_dp], q0, v0, opt, rb, te(1:101))
    call ts%check_less(maxval(rb%res_vel), 1.0e-12_dp, "velocity projection: |G v| small")

    ! ---------------------------------------------------------------- every k steps
    opt%projection = PROJ_POSITION_VELOCITY
    opt%every = 10
    call constrained_solve(cs, [0.0_dp, 20.0_dp], q0, v0, opt, rb, te(1:21))
    call ts%check(rb%success .and. rb%nproj == rb%naccept/10, "projection every 10 steps")
    call ts%check_less(maxval(rb%res_pos), 1.0e-12_dp, &
                       "every 10 steps: residual at the (projected) outputs")
    opt%every = 1

    ! ---------------------------------------------------------------- convergence orders
    call generalized_solve_ref()
    ord = order_of(METHOD_RK4, 0.04_dp, PROJ_POSITION_VELOCITY)
    call ts%check(ord > 3.7_dp .and. ord < 4.4_dp, "projected RK4 has order 4 ("// &
                  fmt(ord)//")")
    ord = order_of(METHOD_DOPRI5, 0.08_dp, PROJ_POSITION_VELOCITY)
    call ts%check(ord > 4.6_dp .and. ord < 5.5_dp, "projected DOPRI5 has order 5 ("// &
                  fmt(ord)//")")
    ord = order_of(METHOD_DOP853, 0.2_dp, PROJ_POSITION_VELOCITY)
    call ts%check(ord > 7.4_dp .and. ord < 8.8_dp, "projected DOP853 has order 8 ("// &
                  fmt(ord)//")")
    ! Verner 9(8) is not yet asymptotic at these steps on this problem (the core integrator
    ! on the generalized pendulum shows ratios of 2^10.5 too): assert that projection does
    ! not lower the order below 9.
    ord = order_of(METHOD_VERNER98, 0.2_dp, PROJ_POSITION_VELOCITY)
    call ts%check(ord > 8.5_dp .and. ord < 12.0_dp, "projected VERNER98: order >= 9 ("// &
                  fmt(ord)//")")
    ord = order_of(METHOD_RK4, 0.04_dp, PROJ_NONE)
    call ts%check(ord > 3.7_dp .and. ord < 4.4_dp, "unprojected RK4 has order 4 ("// &
                  fmt(ord)//")")

    ! ---------------------------------------------------------------- consistent start
    opt = constrained_options()
    opt%ode%rtol = 1.0e-10_dp
    opt%ode%atol = 1.0e-10_dp
    call constrained_solve(cs, [0.0_dp, 1.0_dp], 1.1_dp*q0, &
                           [0.5_dp*sin(th0) + cos(th0), -0.5_dp*cos(th0) + sin(th0)], opt, r)
    call ts%check(r%success, "inconsistent start is projected")
    call ts%check_close(r%dq0, 0.1_dp*l, 1.0e-12_dp, "distance moved by the position projection")
    call ts%check_close(r%dv0, 0.5_dp, 1.0e-12_dp, "velocity change of the velocity projection")
    call ts%check_less(r%res_pos(1) + r%res_vel(1), 1.0e-14_dp, "start now on the manifold")
    call ts%check_close(r%v(1, 1), cos(th0), 1.0e-13_dp, "tangential velocity kept")

    ! ---------------------------------------------------------------- double pendulum drift
    call make_constrained("double_pendulum_xy", [real(dp) ::], dp2, info, msg)
    block
        real(dp), allocatable :: qq(:), vv(:)
        call mech_initial_state("double_pendulum_xy", [real(dp) ::], qq, vv, info)
        opt = constrained_options()
        opt%ode%rtol = 1.0e-8_dp
        opt%ode%atol = 1.0e-8_dp
        opt%save_steps = .false.
        opt%projection = PROJ_NONE
        call constrained_solve(dp2, [0.0_dp, 200.0_dp], qq, vv, opt, rn)
        opt%projection = PROJ_POSITION_VELOCITY
        call constrained_solve(dp2, [0.0_dp, 200.0_dp], qq, vv, opt, r)
        call ts%check(r%success .and. rn%success, "double pendulum DOP853 rtol 1e-8, 200 s")
        call ts%check(rn%res_pos(rn%nt) > 1.0e-8_dp, "double pendulum: index-1 drift exists")
        call ts%check_less(r%res_pos(r%nt) + r%res_vel(r%nt), 1.0e-12_dp, &
                           "double pendulum: projected residuals")
    end block

    ! gfortran keeps a deferred-length character of the main program on its stack, not in
    ! static storage: free it, or LeakSanitizer reports its last value as leaked
    if (allocated(msg)) deallocate (msg)
    call ts%finish()

contains

    function fmt(x) result(s)
        real(dp), intent(in) :: x
        character(len=:), allocatable :: s
        character(len=16) :: b
        write (b, '(f6.2)') x
        s = trim(adjustl(b))
    end function fmt

    subroutine generalized_solve_ref()
        gopt%method = METHOD_DOP853
        gopt%rtol = 1.0e-14_dp
        gopt%atol = 1.0e-14_dp
        call generalized_solve(gs, [0.0_dp, 2.0_dp], [th0], [0.0_dp], gopt, gr)
    end subroutine generalized_solve_ref

    !> Observed order from fixed steps h and h/2 over [0, 2]: log2(err(h)/err(h/2)).
    function order_of(method, h, proj) result(p)
        integer, intent(in) :: method, proj
        real(dp), intent(in) :: h
        real(dp) :: p, e(2), th, hh
        type(constrained_options) :: o
        type(constrained_result) :: rr
        integer :: j
        th = gr%y(1, gr%nt)
        do j = 1, 2
            hh = h/2.0_dp**(j - 1)
            o%ode%method = method
            o%ode%first_step = hh
            o%ode%max_step = hh
            o%ode%rtol = 1.0e3_dp      ! huge tolerances: every step of size h accepted
            o%ode%atol = 1.0e3_dp
            o%projection = proj
            o%save_steps = .false.
            call constrained_solve(cs, [0.0_dp, 2.0_dp], q0, v0, o, rr)
            e(j) = max(abs(rr%q(1, rr%nt) - l*sin(th)), abs(rr%q(2, rr%nt) + l*cos(th)))
        end do
        p = log(e(1)/e(2))/log(2.0_dp)
    end function order_of

end program test_mechanics_projection
