!> Jordan structure of the eigenvalues of a real matrix that lie on the imaginary axis.
!!
!! A linearisation y' = A y whose spectrum has no positive real part is bounded only if every
!! eigenvalue on the imaginary axis is semisimple: a Jordan block of size s at lambda = i w
!! gives solutions t^(s-1) exp(i w t), a secular growth (at lambda = 0 a drift along the
!! block's eigenvector: the cart of the lecture notes, whose position x drifts as C0 + C1 t
!! while the pendulum swings). The eigenvalues that dgeev returns for a block of size s are
!! split by rounding into a small circle of radius ~ (eps |A|)^(1/s), so the structure is
!! decided on clusters, not on single eigenvalues:
!!
!! - the eigenvalues are grouped by single linkage, |lambda_i - lambda_j| <= sqrt(tol) S
!!   (S = max(1, max |lambda|));
!! - a cluster of m eigenvalues whose mean lambda lies on the axis (|Re| <= tol S) is tested
!!   as an m-fold eigenvalue: nu_k = n - rank((A - lambda I)^k), k = 1..m, with LAPACK's SVD
!!   and singular values <= tol B^k counted as zero (B = max(1, ||A - lambda I||_2)); for a
!!   complex lambda the rank is that of the real 2n x 2n representation, halved;
!! - the cluster is resolved when nu_m = m (it is an m-fold eigenvalue within the
!!   tolerance); then nu_1 is its geometric multiplicity and the largest Jordan block is the
!!   smallest k with nu_k = m (the number of blocks of size >= k is nu_k - nu_(k-1));
!!   otherwise (close but distinct eigenvalues, or a tolerance too coarse for the data) it
!!   is reported unresolved and the callers call the linearisation inconclusive.
module conmech_jordan
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_rank, only: singular_values, null_space, range_basis
    implicit none
    private

    public :: axis_cluster, jordan_structure, zero_drift

    !> One eigenvalue on the imaginary axis (the mean of its cluster; Re set to 0, Im >= 0:
    !! the conjugate -i w has the same structure) with its multiplicities.
    type :: axis_cluster
        real(dp) :: omega = 0.0_dp        !! the eigenvalue is i*omega (omega >= 0)
        integer :: multiplicity = 1       !! algebraic multiplicity m
        integer :: geometric = 1          !! geometric multiplicity nu_1
        integer :: largest_block = 1      !! size of the largest Jordan block
        logical :: resolved = .true.      !! nu_m = m: an m-fold eigenvalue within tol
    end type axis_cluster

