!> Cost of one RATTLE step on the built-in pendulum_xy and double_pendulum_xy (no
!! stored steps): wall time per step, for callgrind or gprof profiles.
!!
!!     fpm run --example rattle_step --profile release -- [NSTEPS [1|2]]
!!
!! (the second argument: only pendulum_xy (1) or only double_pendulum_xy (2); for
!! `valgrind --tool=callgrind`, instruction counts per step of one system)
program rattle_step
    use conmech_kinds, only: dp
    use conmech_constrained_system, only: constrained_system
    use conmech_constrained_solver, only: constrained_options, constrained_result
    use conmech_rattle, only: rattle_solve
    use conmech_systems_mech, only: make_constrained
    implicit none
    class(constrained_system), allocatable :: sys
    type(constrained_options) :: opt
    type(constrained_result) :: res
    real(dp), allocatable :: q0(:), v0(:)
    character(len=:), allocatable :: msg
    character(len=32) :: arg
    integer :: nsteps, info, k, only
    integer(8) :: c0, c1, rate
    character(len=20), parameter :: names(2) = [character(len=20) :: "pendulum_xy", &
                                                "double_pendulum_xy"]
    nsteps = 1000000
    if (command_argument_count() >= 1) then
        call get_command_argument(1, arg)
        read (arg, *) nsteps
    end if
    only = 0
    if (command_argument_count() >= 2) then
        call get_command_argument(2, arg)
        read (arg, *) only
    end if
    do k = 1, 2
        if (only /= 0 .and. k /= only) cycle
        call make_constrained(trim(names(k)), [real(dp) ::], sys, info, msg)
        if (k == 1) then
            q0 = [sin(1.0_dp), -cos(1.0_dp)]
            v0 = [0.0_dp, 0.0_dp]
        else
            q0 = [sin(1.0_dp), -cos(1.0_dp), sin(1.0_dp) + 1.0_dp, -cos(1.0_dp)]
            v0 = [0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp]
        end if
        opt%ode%first_step = 0.01_dp
        opt%ode%max_steps = huge(1)
        opt%save_steps = .false.
        call system_clock(c0, rate)
        call rattle_solve(sys, [0.0_dp, 0.01_dp*nsteps], q0, v0, opt, res)
        call system_clock(c1)
        write (*, '(a20, a, i0, a, f8.3, a, i0, a, es10.3, a, es9.2)') names(k), &
            " steps ", res%naccept, " us/step ", &
            1.0e6_dp*real(c1 - c0, dp)/real(rate, dp)/max(res%naccept, 1), &
            " nfev ", res%nfev, " dE ", res%energy(res%nt) - res%energy(1), &
            " res ", max(res%res_pos(res%nt), res%res_vel(res%nt))
    end do
end program rattle_step
