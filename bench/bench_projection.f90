!> Cost of projection and residual vs work for the constrained integrators.
!!
!! `fpm run --example bench_projection [-- --quick]` times DOP853 on the Cartesian pendulum
!! and double pendulum without projection (plain index-1 form), with Baumgarte, velocity
!! projection and position + velocity projection, and prints a Markdown report: time per
!! step, ratios to the unprojected run measured in the same process, right-hand side
!! evaluations, and the final residuals for a range of tolerances (residual vs work).
program bench_projection
    use conmech
    implicit none
    integer, parameter :: nproj = 4
    integer, parameter :: kinds(nproj) = [PROJ_NONE, PROJ_BAUMGARTE, PROJ_VELOCITY, &
                                          PROJ_POSITION_VELOCITY]
    character(len=*), parameter :: names(nproj) = [character(len=17) :: "none", &
                                                   "baumgarte", "velocity", "position+velocity"]
    character(len=*), parameter :: systems(2) = [character(len=18) :: "pendulum_xy", &
                                                 "double_pendulum_xy"]
    real(dp) :: tend, tol(4)
    integer :: isys, jp, it, nrep
    character(len=32) :: arg
    logical :: quick

    quick = .false.
    if (command_argument_count() >= 1) then
        call get_command_argument(1, arg)
        quick = trim(arg) == "--quick"
    end if
    tend = 1000.0_dp
    nrep = 3
    if (quick) then
        tend = 100.0_dp
        nrep = 1
    end if
    tol = [1.0e-6_dp, 1.0e-8_dp, 1.0e-10_dp, 1.0e-12_dp]

    write (*, '(a)') "# Cost of projection (DOP853)"
    write (*, '(a)') ""
    write (*, '(a,f0.0,a,i0,a)') "t in [0, ", tend, "], gfortran (fpm --profile release), "// &
        "one core; CPU time per step = best of ", 2*nrep + 1, " interleaved rounds (each "// &
        "round runs "// &
        "every stabilisation once). Ratios are to the unprojected DOP853 of the core "// &
        "integrator (ode_solve on the index-1 form), measured in the same process; 'none' "// &
        "is constrained_solve without projection (ode_solve with the diagnostics at the "// &
        "outputs)."
    do isys = 1, 2
        write (*, '(a)') ""
        write (*, '(a)') "## "//trim(systems(isys))//": time per step at rtol = atol = 1e-10"
        write (*, '(a)') ""
        write (*, '(a)') "| stabilisation | steps | nfev | us/step | ratio | max |phi| | "// &
            "max |G v| |"
        write (*, '(a)') "|---|---|---|---|---|---|---|"
        call time_table(trim(systems(isys)), 1.0e-10_dp)
        write (*, '(a)') ""
        write (*, '(a)') "## "//trim(systems(isys))//": residual vs work"
        write (*, '(a)') ""
        write (*, '(a)') "| stabilisation | tol | nfev | time [ms] | final |phi| | final |G v| |"
        write (*, '(a)') "|---|---|---|---|---|---|"
        do jp = 1, nproj
            do it = 1, size(tol)
                call work_row(trim(systems(isys)), jp, tol(it))
            end do
        end do
    end do

contains

    subroutine run(name, jp, rtol, res, secs, nrun)
        character(len=*), intent(in) :: name
        integer, intent(in) :: jp, nrun
        real(dp), intent(in) :: rtol
        type(constrained_result), intent(out) :: res
        real(dp), intent(out) :: secs
        class(constrained_system), allocatable :: cs
        type(constrained_options) :: opt
        real(dp), allocatable :: q0(:), v0(:)
        integer :: info, rep
        real(dp) :: c0, c1
        character(len=:), allocatable :: msg
        call make_constrained(name, [real(dp) ::], cs, info, msg)
        call mech_initial_state(name, [real(dp) ::], q0, v0, info)
        opt%ode%method = METHOD_DOP853
        opt%ode%rtol = rtol
        opt%ode%atol = rtol
        opt%ode%max_steps = 10000000
        opt%projection = kinds(jp)
        opt%save_steps = .false.
        secs = huge(1.0_dp)
        do rep = 1, nrun
            call cpu_time(c0)
            call constrained_solve(cs, [0.0_dp, tend], q0, v0, opt, res)
            call cpu_time(c1)
            secs = min(secs, c1 - c0)
        end do
    end subroutine run

    !> Interleaved timing: every round runs each stabilisation once; best round kept.
    subroutine time_table(name, rtol)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: rtol
        type(constrained_result) :: res(nproj)
        real(dp) :: secs, best(nproj), base
        integer :: jp, round
        best = huge(1.0_dp)
        do round = 1, 2*nrep + 1
            do jp = 1, nproj
                call run(name, jp, rtol, res(jp), secs, 1)
                best(jp) = min(best(jp), secs/res(jp)%naccept)
            end do
        end do
        call core_row(name, rtol, base)
        do jp = 1, nproj
            write (*, '(a,i0,a,i0,a,f0.3,a,f0.2,a,es9.2,a,es9.2,a)') "| "//trim(names(jp))// &
                " | ", res(jp)%naccept, " | ", res(jp)%nfev, " | ", 1.0e6_dp*best(jp), " | ", &
                best(jp)/base, " | ", maxval(res(jp)%res_pos), " | ", &
                maxval(res(jp)%res_vel), " |"
        end do
    end subroutine time_table

    !> Reference: the core `ode_solve` (DOP853) on the same index-1 first-order system.
    subroutine core_row(name, rtol, best)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: rtol
        real(dp), intent(out) :: best
        type(constrained_ode) :: f
        type(ode_options) :: opt
        type(ode_result) :: res
        real(dp), allocatable :: q0(:), v0(:)
        real(dp) :: c0, c1
        integer :: info, rep
        character(len=:), allocatable :: msg
        call make_constrained(name, [real(dp) ::], f%mech, info, msg)
        call mech_initial_state(name, [real(dp) ::], q0, v0, info)
        opt%method = METHOD_DOP853
        opt%rtol = rtol
        opt%atol = rtol
        opt%max_steps = 10000000
        opt%save_steps = .false.
        best = huge(1.0_dp)
        do rep = 1, 2*nrep + 1
            call cpu_time(c0)
            call ode_solve(f, [0.0_dp, tend], [q0, v0], opt, res)
            call cpu_time(c1)
            best = min(best, (c1 - c0)/res%stats%naccept)
        end do
        write (*, '(a,i0,a,i0,a,f0.3,a,f0.2,a)') "| (core ode_solve, index-1) | ", &
            res%stats%naccept, " | ", res%stats%nfev, " | ", 1.0e6_dp*best, " | 1.00 | | |"
    end subroutine core_row

    subroutine work_row(name, jp, rtol)
        character(len=*), intent(in) :: name
        integer, intent(in) :: jp
        real(dp), intent(in) :: rtol
        type(constrained_result) :: res
        real(dp) :: secs
        call run(name, jp, rtol, res, secs, nrep)
        write (*, '(a,es8.1,a,i0,a,f0.2,a,es9.2,a,es9.2,a)') "| "//trim(names(jp))//" | ", &
            rtol, " | ", res%nfev, " | ", 1.0e3_dp*secs, " | ", res%res_pos(res%nt), " | ", &
            res%res_vel(res%nt), " |"
    end subroutine work_row

end program bench_projection