contains

    !> Jordan structure of A on the imaginary axis. wr, wi: the eigenvalues of A (dgeev);
    !! tol: relative tolerance (as in the equilibrium classification). Returns the on-axis
    !! clusters with omega >= 0 in clusters(1:ncl), and for each eigenvalue whether it
    !! belongs to a resolved on-axis cluster (`on_axis`).
    subroutine jordan_structure(a, wr, wi, tol, clusters, ncl, on_axis, info)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(in) :: wr(:), wi(:)
        real(dp), intent(in) :: tol
        type(axis_cluster), intent(out) :: clusters(:)
        integer, intent(out) :: ncl
        logical, intent(out) :: on_axis(:)
        integer, intent(out) :: info
        integer :: n, i, j, k, m, pass, lab(size(wr)), nu(size(wr))
        real(dp) :: scale, eps, ctol, mre, mim
        logical :: done(size(wr))
        n = size(wr)
        ncl = 0
        on_axis = .false.
        info = CM_SUCCESS
        if (size(a, 1) /= n .or. size(a, 2) /= n .or. size(wi) /= n .or. &
            size(on_axis) /= n .or. size(clusters) < n .or. .not. (tol >= 0.0_dp)) then
            info = CM_BAD_INPUT
            return
        end if
        if (n == 0) return
        scale = max(1.0_dp, maxval(sqrt(wr**2 + wi**2)))
        eps = tol*scale
        ctol = sqrt(tol)*scale
        ! single-linkage clusters: lab(i) is the smallest index of i's cluster
        do i = 1, n
            lab(i) = i
        end do
        do i = 1, n
            do j = i + 1, n
                if (hypot(wr(i) - wr(j), wi(i) - wi(j)) <= ctol) call merge(lab, i, j)
            end do
        end do
        do i = 1, n
            lab(i) = root(lab, i)
        end do
        ! pass 1: clusters at i w with w >= 0; pass 2: their conjugates (membership only)
        do pass = 1, 2
            done = .false.
            do i = 1, n
                if (done(i)) cycle
                m = count(lab == lab(i))
                mre = sum(wr, mask=lab == lab(i))/m
                mim = sum(wi, mask=lab == lab(i))/m
                where (lab == lab(i)) done = .true.
                if (abs(mre) > eps) cycle
                if (abs(mim) <= eps) mim = 0.0_dp
                if (pass == 2) then
                    if (mim < 0.0_dp) call conjugate_resolved(clusters, ncl, -mim, eps, lab, &
                                                              lab(i), on_axis)
                    cycle
                end if
                if (mim < 0.0_dp) cycle
                ncl = ncl + 1
                clusters(ncl)%omega = mim
                clusters(ncl)%multiplicity = m
                if (m > 1) then
                    call nullities(a, mim, m, tol, nu(1:m), info)
                    if (info /= CM_SUCCESS) return
                    clusters(ncl)%geometric = nu(1)
                    clusters(ncl)%resolved = nu(m) == m
                    clusters(ncl)%largest_block = m
                    do k = 1, m
                        if (nu(k) == m) then
                            clusters(ncl)%largest_block = k
                            exit
                        end if
                    end do
                end if
                if (clusters(ncl)%resolved) where (lab == lab(i)) on_axis = .true.
            end do
        end do
    end subroutine jordan_structure

    !> Mark the members of cluster `label` (an on-axis cluster at -i w) as resolved when the
    !! recorded cluster at +i w is.
    pure subroutine conjugate_resolved(clusters, ncl, w, eps, lab, label, on_axis)
        type(axis_cluster), intent(in) :: clusters(:)
        integer, intent(in) :: ncl
        real(dp), intent(in) :: w, eps
        integer, intent(in) :: lab(:), label
        logical, intent(inout) :: on_axis(:)
        integer :: c
        do c = 1, ncl
            if (abs(clusters(c)%omega - w) <= max(eps, 1.0e-3_dp*w) .and. &
                clusters(c)%resolved .and. clusters(c)%omega > 0.0_dp) then
                where (lab == label) on_axis = .true.
                return
            end if
        end do
    end subroutine conjugate_resolved

    pure recursive function root(lab, i) result(r)
        integer, intent(in) :: lab(:), i
        integer :: r
        r = i
        if (lab(i) /= i) r = root(lab, lab(i))
    end function root

    pure subroutine merge(lab, i, j)
        integer, intent(inout) :: lab(:)
        integer, intent(in) :: i, j
        integer :: ri, rj
        ri = root(lab, i)
        rj = root(lab, j)
        if (ri < rj) then
            lab(rj) = ri
        else if (rj < ri) then
            lab(ri) = rj
        end if
    end subroutine merge

    !> nu_k = dim ker (A - i w I)^k, k = 1..m (complex w > 0: real 2n x 2n representation).
    subroutine nullities(a, w, m, tol, nu, info)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(in) :: w, tol
        integer, intent(in) :: m
        integer, intent(out) :: nu(:)
        integer, intent(out) :: info
        real(dp), allocatable :: b(:, :), p(:, :), s(:)
        real(dp) :: bscale
        integer :: n, nn, fac, k, i
        n = size(a, 1)
        if (w == 0.0_dp) then
            nn = n
            fac = 1
            allocate (b(n, n))
            b = a
        else
            nn = 2*n
            fac = 2
            allocate (b(nn, nn))
            b = 0.0_dp
            b(1:n, 1:n) = a
            b(n + 1:nn, n + 1:nn) = a
            do i = 1, n
                b(i, n + i) = w
                b(n + i, i) = -w
            end do
        end if
        allocate (s(nn), p(nn, nn))
        call singular_values(b, s, info)
        if (info /= CM_SUCCESS) return
        bscale = max(1.0_dp, s(1))
        p = b
        nu = 0
        do k = 1, m
            if (k > 1) p = matmul(p, b)
            call singular_values(p, s, info)
            if (info /= CM_SUCCESS) return
            nu(k) = (nn - count(s > tol*bscale**k))/fac
            if (nu(k) >= m) then
                nu(k:m) = nu(k)
                exit
            end if
        end do
    end subroutine nullities

    !> Directions of secular drift at the eigenvalue 0 with largest Jordan block `block`
    !! (>= 2): the range of A^(block-1) on the generalized kernel ker A^block, an orthonormal
    !! basis in drift(:, 1:ndrift) (each column's largest component positive). These are the
    !! eigenvectors along which the linear solutions grow like t^(block-1).
    subroutine zero_drift(a, block, tol, drift, ndrift, info)
        real(dp), intent(in) :: a(:, :)
        integer, intent(in) :: block
        real(dp), intent(in) :: tol
        real(dp), intent(out) :: drift(:, :)
        integer, intent(out) :: ndrift
        integer, intent(out) :: info
        real(dp), allocatable :: p(:, :), s(:), ker(:, :), x(:, :)
        real(dp) :: ascale
        integer :: n, k, nk, j, imax
        n = size(a, 1)
        ndrift = 0
        drift = 0.0_dp
        if (block < 2 .or. size(drift, 1) /= n .or. size(drift, 2) < n) then
            info = CM_BAD_INPUT
            return
        end if
        allocate (p(n, n), s(n), ker(n, n))
        call singular_values(a, s, info)
        if (info /= CM_SUCCESS) return
        ascale = max(1.0_dp, s(1))
        p = a
        do k = 2, block
            p = matmul(p, a)
        end do
        call null_space(p, tol*ascale**block, ker, nk, info)
        if (info /= CM_SUCCESS .or. nk == 0) return
        ! p = A^(block-1)
        p = a
        do k = 2, block - 1
            p = matmul(p, a)
        end do
        allocate (x(n, nk))
        x = matmul(p, ker(:, 1:nk))
        call singular_values(x, s(1:min(n, nk)), info)
        if (info /= CM_SUCCESS) return
        call range_basis(x, sqrt(tol)*max(s(1), tiny(1.0_dp)), drift, ndrift, info)
        do j = 1, ndrift
            imax = maxloc(abs(drift(:, j)), 1)
            if (drift(imax, j) < 0.0_dp) drift(:, j) = -drift(:, j)
        end do
    end subroutine zero_drift

end module conmech_jordan
