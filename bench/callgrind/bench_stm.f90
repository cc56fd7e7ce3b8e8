!> Arenstorf orbit, DOP853 rtol = atol = 1e-10, one period per repetition:
!!   bench_stm time            timing ratios in one run: integrate_stm (analytic Jacobian)
!!                             against the hand-written 20-equation system, and the orbit
!!                             alone (4 equations)
!!   bench_stm 4|20|stm|prod|user REPS   REPS periods of one case, for callgrind
!!                             (bench/callgrind.sh); stm: integrate_stm on a user system
!!                             with rhs_jacobian (J formed, generic product); prod: on the
!!                             built-in arenstorf (its own rhs_jacobian_product); user:
!!                             on a user system with rhs_jacobian_product (the
!!                             hand-written system's arithmetic)
!! Run: fpm run --example bench_stm --profile release -- time
program bench_stm
    use conmech
    use bench_arenstorf_systems
    implicit none
    character(len=16) :: arg
    integer :: reps, nargs
    nargs = command_argument_count()
    arg = "time"
    if (nargs >= 1) call get_command_argument(1, arg)
    if (trim(arg) == "time") then
        call timing()
    else
        reps = 1
        if (nargs >= 2) then
            block
                character(len=16) :: a2
                call get_command_argument(2, a2)
                read (a2, *) reps
            end block
        end if
        call run_case(trim(arg), reps)
    end if
contains

    subroutine run_case(which, reps)
        character(len=*), intent(in) :: which
        integer, intent(in) :: reps
        type(arenstorf) :: s4
        type(are_stm) :: s20
        type(are_jac) :: sj
        type(are_prod) :: sp
        type(ode_options) :: opt
        type(ode_stats) :: st
        real(dp) :: y(20), phi(4, 4)
        integer :: r, info, i
        opt%method = METHOD_DOP853; opt%rtol = 1.0e-10_dp; opt%atol = 1.0e-10_dp
        info = 0
        do r = 1, reps
            y = 0.0_dp; y(1:4) = arenstorf_y0
            do i = 0, 3
                y(5 + 5*i) = 1.0_dp
            end do
            select case (which)
            case ("4")
                call ode_integrate(s4, 0.0_dp, arenstorf_period, y(1:4), opt, info, st)
            case ("20")
                call ode_integrate(s20, 0.0_dp, arenstorf_period, y, opt, info, st)
            case ("prod")
                phi = reshape(y(5:20), [4, 4])
                call integrate_stm(s4, 0.0_dp, arenstorf_period, y(1:4), phi, opt, info, &
                                   stats=st)
                y(5:20) = reshape(phi, [16])
            case ("user")
                phi = reshape(y(5:20), [4, 4])
                call integrate_stm(sp, 0.0_dp, arenstorf_period, y(1:4), phi, opt, info, &
                                   stats=st)
                y(5:20) = reshape(phi, [16])
            case default
                phi = reshape(y(5:20), [4, 4])
                call integrate_stm(sj, 0.0_dp, arenstorf_period, y(1:4), phi, opt, info, &
                                   stats=st)
                y(5:20) = reshape(phi, [16])
            end select
        end do
        print '(a,a,a,i0,a,i0,a,es10.2)', "case ", which, " nfev ", st%nfev, " info ", info, &
            " closure ", maxval(abs(y(1:4) - arenstorf_y0))
    end subroutine run_case

    subroutine timing()
        type(are_stm) :: s20
        type(are_jac) :: sj
        type(arenstorf) :: s4
        type(ode_options) :: opt
        type(are_prod) :: su
        type(ode_stats) :: st1, st2, st3, st4
        real(dp) :: y(20), phi(4, 4), yh(20), t_hand, t_stm, t_4, t_prod, t_user, best(5), tt
        real(dp) :: phip(4, 4), phiu(4, 4)
        integer :: rep, round, info, i, nrep
        integer(8) :: c0, c1, rate
        opt%method = METHOD_DOP853; opt%rtol = 1.0e-10_dp; opt%atol = 1.0e-10_dp
        nrep = 100
        best = huge(1.0_dp)
        do round = 1, 7      ! interleaved rounds, best of each: robust on a busy machine
            call system_clock(c0, rate)
            do rep = 1, nrep
                yh = 0.0_dp; yh(1:4) = arenstorf_y0
                do i = 0, 3
                    yh(5 + 5*i) = 1.0_dp
                end do
                call ode_integrate(s20, 0.0_dp, arenstorf_period, yh, opt, info, st1)
            end do
            call system_clock(c1)
            tt = real(c1 - c0, dp)/real(rate, dp)/nrep
            best(1) = min(best(1), tt)
            call system_clock(c0)
            do rep = 1, nrep
                y(1:4) = arenstorf_y0
                phi = 0.0_dp
                do i = 1, 4
                    phi(i, i) = 1.0_dp
                end do
                call integrate_stm(sj, 0.0_dp, arenstorf_period, y(1:4), phi, opt, info, &
                                   stats=st2)
            end do
            call system_clock(c1)
            tt = real(c1 - c0, dp)/real(rate, dp)/nrep
            best(2) = min(best(2), tt)
            call system_clock(c0)
            do rep = 1, nrep
                y(1:4) = arenstorf_y0
                call ode_integrate(s4, 0.0_dp, arenstorf_period, y(1:4), opt, info)
            end do
            call system_clock(c1)
            tt = real(c1 - c0, dp)/real(rate, dp)/nrep
            best(3) = min(best(3), tt)
            call system_clock(c0)
            do rep = 1, nrep
                y(1:4) = arenstorf_y0
                phip = 0.0_dp
                do i = 1, 4
                    phip(i, i) = 1.0_dp
                end do
                call integrate_stm(s4, 0.0_dp, arenstorf_period, y(1:4), phip, opt, info, &
                                   stats=st3)
            end do
            call system_clock(c1)
            tt = real(c1 - c0, dp)/real(rate, dp)/nrep
            best(4) = min(best(4), tt)
            call system_clock(c0)
            do rep = 1, nrep
                y(1:4) = arenstorf_y0
                phiu = 0.0_dp
                do i = 1, 4
                    phiu(i, i) = 1.0_dp
                end do
                call integrate_stm(su, 0.0_dp, arenstorf_period, y(1:4), phiu, opt, info, &
                                   stats=st4)
            end do
            call system_clock(c1)
            tt = real(c1 - c0, dp)/real(rate, dp)/nrep
            best(5) = min(best(5), tt)
        end do
        t_hand = best(1); t_stm = best(2); t_4 = best(3); t_prod = best(4); t_user = best(5)
        print '(a)', "Arenstorf period, DOP853 tol 1e-10 (best of 7 rounds of 100 periods)"
        print '(a,f9.1,a,i0)', "  hand-written 20 equations   us/period ", t_hand*1.0e6_dp, &
            "   nfev ", st1%nfev
        print '(a,f9.1,a,i0)', "  integrate_stm (analytic J)  us/period ", t_stm*1.0e6_dp, &
            "   nfev ", st2%nfev
        print '(a,f9.1,a,i0)', "  integrate_stm (J x product) us/period ", t_prod*1.0e6_dp, &
            "   nfev ", st3%nfev
        print '(a,f9.1,a,i0)', "  integrate_stm (user J x)    us/period ", t_user*1.0e6_dp, &
            "   nfev ", st4%nfev
        print '(a,f9.1)', "  orbit alone (4 equations)   us/period ", t_4*1.0e6_dp
        print '(a,f6.3,a)', "  integrate_stm (analytic J) / hand-written = ", t_stm/t_hand
        print '(a,f6.3,a)', "  integrate_stm (J x product) / hand-written = ", t_prod/t_hand, &
            "   (target <= 1.1)"
        print '(a,f6.3,a)', "  integrate_stm (user J x) / hand-written = ", t_user/t_hand, &
            "   (target <= 1.1)"
        print '(a,3es10.2)', "  STM vs hand-written, relative (J, built-in J x, user J x) ", &
            maxval(abs(reshape(phi, [16]) - yh(5:20)))/maxval(abs(yh(5:20))), &
            maxval(abs(reshape(phip, [16]) - yh(5:20)))/maxval(abs(yh(5:20))), &
            maxval(abs(reshape(phiu, [16]) - yh(5:20)))/maxval(abs(yh(5:20)))
    end subroutine timing

end program bench_stm
