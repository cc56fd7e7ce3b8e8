!> The main job: a short tour of conmech printed to the terminal.
!!   fpm run tour
program tour
    use conmech
    use app_events, only: theta_events
    use app_cli, only: cli_parser
    implicit none
    character(len=*), parameter :: help = "usage: tour [--help] [--version]"//new_line("a")// &
        "A short tour of conmech printed to the terminal: a pendulum's period against the"// &
        new_line("a")//"elliptic integral, a Kepler orbit with two integrators, and Hill's"// &
        " variation orbit"//new_line("a")//"with its perigee constant against Hill's "// &
        "value. It takes no options."//new_line("a")//"Example:"//new_line("a")// &
        "  fpm run tour"
    type(cli_parser) :: cli
    character(len=:), allocatable :: key

    call cli%start("tour", help)
    if (len(cli%input) > 0) call cli%fail("tour takes no --input")
    do while (cli%next(key))
        call cli%unknown()
    end do
    deallocate (key)
    call cli%clear()
    write (*, '(a)') "conmech tour"
    write (*, '(a)') "============"
    call pendulum_part()
    call kepler_part()
    call hill_part()

contains

    !> Complete elliptic integral of the first kind K(k) by the arithmetic-geometric mean.
    pure real(dp) function ellipk(k)
        real(dp), intent(in) :: k
        real(dp) :: a, b, c
        a = 1.0_dp
        b = sqrt(1.0_dp - k**2)
        do
            c = 0.5_dp*(a + b)
            b = sqrt(a*b)
            a = c
            if (abs(a - b) <= 4.0_dp*epsilon(1.0_dp)*a) exit
        end do
        ellipk = pi/(2.0_dp*a)
    end function ellipk

    subroutine pendulum_part()
        type(pendulum_theta) :: sys
        type(ode_options) :: opt
        type(ode_result) :: res
        type(theta_events) :: ev
        real(dp) :: th0, t_exact, t_num, e0, edrift
        th0 = 2.0_dp
        opt%rtol = 1.0e-12_dp
        opt%atol = 1.0e-12_dp
        ev%direction = [1]
        ev%terminal = [.false.]
        call ode_solve(sys, [0.0_dp, 20.0_dp], [th0, 0.0_dp], opt, res, events=ev)
        e0 = sys%energy([th0, 0.0_dp])
        edrift = abs(sys%energy(res%y(:, res%nt)) - e0)/abs(e0)
        t_exact = 4.0_dp*sqrt(sys%l/sys%g)*ellipk(sin(th0/2.0_dp))
        t_num = res%ev_t(res%nev) - res%ev_t(res%nev - 1)
        write (*, '(/,a)') "Pendulum theta'' = -(g/l) sin(theta), theta(0) = 2 rad, " // &
            "DOP853, tol 1e-12"
        write (*, '(a,f18.14)') "  period from events     ", t_num
        write (*, '(a,f18.14)') "  4 sqrt(l/g) K(sin 1)   ", t_exact
        write (*, '(a,es10.2)') "  relative energy drift over t = 20:", edrift
        write (*, '(a,i0,a,i0,a,i0)') "  nfev ", res%stats%nfev, ", accepted ", &
            res%stats%naccept, ", rejected ", res%stats%nreject
    end subroutine pendulum_part

    subroutine kepler_part()
        type(kepler_2d) :: sys
        type(ode_options) :: opt
        type(ode_result) :: res
        real(dp) :: y0(4), e, period
        integer :: m
        e = 0.6_dp
        y0 = [1.0_dp - e, 0.0_dp, 0.0_dp, sqrt((1.0_dp + e)/(1.0_dp - e))]
        period = 2.0_dp*pi
        write (*, '(/,a)') "Kepler orbit, eccentricity 0.6, one period, tol 1e-10"
        write (*, '(a)') "  method   closure error   energy error   angular-momentum error   nfev"
        do m = METHOD_DOPRI5, METHOD_DOP853
            opt%method = m
            opt%rtol = 1.0e-10_dp
            opt%atol = 1.0e-10_dp
            call ode_solve(sys, [0.0_dp, period], y0, opt, res)
            associate (y => res%y(:, res%nt))
                write (*, '(2x,a8,es13.2,es15.2,es22.2,i10)') merge("DOPRI5", "DOP853", &
                    m == METHOD_DOPRI5), maxval(abs(y - y0)), &
                    abs(sys%energy(y) - sys%energy(y0)), &
                    abs(y(1)*y(4) - y(2)*y(3) - (y0(1)*y0(4) - y0(2)*y0(3))), res%stats%nfev
            end associate
        end do
    end subroutine kepler_part

    subroutine hill_part()
        type(hill_orbit) :: orb
        real(dp), parameter :: m_hill = 0.080848933808312_dp
        real(dp), parameter :: c_hill = 1.0715832774160_dp
        integer :: i
        call hill_variation_orbit(m_hill, 1.0_dp, orb)
        write (*, '(/,a)') "Hill's lunar problem, variation orbit at Hill's m = 0.080848933808312"
        if (orb%info /= CM_SUCCESS) then
            write (*, '(a)') "  failed: "//orb%message
            return
        end if
        write (*, '(a,2f20.16)') "  x0, y'0                  ", orb%y0(1), orb%y0(4)
        write (*, '(a,f20.16)') "  Jacobi constant          ", orb%jacobi
        write (*, '(a)') "  Floquet multipliers of the monodromy matrix (the pair at 1 is " // &
            "the trivial"
        write (*, '(a)') "  Jordan block, accurate only to ~sqrt(eps); stability is read " // &
            "from the trace):"
        do i = 1, 4
            write (*, '(4x,f19.15,sp,f19.15,"i")') orb%mr(i), orb%mi(i)
        end do
        write (*, '(a,f20.16)') "  stability index S        ", orb%stability_index
        write (*, '(a,f20.16)') "  perigee constant c       ", orb%c
        write (*, '(a,f17.13,a,es9.2)') "  Hill (1877)              ", c_hill, &
            "   difference", abs(orb%c - c_hill)
        write (*, '(a,i0,a,i0)') "  Newton iterations ", orb%iterations, ", nfev ", orb%nfev
    end subroutine hill_part

end program tour
