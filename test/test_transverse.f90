!> Transverse linearisation of any planar natural (+ gyroscopic) system: the multipliers of
!! the 2 x 2 Hill's equation N'' + Phi N = 0 equal the non-trivial multipliers of the 4 x 4
!! monodromy, on a loop orbit of the Henon-Heiles potential and on Hill's variation orbit.
module transverse_test_systems
    use conmech
    implicit none
    private
    public :: henon_heiles, hill_natural

    !> V = (x^2 + y^2)/2 + x^2 y - y^3/3 (Henon and Heiles 1964), Omega = 0.
    type, extends(planar_natural_system) :: henon_heiles
    contains
        procedure :: potential => hh_potential
    end type henon_heiles

    !> Hill's problem as a natural system in the rotating frame: V = -F, Omega = -m.
    type, extends(planar_natural_system) :: hill_natural
        real(dp) :: m = 0.080848933808312_dp
    contains
        procedure :: potential => hn_potential
    end type hill_natural

contains

    subroutine hh_potential(self, q, v, g, h)
        class(henon_heiles), intent(in) :: self
        real(dp), intent(in) :: q(2)
        real(dp), intent(out) :: v, g(2), h(2, 2)
        v = 0.5_dp*(q(1)**2 + q(2)**2) + q(1)**2*q(2) - q(2)**3/3.0_dp
        g = [q(1) + 2.0_dp*q(1)*q(2), q(2) + q(1)**2 - q(2)**2]
        h = reshape([1.0_dp + 2.0_dp*q(2), 2.0_dp*q(1), 2.0_dp*q(1), 1.0_dp - 2.0_dp*q(2)], &
                    [2, 2])
    end subroutine hh_potential

    subroutine hn_potential(self, q, v, g, h)
        class(hill_natural), intent(in) :: self
        real(dp), intent(in) :: q(2)
        real(dp), intent(out) :: v, g(2), h(2, 2)
        real(dp) :: fx, fy, fxx, fxy, fyy
        v = -(1.0_dp/norm2(q) + 1.5_dp*self%m**2*q(1)**2)
        call hill_grad_f(self%m, 1.0_dp, q(1), q(2), fx, fy)
        call hill_hess_f(self%m, 1.0_dp, q(1), q(2), fxx, fxy, fyy)
        g = -[fx, fy]
        h = -reshape([fxx, fxy, fxy, fyy], [2, 2])
    end subroutine hn_potential

end module transverse_test_systems

program test_transverse
    use conmech
    use conmech_testing
    use transverse_test_systems
    implicit none
    type(test_suite) :: ts
    real(dp), parameter :: m_hill = 0.080848933808312_dp

    ts%name = "test_transverse"
    call test_henon_heiles()
    call test_hill()
    call ts%finish()

contains

    !> The 2 x 2 multipliers against the non-trivial pair of the 4 x 4 monodromy: the
    !! half trace of the 2 x 2 equals S = (trace M - 2)/2.
    subroutine compare(sys, y0, period, what, s_ref)
        class(planar_natural_system), intent(inout) :: sys
        real(dp), intent(in) :: y0(4), period
        character(len=*), intent(in) :: what
        real(dp), intent(in), optional :: s_ref   !! S of the 4 x 4 by another method
        type(transverse_result) :: tr
        type(ode_options) :: oo
        real(dp) :: y(4), phi(4, 4), s
        integer :: info, j
        call transverse_monodromy(sys, y0, period, tr, rtol=1.0e-14_dp)
        call ts%check(tr%info == CM_SUCCESS, what//": transverse integration")
        oo%method = METHOD_VERNER98
        oo%rtol = 1.0e-14_dp
        oo%atol = 1.0e-14_dp
        y = y0
        phi = 0.0_dp
        do j = 1, 4
            phi(j, j) = 1.0_dp
        end do
        call integrate_stm(sys, 0.0_dp, period, y, phi, oo, info)
        s = 0.5_dp*(phi(1, 1) + phi(2, 2) + phi(3, 3) + phi(4, 4) - 2.0_dp)
        if (present(s_ref)) s = s_ref
        call ts%check_close(tr%half_trace, s, 1.0e-12_dp, what//": 2x2 half trace = S of 4x4")
        call ts%check_close(tr%det, 1.0_dp, 1.0e-12_dp, what//": det of the 2x2 = 1")
        write (*, '(a, 3es24.15)') "  "//what//": S(4x4), half trace(2x2), closure", s, &
            tr%half_trace, tr%closure
    end subroutine compare

    subroutine test_henon_heiles()
        type(henon_heiles) :: hh
        type(periodic_orbit) :: po
        type(shooting_options) :: so
        so%rtol = 1.0e-13_dp
        so%atol = 1.0e-13_dp
        ! a loop orbit symmetric about the y axis (x = 0, y' = 0 at t = 0 and T/2) with the
        ! period fixed at 1.97 pi (isolated at a fixed period; energy 0.05)
        call find_symmetric_orbit(hh, [0.0_dp, 0.2_dp, 0.25_dp, 0.0_dp], [2, 3], &
                                  0.985_dp*acos(-1.0_dp), [1, 4], po, so)
        call ts%check(po%info == CM_SUCCESS, "Henon-Heiles loop orbit found")
        if (po%info /= CM_SUCCESS) return
        call ts%check(abs(po%y0(3)) > 0.1_dp .and. abs(hh%energy(po%y0) - 0.05_dp) < 1.0e-3_dp, &
                      "the loop orbit (|x'(0)| > 0, E ~ 0.05)")
        write (*, '(a, 4f12.8, a, f10.6)') "  HH orbit y0 =", po%y0, "  E =", hh%energy(po%y0)
        call compare(hh, po%y0, po%period, "Henon-Heiles")
    end subroutine test_henon_heiles

    subroutine test_hill()
        type(hill_natural) :: hn
        type(hill_orbit) :: orb
        type(hill_transverse_result) :: htr
        hn%m = m_hill
        hn%omega = -m_hill
        call hill_variation_orbit(m_hill, 1.0_dp, orb)
        ! the 4 x 4 by symmetry from the quarter-period STM (the fast path): S of an adaptive
        ! full-period STM from the same start is 1.3e-12 off, as S is sensitive to the start
        ! (dS/du ~ 1e3 through the Jordan block), the 2 x 2 equation is not
        call compare(hn, orb%y0, orb%period, "Hill", orb%stability_index)
        ! the general construction reproduces Hill's own (seed 000) transverse equation
        call hill_transverse(orb, htr, rtol=1.0e-14_dp)
        block
            type(transverse_result) :: tr
            call transverse_monodromy(hn, orb%y0, orb%period, tr, rtol=1.0e-14_dp)
            call ts%check(maxval(abs(tr%monodromy - htr%monodromy)) < 1.0e-11_dp, &
                          "general = Hill-specific transverse monodromy")
        end block
    end subroutine test_hill

end program test_transverse
