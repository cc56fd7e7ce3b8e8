!> Eigenvalues of a product of matrices A_K ... A_2 A_1 without forming the product: the
!! periodic QR algorithm (Bojanczyk, Golub and Van Dooren 1992; Hench and Laub 1994;
!! Kressner 2006, "The periodic QR algorithm is a disguised QR algorithm").
!!
!! Why. The monodromy of an unstable periodic orbit is a product of segment state
!! transition matrices whose product has singular values spread from mu_max to 1/mu_max.
!! The eigenvalues of the formed product are only accurate to eps |M| ~ eps mu_max in
!! absolute terms: for mu_max = 1e9 the multiplier 1/mu_max = 1e-9 has no correct digit.
!! Orthogonal transformations applied factor by factor are backward stable for each factor:
!! the computed eigenvalues are the exact ones of A_k + E_k with |E_k| ~ eps |A_k|, which
!! keeps the small multipliers' digits as long as each factor is well conditioned.
!!
!! Method. Orthogonal Q_1 .. Q_K (Q_{K+1} = Q_1) bring H_k = Q_{k+1}^T A_k Q_k to periodic
!! Hessenberg-triangular form: H_1 .. H_{K-1} upper triangular, H_K upper Hessenberg (QR
!! factorisations passed round the cycle, then Householder reflectors column by column with
!! the triangular factors restored after each). Francis double-shift steps then chase a
!! 3 x 3 bulge through the factors: each reflector applied to the rows of one factor is
!! applied to the columns of the next, and the triangular factors are re-triangularised
!! by two reflectors per bulge position. Shifts and the first column of
!! (P - s1)(P - s2) e1 come from the leading and trailing 2 x 2/3 x 3 blocks of the
!! factors, multiplied as running products renormalised after every factor with their log
!! scales kept (no overflow or underflow however many factors, however spread). A
!! subdiagonal entry of H_K below eps times its neighbours is set to zero (deflation);
!! converged 1 x 1 blocks give the eigenvalue as the product of the diagonal entries, 2 x 2
!! blocks from the product of the 2 x 2 blocks, the smaller of a real pair as det/larger
!! with the determinant multiplied factor by factor (exact to relative rounding).
module conmech_periodic_schur
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_lapack, only: la_finite
    use conmech_lapack_qr, only: dgeqrf, dormqr, dlarfg, dlarf
    implicit none
    private

    public :: periodic_eigenvalues

