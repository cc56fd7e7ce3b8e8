!> A pendulum in sheared coordinates (x = q1 + a q2, y = q2): constant, non-diagonal mass
!! m [1, a; a, 1 + a^2]. RATTLE is covariant under constant linear changes of coordinates,
!! so its steps map to those of pendulum_xy.
module test_rattle_sheared
    use conmech
    implicit none
    private
    public :: sheared_pendulum
    type, extends(constrained_system) :: sheared_pendulum
        real(dp) :: a = 0.7_dp, m = 1.0_dp, g = 9.81_dp, l = 1.0_dp
    contains
        procedure :: mass => sh_mass
        procedure :: forces => sh_forces
        procedure :: phi => sh_phi
        procedure :: phi_jac => sh_jac
    end type sheared_pendulum
contains
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
    use test_rattle_sheared, only: sheared_pendulum
    implicit none
    type(sheared_pendulum) :: sh
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
end program test_rattle
