!> The finite-difference defaults (phi_jac, phi_t, phi_gamma for rheonomic constraints,
!! nh_gamma) against the analytic built-ins, and backward integration.
module test_mech_default_types
    use conmech
    implicit none

    !> Pendulum with a moving support, phi only (rheonomic): everything else by default.
    type, extends(constrained_system) :: moving_fd
        real(dp) :: g = 9.81_dp, l = 0.9_dp, a = 0.5_dp, b = 0.2_dp, w = 4.0_dp
    contains
        procedure :: mass => mf_mass
        procedure :: forces => mf_forces
        procedure :: phi => mf_phi
    end type moving_fd

    !> The rod with the non-holonomic constraint: A and b only, nh_gamma by default.
    type, extends(rod_two_masses) :: rod_fd
    contains
        procedure :: nh_gamma => rf_nh_gamma
    end type rod_fd

contains

    subroutine mf_mass(self, t, q, mm)
        class(moving_fd), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = 0.0_dp
        mm(1, 1) = 1.0_dp
        mm(2, 2) = 1.0_dp
    end subroutine mf_mass
    subroutine mf_forces(self, t, q, v, f)
        class(moving_fd), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = [0.0_dp, -self%g]
    end subroutine mf_forces
    subroutine mf_phi(self, t, q, c)
        class(moving_fd), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        real(dp) :: s
        s = 0.5_dp*self%a*t**2 + self%b*sin(self%w*t)
        c(1) = 0.5_dp*((q(1) - s)**2 + q(2)**2 - self%l**2)
    end subroutine mf_phi

    !> Delegates to the finite-difference default (the parent's is analytic).
    subroutine rf_nh_gamma(self, t, q, v, gam)
        class(rod_fd), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        call fd_nh_gamma(self, t, q, v, gam)
    end subroutine rf_nh_gamma

end module test_mech_default_types

program test_mechanics_defaults
    use conmech
    use conmech_testing, only: test_suite
    use test_mech_default_types
    implicit none
    type(test_suite) :: ts
    class(constrained_system), allocatable :: cs
    type(constrained_options) :: opt
    type(constrained_result) :: r1, r2
    real(dp) :: te(41), a1(4), a2(4), l1(2), l2(2), q(2), v(2)
    integer :: info, i
    character(len=:), allocatable :: msg

    ts%name = "test_mechanics_defaults"
    opt%ode%rtol = 1.0e-11_dp
    opt%ode%atol = 1.0e-11_dp
    do i = 1, size(te)
        te(i) = (i - 1)*0.1_dp
    end do

    ! ---------------------------------------------------------------- rheonomic defaults
    block
        type(moving_fd) :: mf
        mf%n = 2
        mf%n_hol = 1
        mf%rheonomic = .true.
        call make_constrained("pendulum_moving_xy", [1.0_dp, 9.81_dp, 0.9_dp, 0.5_dp, 0.2_dp, &
                                                     4.0_dp], cs, info, msg)
        q = [0.9_dp*sin(0.6_dp) + 0.3_dp, -0.9_dp*cos(0.6_dp)]
        v = [1.1_dp, -0.4_dp]
        call constrained_accel(mf, 0.7_dp, q, v, a1(1:2), l1(1:1), info, msg)
        call constrained_accel(cs, 0.7_dp, q, v, a2(1:2), l2(1:1), info, msg)
        call ts%check_less(maxval(abs(a1(1:2) - a2(1:2))), 1.0e-8_dp, &
                           "rheonomic FD defaults (G, phi_t, gamma): accelerations")
        call ts%check_less(abs(l1(1) - l2(1)), 1.0e-8_dp, "rheonomic FD defaults: multiplier")
        q = [0.9_dp*sin(0.6_dp), -0.9_dp*cos(0.6_dp)]
        call constrained_solve(mf, [0.0_dp, 4.0_dp], q, [0.8_dp, 0.0_dp], opt, r1, te)
        call constrained_solve(cs, [0.0_dp, 4.0_dp], q, [0.8_dp, 0.0_dp], opt, r2, te)
        call ts%check(r1%success .and. r2%success, "rheonomic FD system solves")
        call ts%check_less(maxval(abs(r1%q - r2%q)), 1.0e-8_dp, &
                           "rheonomic FD defaults: same motion over 4 s")
        call ts%check_less(maxval(r1%res_vel), 1.0e-10_dp, &
                           "rheonomic FD: velocity residual (with the FD phi_t)")
    end block

    ! ---------------------------------------------------------------- non-holonomic default
    block
        type(rod_fd) :: rf
        real(dp), allocatable :: q0(:), v0(:)
        rf%n = 4
        rf%n_hol = 1
        rf%n_nh = 1
        call make_constrained("rod_two_masses", [real(dp) ::], cs, info, msg)
        call mech_initial_state("rod_two_masses", [real(dp) ::], q0, v0, info)
        call constrained_accel(rf, 0.0_dp, q0, v0, a1, l1, info, msg)
        call constrained_accel(cs, 0.0_dp, q0, v0, a2, l2, info, msg)
        call ts%check_less(maxval(abs(a1 - a2)) + maxval(abs(l1 - l2)), 1.0e-10_dp, &
                           "non-holonomic FD default nh_gamma: accelerations, multipliers")
    end block

    ! ---------------------------------------------------------------- backward in time
    block
        real(dp) :: tb(2)
        call make_constrained("pendulum_xy", [real(dp) ::], cs, info, msg)
        q = [sin(1.0_dp), -cos(1.0_dp)]
        call constrained_solve(cs, [0.0_dp, 3.0_dp], q, [0.0_dp, 0.0_dp], opt, r1)
        tb = [3.0_dp, 0.0_dp]
        call constrained_solve(cs, tb, r1%q(:, r1%nt), r1%v(:, r1%nt), opt, r2)
        call ts%check(r2%success .and. r2%t(r2%nt) == 0.0_dp, "backward integration succeeds")
        call ts%check_less(maxval(abs(r2%q(:, r2%nt) - q)), 1.0e-9_dp, &
                           "forward then backward returns to q0")
        call ts%check_less(maxval(r2%res_pos), 1.0e-13_dp, "backward: projected residuals")
    end block

    ! ---------------------------------------------------------------- same step control as core
    block
        type(constrained_ode) :: f
        type(ode_options) :: oo
        type(ode_result) :: orr
        integer :: meth
        real(dp), allocatable :: q0(:), v0(:)
        call make_constrained("double_pendulum_xy", [real(dp) ::], f%mech, info, msg)
        call mech_initial_state("double_pendulum_xy", [real(dp) ::], q0, v0, info)
        do meth = METHOD_DOPRI5, METHOD_DOP853
            oo%method = meth
            oo%rtol = 1.0e-8_dp
            oo%atol = 1.0e-8_dp
            oo%save_steps = .false.
            call ode_solve(f, [0.0_dp, 10.0_dp], [q0, v0], oo, orr)
            opt = constrained_options()
            opt%ode = oo
            opt%projection = PROJ_NONE
            opt%save_steps = .false.
            call constrained_solve(f%mech, [0.0_dp, 10.0_dp], q0, v0, opt, r1)
            call ts%check(r1%naccept == orr%stats%naccept .and. &
                          r1%nreject == orr%stats%nreject .and. r1%nfev == orr%stats%nfev, &
                          "no projection: the same steps and nfev as the core ode_solve")
            call ts%check_less(maxval(abs(r1%q(:, r1%nt) - orr%y(1:4, orr%nt))), 1.0e-12_dp, &
                               "no projection: the same end state as the core ode_solve")
        end do
    end block

    ! ---------------------------------------------------------------- large coordinates
    block
        real(dp) :: ll
        integer :: k
        opt = constrained_options()
        opt%ode%rtol = 1.0e-11_dp
        opt%ode%atol = 1.0e-11_dp
        do k = 1, 2
            ll = 10.0_dp**(2*k)
            call make_constrained("pendulum_xy", [1.0_dp, 9.81_dp, ll], cs, info, msg)
            q = [ll*sin(1.0_dp), -ll*cos(1.0_dp)]
            call constrained_solve(cs, [0.0_dp, 10.0_dp], q, [0.0_dp, 0.0_dp], opt, r1)
            call ts%check(r1%success, "projection converges at round-off for l = 1e"// &
                          achar(48 + 2*k)//": "//r1%message)
            call ts%check_less(maxval(r1%res_pos)/ll**2, 1.0e-14_dp, &
                               "large l: |phi|/l^2 at round-off")
        end do
    end block

    ! gfortran keeps a deferred-length character of the main program on its stack, not in
    ! static storage: free it, or LeakSanitizer reports its last value as leaked
    if (allocated(msg)) deallocate (msg)
    call ts%finish()
end program test_mechanics_defaults
