!> The periodic QR algorithm (conmech_periodic_schur) and the multipliers of a product of
!! factors (conmech_periodic_multipliers) against products with known eigenvalues.
program test_periodic_schur
    use conmech_kinds, only: dp, pi
    use conmech_status
    use conmech_testing, only: test_suite
    use conmech_lapack, only: la_eig, la_solve
    use conmech_periodic_schur, only: periodic_eigenvalues
    use conmech_periodic_multipliers, only: multiplier_set, product_multipliers
    implicit none
    type(test_suite) :: suite
    suite%name = "test_periodic_schur"
    call random_against_formed_product()
    call graded_product_with_known_eigenvalues()
    call single_factor_and_sizes()
    call many_factors_far_apart()
    call deflated_flow_direction()
    call suite%finish()

contains

    !> A deterministic "random" matrix (entries in [-1/2, 1/2]).
    subroutine fill(a, seed)
        real(dp), intent(out) :: a(:, :)
        integer, intent(in) :: seed
        integer :: i, j
        do j = 1, size(a, 2)
            do i = 1, size(a, 1)
                a(i, j) = modulo(sin(real(seed*131 + i*17 + j*29, dp))*43758.5453_dp, 1.0_dp) &
                          - 0.5_dp
            end do
        end do
    end subroutine fill

    !> Well-conditioned factors: the periodic eigenvalues equal those of the formed product.
    subroutine random_against_formed_product()
        integer, parameter :: n = 6, k = 5
        real(dp) :: a(n, n, k), p(n, n), wr(n), wi(n), er(n), ei(n), d, worst
        integer :: l, i, j, info
        do l = 1, k
            call fill(a(:, :, l), l)
            do i = 1, n
                a(i, i, l) = a(i, i, l) + 1.5_dp
            end do
        end do
        p = a(:, :, 1)
        do l = 2, k
            p = matmul(a(:, :, l), p)
        end do
        call periodic_eigenvalues(a, wr, wi, info)
        call suite%check(info == CM_SUCCESS, "periodic QR converges (6 x 6, 5 factors)")
        call la_eig(p, er, ei, info)
        worst = 0.0_dp
        do i = 1, n
            d = huge(1.0_dp)
            do j = 1, n
                d = min(d, hypot(er(j) - wr(i), ei(j) - wi(i)))
            end do
            worst = max(worst, d/hypot(wr(i), wi(i)))
        end do
        call suite%check_less(worst, 1.0e-11_dp, "eigenvalues = eig of the formed product")
    end subroutine random_against_formed_product

    !> A_l = S_{l+1} T_l S_l^{-1} (S_{K+1} = S_1) with T_l upper triangular except a 2 x 2
    !! rotation block: the product is S_1 (T_K ... T_1) S_1^{-1}, eigenvalues known in
    !! closed form: 1e12, 1e-12, 3, 1/3 and 0.9 exp(+-i K theta). The formed product
    !! loses the small ones; the periodic QR keeps them to ~1e-12 relative.
    subroutine graded_product_with_known_eigenvalues()
        integer, parameter :: n = 6, k = 12
        real(dp) :: a(n, n, k), s(n, n, k + 1), t(n, n), x(n, n), p(n, n), wr(n), wi(n)
        real(dp) :: want_r(n), want_i(n), er(n), ei(n), d(n), th, rel, worst, worst_formed
        integer :: l, i, j, info
        th = 0.3_dp
        do l = 1, k
            call fill(s(:, :, l), 100 + l)
            do i = 1, n
                s(i, i, l) = s(i, i, l) + 2.0_dp
            end do
        end do
        s(:, :, k + 1) = s(:, :, 1)
        d = [1.0e12_dp**(1.0_dp/k), 1.0e-12_dp**(1.0_dp/k), 3.0_dp**(1.0_dp/k), &
             (1.0_dp/3.0_dp)**(1.0_dp/k), 0.0_dp, 0.0_dp]
        do l = 1, k
            call fill(t, 300 + l)
            do j = 1, n
                do i = j + 1, n
                    t(i, j) = 0.0_dp
                end do
                t(j, j) = d(j)
            end do
            t(5:6, 5:6) = 0.9_dp**(1.0_dp/k)*reshape([cos(th), sin(th), -sin(th), &
                                                       cos(th)], [2, 2])
            ! a_l = s_{l+1} t s_l^{-1}: solve s_l^T a^T = (s_{l+1} t)^T
            call la_solve(transpose(s(:, :, l)), transpose(matmul(s(:, :, l + 1), t)), x, &
                          info)
            a(:, :, l) = transpose(x)
        end do
        want_r = [1.0e12_dp, 1.0e-12_dp, 3.0_dp, 1.0_dp/3.0_dp, 0.9_dp*cos(k*th), &
                  0.9_dp*cos(k*th)]
        want_i = [0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 0.9_dp*sin(k*th), -0.9_dp*sin(k*th)]
        call periodic_eigenvalues(a, wr, wi, info)
        call suite%check(info == CM_SUCCESS, "periodic QR converges (graded product)")
        worst = 0.0_dp
        do i = 1, n
            rel = huge(1.0_dp)
            do j = 1, n
                rel = min(rel, hypot(wr(j) - want_r(i), wi(j) - want_i(i)) &
                          /hypot(want_r(i), want_i(i)))
            end do
            worst = max(worst, rel)
        end do
        call suite%check_less(worst, 1.0e-11_dp, "every eigenvalue to 1e-11 relative, "// &
                              "1e-12 and 1e12 included")
        p = a(:, :, 1)
        do l = 2, k
            p = matmul(a(:, :, l), p)
        end do
        call la_eig(p, er, ei, info)
        worst_formed = minval(abs(er - 1.0e-12_dp))/1.0e-12_dp
        call suite%check(worst_formed > 1.0e-3_dp, "(the formed product loses 1e-12)")
    end subroutine graded_product_with_known_eigenvalues

    !> 400 factors whose product has the eigenvalues 1e200, 1 and 1e-200 (each factor's
    !! diagonal 1e(+-1/2), scaled products underflow after ~50 factors): the iteration
    !! carries its products with log scales and finds all three to 1e-12 relative.
    subroutine many_factors_far_apart()
        integer, parameter :: n = 3, k = 400
        real(dp) :: a(n, n, k), s(n, n, k + 1), t(n, n), x(n, n), wr(n), wi(n), want(n)
        real(dp) :: d(n), worst, rel
        integer :: l, i, j, info
        do l = 1, k
            call fill(s(:, :, l), 500 + l)
            do i = 1, n
                s(i, i, l) = s(i, i, l) + 2.0_dp
            end do
        end do
        s(:, :, k + 1) = s(:, :, 1)
        d = [10.0_dp**(200.0_dp/k), 1.0_dp, 10.0_dp**(-200.0_dp/k)]
        do l = 1, k
            call fill(t, 900 + l)
            do j = 1, n
                do i = j + 1, n
                    t(i, j) = 0.0_dp
                end do
                t(j, j) = d(j)
            end do
            call la_solve(transpose(s(:, :, l)), transpose(matmul(s(:, :, l + 1), t)), x, &
                          info)
            a(:, :, l) = transpose(x)
        end do
        want = [1.0e200_dp, 1.0_dp, 1.0e-200_dp]
        call periodic_eigenvalues(a, wr, wi, info)
        call suite%check(info == CM_SUCCESS, "periodic QR converges (400 factors)")
        worst = 0.0_dp
        do i = 1, n
            rel = huge(1.0_dp)
            do j = 1, n
                rel = min(rel, abs(wr(j) - want(i))/want(i))
            end do
            worst = max(worst, rel)
        end do
        call suite%check_less(worst, 1.0e-10_dp, "1e200, 1, 1e-200 from 400 factors")
    end subroutine many_factors_far_apart

    subroutine single_factor_and_sizes()
        real(dp) :: a1(1, 1, 3), a2(2, 2, 1), wr(2), wi(2), w1(1), v1(1)
        integer :: info
        a1(1, 1, :) = [2.0_dp, -3.0_dp, 0.5_dp]
        call periodic_eigenvalues(a1, w1, v1, info)
        call suite%check_close(w1(1), -3.0_dp, 1.0e-15_dp, "1 x 1 factors: the product")
        a2(:, :, 1) = reshape([0.0_dp, 1.0_dp, -1.0_dp, 0.0_dp], [2, 2])
        call periodic_eigenvalues(a2, wr, wi, info)
        call suite%check(info == CM_SUCCESS .and. abs(wr(1)) < 1.0e-15_dp .and. &
                         abs(abs(wi(1)) - 1.0_dp) < 1.0e-15_dp, "a rotation: +-i")
        call periodic_eigenvalues(a2(:, :, 1:0), wr, wi, info)
        call suite%check(info == CM_BAD_INPUT, "no factor: CM_BAD_INPUT")
    end subroutine single_factor_and_sizes

    !> Segments of the STM of a saddle q'' = q beside an oscillator u'' = -u over four of
    !! its periods (T = 8 pi): the orbit u = sin t (q = 0) has the multipliers e^T, e^-T
    !! (7e-12) and the trivial 1, 1; its vector field is carried exactly by each segment.
    subroutine deflated_flow_direction()
        integer, parameter :: k = 40
        real(dp) :: phi(4, 4, k), fs(4, k), fe(4, k), h, c, s, tt, ch, sh
        type(multiplier_set) :: ms
        integer :: l
        real(dp) :: mumax, mumin, w
        ! y = (q, p) saddle (q'' = q) x oscillator (u'' = -u): STM over h
        tt = 8.0_dp*pi
        h = tt/k
        ch = cosh(h)
        sh = sinh(h)
        c = cos(h)
        s = sin(h)
        do l = 1, k
            phi(:, :, l) = 0.0_dp
            phi(1:2, 1:2, l) = reshape([ch, sh, sh, ch], [2, 2])
            phi(3:4, 3:4, l) = reshape([c, -s, s, c], [2, 2])
            ! the oscillator's orbit u = sin t is "the periodic orbit": f = (0, 0, u', u'')
            fs(:, l) = [0.0_dp, 0.0_dp, cos((l - 1)*h), -sin((l - 1)*h)]
            fe(:, l) = [0.0_dp, 0.0_dp, cos(l*h), -sin(l*h)]
        end do
        call product_multipliers(phi, ms, fs, fe)
        call suite%check(ms%info == CM_SUCCESS .and. ms%deflated, "deflated multipliers")
        w = tt
        mumax = maxval(ms%mr)
        mumin = minval(abs(ms%mr))
        call suite%check_close(mumax/exp(w), 1.0_dp, 1.0e-12_dp, "mu_max = e^(8 pi)")
        call suite%check_close(mumin*mumax, 1.0_dp, 1.0e-10_dp, "mu_min mu_max = 1 (mu_max 8e10)")
        call suite%check(all(ms%err >= 0.0_dp) .and. ms%accuracy < 1.0e-10_dp, &
                         "error estimates small and finite")
    end subroutine deflated_flow_direction

end program test_periodic_schur
