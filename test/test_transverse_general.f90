!> The transverse linearisation of any periodic orbit (conmech_transverse_general): the
!! double pendulum in angles (generalized coordinates, energy removed) and in Cartesian
!! coordinates with two rod constraints (excessive coordinates, constraint manifold and
!! energy removed) give the same two multipliers, equal to the non-trivial ones of the full
!! monodromy; the frame is periodic and orthonormal; a non-periodic orbit is refused.
program test_transverse_general
    use conmech
    use conmech_testing
    use conmech_transverse_model, only: transverse_model
    use conmech_transverse_mech, only: generalized_model, constrained_model, constrained_index1
    use conmech_transverse_general
    use conmech_rotation_log, only: rotation_log, rotation_log_init
    implicit none
    type(test_suite) :: ts
    real(dp) :: y0(4), period
    complex(dp) :: mu_angles(2)

    ts%name = "test_transverse_general"
    call test_rotation_log()
    call find_orbit(y0, period)
    call test_angles(y0, period, mu_angles)
    call test_cartesian(y0, period, mu_angles)
    call test_bad_orbit(y0, period)
    call ts%finish()

contains

    !> R^s R^(1-s) = R and R^1 = R for a random rotation in SO(5) (exp of a skew matrix).
    subroutine test_rotation_log()
        type(rotation_log) :: rl
        real(dp) :: s(5, 5), r(5, 5), e1(5, 5), e2(5, 5), p(5, 5), term(5, 5)
        integer :: info, j, i
        character(len=:), allocatable :: msg
        s = 0.0_dp
        do j = 1, 5
            do i = 1, j - 1
                s(i, j) = 0.3_dp*sin(real(7*i + 3*j, dp))
                s(j, i) = -s(i, j)
            end do
        end do
        ! r = exp(s) by its Taylor series (|s| < 1: 30 terms are exact to round-off)
        r = 0.0_dp
        term = 0.0_dp
        do j = 1, 5
            r(j, j) = 1.0_dp
            term(j, j) = 1.0_dp
        end do
        do j = 1, 30
            term = matmul(term, s)/j
            r = r + term
        end do
        call rotation_log_init(r, rl, info, msg)
        call ts%check(info == CM_SUCCESS, "rotation_log of a rotation in SO(5)")
        call rl%power(1.0_dp, e1)
        call ts%check_less(maxval(abs(e1 - r)), 1.0e-14_dp, "R^1 = R")
        call rl%power(0.3_dp, e1)
        call rl%power(0.7_dp, e2)
        call ts%check_less(maxval(abs(matmul(e1, e2) - r)), 1.0e-14_dp, "R^0.3 R^0.7 = R")
        call rl%generator(p)
        call ts%check_less(maxval(abs(p + transpose(p))), 1.0e-14_dp, "log R is skew")
        call ts%check_less(maxval(abs(p - s)), 1.0e-13_dp, "log exp(S) = S (|S| < pi)")
    end subroutine test_rotation_log

    !> The double pendulum's slow normal-mode orbit through th1 = 0.6 at rest.
    subroutine find_orbit(y0, period)
        real(dp), intent(out) :: y0(4), period
        class(ode_system), allocatable :: sys
        type(periodic_orbit) :: po
        type(shooting_options) :: so
        integer :: info
        character(len=:), allocatable :: msg
        real(dp) :: w
        call make_system("double_pendulum", [1.0_dp, 1.0_dp, 1.0_dp, 1.0_dp, 9.81_dp], sys, &
                         info, msg)
        w = sqrt(9.81_dp*(2.0_dp - sqrt(2.0_dp)))
        call find_symmetric_orbit(sys, [0.6_dp, sqrt(2.0_dp)*0.6_dp, 0.0_dp, 0.0_dp], [2], &
                                  acos(-1.0_dp)/w, [3, 4], po, so, free_time=.true.)
        call ts%check(po%info == CM_SUCCESS, "double pendulum orbit found")
        y0 = po%y0
        period = po%period
    end subroutine find_orbit

    subroutine test_angles(y0, period, mu)
        real(dp), intent(in) :: y0(4), period
        complex(dp), intent(out) :: mu(2)
        type(generalized_ode) :: sys
        type(generalized_model) :: model
        type(transverse_options) :: opt
        type(transverse_frame) :: fr
        real(dp) :: x(4), qp(4, 2), ap(2, 2), bp(2, 1), x0(4), qp0(4, 2), ap0(2, 2)
        complex(dp) :: full(4), nt(2)
        integer :: info
        character(len=:), allocatable :: msg
        call make_generalized("double_pendulum", [1.0_dp, 1.0_dp, 1.0_dp, 1.0_dp, 9.81_dp], &
                              sys%mech, info, msg)
        allocate (model%mech, source=sys%mech)
        call transverse_build(sys, model, y0, period, opt, fr)
        call ts%check(fr%info == CM_SUCCESS .and. fr%k == 2 .and. fr%reduced, &
                      "angles: k = 2 with the energy removed")
        mu = cmplx(fr%mr, fr%mi, dp)
        full = cmplx(fr%fr, fr%fi, dp)
        nt = nontrivial(full, mu)
        call ts%check_less(maxval(abs(nt - mu)), 1.0e-10_dp, "angles: transverse = full "// &
                           "non-trivial multipliers")
        call ts%check_less(abs(abs(mu(1)) - 1.0_dp), 1.0e-10_dp, "angles: |mu| = 1 (elliptic)")
        call transverse_eval(fr, 0.0_dp, x0, qp0, ap0, bp, info)
        ! just below T: the transported frame Q(T) R^(-1) returns to Q(0)
        call transverse_eval(fr, period*(1.0_dp - 1.0e-13_dp), x, qp, ap, bp, info)
        call ts%check_less(maxval(abs(qp - qp0)) + maxval(abs(ap - ap0))/maxval(abs(ap0)), &
                           1.0e-9_dp, "angles: frame and A_perp periodic")
        call transverse_eval(fr, 0.37_dp*period, x, qp, ap, bp, info)
        call ts%check_less(maxval(abs(matmul(transpose(qp), qp) - &
                                      reshape([1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2]))), &
                           1.0e-10_dp, "angles: frame orthonormal")
    end subroutine test_angles

    subroutine test_cartesian(y0, period, mu_angles)
        real(dp), intent(in) :: y0(4), period
        complex(dp), intent(in) :: mu_angles(2)
        type(constrained_index1) :: sys
        type(constrained_model) :: model
        type(transverse_options) :: opt
        type(transverse_frame) :: fr
        real(dp) :: z(8), a, b, va, vb
        complex(dp) :: mu(2), full(8), nt(2)
        integer :: info
        character(len=:), allocatable :: msg
        call make_constrained("double_pendulum_xy", [1.0_dp, 1.0_dp, 1.0_dp, 1.0_dp, 9.81_dp], &
                              sys%mech, info, msg)
        allocate (model%mech, source=sys%mech)
        a = y0(1)
        b = y0(2)
        va = y0(3)
        vb = y0(4)
        z = [sin(a), -cos(a), sin(a) + sin(b), -cos(a) - cos(b), cos(a)*va, sin(a)*va, &
             cos(a)*va + cos(b)*vb, sin(a)*va + sin(b)*vb]
        call transverse_build(sys, model, z, period, opt, fr)
        call ts%check(fr%info == CM_SUCCESS .and. fr%k == 2 .and. fr%nc == 4, &
                      "Cartesian: 8 - 1 - 4 - 1 = 2 transverse coordinates")
        mu = cmplx(fr%mr, fr%mi, dp)
        full = cmplx(fr%fr, fr%fi, dp)
        nt = nontrivial(full, mu)
        call ts%check_less(maxval(abs(nt - mu)), 1.0e-10_dp, "Cartesian: transverse = full "// &
                           "non-trivial multipliers")
        call ts%check_less(minval(abs(mu(1) - mu_angles)) + minval(abs(mu(2) - mu_angles)), &
                           1.0e-10_dp, "Cartesian multipliers = those in angles")
    end subroutine test_cartesian

    subroutine test_bad_orbit(y0, period)
        real(dp), intent(in) :: y0(4), period
        type(generalized_ode) :: sys
        type(generalized_model) :: model
        type(transverse_options) :: opt
        type(transverse_frame) :: fr
        integer :: info
        character(len=:), allocatable :: msg
        call make_generalized("double_pendulum", [1.0_dp, 1.0_dp, 1.0_dp, 1.0_dp, 9.81_dp], &
                              sys%mech, info, msg)
        allocate (model%mech, source=sys%mech)
        call transverse_build(sys, model, y0, 0.8_dp*period, opt, fr)
        call ts%check(fr%info == CM_BAD_INPUT .and. index(fr%message, "not periodic") > 0, &
                      "a non-periodic orbit is refused: "//fr%message)
        opt%energy = ENERGY_REQUIRED
        call transverse_build(sys, transverse_model(), y0, period, opt, fr)
        call ts%check(fr%info == CM_BAD_INPUT .and. index(fr%message, "no energy") > 0, &
                      "energy required without one: "//fr%message)
    end subroutine test_bad_orbit

    !> The entries of `full` nearest to each of `mu` (each used once).
    function nontrivial(full, mu) result(nt)
        complex(dp), intent(in) :: full(:), mu(:)
        complex(dp) :: nt(size(mu))
        logical :: used(size(full))
        integer :: i, j, jb
        used = .false.
        do i = 1, size(mu)
            jb = 0
            do j = 1, size(full)
                if (used(j)) cycle
                if (jb == 0) then
                    jb = j
                else if (abs(full(j) - mu(i)) < abs(full(jb) - mu(i))) then
                    jb = j
                end if
            end do
            used(jb) = .true.
            nt(i) = full(jb)
        end do
    end function nontrivial

end program test_transverse_general
