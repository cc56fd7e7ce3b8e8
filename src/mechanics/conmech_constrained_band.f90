!> Banded linear algebra of constrained systems whose constraint Jacobian has a band
!! (row-window) structure and whose mass matrix is diagonal.
!!
!! Row i of G (m x n) has its nonzeros among the w consecutive columns
!! first(i) .. first(i) + w - 1, stored as gb(i, 1:w) ("row windows"; `first`
!! nondecreasing). Then the Schur complement S = G D^-1 G^T (D = diag(d)) is banded with
!! kd = max{k - i : the windows of rows i < k overlap} superdiagonals, and the
!! acceleration-level KKT system costs O(m (w + kd)^2) instead of O(m^2 n): LAPACK's
!! banded Cholesky (dpbtrf/dpbtrs) in upper band storage ab(kd + 1, m),
!! ab(kd + 1 + i - j, j) = S(i, j) for j - kd <= i <= j. A chain of N links has w = 4,
!! kd = 1 (S tridiagonal): O(N) per evaluation.
!!
!! With a constant mass whose inverse is banded (half-bandwidth bm, stored as
!! minv(j, k) = M^-1(j, j + k), k = -bm..bm) the same holds with the windows widened by
!! bm: S = C M^-1 C^T by `band_schur_minv`, O(m (w + 2 bm) (w + kd)).
!!
!! Pure routines on arrays (no system types, no saved state): thread-safe.
module conmech_constrained_band
    use conmech_kinds, only: dp
    implicit none
    private

    public :: band_width_of, band_schur, band_gmul, band_gtmul, band_factor, band_solve
    public :: band_dense, band_windows, band_schur_minv, band_minv_mul, band_order

    interface
        subroutine dpbtrf(uplo, n, kd, ab, ldab, info)
            import :: dp
            character(len=1), intent(in) :: uplo
            integer, intent(in) :: n, kd, ldab
            real(dp), intent(inout) :: ab(ldab, *)
            integer, intent(out) :: info
        end subroutine dpbtrf
        subroutine dpbtrs(uplo, n, kd, nrhs, ab, ldab, b, ldb, info)
            import :: dp
            character(len=1), intent(in) :: uplo
            integer, intent(in) :: n, kd, nrhs, ldab, ldb
            real(dp), intent(in) :: ab(ldab, *)
            real(dp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine dpbtrs
    end interface

contains

    !> Superdiagonals kd of S = G D^-1 G^T for row windows of width w starting at `first`;
    !! -1 if `first` is not nondecreasing or a window leaves 1..n (use the dense path).
    !! `reach` (default 0): half-bandwidth of a banded M^-1 in place of D^-1.
    pure integer function band_width_of(first, w, n, reach) result(kd)
        integer, intent(in) :: first(:), w, n
        integer, intent(in), optional :: reach
        integer :: i, k, m, ext
        ext = 0
        if (present(reach)) ext = reach
        m = size(first)
        kd = 0
        do i = 1, m
            if (first(i) < 1 .or. first(i) + w - 1 > n) then
                kd = -1
                return
            end if
        end do
        do i = 2, m
            if (first(i) < first(i - 1)) then
                kd = -1
                return
            end if
        end do
        do i = 1, m
            k = i + 1
            do while (k <= m)
                if (first(k) > first(i) + w - 1 + ext) exit
                k = k + 1
            end do
            kd = max(kd, k - 1 - i)
        end do
    end function band_width_of

    !> ab = S = G D^-1 G^T in upper band storage (kd superdiagonals).
    pure subroutine band_schur(gb, first, dinv, kd, ab)
        real(dp), intent(in) :: gb(:, :), dinv(:)
        integer, intent(in) :: first(:), kd
        real(dp), intent(out) :: ab(:, :)
        integer :: i, k, m, w, j0, j1, j
        real(dp) :: s
        m = size(gb, 1)
        w = size(gb, 2)
        ab = 0.0_dp
        do k = 1, m
            do i = max(1, k - kd), k
                ! columns shared by the windows of rows i <= k
                j0 = first(k)
                j1 = first(i) + w - 1
                s = 0.0_dp
                do j = j0, j1
                    s = s + gb(i, j - first(i) + 1)*gb(k, j - first(k) + 1)*dinv(j)
                end do
                ab(kd + 1 + i - k, k) = s
            end do
        end do
    end subroutine band_schur

    !> ab = S = C M^-1 C^T in upper band storage (kd superdiagonals) for a banded M^-1
    !! (minv(j, k) = M^-1(j, j + k), k = -bm..bm): u = M^-1 c_k on its reach, then the
    !! products with the windows of the rows i = k - kd .. k.
    pure subroutine band_schur_minv(cb, first, minv, bm, kd, ab)
        real(dp), intent(in) :: cb(:, :)
        integer, intent(in) :: first(:), bm, kd
        real(dp), intent(in) :: minv(:, -bm:)
        real(dp), intent(out) :: ab(:, :)
        real(dp) :: u(size(minv, 1)), s, cv
        integer :: i, k, m, w, n, j, l, lo, hi, jj
        m = size(cb, 1)
        w = size(cb, 2)
        n = size(minv, 1)
        ab = 0.0_dp
        do k = 1, m
            lo = max(1, first(k) - bm)
            hi = min(n, first(k) + w - 1 + bm)
            u(lo:hi) = 0.0_dp
            do jj = 1, w
                j = first(k) + jj - 1
                cv = cb(k, jj)
                do l = max(1, j - bm), min(n, j + bm)
                    u(l) = u(l) + minv(l, j - l)*cv
                end do
            end do
            do i = max(1, k - kd), k
                s = 0.0_dp
                do jj = 1, w
                    j = first(i) + jj - 1
                    if (j >= lo .and. j <= hi) s = s + cb(i, jj)*u(j)
                end do
                ab(kd + 1 + i - k, k) = s
            end do
        end do
    end subroutine band_schur_minv

    !> z = M^-1 x for a banded M^-1 (minv(j, k) = M^-1(j, j + k), k = -bm..bm).
    pure subroutine band_minv_mul(minv, bm, x, z)
        integer, intent(in) :: bm
        real(dp), intent(in) :: minv(:, -bm:), x(:)
        real(dp), intent(out) :: z(:)
        integer :: j, k, n
        real(dp) :: s
        n = size(minv, 1)
        do j = 1, n
            s = 0.0_dp
            do k = max(-bm, 1 - j), min(bm, n - j)
                s = s + minv(j, k)*x(j + k)
            end do
            z(j) = s
        end do
    end subroutine band_minv_mul

    !> Stable order of rows by their first column (counting sort, O(n + m)): row p of the
    !! ordered set is row perm(p) of the given one.
    pure subroutine band_order(first, n, perm)
        integer, intent(in) :: first(:), n
        integer, intent(out) :: perm(:)
        integer :: cnt(0:n + 1), i, k
        cnt = 0
        do i = 1, size(first)
            k = min(max(first(i), 0), n + 1)
            cnt(k) = cnt(k) + 1
        end do
        do k = 1, n + 1
            cnt(k) = cnt(k) + cnt(k - 1)
        end do
        do i = size(first), 1, -1
            k = min(max(first(i), 0), n + 1)
            perm(cnt(k)) = i
            cnt(k) = cnt(k) - 1
        end do
    end subroutine band_order

    !> y = G x (m) from the row windows.
    pure subroutine band_gmul(gb, first, x, y)
        real(dp), intent(in) :: gb(:, :), x(:)
        integer, intent(in) :: first(:)
        real(dp), intent(out) :: y(:)
        integer :: i, w
        w = size(gb, 2)
        do i = 1, size(gb, 1)
            y(i) = dot_product(gb(i, :), x(first(i):first(i) + w - 1))
        end do
    end subroutine band_gmul

    !> z = G^T lam (n) from the row windows.
    pure subroutine band_gtmul(gb, first, lam, z)
        real(dp), intent(in) :: gb(:, :), lam(:)
        integer, intent(in) :: first(:)
        real(dp), intent(out) :: z(:)
        integer :: i, w
        w = size(gb, 2)
        z = 0.0_dp
        do i = 1, size(gb, 1)
            z(first(i):first(i) + w - 1) = z(first(i):first(i) + w - 1) + lam(i)*gb(i, :)
        end do
    end subroutine band_gtmul

    !> Banded Cholesky of ab in place (dpbtrf); info > 0: not positive definite (e.g.
    !! redundant constraints: use the rank-revealing dense path).
    subroutine band_factor(ab, kd, info)
        real(dp), intent(inout) :: ab(:, :)
        integer, intent(in) :: kd
        integer, intent(out) :: info
        call dpbtrf('U', size(ab, 2), kd, ab, size(ab, 1), info)
    end subroutine band_factor

    !> Solve S x = r with the factor from band_factor; r is overwritten by x.
    subroutine band_solve(ab, kd, r, info)
        real(dp), intent(in) :: ab(:, :)
        integer, intent(in) :: kd
        real(dp), intent(inout) :: r(:)
        integer, intent(out) :: info
        call dpbtrs('U', size(ab, 2), kd, 1, ab, size(ab, 1), r, size(r), info)
    end subroutine band_solve

    !> The dense G (m x n) of the row windows.
    pure subroutine band_dense(gb, first, g)
        real(dp), intent(in) :: gb(:, :)
        integer, intent(in) :: first(:)
        real(dp), intent(out) :: g(:, :)
        integer :: i, w
        w = size(gb, 2)
        g = 0.0_dp
        do i = 1, size(gb, 1)
            g(i, first(i):first(i) + w - 1) = gb(i, :)
        end do
    end subroutine band_dense

    !> The row windows of a dense g (m x n), the inverse of `band_dense`: gb(i, :) =
    !! g(i, first(i) + 0:w-1) (w = size(gb, 2)), each window holding every nonzero of its
    !! row and starting at its first nonzero where it fits (else at n - w + 1). When some
    !! row's nonzeros span more than w columns, or w > n, first = 0 (no band structure).
    pure subroutine band_windows(g, gb, first)
        real(dp), intent(in) :: g(:, :)
        real(dp), intent(out) :: gb(:, :)
        integer, intent(out) :: first(:)
        integer :: i, j0, j1, n, w
        n = size(g, 2)
        w = size(gb, 2)
        gb = 0.0_dp
        first = 0
        if (w > n) return
        do i = 1, size(g, 1)
            j0 = 1
            do while (j0 < n .and. g(i, j0) == 0.0_dp)
                j0 = j0 + 1
            end do
            j1 = n
            do while (j1 > j0 .and. g(i, j1) == 0.0_dp)
                j1 = j1 - 1
            end do
            if (j1 - j0 + 1 > w) then
                first = 0
                return
            end if
            first(i) = min(j0, n - w + 1)
            gb(i, :) = g(i, first(i):first(i) + w - 1)
        end do
    end subroutine band_windows

end module conmech_constrained_band
