!> A pendulum in sheared coordinates (x = q1 + a q2, y = q2): constant, non-diagonal mass
!! m [1, a; a, 1 + a^2]. RATTLE is covariant under constant linear changes of coordinates,
!! so its steps map to those of pendulum_xy.
module test_rattle_sheared
    use conmech
    implicit none
    private
    public :: sheared_pendulum, x_crossing
    !> g = q(1): the pendulum_xy bob crosses the vertical (theta = 0).
    type, extends(ode_events) :: x_crossing
    contains
        procedure :: eval => xc_eval
    end type x_crossing
    type, extends(constrained_system) :: sheared_pendulum
        real(dp) :: a = 0.7_dp, m = 1.0_dp, g = 9.81_dp, l = 1.0_dp
    contains
        procedure :: mass => sh_mass
        procedure :: forces => sh_forces
        procedure :: phi => sh_phi
        procedure :: phi_jac => sh_jac
    end type sheared_pendulum
contains
    subroutine xc_eval(self, t, y, g)
        class(x_crossing), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: g(:)
        g(1) = y(1)
    end subroutine xc_eval
    subroutine sh_mass(self, t, q, mm)
        class(sheared_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = self%m*reshape([1.0_dp, self%a, self%a, 1.0_dp + self%a**2], [2, 2])
    end subroutine sh_mass
    subroutine sh_forces(self, t, q, v, f)
        class(sheared_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = [0.0_dp, -self%m*self%g]
    end subroutine sh_forces
    subroutine sh_phi(self, t, q, c)
        class(sheared_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c(1) = 0.5_dp*((q(1) + self%a*q(2))**2 + q(2)**2 - self%l**2)
    end subroutine sh_phi
    subroutine sh_jac(self, t, q, g)
        class(sheared_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        g(1, 1) = q(1) + self%a*q(2)
        g(1, 2) = self%a*(q(1) + self%a*q(2)) + q(2)
    end subroutine sh_jac
end module test_rattle_sheared

!> RATTLE through rattle_solve: constraints at round-off, bounded energy, second order,
!! bad input.
program test_rattle
    use conmech
    use conmech_rattle, only: rattle_solve
    use conmech_testing, only: test_suite
    use test_rattle_sheared, only: sheared_pendulum, x_crossing
    implicit none
    type(sheared_pendulum) :: sh
    type(x_crossing) :: ev
    real(dp) :: tq(3), period
    type(test_suite) :: ts
    class(constrained_system), allocatable :: cs
    type(constrained_options) :: opt
    type(constrained_result) :: r, r2, r4
    real(dp), parameter :: g = 9.81_dp, l = 1.0_dp, th0 = 1.0_dp
    real(dp) :: q0(2), v0(2), e(3), de_first, de_last, e0
    integer :: info, i, k
    character(len=:), allocatable :: msg

    ts%name = "test_rattle"
    call make_constrained("pendulum_xy", [1.0_dp, g, l], cs, info, msg)
    q0 = [l*sin(th0), -l*cos(th0)]
    v0 = 0.0_dp
    opt%ode%first_step = 0.01_dp
    opt%ode%max_steps = 1000000
    call rattle_solve(cs, [0.0_dp, 500.0_dp], q0, v0, opt, r)
    call ts%check(r%success .and. r%naccept == 50000, "50000 steps: "//r%message)
    call ts%check_less(maxval(abs(r%res_pos)), 1.0e-12_dp, "max |phi|")
    call ts%check_less(maxval(abs(r%res_vel)), 1.0e-12_dp, "max |G v|")
    e0 = r%energy(1)
    k = r%nt/10
    de_first = maxval(abs(r%energy(1:k) - e0))
    de_last = maxval(abs(r%energy(r%nt - k + 1:r%nt) - e0))
    print "(a,2es10.2)", "  energy error first, last 10 %:", de_first, de_last
    call ts%check(de_last <= 1.05_dp*de_first .and. de_first < 1.0e-2_dp, &
                  "energy error bounded, no trend")

    ! order 2: errors at t = 1 with h, h/2 against h/4 (Richardson-free ratio test)
    opt%ode%first_step = 0.02_dp
    call rattle_solve(cs, [0.0_dp, 1.0_dp], q0, v0, opt, r)
    opt%ode%first_step = 0.01_dp
    call rattle_solve(cs, [0.0_dp, 1.0_dp], q0, v0, opt, r2)
    opt%ode%first_step = 0.005_dp
    call rattle_solve(cs, [0.0_dp, 1.0_dp], q0, v0, opt, r4)
    e(1) = maxval(abs(r%q(:, r%nt) - r2%q(:, r2%nt)))
    e(2) = maxval(abs(r2%q(:, r2%nt) - r4%q(:, r4%nt)))
    call ts%check_close(log(e(1)/e(2))/log(2.0_dp), 2.0_dp, 0.15_dp, "observed order")

    ! a constant non-diagonal mass (inverted once, and the general path factorising it at
    ! every step) gives the steps of the diagonal pendulum_xy mapped by x = q1 + a q2
    sh%n = 2
    sh%n_hol = 1
    opt%ode%first_step = 0.01_dp
    call rattle_solve(cs, [0.0_dp, 20.0_dp], q0, v0, opt, r)
    do k = 1, 2
        sh%constant_mass = k == 1
        call rattle_solve(sh, [0.0_dp, 20.0_dp], [q0(1) - sh%a*q0(2), q0(2)], &
                          [v0(1) - sh%a*v0(2), v0(2)], opt, r2)
        call ts%check(r2%success .and. r2%nt == r%nt, "sheared pendulum: "//r2%message)
        call ts%check_less(max(maxval(abs(r2%q(1, :) + sh%a*r2%q(2, :) - r%q(1, :))), &
                               maxval(abs(r2%q(2, :) - r%q(2, :))), &
                               maxval(abs(r2%v(1, :) + sh%a*r2%v(2, :) - r%v(1, :)))), &
                           1.0e-11_dp, "non-diagonal mass = mapped pendulum_xy steps")
        call ts%check_less(maxval(abs(r2%res_pos)), 1.0e-13_dp, "sheared: max |phi|")
    end do

    ! events: theta = 0 at T/4, 3T/4, ... (T from the complete elliptic integral K(k),
    ! k = sin(theta0/2), by the arithmetic-geometric mean: T = 2 pi sqrt(l/g) / AGM(1, cos
    ! (theta0/2))); event times of order 2 in h
    period = 2.0_dp*acos(-1.0_dp)*sqrt(l/g)/agm(1.0_dp, cos(th0/2.0_dp))
    ev%direction = [0]
    ev%terminal = [.false.]
    opt%ode%first_step = 0.02_dp
    call rattle_solve(cs, [0.0_dp, 2.0_dp*period], q0, v0, opt, r, events=ev)
    call ts%check(r%success .and. r%nev == 4, "four crossings of theta = 0 in two periods")
    ! the numerical period differs from T by O(h^2): the crossing-time errors grow as
    ! (2k+1) times the first one
    e = 0.0_dp
    do k = 2, 4
        e(k - 1) = (r%ev_t(k) - (2*k - 1)*0.25_dp*period)/(2*k - 1)
    end do
    call ts%check_less(abs(r%ev_t(1) - 0.25_dp*period), 1.0e-3_dp, "first crossing ~ T/4")
    call ts%check_less(maxval(abs(e/(r%ev_t(1) - 0.25_dp*period) - 1.0_dp)), 0.1_dp, &
                       "crossing-time errors grow as (2k+1) x the first (a period error)")
    call ts%check_less(maxval(abs(r%ev_q(1, :))), 1.0e-13_dp, "q1 = 0 at the events")
    call ts%check_less(maxval(abs(sqrt(r%ev_q(1, :)**2 + r%ev_q(2, :)**2) - l)), &
                       1.0e-14_dp, "event states on the constraint")
    ! terminal, falling only (the first crossing): order 2 in h
    ev%direction = [-1]
    ev%terminal = [.true.]
    do k = 1, 3
        opt%ode%first_step = 0.04_dp/2.0_dp**(k - 1)
        call rattle_solve(cs, [0.0_dp, 2.0_dp*period], q0, v0, opt, r, events=ev)
        call ts%check(r%status == CM_EVENT_STOP .and. r%nev == 1, "terminal event: "// &
                      r%message)
        call ts%check(abs(r%t(r%nt) - r%ev_t(1)) == 0.0_dp .and. r%q(1, r%nt) == &
                      r%ev_q(1, 1), "the run ends at the event state")
        tq(k) = abs(r%ev_t(1) - 0.25_dp*period)
    end do
    print "(a,3es10.2)", "  first crossing time errors (h = 0.04, 0.02, 0.01):", tq
    call ts%check_close(log(tq(1)/tq(2))/log(2.0_dp), 2.0_dp, 0.2_dp, "event time order 1")
    call ts%check_close(log(tq(2)/tq(3))/log(2.0_dp), 2.0_dp, 0.2_dp, "event time order 2")
    ! with t_eval: the points after the terminal event are not output
    call rattle_solve(cs, [0.0_dp, 2.0_dp*period], q0, v0, opt, r, &
                      t_eval=[0.1_dp, 0.2_dp, 0.3_dp, 1.0_dp], events=ev)
    call ts%check(r%status == CM_EVENT_STOP .and. r%nt == 3, "t_eval cut at the event")

    ! bad input
    opt%ode%first_step = 0.0_dp
    call rattle_solve(cs, [0.0_dp, 1.0_dp], q0, v0, opt, r)
    call ts%check(r%status == CM_BAD_INPUT .and. index(r%message, "first_step") > 0, &
                  "no step: "//r%message)
    call make_constrained("rod_two_masses", [9.81_dp, 1.0_dp], cs, info, msg)
    opt%ode%first_step = 0.01_dp
    call rattle_solve(cs, [0.0_dp, 1.0_dp], [0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp], &
                      [(0.0_dp, i=1, 4)], opt, r)
    call ts%check(r%status == CM_BAD_INPUT .and. index(r%message, "holonomic") > 0, &
                  "non-holonomic system: "//r%message)
    ! gfortran keeps a deferred-length character of the main program on its stack, not in
    ! static storage: free it, or LeakSanitizer reports its last value as leaked
    if (allocated(msg)) deallocate (msg)
    call ts%finish()
contains

    !> Arithmetic-geometric mean.
    pure real(dp) function agm(a0, b0)
        real(dp), intent(in) :: a0, b0
        real(dp) :: a, b, an
        integer :: it
        a = a0
        b = b0
        do it = 1, 40
            an = 0.5_dp*(a + b)
            b = sqrt(a*b)
            a = an
        end do
        agm = a
    end function agm
end program test_rattle
