!> The rolling rubber ball derived from T, U and its constraints in Python and emitted as
!! Fortran (rolling_ball_model.f90, by `python -m conmech.symbolic emit
!! example/models/rolling_ball.py -o example/rolling_ball_model.f90`), run with
!! constrained_solve beside the hand-written built-in "rolling_ball": trajectories,
!! multipliers and the closed-form parabola x = u t + a t^2/2, a = g sin(alpha)/(1 + I/(m R^2)).
!!   fpm run --example user_ball
program user_ball
    use conmech
    use rolling_ball_model, only: rolling_ball_sym, new_rolling_ball_sym
    implicit none
    type(rolling_ball_sym) :: sym
    class(constrained_system), allocatable :: builtin
    type(constrained_options) :: opt
    type(constrained_result) :: rs, rb
    real(dp) :: te(31), q0(6), v0(6), e0(4), om(3), acc, eq, ev, el, ex
    real(dp), parameter :: u = 0.4_dp, w = 1.1_dp
    integer :: info, i
    character(len=:), allocatable :: msg

    sym = new_rolling_ball_sym()
    call make_constrained("rolling_ball", [sym%m, sym%R, sym%I, sym%g, sym%alpha], builtin, &
                          info, msg)
    opt%ode%rtol = 1.0e-12_dp
    opt%ode%atol = 1.0e-12_dp
    te = [(0.1_dp*i, i = 0, 30)]
    e0 = [0.5_dp, 0.5_dp, -0.5_dp, 0.5_dp]
    om = [-w/sym%R, u/sym%R, 0.0_dp]
    q0 = [0.0_dp, 0.0_dp, e0]
    ! e' = (0, w)/2 * e (space-frame angular velocity w: rolling, no spin)
    v0(1:2) = [u, w]
    v0(3) = -0.5_dp*dot_product(om, e0(2:4))
    v0(4:6) = 0.5_dp*(e0(1)*om + [om(2)*e0(4) - om(3)*e0(3), om(3)*e0(2) - om(1)*e0(4), &
                                  om(1)*e0(3) - om(2)*e0(2)])
    call constrained_solve(sym, [0.0_dp, 3.0_dp], q0, v0, opt, rs, te)
    call constrained_solve(builtin, [0.0_dp, 3.0_dp], q0, v0, opt, rb, te)
    if (.not. (rs%success .and. rb%success)) then
        write (*, '(a)') "integration failed"
        stop 1
    end if
    eq = maxval(abs(rs%q - rb%q))/maxval(abs(rb%q))
    ev = maxval(abs(rs%v - rb%v))/maxval(abs(rb%v))
    el = maxval(abs(rs%lam - rb%lam))/maxval(abs(rb%lam))
    acc = sym%g*sin(sym%alpha)/(1.0_dp + sym%I/(sym%m*sym%R**2))
    ex = maxval(abs(rs%q(1, :) - u*te - 0.5_dp*acc*te**2))
    write (*, '(a, 3es10.2)') "symbolic vs built-in (q, v, lambda): ", eq, ev, el
    write (*, '(a, es10.2)') "parabola x = u t + a t^2/2: ", ex
    write (*, '(a, 2es10.2)') "constraint residuals (pos, vel): ", maxval(rs%res_pos), &
        maxval(rs%res_vel)
    write (*, '(a, es10.2)') "energy drift: ", maxval(abs(rs%energy - rs%energy(1)))
end program user_ball
