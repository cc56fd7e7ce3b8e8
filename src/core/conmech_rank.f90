!> Numerical rank, null spaces, orthonormal ranges and minimum-norm least-squares solutions
!! by LAPACK's singular value decomposition (dgesvd, dgelsd).
!!
!! A singular value sigma_i counts as zero when sigma_i <= thresh; the callers choose thresh
!! (typically a relative tolerance times the matrix's largest singular value, or times a
!! scale they know). The SVD is the rank-revealing factorisation of choice here: the
!! matrices are small (a Jacobian at an equilibrium, a constraint Jacobian) and the rank
!! decision is the whole point.
module conmech_rank
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT, CM_NO_CONVERGENCE
    use conmech_lapack, only: dgesvd, dgelsd, la_input_status, la_status
    implicit none
    private

    public :: svd, singular_values, numerical_rank, null_space, range_basis, min_norm_solve
    public :: identity

contains

    !> Full SVD A = U diag(s) V^T of an m x n matrix (dgesvd, jobu = jobvt = 'A'):
    !! u (m x m), s (min(m, n), descending), vt (n x n).
    subroutine svd(a, u, s, vt, info)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(out) :: u(:, :)
        real(dp), intent(out) :: s(:)
        real(dp), intent(out) :: vt(:, :)
        integer, intent(out) :: info
        integer :: m, n
        m = size(a, 1)
        n = size(a, 2)
        info = la_input_status(size(u, 1) == m .and. size(u, 2) == m .and. size(vt, 1) == n &
                               .and. size(vt, 2) == n .and. size(s) == min(m, n), a)
        if (info /= CM_SUCCESS) return
        if (m == 0 .or. n == 0) then
            info = CM_SUCCESS
            if (m > 0) u = identity(m)
            if (n > 0) vt = identity(n)
            return
        end if
        call run_dgesvd('A', a, s, u, vt, info)
    end subroutine svd

    !> Singular values of an m x n matrix (descending; dgesvd without vectors).
    subroutine singular_values(a, s, info)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(out) :: s(:)
        integer, intent(out) :: info
        real(dp) :: du(1, 1), dv(1, 1)
        integer :: m, n
        m = size(a, 1)
        n = size(a, 2)
        info = la_input_status(size(s) == min(m, n), a)
        if (info /= CM_SUCCESS) return
        if (m == 0 .or. n == 0) return
        call run_dgesvd('N', a, s, du, dv, info)
    end subroutine singular_values

    !> dgesvd on a copy of the m x n matrix a, after its workspace query: job 'A' (all of
    !! u (m x m) and vt (n x n)) or 'N' (the values only; u and vt 1 x 1 placeholders).
    subroutine run_dgesvd(job, a, s, u, vt, info)
        character(len=1), intent(in) :: job
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(out) :: s(:)
        real(dp), intent(out) :: u(:, :), vt(:, :)
        integer, intent(out) :: info
        real(dp), allocatable :: tmp(:, :), work(:)
        real(dp) :: wq(1)
        integer :: m, n, lwork, lainfo
        m = size(a, 1)
        n = size(a, 2)
        allocate (tmp(m, n))
        tmp = a
        call dgesvd(job, job, m, n, tmp, m, s, u, size(u, 1), vt, size(vt, 1), wq, -1, lainfo)
        lwork = max(1, int(wq(1)))
        allocate (work(lwork))
        call dgesvd(job, job, m, n, tmp, m, s, u, size(u, 1), vt, size(vt, 1), work, lwork, &
                    lainfo)
        info = la_status(lainfo, CM_NO_CONVERGENCE)
    end subroutine run_dgesvd

    !> Numerical rank: the number of singular values > thresh.
    subroutine numerical_rank(a, thresh, rank, info)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(in) :: thresh
        integer, intent(out) :: rank
        integer, intent(out) :: info
        real(dp) :: s(min(size(a, 1), size(a, 2)))
        rank = 0
        call singular_values(a, s, info)
        if (info /= CM_SUCCESS) return
        rank = count(s > thresh)
    end subroutine numerical_rank

    !> Orthonormal basis of the null space of an m x n matrix: the right singular vectors of
    !! the singular values <= thresh (and of the n - m missing ones when m < n).
    !! basis(:, 1:nnull) holds it; basis must have n rows and at least n columns.
    subroutine null_space(a, thresh, basis, nnull, info)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(in) :: thresh
        real(dp), intent(out) :: basis(:, :)
        integer, intent(out) :: nnull
        integer, intent(out) :: info
        real(dp), allocatable :: u(:, :), vt(:, :)
        integer :: n, r
        n = size(a, 2)
        nnull = 0
        basis = 0.0_dp
        if (size(basis, 1) /= n .or. size(basis, 2) < n) then
            info = CM_BAD_INPUT
            return
        end if
        call svd_rank(a, thresh, u, vt, r, info)
        if (info /= CM_SUCCESS) return
        nnull = n - r
        if (nnull > 0) basis(:, 1:nnull) = transpose(vt(r + 1:n, :))
    end subroutine null_space

    !> Orthonormal basis of the range (column space) of an m x n matrix: the left singular
    !! vectors of the singular values > thresh; basis(:, 1:r) holds it (basis: m rows, at
    !! least min(m, n) columns).
    subroutine range_basis(a, thresh, basis, r, info)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(in) :: thresh
        real(dp), intent(out) :: basis(:, :)
        integer, intent(out) :: r
        integer, intent(out) :: info
        real(dp), allocatable :: u(:, :), vt(:, :)
        integer :: m, n
        m = size(a, 1)
        n = size(a, 2)
        r = 0
        basis = 0.0_dp
        if (size(basis, 1) /= m .or. size(basis, 2) < min(m, n)) then
            info = CM_BAD_INPUT
            return
        end if
        call svd_rank(a, thresh, u, vt, r, info)
        if (r > 0) basis(:, 1:r) = u(:, 1:r)
    end subroutine range_basis

    !> The full SVD of a (u: m x m, vt: n x n) and the number r of its singular values
    !! > thresh (0 when the SVD fails).
    subroutine svd_rank(a, thresh, u, vt, r, info)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(in) :: thresh
        real(dp), allocatable, intent(out) :: u(:, :), vt(:, :)
        integer, intent(out) :: r
        integer, intent(out) :: info
        real(dp) :: s(min(size(a, 1), size(a, 2)))
        allocate (u(size(a, 1), size(a, 1)), vt(size(a, 2), size(a, 2)))
        r = 0
        call svd(a, u, s, vt, info)
        if (info == CM_SUCCESS) r = count(s > thresh)
    end subroutine svd_rank

    !> Minimum-norm least-squares solution x = A^+ b of A x = b (dgelsd; m x n A, one
    !! right-hand side), singular values <= rcond * sigma_max treated as zero; `rank` is
    !! the effective rank. A and b are not changed.
    subroutine min_norm_solve(a, b, x, rcond, rank, info)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(in) :: b(:)
        real(dp), intent(out) :: x(:)
        real(dp), intent(in) :: rcond
        integer, intent(out) :: rank
        integer, intent(out) :: info
        real(dp), allocatable :: tmp(:, :), rhs(:, :), s(:), work(:)
        integer, allocatable :: iwork(:)
        real(dp) :: wq(1)
        integer :: m, n, lwork, lainfo, iq(1)
        m = size(a, 1)
        n = size(a, 2)
        rank = 0
        x = 0.0_dp
        info = la_input_status(size(b) == m .and. size(x) == n .and. m > 0 .and. n > 0, a, &
                               reshape(b, [size(b), 1]))
        if (info /= CM_SUCCESS) return
        allocate (tmp(m, n), rhs(max(m, n), 1), s(min(m, n)))
        tmp = a
        rhs = 0.0_dp
        rhs(1:m, 1) = b
        call dgelsd(m, n, 1, tmp, m, rhs, max(m, n), s, rcond, rank, wq, -1, iq, lainfo)
        lwork = max(1, int(wq(1)))
        allocate (work(lwork), iwork(max(1, iq(1))))
        call dgelsd(m, n, 1, tmp, m, rhs, max(m, n), s, rcond, rank, work, lwork, iwork, &
                    lainfo)
        info = la_status(lainfo, CM_NO_CONVERGENCE)
        if (info == CM_SUCCESS) x = rhs(1:n, 1)
    end subroutine min_norm_solve

    !> The n x n identity matrix.
    pure function identity(n) result(e)
        integer, intent(in) :: n
        real(dp) :: e(n, n)
        integer :: i
        e = 0.0_dp
        do i = 1, n
            e(i, i) = 1.0_dp
        end do
    end function identity

end module conmech_rank
