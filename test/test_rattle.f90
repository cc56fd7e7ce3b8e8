!> RATTLE through rattle_solve: constraints at round-off, bounded energy, second order,
!! bad input.
program test_rattle
    use conmech
    use conmech_rattle, only: rattle_solve
    use conmech_testing, only: test_suite
    implicit none
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
