!> Hill's lunar problem: variation orbit, monodromy, perigee constant, transverse equation.
program test_hill
    use conmech_kinds, only: dp, pi
    use conmech_status
    use conmech_hill
    use conmech_hill_orbit
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    type(hill_orbit) :: orb, orbf
    type(hill_orbit_options) :: opt
    type(hill_transverse_result) :: tr
    real(dp), parameter :: m_hill = 0.080848933808312_dp, c_hill = 1.0715832774160_dp
    ts%name = "test_hill"
    call hill_variation_orbit(m_hill, 1.0_dp, orb)
    call ts%check(orb%info == CM_SUCCESS, "variation orbit converges at Hill's m")
    print *, orb%y0, orb%c, orb%iterations, orb%nfev, orb%stability_index
    call ts%check_close(orb%c, c_hill, 1.0e-12_dp, "c from the 4x4 monodromy (symmetry)")
    opt%full_period = .true.
    call hill_variation_orbit(m_hill, 1.0_dp, orbf, opt)
    call ts%check_close(orbf%c, c_hill, 1.0e-12_dp, "c from the direct 2 pi monodromy")
    print *, maxval(abs(orb%monodromy - orbf%monodromy))
    call hill_transverse(orb, tr)
    print *, tr%c, tr%det
    call ts%check_close(tr%c, c_hill, 1.0e-11_dp, "c from the transverse Hill equation")
    call ts%finish()
end program test_hill
