!> A short tour of the stability layer: equilibria of the pendulum, the Lagrange-Dirichlet
!! test, a limit cycle by shooting with its Floquet multipliers, and Mathieu's equation.
!!
!!   fpm run --example stability_tour
program stability_tour
    use conmech
    implicit none
    type(pendulum_theta) :: pend
    type(van_der_pol) :: vdp
    type(equilibrium_result) :: eq
    type(periodic_orbit) :: orbit
    type(hill_result) :: mathieu
    real(dp) :: w(1)
    logical :: stable
    integer :: info, i

    ! equilibria: theta = 0 is a centre, theta = pi a saddle
    call analyze_equilibrium(pend, [0.0_dp, 0.0_dp], eq)
    write (*, '(a, 2f10.5, 2a)') "pendulum at 0:  eigenvalue", eq%wr(1), eq%wi(1), "i  ", &
        classification_name(eq%kind)
    call analyze_equilibrium(pend, [pi, 0.0_dp], eq)
    write (*, '(a, 2f10.5, 2a)') "pendulum at pi: eigenvalue", eq%wr(1), eq%wi(1), "i  ", &
        classification_name(eq%kind)

    ! Lagrange-Dirichlet: V = -(g/l) cos(theta), V'' = (g/l) cos(theta) at theta = 0
    call lagrange_dirichlet(reshape([pend%g/pend%l], [1, 1]), stable, w, info)
    write (*, '(a, l2)') "potential minimum at 0 (Lagrange-Dirichlet):", stable

    ! the Van der Pol limit cycle: period and multipliers (1 and exp(int div f))
    call find_periodic_orbit(vdp, [2.0_dp, 0.0_dp], 6.5_dp, orbit)
    if (orbit%info /= CM_SUCCESS) error stop orbit%message
    write (*, '(a, f18.13)') "Van der Pol (mu = 1) period:", orbit%period
    do i = 1, 2
        write (*, '(a, i0, a, es12.4)') "  multiplier ", i, ":", orbit%floquet%mr(i)
    end do

    ! Mathieu's equation y'' + (a - 2 q cos 2t) y = 0 at a = 1, q = 0.2 (first tongue)
    call hill_solve(mathieu_phi, pi, mathieu)
    write (*, '(a, f10.6, a, l2)') "Mathieu a = 1, q = 0.2: half trace", &
        mathieu%half_trace, ", stable:", mathieu%stable

contains

    function mathieu_phi(t) result(p)
        real(dp), intent(in) :: t
        real(dp) :: p
        p = 1.0_dp - 0.4_dp*cos(2.0_dp*t)
    end function mathieu_phi

end program stability_tour
