!> Hill's-equation solver against Mathieu's equation y'' + (a - 2 q cos 2t) y = 0.
!! Reference boundaries from an independent method: the characteristic values a_r(q), b_r(q)
!! are eigenvalues of the symmetric tridiagonal Fourier (Hill-determinant) matrices
!! (LAPACK dsyev), e.g. even pi-periodic: diag (2r)^2, off-diagonal q (sqrt(2) q first).
program test_stability_mathieu
    use conmech_kinds, only: dp, pi
    use conmech_status
    use conmech_lapack, only: la_sym_eig
    use conmech_floquet
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    real(dp) :: a_par, q_par
    real(dp) :: a0, b1, a1, b2, a2
    type(hill_result) :: r
    real(dp), parameter :: del = 1.0e-5_dp
    ts%name = "test_stability_mathieu"

    q_par = 1.0_dp
    call characteristic(q_par, a0, b1, a1, b2, a2)
    ! tabulated values (Abramowitz-Stegun 20.1) for q = 1 as a check of the reference
    call ts%check_close(a0, -0.4551386041_dp, 1.0e-9_dp, "reference a0(1)")
    call ts%check_close(b1, -0.1102488170_dp, 1.0e-9_dp, "reference b1(1)")
    call ts%check_close(a1, 1.8591080725_dp, 1.0e-9_dp, "reference a1(1)")

    call boundary(a0, +1.0_dp, .false., .true., "a0")   ! unstable below a0, stable above
    call boundary(b1, -1.0_dp, .true., .false., "b1")   ! stable below b1, unstable above
    call boundary(a1, -1.0_dp, .false., .true., "a1")   ! unstable tongue (b1, a1)
    call boundary(b2, +1.0_dp, .true., .false., "b2")
    call boundary(a2, +1.0_dp, .false., .true., "a2")

    ! q = 0: y'' + a y = 0, half trace cos(sqrt(a) pi) exactly
    q_par = 0.0_dp
    a_par = 2.3_dp
    call hill_solve(mathieu_phi, pi, r)
    call ts%check_close(r%half_trace, cos(sqrt(2.3_dp)*pi), 1.0e-10_dp, "q = 0 half trace")
    call ts%check_close(r%det, 1.0_dp, 1.0e-10_dp, "det M = 1 (Liouville)")

    ! coefficient given by samples: same monodromy as the function
    q_par = 3.0_dp
    a_par = 4.0_dp
    call samples_vs_function()

    ! bad input
    call hill_solve(mathieu_phi, -1.0_dp, r)
    call ts%check(r%info == CM_BAD_INPUT, "negative period: bad input")
    call hill_solve_samples([1.0_dp, 2.0_dp], pi, r)
    call ts%check(r%info == CM_BAD_INPUT, "two samples: bad input")
    call ts%finish()

contains

    function mathieu_phi(t) result(p)
        real(dp), intent(in) :: t
        real(dp) :: p
        p = a_par - 2.0_dp*q_par*cos(2.0_dp*t)
    end function mathieu_phi

    !> At the boundary the half trace over pi is `edge` (+1 pi-periodic, -1 2pi-periodic);
    !! on each side the stability is as given.
    subroutine boundary(ab, edge, stable_below, stable_above, name)
        real(dp), intent(in) :: ab, edge
        logical, intent(in) :: stable_below, stable_above
        character(len=*), intent(in) :: name
        a_par = ab
        call hill_solve(mathieu_phi, pi, r, rtol=1.0e-13_dp)
        call ts%check_close(r%half_trace, edge, 1.0e-9_dp, name//": half trace at the boundary")
        a_par = ab - del
        call hill_solve(mathieu_phi, pi, r)
        call ts%check(r%stable .eqv. stable_below, name//": stability just below")
        a_par = ab + del
        call hill_solve(mathieu_phi, pi, r)
        call ts%check(r%stable .eqv. stable_above, name//": stability just above")
    end subroutine boundary

    subroutine samples_vs_function()
        type(hill_result) :: rf, rs
        real(dp) :: p(32)
        integer :: j
        call hill_solve(mathieu_phi, pi, rf)
        do j = 1, 32
            p(j) = mathieu_phi(pi*real(j - 1, dp)/32.0_dp)
        end do
        call hill_solve_samples(p, pi, rs)
        call ts%check_less(maxval(abs(rf%monodromy - rs%monodromy)), 1.0e-9_dp, &
                           "samples (trigonometric interpolation) = function")
    end subroutine samples_vs_function

    !> a0, b1, a1, b2, a2 of Mathieu's equation at q from truncated Fourier matrices.
    subroutine characteristic(q, a0, b1, a1, b2, a2)
        real(dp), intent(in) :: q
        real(dp), intent(out) :: a0, b1, a1, b2, a2
        integer, parameter :: nt = 40
        real(dp) :: m(nt, nt), w(nt)
        integer :: r, info
        ! even, period pi: cos(2 r t), r = 0..nt-1
        m = 0.0_dp
        do r = 0, nt - 1
            m(r + 1, r + 1) = (2.0_dp*r)**2
            if (r < nt - 1) then
                m(r + 1, r + 2) = q
                m(r + 2, r + 1) = q
            end if
        end do
        m(1, 2) = sqrt(2.0_dp)*q
        m(2, 1) = sqrt(2.0_dp)*q
        call la_sym_eig(m, w, info)
        a0 = w(1)
        a2 = w(2)
        ! odd, period pi: sin(2 r t), r = 1..nt
        m = 0.0_dp
        do r = 1, nt
            m(r, r) = (2.0_dp*r)**2
            if (r < nt) then
                m(r, r + 1) = q
                m(r + 1, r) = q
            end if
        end do
        call la_sym_eig(m, w, info)
        b2 = w(1)
        ! period 2 pi: cos((2r+1) t) (first diagonal 1 + q), sin((2r+1) t) (1 - q)
        m = 0.0_dp
        do r = 0, nt - 1
            m(r + 1, r + 1) = (2.0_dp*r + 1.0_dp)**2
            if (r < nt - 1) then
                m(r + 1, r + 2) = q
                m(r + 2, r + 1) = q
            end if
        end do
        m(1, 1) = 1.0_dp + q
        call la_sym_eig(m, w, info)
        a1 = w(1)
        m(1, 1) = 1.0_dp - q
        call la_sym_eig(m, w, info)
        b1 = w(1)
    end subroutine characteristic

end program test_stability_mathieu
