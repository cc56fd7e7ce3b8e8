!> Pendulum and double pendulum: excessive vs generalized coordinates, the seed's
!! multiplier, the elliptic-integral period, redundant constraints, FD defaults.
module test_mech_pendulum_types
    use conmech
    implicit none

    !> The pendulum constraint written twice (redundant, rank 1).
    type, extends(pendulum_xy) :: pendulum_twice
    contains
        procedure :: phi => tw_phi
        procedure :: phi_jac => tw_jac
        procedure :: phi_gamma => tw_gamma
    end type pendulum_twice

    !> The built-in pendulum with its analytic Jacobian and acceleration term replaced by
    !! the library's finite-difference defaults (fd_phi_jac, fd_phi_gamma).
    type, extends(pendulum_xy) :: pendulum_fd
    contains
        procedure :: phi_jac => fdp_jac
        procedure :: phi_gamma => fdp_gamma
    end type pendulum_fd

    !> theta = 0 crossings of the generalized pendulum (y = [theta, theta']).
    type, extends(ode_events) :: bottom_crossing
    contains
        procedure :: eval => bottom_eval
    end type bottom_crossing

contains

    subroutine bottom_eval(self, t, y, g)
        class(bottom_crossing), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: g(:)
        g(1) = y(1)
    end subroutine bottom_eval

    subroutine tw_phi(self, t, q, c)
        class(pendulum_twice), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c(1) = 0.5_dp*(q(1)**2 + q(2)**2 - self%l**2)
        c(2) = c(1)
    end subroutine tw_phi
    subroutine tw_jac(self, t, q, g)
        class(pendulum_twice), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        g(1, :) = q(1:2)
        g(2, :) = q(1:2)
    end subroutine tw_jac
    subroutine tw_gamma(self, t, q, v, gam)
        class(pendulum_twice), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        gam = -(v(1)**2 + v(2)**2)
    end subroutine tw_gamma

    subroutine fdp_jac(self, t, q, g)
        class(pendulum_fd), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        call fd_phi_jac(self, t, q, g)
    end subroutine fdp_jac
    subroutine fdp_gamma(self, t, q, v, gam)
        class(pendulum_fd), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        call fd_phi_gamma(self, t, q, v, gam)
    end subroutine fdp_gamma

    !> Complete elliptic integral of the first kind K(k) by the arithmetic-geometric mean.
    pure function ellipk_agm(k) result(kk)
        real(dp), intent(in) :: k
        real(dp) :: kk, a, b, an
        integer :: i
        a = 1.0_dp
        b = sqrt(1.0_dp - k**2)
        do i = 1, 60
            an = 0.5_dp*(a + b)
            b = sqrt(a*b)
            a = an
            if (abs(a - b) <= 4.0_dp*epsilon(1.0_dp)*a) exit
        end do
        kk = acos(-1.0_dp)/(2.0_dp*a)
    end function ellipk_agm

end module test_mech_pendulum_types

program test_mechanics_pendulum
    use conmech
    use conmech_testing, only: test_suite
    use test_mech_pendulum_types
    implicit none
    type(test_suite) :: ts
    real(dp), parameter :: g = 9.81_dp, l = 1.3_dp, m = 0.7_dp, th0 = 1.2_dp
    real(dp) :: period, kk, lam_seed, err, errl, errp, t_eval(401)
    class(constrained_system), allocatable :: cs
    class(generalized_system), allocatable :: gs
    type(constrained_options) :: copt
    type(ode_options) :: gopt
    type(constrained_result) :: cr, cr2
    type(ode_result) :: gr
    integer :: info, i
    character(len=:), allocatable :: msg

    ts%name = "test_mechanics_pendulum"

    ! ---------------------------------------------------------------- period and K by the AGM
    kk = ellipk_agm(sin(th0/2.0_dp))
    period = 4.0_dp*sqrt(l/g)*kk
    do i = 1, size(t_eval)
        t_eval(i) = (i - 1)*20.0_dp*period/(size(t_eval) - 1)
    end do

    call make_constrained("pendulum_xy", [m, g, l], cs, info, msg)
    call ts%check(info == CM_SUCCESS, "make_constrained pendulum_xy")
    call make_generalized("pendulum_angle", [m, g, l], gs, info, msg)
    call ts%check(info == CM_SUCCESS, "make_generalized pendulum_angle")

    copt%ode%method = METHOD_DOP853
    copt%ode%rtol = 1.0e-13_dp
    copt%ode%atol = 1.0e-13_dp
    call constrained_solve(cs, [0.0_dp, t_eval(size(t_eval))], &
                           [l*sin(th0), -l*cos(th0)], [0.0_dp, 0.0_dp], copt, cr, t_eval)
    call ts%check(cr%success, "projected DOP853 on pendulum_xy succeeds: "//cr%message)
    gopt%method = METHOD_DOP853
    gopt%rtol = 1.0e-13_dp
    gopt%atol = 1.0e-13_dp
    call generalized_solve(gs, [0.0_dp, t_eval(size(t_eval))], [th0], [0.0_dp], gopt, gr, &
                           t_eval)
    call ts%check(gr%success, "DOP853 on pendulum_angle succeeds")
    call ts%check(cr%nt == size(t_eval) .and. gr%nt == size(t_eval), "outputs at t_eval")

    ! excessive vs generalized over 20 periods
    err = 0.0_dp
    errl = 0.0_dp
    errp = 0.0_dp
    do i = 1, cr%nt
        err = max(err, abs(cr%q(1, i) - l*sin(gr%y(1, i))), abs(cr%q(2, i) + l*cos(gr%y(1, i))))
        lam_seed = m/l**2*(cr%q(2, i)*g - cr%v(1, i)**2 - cr%v(2, i)**2)
        errl = max(errl, abs(cr%lam(1, i) - lam_seed)/(m*g))
        errp = max(errp, abs(cr%power(i)))
    end do
    call ts%check_less(err, 1.0e-9_dp, "pendulum (x,y) = l (sin th, -cos th) over 20 periods")
    call ts%check_less(errl, 1.0e-12_dp, "lambda = m/l^2 (y g - xd^2 - yd^2) (seed 000)")
    call ts%check_less(errp, 1.0e-10_dp, "reaction power is zero (ideal constraint)")
    call ts%check_less(maxval(abs(cr%reaction(:, 5) - cr%lam(1, 5)*cr%q(:, 5))), 1.0e-14_dp, &
                       "reaction R = lambda (x, y)")
    call ts%check_less(maxval(abs(cr%energy - cr%energy(1))), 1.0e-11_dp, "energy conserved")
    call ts%check_less(maxval(cr%res_pos), 1.0e-13_dp, "position residual")
    ! the period: th(T/2) = -th0 and th(T) = th0 (the solution at 20 T with 400 samples:
    ! sample 21 is T, sample 11 is T/2)
    call ts%check_close(gr%y(1, 11), -th0, 1.0e-10_dp, "theta(T/2) = -theta0, T = 4 sqrt(l/g) K")
    call ts%check_close(gr%y(1, 21), th0, 1.0e-10_dp, "theta(T) = theta0")
    call ts%check_close(gr%y(1, 401), th0, 1.0e-9_dp, "theta(20 T) = theta0")
    call ts%check_close(cr%q(1, 11), -l*sin(th0), 1.0e-10_dp, "x(T/2) = -l sin theta0")
    ! a wrong K would be seen: a 1e-6 relative change of T moves th(T/2) by > 1e-6
    call ts%check(abs(gr%y(2, 11)) < 1.0e-9_dp, "velocity zero at T/2 (turning point)")

    ! events through generalized_solve: the bob passes the bottom at T/4 and 3T/4
    block
        type(bottom_crossing) :: ev
        type(ode_result) :: er
        ev%direction = [0]
        ev%terminal = [.false.]
        call generalized_solve(gs, [0.0_dp, period], [th0], [0.0_dp], gopt, er, events=ev)
        call ts%check(er%nev == 2, "events: two bottom passages per period")
        if (er%nev == 2) then
            call ts%check_close(er%ev_t(1), 0.25_dp*period, 1.0e-9_dp, "event at T/4")
            call ts%check_close(er%ev_t(2), 0.75_dp*period, 1.0e-9_dp, "event at 3T/4")
        end if
    end block

    ! the projection as a step hook of the core ode_solve, with events (x = 0 at T/4, 3T/4)
    block
        type(bottom_crossing) :: ev
        type(ode_result) :: er
        type(constrained_ode) :: f
        type(projection_hook) :: hk
        real(dp) :: rp, rv, worst
        ev%direction = [0]
        ev%terminal = [.false.]
        allocate (f%mech, source=cs)
        allocate (hk%mech, source=cs)
        call ode_solve(f, [0.0_dp, period], [l*sin(th0), -l*cos(th0), 0.0_dp, 0.0_dp], gopt, &
                       er, events=ev, hook=hk)
        call ts%check(er%success .and. er%nev == 2, "hook: projected ode_solve with events")
        call ts%check(hk%nproj == er%stats%naccept, "hook: every accepted step projected")
        if (er%nev == 2) then
            call ts%check_close(er%ev_t(1), 0.25_dp*period, 1.0e-9_dp, "hook: event at T/4")
            call ts%check_close(er%ev_t(2), 0.75_dp*period, 1.0e-9_dp, "hook: event at 3T/4")
        end if
        worst = 0.0_dp
        do i = 1, er%nt
            call constraint_residuals(cs, er%t(i), er%y(1:2, i), er%y(3:4, i), rp, rv)
            worst = max(worst, rp, rv)
        end do
        call ts%check_less(worst, 1.0e-13_dp, "hook: residuals at the steps")
    end block

    ! constrained_solve with events: x = 0 at T/4 (falling) and 3T/4 (rising); direction -1
    ! and terminal: the run ends at the projected event state T/4
    block
        type(bottom_crossing) :: ev
        real(dp) :: rp, rv
        ev%direction = [0]
        ev%terminal = [.false.]
        call constrained_solve(cs, [0.0_dp, period], [l*sin(th0), -l*cos(th0)], &
                               [0.0_dp, 0.0_dp], copt, cr2, events=ev)
        call ts%check(cr2%success .and. cr2%nev == 2, "solve: two events per period")
        if (cr2%nev == 2) then
            call ts%check_less(maxval(abs(cr2%ev_t - [0.25_dp, 0.75_dp]*period)), 1.0e-10_dp, &
                               "solve: events at T/4, 3T/4")
            call constraint_residuals(cs, cr2%ev_t(2), cr2%ev_q(:, 2), cr2%ev_v(:, 2), rp, rv)
            call ts%check_less(max(rp, rv), 5.0e-14_dp, "solve: event state projected")
        end if
        ev%direction = [-1]
        ev%terminal = [.true.]
        call constrained_solve(cs, [0.0_dp, period], [l*sin(th0), -l*cos(th0)], &
                               [0.0_dp, 0.0_dp], copt, cr2, events=ev)
        call ts%check(cr2%status == CM_EVENT_STOP .and. cr2%nev == 1 .and. cr2%nt > 1, &
                      "solve: terminal event, "//cr2%message)
        if (cr2%nev == 1 .and. cr2%nt > 1) then
            call ts%check(cr2%t(cr2%nt) == cr2%ev_t(1) .and. all(cr2%q(:, cr2%nt) == &
                          cr2%ev_q(:, 1)), "solve: the run ends at the event state")
            call ts%check_less(max(cr2%res_pos(cr2%nt), cr2%res_vel(cr2%nt)), 1.0e-14_dp, &
                               "solve: final state on the constraints")
        end if
    end block

    ! ---------------------------------------------------------------- redundant constraints
    block
        type(pendulum_twice) :: tw
        tw%m = m; tw%g = g; tw%l = l
        tw%n = 2; tw%n_hol = 2
        call constrained_solve(tw, [0.0_dp, t_eval(size(t_eval))], &
                               [l*sin(th0), -l*cos(th0)], [0.0_dp, 0.0_dp], copt, cr2, t_eval)
        call ts%check(cr2%success, "redundant constraints solve: "//cr2%message)
        call ts%check(cr2%rank == 1, "rank of the duplicated constraint is 1")
        call ts%check_less(maxval(abs(cr2%q - cr%q)), 1.0e-10_dp, &
                           "redundant constraints: same motion")
        call ts%check_less(maxval(abs(cr2%reaction - cr%reaction)), 1.0e-9_dp, &
                           "redundant constraints: same reactions")
        call ts%check_less(maxval(abs(cr2%lam(1, :) - 0.5_dp*cr%lam(1, :))) + &
                           maxval(abs(cr2%lam(2, :) - 0.5_dp*cr%lam(1, :))), 1.0e-9_dp, &
                           "redundant constraints: minimum-norm lambda splits evenly")
    end block

    ! ------------------------------------ redundant constraints with RATTLE and Radau IIA
    ! RATTLE's minimum-norm position and velocity solves, and Radau IIA on an independent
    ! combination of the rows, give the motion of the single constraint
    block
        type(pendulum_twice) :: tw
        type(constrained_options) :: o
        type(constrained_result) :: r1, r2
        real(dp) :: te(41)
        integer :: k
        tw%m = m; tw%g = g; tw%l = l
        tw%n = 2; tw%n_hol = 2
        te = t_eval(1:41)
        do k = 1, 2
            o = copt
            if (k == 1) then
                o%ode%method = METHOD_RATTLE
                o%ode%first_step = 0.005_dp
            else
                o%ode%method = METHOD_RADAU5
                o%ode%rtol = 1.0e-10_dp
                o%ode%atol = 1.0e-10_dp
            end if
            call constrained_solve(cs, [0.0_dp, te(size(te))], [l*sin(th0), -l*cos(th0)], &
                                   [0.0_dp, 0.0_dp], o, r1, te)
            call constrained_solve(tw, [0.0_dp, te(size(te))], [l*sin(th0), -l*cos(th0)], &
                                   [0.0_dp, 0.0_dp], o, r2, te)
            call ts%check(r1%success .and. r2%success, "redundant rows, method "// &
                          merge("RATTLE", "Radau ", k == 1)//": "//r2%message)
            if (.not. (r1%success .and. r2%success)) cycle
            call ts%check(r2%rank == 1, "redundant rows: rank 1")
            call ts%check_less(maxval(abs(r2%q - r1%q)), merge(1.0e-11_dp, 1.0e-8_dp, k == 1), &
                               "redundant rows: the motion of the single constraint")
            call ts%check_less(maxval(r2%res_pos), 1.0e-10_dp, "redundant rows: both hold")
            call ts%check_less(maxval(abs(r2%reaction - r1%reaction)), 1.0e-6_dp, &
                               "redundant rows: the same reaction force")
        end do
    end block

    ! ---------------------------------------------------------------- FD defaults
    block
        type(pendulum_fd) :: pf
        real(dp) :: a1(2), a2(2), l1(1), l2(1), q(2), v(2)
        pf%m = m; pf%g = g; pf%l = l
        pf%n = 2; pf%n_hol = 1
        q = [l*sin(0.4_dp), -l*cos(0.4_dp)]
        v = [2.0_dp*cos(0.4_dp), 2.0_dp*sin(0.4_dp)]
        call constrained_accel(pf, 0.0_dp, q, v, a1, l1, info, msg)
        call constrained_accel(cs, 0.0_dp, q, v, a2, l2, info, msg)
        call ts%check_less(maxval(abs(a1 - a2)), 1.0e-9_dp, &
                           "FD default Jacobian and gamma: accelerations match analytic")
        call ts%check_less(abs(l1(1) - l2(1)), 1.0e-9_dp, "FD default: multiplier matches")
        call constrained_solve(pf, [0.0_dp, 5.0_dp*period], [l*sin(th0), -l*cos(th0)], &
                               [0.0_dp, 0.0_dp], copt, cr2, t_eval(1:101))
        call ts%check(cr2%success .and. cr2%nt == 101, "FD defaults solve: "//cr2%message)
        if (cr2%nt == 101) call ts%check_less(maxval(abs(cr2%q - cr%q(:, 1:101))), 1.0e-7_dp, &
                           "FD defaults: same motion over 5 periods")
    end block

    ! ---------------------------------------------------------------- double pendulum
    block
        real(dp) :: te(201), x1, y1, x2, y2, maxerr
        real(dp), parameter :: p(5) = [1.0_dp, 0.6_dp, 1.0_dp, 0.8_dp, 9.81_dp]
        real(dp), parameter :: a1 = 0.3_dp, a2 = -0.2_dp
        do i = 1, size(te)
            te(i) = (i - 1)*0.1_dp
        end do
        call make_constrained("double_pendulum_xy", p, cs, info, msg)
        call make_generalized("double_pendulum", p, gs, info, msg)
        call constrained_solve(cs, [0.0_dp, te(size(te))], &
                               [p(3)*sin(a1), -p(3)*cos(a1), p(3)*sin(a1) + p(4)*sin(a2), &
                                -p(3)*cos(a1) - p(4)*cos(a2)], [0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp], &
                               copt, cr, te)
        call generalized_solve(gs, [0.0_dp, te(size(te))], [a1, a2], [0.0_dp, 0.0_dp], gopt, &
                               gr, te)
        call ts%check(cr%success .and. gr%success, "double pendulum: both solves succeed")
        maxerr = 0.0_dp
        do i = 1, size(te)
            x1 = p(3)*sin(gr%y(1, i)); y1 = -p(3)*cos(gr%y(1, i))
            x2 = x1 + p(4)*sin(gr%y(2, i)); y2 = y1 - p(4)*cos(gr%y(2, i))
            maxerr = max(maxerr, maxval(abs(cr%q(:, i) - [x1, y1, x2, y2])))
        end do
        call ts%check_less(maxerr, 1.0e-9_dp, &
                           "double pendulum: Cartesian vs angles agree over 20 s (~10 periods)")
        call ts%check_less(maxval(abs(cr%energy - cr%energy(1))), 1.0e-11_dp, &
                           "double pendulum (x,y): energy conserved")
        call ts%check_less(maxval(abs(cr%power)), 1.0e-10_dp, "double pendulum: zero power")
    end block

    ! gfortran keeps a deferred-length character of the main program on its stack, not in
    ! static storage: free it, or LeakSanitizer reports its last value as leaked
    if (allocated(msg)) deallocate (msg)
    call ts%finish()
end program test_mechanics_pendulum