contains

    !> Eigenvalues (wr + i wi) of the product a(:, :, K) ... a(:, :, 1) (n x n factors).
    !! info: CM_SUCCESS, CM_BAD_INPUT (shapes), CM_NONFINITE, CM_NO_CONVERGENCE (the
    !! iteration did not converge in 40 n sweeps). Eigenvalues beyond the range of
    !! real(dp) are returned as +-huge.
    subroutine periodic_eigenvalues(a, wr, wi, info)
        real(dp), intent(in) :: a(:, :, :)
        real(dp), intent(out) :: wr(:), wi(:)
        integer, intent(out) :: info
        real(dp), allocatable :: h(:, :, :)
        integer :: n, k
        n = size(a, 1)
        k = size(a, 3)
        wr = 0.0_dp
        wi = 0.0_dp
        if (size(a, 2) /= n .or. n < 1 .or. k < 1 .or. size(wr) /= n .or. &
            size(wi) /= n) then
            info = CM_BAD_INPUT
            return
        end if
        if (.not. la_finite(reshape(a, [n*n*k]))) then
            info = CM_NONFINITE
            return
        end if
        h = a
        call hessenberg_triangular(h, n, k, info)
        if (info /= CM_SUCCESS) return
        call periodic_qr(h, n, k, wr, wi, info)
    end subroutine periodic_eigenvalues

    !> QR factorisation of the m x m block h(i0:i0+m-1, i0:i0+m-1, l), its Q applied to the
    !! rows i0.. of factor l (all columns from i0) and to the columns of factor l + 1 (cyclic).
    subroutine block_qr(h, n, k, l, i0, m, info)
        real(dp), intent(inout) :: h(n, n, k)
        integer, intent(in) :: n, k, l, i0, m
        integer, intent(out) :: info
        real(dp) :: tau(m), wq(1)
        real(dp), allocatable :: work(:), blk(:, :)
        integer :: lwork, ln, i1, j
        i1 = i0 + m - 1
        ln = merge(1, l + 1, l == k)
        blk = h(i0:i1, i0:i1, l)
        call dgeqrf(m, m, blk, m, tau, wq, -1, info)
        lwork = max(1, int(wq(1)), n*m)
        allocate (work(lwork))
        call dgeqrf(m, m, blk, m, tau, work, lwork, info)
        if (info /= 0) then
            info = CM_LAPACK_ERROR
            return
        end if
        ! rows i0:i1 of factor l, columns i1+1:n (the block itself becomes R)
        if (i1 < n) call dormqr('L', 'T', m, n - i1, m, blk, m, tau, h(i0, i1 + 1, l), &
                                n, work, lwork, info)
        do j = 1, m
            h(i0:i0 + j - 1, i0 + j - 1, l) = blk(1:j, j)
            h(i0 + j:i1, i0 + j - 1, l) = 0.0_dp
        end do
        ! columns i0:i1 of the next factor
        call dormqr('R', 'N', n, m, m, blk, m, tau, h(1, i0, ln), n, work, lwork, &
                    info)
        if (info /= 0) info = CM_LAPACK_ERROR
    end subroutine block_qr

    !> Periodic Hessenberg-triangular form in place: h(:, :, 1:k-1) upper triangular,
    !! h(:, :, k) upper Hessenberg, by orthogonal transformations passed round the cycle.
    subroutine hessenberg_triangular(h, n, k, info)
        real(dp), intent(inout) :: h(n, n, k)
        integer, intent(in) :: n, k
        integer, intent(out) :: info
        real(dp) :: tau, alpha, work(max(n, 1))
        real(dp) :: v(n)
        integer :: l, j, m
        info = CM_SUCCESS
        do l = 1, k - 1
            call block_qr(h, n, k, l, 1, n, info)
            if (info /= CM_SUCCESS) return
        end do
        do j = 1, n - 2
            m = n - j
            ! reflector on rows j+1..n of the Hessenberg factor, zeroing h(j+2:n, j, k)
            alpha = h(j + 1, j, k)
            v(1:m - 1) = h(j + 2:n, j, k)
            call dlarfg(m, alpha, v, 1, tau)
            h(j + 1, j, k) = alpha
            h(j + 2:n, j, k) = 0.0_dp
            v(2:m) = v(1:m - 1)
            v(1) = 1.0_dp
            call dlarf('L', m, n - j, v, 1, tau, h(j + 1, j + 1, k), n, work)
            ! the same reflector on the columns of factor 1 (position 1 of the cycle)
            call dlarf('R', n, m, v, 1, tau, h(1, j + 1, 1), n, work)
            ! restore the triangular factors on rows/columns j+1..n
            do l = 1, k - 1
                call block_qr(h, n, k, l, j + 1, m, info)
                if (info /= CM_SUCCESS) return
            end do
        end do
    end subroutine hessenberg_triangular

    !> Apply the reflector (v(1:nr), tau) acting at the cycle position between factor
    !! `l` (columns) and factor `l - 1` (rows; factor k for l = 1) on indices j..j+nr-1.
    !! Rows are updated on columns c0..n, columns on rows 1..r1.
    subroutine apply_at(h, n, k, l, j, nr, v, tau, c0, r1)
        real(dp), intent(inout) :: h(n, n, k)
        integer, intent(in) :: n, k, l, j, nr, c0, r1
        real(dp), intent(in) :: v(:), tau
        real(dp) :: work(max(n, 1))
        integer :: lp
        lp = merge(k, l - 1, l == 1)
        call dlarf('L', nr, n - c0 + 1, v, 1, tau, h(j, c0, lp), n, work)
        call dlarf('R', r1, nr, v, 1, tau, h(1, j, l), n, work)
    end subroutine apply_at

    !> Double-shift periodic QR iteration on the Hessenberg-triangular factors.
    subroutine periodic_qr(h, n, k, wr, wi, info)
        real(dp), intent(inout) :: h(n, n, k)
        integer, intent(in) :: n, k
        real(dp), intent(out) :: wr(:), wi(:)
        integer, intent(out) :: info
        real(dp), parameter :: eps = epsilon(1.0_dp)
        real(dp) :: x(3), v(3), tau, tr, dt, b(2, 2), r, tst, lb
        integer :: ilo, ihi, l, j, nr, iter, its, c, lf
        info = CM_SUCCESS
        ihi = n
        iter = 0
        its = 0
        do while (ihi >= 1)
            ! the largest ilo with a negligible subdiagonal entry h(ilo, ilo-1, k)
            ilo = 1
            do l = ihi, 2, -1
                tst = abs(h(l - 1, l - 1, k)) + abs(h(l, l, k))
                if (tst == 0.0_dp) tst = maxval(abs(h(max(1, l - 2):min(n, l + 1), &
                                                      max(1, l - 2):min(n, l + 1), k)))
                if (abs(h(l, l - 1, k)) <= eps*tst) then
                    h(l, l - 1, k) = 0.0_dp
                    ilo = l
                    exit
                end if
            end do
            if (ilo == ihi) then
                call one_by_one(h, k, ihi, wr(ihi))
                wi(ihi) = 0.0_dp
                ihi = ihi - 1
                iter = 0
                cycle
            end if
            if (ilo == ihi - 1) then
                call two_by_two(h, k, ilo, wr(ilo:ihi), wi(ilo:ihi))
                ihi = ihi - 2
                iter = 0
                cycle
            end if
            iter = iter + 1
            its = its + 1
            if (its > 40*max(n, 10)) then
                info = CM_NO_CONVERGENCE
                return
            end if
            ! the trailing 2 x 2 block of the product as e^lb b (shifts: its eigenvalues)
            call trailing_product(h, k, ihi, b, lb)
            tr = b(1, 1) + b(2, 2)
            dt = b(1, 1)*b(2, 2) - b(1, 2)*b(2, 1)
            if (mod(iter, 10) == 0) then
                ! exceptional shifts: a complex pair at the modulus of the trailing block
                r = max(abs(b(1, 1)), abs(b(2, 2)), abs(b(2, 1)), sqrt(abs(dt)))
                tr = 1.5_dp*r
                dt = r*r
            end if
            call first_column(h, k, ilo, tr, dt, lb, x)
            do j = ilo, ihi - 1
                nr = min(3, ihi - j + 1)
                if (j == ilo) then
                    v(1:nr) = x(1:nr)
                else
                    v(1:nr) = h(j:j + nr - 1, j - 1, k)
                end if
                call dlarfg(nr, v(1), v(2:nr), 1, tau)
                if (j > ilo) then
                    h(j, j - 1, k) = v(1)
                    h(j + 1:j + nr - 1, j - 1, k) = 0.0_dp
                end if
                v(1) = 1.0_dp
                ! position 1: rows of the Hessenberg factor, columns of factor 1
                call apply_at(h, n, k, 1, j, nr, v, tau, j, min(n, j + nr))
                ! restore the triangular factors 1..k-1 (two reflectors per factor)
                do lf = 1, k - 1
                    do c = 0, nr - 2
                        v(1:nr - c) = h(j + c:j + nr - 1, j + c, lf)
                        call dlarfg(nr - c, v(1), v(2:nr - c), 1, tau)
                        h(j + c, j + c, lf) = v(1)
                        h(j + c + 1:j + nr - 1, j + c, lf) = 0.0_dp
                        v(1) = 1.0_dp
                        call apply_at(h, n, k, lf + 1, j + c, nr - c, v, tau, j + c + 1, &
                                      min(n, j + nr))
                    end do
                end do
            end do
        end do
    end subroutine periodic_qr

    !> The trailing 2 x 2 block (rows/columns ihi-1..ihi) of the product H_k ... H_1 as
    !! e^lscale b, max |b| = 1 (the running product renormalised after every factor: no
    !! overflow or underflow however many factors); ihi >= 3.
    pure subroutine trailing_product(h, k, ihi, b, lscale)
        real(dp), intent(in) :: h(:, :, :)
        integer, intent(in) :: k, ihi
        real(dp), intent(out) :: b(2, 2), lscale
        real(dp) :: t(3, 3), u(3, 3)
        integer :: l, i0
        i0 = ihi - 2
        t = 0.0_dp
        t(1, 1) = 1.0_dp
        t(2, 2) = 1.0_dp
        t(3, 3) = 1.0_dp
        lscale = 0.0_dp
        do l = 1, k - 1
            u = h(i0:ihi, i0:ihi, l)
            u(2, 1) = 0.0_dp
            u(3, 1) = 0.0_dp
            u(3, 2) = 0.0_dp
            t = matmul(u, t)
            call renormalise(t, lscale)
        end do
        b = matmul(h(ihi - 1:ihi, i0:ihi, k), t(:, 2:3))
        call renormalise(b, lscale)
    end subroutine trailing_product

    !> a = a/max|a| (unless zero), lscale += log(max|a|).
    pure subroutine renormalise(a, lscale)
        real(dp), intent(inout) :: a(:, :), lscale
        real(dp) :: c
        c = maxval(abs(a))
        if (c > 0.0_dp) then
            a = a/c
            lscale = lscale + log(c)
        end if
    end subroutine renormalise

    !> The direction of the first three entries of (P - s1)(P - s2) e_ilo for the product
    !! P, with s1 + s2 = tr e^lb and s1 s2 = dt e^(2 lb). P e and P^2 e are carried with
    !! their own log scales; the three terms are added after scaling by the largest, so that
    !! nothing overflows and a term far below the others underflows harmlessly to zero.
    pure subroutine first_column(h, k, ilo, tr, dt, lb, x)
        real(dp), intent(in) :: h(:, :, :), tr, dt, lb
        integer, intent(in) :: k, ilo
        real(dp), intent(out) :: x(3)
        real(dp) :: t2(2, 2), u(2), pe(2), c(2, 2), v2(3), lt, l1, l2, c1, c2, e1, e2, e3, em
        real(dp) :: w(2, 2)
        integer :: l, i
        i = ilo
        t2 = reshape([1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2])
        lt = 0.0_dp
        do l = 1, k - 1
            c = h(i:i + 1, i:i + 1, l)
            c(2, 1) = 0.0_dp
            t2 = matmul(c, t2)
            call renormalise(t2, lt)
        end do
        ! P e_i = e^lt t2(1, 1) H_k(i:i+1, i)
        pe = t2(1, 1)*h(i:i + 1, i, k)
        c1 = maxval(abs(pe))
        x = 0.0_dp
        if (.not. (c1 > 0.0_dp)) then
            x(1) = 1.0_dp
            return
        end if
        pe = pe/c1
        l1 = lt + log(c1)
        ! P^2 e_i = H_k(i:i+2, i:i+1) (e^lt t2) (e^l1 pe)
        w = t2
        u = matmul(w, pe)
        v2 = matmul(h(i:i + 2, i:i + 1, k), u)
        c2 = maxval(abs(v2))
        if (c2 > 0.0_dp) then
            v2 = v2/c2
            l2 = lt + l1 + log(c2)
        else
            l2 = -huge(1.0_dp)
        end if
        e1 = l2
        e2 = -huge(1.0_dp)
        if (tr /= 0.0_dp) e2 = lb + l1 + log(abs(tr))
        e3 = -huge(1.0_dp)
        if (dt /= 0.0_dp) e3 = 2.0_dp*lb + log(abs(dt))
        em = max(e1, e2, e3)
        x = scale_exp(e1 - em)*v2
        if (tr /= 0.0_dp) x(1:2) = x(1:2) - sign(scale_exp(e2 - em), tr)*pe
        if (dt /= 0.0_dp) x(1) = x(1) + sign(scale_exp(e3 - em), dt)
    contains
        pure real(dp) function scale_exp(d) result(y)
            real(dp), intent(in) :: d
            if (d < log(tiny(1.0_dp))) then
                y = 0.0_dp
            else
                y = exp(min(d, 0.0_dp))
            end if
        end function scale_exp
    end subroutine first_column

    !> The eigenvalue of a converged 1 x 1 block: the product of the diagonal entries.
    pure subroutine one_by_one(h, k, i, w)
        real(dp), intent(in) :: h(:, :, :)
        integer, intent(in) :: k, i
        real(dp), intent(out) :: w
        real(dp) :: lg, sg
        integer :: l
        lg = 0.0_dp
        sg = 1.0_dp
        do l = 1, k
            if (h(i, i, l) == 0.0_dp) then
                w = 0.0_dp
                return
            end if
            lg = lg + log(abs(h(i, i, l)))
            sg = sg*sign(1.0_dp, h(i, i, l))
        end do
        w = sg*safe_exp(lg)
    end subroutine one_by_one

    !> The two eigenvalues of a converged 2 x 2 block at rows/columns i, i+1: from the
    !! product of the scaled 2 x 2 blocks (trace) and the determinant multiplied factor by
    !! factor; a real pair's smaller member as det/larger.
    pure subroutine two_by_two(h, k, i, wr, wi)
        real(dp), intent(in) :: h(:, :, :)
        integer, intent(in) :: k, i
        real(dp), intent(out) :: wr(2), wi(2)
        real(dp) :: b(2, 2), c(2, 2), sc, lscale, ldet, sdet, d, tr, dt, disc, l1, ml
        integer :: l
        b = reshape([1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2])
        lscale = 0.0_dp
        ldet = 0.0_dp
        sdet = 1.0_dp
        do l = 1, k
            c = h(i:i + 1, i:i + 1, l)
            if (l < k) c(2, 1) = 0.0_dp
            sc = maxval(abs(c))
            d = c(1, 1)*c(2, 2) - c(1, 2)*c(2, 1)
            if (.not. (sc > 0.0_dp) .or. d == 0.0_dp) then
                ! a singular factor: the formed (scaled) product decides
                sdet = 0.0_dp
                if (.not. (sc > 0.0_dp)) sc = 1.0_dp
            else
                ldet = ldet + log(abs(d))
                sdet = sdet*sign(1.0_dp, d)
            end if
            b = matmul(c/sc, b)
            lscale = lscale + log(sc)
            call renormalise(b, lscale)
        end do
        tr = b(1, 1) + b(2, 2)
        if (sdet == 0.0_dp) then
            dt = b(1, 1)*b(2, 2) - b(1, 2)*b(2, 1)
        else
            dt = sdet*safe_exp(ldet - 2.0_dp*lscale)
        end if
        disc = 0.25_dp*tr*tr - dt
        if (disc < 0.0_dp) then
            ml = lscale
            wr = 0.5_dp*tr
            wi(1) = sqrt(-disc)
            wi(2) = -wi(1)
            wr = scaled(wr, ml)
            wi = scaled(wi, ml)
        else
            l1 = 0.5_dp*tr + sign(sqrt(disc), tr)
            wi = 0.0_dp
            wr(1) = scaled_one(l1, lscale)
            if (l1 /= 0.0_dp) then
                if (sdet == 0.0_dp) then
                    wr(2) = scaled_one(dt/l1, lscale)
                else
                    ! det/l1 with the determinant's own scale (no underflow of dt)
                    wr(2) = sdet*sign(1.0_dp, l1)*safe_exp(ldet - log(abs(l1)) - lscale)
                end if
            else
                wr(2) = 0.0_dp
            end if
        end if
    contains
        pure elemental function scaled(x, lg) result(y)
            real(dp), intent(in) :: x, lg
            real(dp) :: y
            if (x == 0.0_dp) then
                y = 0.0_dp
            else
                y = sign(1.0_dp, x)*safe_exp(log(abs(x)) + lg)
            end if
        end function scaled
        pure function scaled_one(x, lg) result(y)
            real(dp), intent(in) :: x, lg
            real(dp) :: y
            y = scaled(x, lg)
        end function scaled_one
    end subroutine two_by_two

    !> exp(x) clipped to huge (no overflow) and to 0 below the underflow threshold.
    pure elemental function safe_exp(x) result(y)
        real(dp), intent(in) :: x
        real(dp) :: y
        if (x > log(huge(1.0_dp))) then
            y = huge(1.0_dp)
        else if (x < log(tiny(1.0_dp))) then
            y = 0.0_dp
        else
            y = exp(x)
        end if
    end function safe_exp

end module conmech_periodic_schur
