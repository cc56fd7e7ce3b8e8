!> Cost per step of a chain of N Cartesian pendulums (pendulum_chain_xy) with position +
!! velocity projection, N = 16 .. 128: the banded path (diagonal mass, tridiagonal-band
!! Schur complement by dpbtrf/dpbtrs) against the dense path of the same system (the
!! general code: Cholesky of M and dense S = C M^-1 C^T with pivoted Cholesky, per
!! evaluation), in one run.
!!
!!     fpm run --profile release --example bench_chain [-- --quick]
!!
!! Prints a Markdown table: steps, CPU time per step (best of 3), the growth exponent
!! between successive N, and the largest residuals max|phi|, max|G v| over the run.
!! A second table: the N-trailer (conmech_systems_trailer: N - 1 rods and N - 1 knife
!! edges, the Pfaffian rows interleaved with the holonomic ones), banded vs dense.
program bench_chain
    use conmech
    use conmech_systems_trailer, only: trailer_chain, trailer_chain_of, trailer_initial_state
    implicit none
    integer, parameter :: ns(4) = [16, 32, 64, 128]
    real(dp) :: tb(size(ns)), td(size(ns)), rb(size(ns)), rd(size(ns))
    integer :: sb(size(ns)), sd(size(ns)), i, nrep
    character(len=32) :: arg
    logical :: quick

    quick = .false.
    if (command_argument_count() >= 1) then
        call get_command_argument(1, arg)
        quick = trim(arg) == "--quick"
    end if
    nrep = 3
    if (quick) nrep = 1
    do i = 1, size(ns)
        call run(ns(i), .true., merge(0.5_dp, 5.0_dp, quick), tb(i), sb(i), rb(i))
        call run(ns(i), .false., merge(0.02_dp, merge(0.5_dp, 0.1_dp, ns(i) <= 32), quick), &
                 td(i), sd(i), rd(i))
    end do
    call table()
    write (*, '(a)') ""
    write (*, '(a)') "N-trailer (N - 1 rods + N - 1 knife edges, Pfaffian rows banded):"
    do i = 1, size(ns)
        call run(ns(i), .true., merge(2.0_dp, 20.0_dp, quick), tb(i), sb(i), rb(i), .true.)
        call run(ns(i), .false., merge(0.02_dp, merge(0.5_dp, 0.1_dp, ns(i) <= 32), quick), &
                 td(i), sd(i), rd(i), .true.)
    end do
    call table()

contains

    subroutine table()
        integer :: i

    write (*, '(a)') "| N | banded: steps | us/step | exponent | max residual | "// &
        "dense: steps | us/step | exponent | max residual | dense/banded |"
    write (*, '(a)') "|---|---|---|---|---|---|---|---|---|---|"
    do i = 1, size(ns)
        if (i == 1) then
            write (*, '(a,i0,a,i0,a,f0.2,a,es9.2,a,i0,a,f0.1,a,es9.2,a,f0.1,a)') "| ", ns(i), &
                " | ", sb(i), " | ", 1.0e6_dp*tb(i), " | | ", rb(i), " | ", sd(i), " | ", &
                1.0e6_dp*td(i), " | | ", rd(i), " | ", td(i)/tb(i), " |"
        else
            write (*, '(a,i0,a,i0,a,f0.2,a,f0.2,a,es9.2,a,i0,a,f0.1,a,f0.2,a,es9.2,a,f0.1,a)') &
                "| ", ns(i), " | ", sb(i), " | ", 1.0e6_dp*tb(i), " | ", &
                log(tb(i)/tb(i - 1))/log(2.0_dp), " | ", rb(i), " | ", sd(i), " | ", &
                1.0e6_dp*td(i), " | ", log(td(i)/td(i - 1))/log(2.0_dp), " | ", rd(i), &
                " | ", td(i)/tb(i), " |"
        end if
    end do
    write (*, '(a,f0.2,a,f0.2)') "Banded: growth exponent from N = 16 to 128: ", &
        log(tb(size(ns))/tb(1))/log(8.0_dp), "; dense: ", log(td(size(ns))/td(1))/log(8.0_dp)
    end subroutine table

    !> Best CPU time per accepted step over nrep runs on [0, tend] (DOP853, 1e-8).
    subroutine run(nl, banded, tend, per_step, steps, resid, trailer)
        integer, intent(in) :: nl
        logical, intent(in) :: banded
        real(dp), intent(in) :: tend
        logical, intent(in), optional :: trailer
        real(dp), intent(out) :: per_step, resid
        integer, intent(out) :: steps
        class(constrained_system), allocatable :: cs
        type(constrained_options) :: opt
        type(constrained_result) :: res
        real(dp), allocatable :: q0(:), v0(:)
        real(dp) :: c0, c1
        integer :: info, rep
        character(len=:), allocatable :: msg
        if (present(trailer)) then
            allocate (cs, source=trailer_chain_of(nl))
            call trailer_initial_state(nl, 1.0_dp, q0, v0)
        else
            call make_constrained("pendulum_chain_xy", [real(nl, dp)], cs, info, msg)
            call mech_initial_state("pendulum_chain_xy", [real(nl, dp)], q0, v0, info)
        end if
        if (.not. banded) then
            cs%diagonal_mass = .false.
            cs%jac_width = 0
            cs%nh_width = 0
        end if
        opt%ode%method = METHOD_DOP853
        opt%ode%rtol = 1.0e-8_dp
        opt%ode%atol = 1.0e-8_dp
        opt%ode%max_steps = 10000000
        opt%projection = PROJ_POSITION_VELOCITY
        opt%save_steps = .true.
        per_step = huge(1.0_dp)
        do rep = 1, nrep
            call cpu_time(c0)
            call constrained_solve(cs, [0.0_dp, tend], q0, v0, opt, res)
            call cpu_time(c1)
            if (.not. res%success) then
                write (*, '(a)') "run failed: "//res%message
                per_step = -1.0_dp
                return
            end if
            per_step = min(per_step, (c1 - c0)/res%naccept)
        end do
        steps = res%naccept
        resid = max(maxval(res%res_pos), maxval(res%res_vel))
    end subroutine run

end program bench_chain
