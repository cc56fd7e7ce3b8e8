!> Structured linear solves of discretised boundary-value problems: a chain of block rows
!!
!!     A_k z_k + B_k z_(k+1) + C_k w = d_k      (k = 1..K, n rows each)
!!
!! in the node unknowns z_1 .. z_(K+1) (n each) and a few border unknowns w (period,
!! parameter), closed by boundary rows  Ba z_1 + Bb z_(K+1) + Bw w = e  (periodicity, phase
!! and energy conditions, symmetry conditions, the pseudo-arclength equation). Multiple
!! shooting (A_k the segment STMs, B_k = -I) and orthogonal collocation after the
!! condensation of each interval's stages have this form.
!!
!! The interior nodes z_2 .. z_K are eliminated one after the other by orthogonal
!! transformations (the stabilised march of AUTO's and COLSYS's block eliminations, with
!! QR instead of partial pivoting): the running block E z_1 + F z_j + G w = h and row j
!! share z_j; the QR factorisation of the stacked 2n x n column [F; A_j] gives n pivot
!! rows R_j z_j + ... (kept for the back substitution) and n rows free of z_j, the next
!! running block. No product of the A_k is ever formed, and every row is transformed
!! orthogonally (no growth), so the solve is backward stable however unstable the orbit:
!! the cost is O(K n^3), never the O((K n)^3) of a dense solve. The final
!! (n + rows) x (2n + |w|) system in (z_1, z_(K+1), w) is solved in the least-squares sense
!! (LAPACK dgelsd: the Gauss-Newton step of an overdetermined consistent system, e.g. a
!! conservative orbit at a fixed period), then z_K .. z_2 by back substitution (dtrtrs).
!! The factorisation does not depend on the boundary rows or the right-hand side, so the
!! corrector and the tangent of a continuation step reuse it.
module conmech_block_chain
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_lapack, only: dgelsd, la_finite
    use conmech_lapack_qr, only: dgeqrf, dormqr, dtrtrs
    implicit none
    private

    public :: block_chain, chain_factor, chain_solve, lstsq_solve

    !> The factorised chain (see the module notes).
    type :: block_chain
        integer :: n = 0, k = 0, nw = 0
        logical :: factored = .false.
        real(dp), allocatable :: qv(:, :, :)     !! (2n, n, K) reflectors of the stacked QRs
        real(dp), allocatable :: qtau(:, :)      !! (n, K) their scalars
        real(dp), allocatable :: pe(:, :, :)     !! (n, n, K) pivot rows' z_1 coefficients
        real(dp), allocatable :: pf(:, :, :)     !! (n, n, K) their z_(j+1) coefficients
        real(dp), allocatable :: pg(:, :, :)     !! (n, nw, K) their w coefficients
        real(dp), allocatable :: e(:, :), f(:, :), g(:, :)  !! final E z_1 + F z_(K+1) + G w
    end type block_chain

contains

    !> Factorise the chain a(:, :, k) z_k + b(:, :, k) z_(k+1) + c(:, :, k) w (c may have
    !! zero columns). info CM_SINGULAR if a pivot block R_j is singular (a column [F; A_j]
    !! without full rank: a singular segment STM).
    subroutine chain_factor(ch, a, b, c, info)
        type(block_chain), intent(inout) :: ch
        real(dp), intent(in) :: a(:, :, :), b(:, :, :), c(:, :, :)
        integer, intent(out) :: info
        real(dp), allocatable :: s(:, :), tmp(:, :), work(:)
        real(dp) :: wq(1)
        integer :: n, k, nw, j, i, lwork
        n = size(a, 1)
        k = size(a, 3)
        nw = size(c, 2)
        ch%factored = .false.
        if (n < 1 .or. k < 1 .or. size(a, 2) /= n .or. any(shape(b) /= [n, n, k]) .or. &
            size(c, 1) /= n .or. size(c, 3) /= k) then
            info = CM_BAD_INPUT
            return
        end if
        if (.not. (la_finite(reshape(a, [n*n*k])) .and. la_finite(reshape(b, [n*n*k])) &
                   .and. la_finite(reshape(c, [n*nw*k])))) then
            info = CM_NONFINITE
            return
        end if
        ch%n = n
        ch%k = k
        ch%nw = nw
        if (allocated(ch%qv)) deallocate (ch%qv, ch%qtau, ch%pe, ch%pf, ch%pg)
        allocate (ch%qv(2*n, n, k), ch%qtau(n, k), ch%pe(n, n, k), ch%pf(n, n, k), &
                  ch%pg(n, nw, k))
        ch%e = a(:, :, 1)
        ch%f = b(:, :, 1)
        ch%g = c(:, :, 1)
        allocate (s(2*n, n), tmp(2*n, 2*n + nw))
        call dgeqrf(2*n, n, s, 2*n, ch%qtau(:, 1), wq, -1, info)
        lwork = max(1, int(wq(1)), (2*n + nw)*n)
        allocate (work(lwork))
        do j = 2, k
            s(1:n, :) = ch%f
            s(n + 1:, :) = a(:, :, j)
            call dgeqrf(2*n, n, s, 2*n, ch%qtau(:, j), work, lwork, info)
            if (info /= 0) then
                info = CM_LAPACK_ERROR
                return
            end if
            do i = 1, n
                if (.not. (abs(s(i, i)) > 0.0_dp)) then
                    info = CM_SINGULAR
                    return
                end if
            end do
            tmp = 0.0_dp
            tmp(1:n, 1:n) = ch%e
            tmp(n + 1:, n + 1:2*n) = b(:, :, j)
            tmp(1:n, 2*n + 1:) = ch%g
            tmp(n + 1:, 2*n + 1:) = c(:, :, j)
            call dormqr('L', 'T', 2*n, 2*n + nw, n, s, 2*n, ch%qtau(:, j), tmp, 2*n, work, &
                        lwork, info)
            if (info /= 0) then
                info = CM_LAPACK_ERROR
                return
            end if
            ch%qv(:, :, j) = s
            ch%pe(:, :, j) = tmp(1:n, 1:n)
            ch%pf(:, :, j) = tmp(1:n, n + 1:2*n)
            ch%pg(:, :, j) = tmp(1:n, 2*n + 1:)
            ch%e = tmp(n + 1:, 1:n)
            ch%f = tmp(n + 1:, n + 1:2*n)
            ch%g = tmp(n + 1:, 2*n + 1:)
        end do
        ch%factored = .true.
        info = CM_SUCCESS
    end subroutine chain_factor

    !> Solve the factorised chain with right-hand sides d(:, k) and the boundary rows
    !! bz1 z_1 + bzk z_(K+1) + bw w = brhs (nr rows; nr may be zero). z(:, 1:K+1), w:
    !! the (least-squares, minimum-norm in (z_1, z_(K+1), w)) solution; `rank` the rank of
    !! the final system (full: 2n + nw). rcond: the rank threshold of dgelsd.
    subroutine chain_solve(ch, d, bz1, bzk, bw, brhs, z, w, rank, info, rcond)
        type(block_chain), intent(in) :: ch
        real(dp), intent(in) :: d(:, :), bz1(:, :), bzk(:, :), bw(:, :), brhs(:)
        real(dp), intent(out) :: z(:, :), w(:)
        integer, intent(out) :: rank, info
        real(dp), intent(in) :: rcond
        real(dp), allocatable :: hp(:, :), v(:, :), m(:, :), rhs(:), sol(:), work(:), r(:, :)
        real(dp) :: h(ch%n), wq(1)
        integer :: n, k, nw, nr, j, lwork, nu
        n = ch%n
        k = ch%k
        nw = ch%nw
        nr = size(brhs)
        rank = 0
        z = 0.0_dp
        w = 0.0_dp
        if (.not. ch%factored .or. any(shape(d) /= [n, k]) .or. &
            any(shape(bz1) /= [nr, n]) .or. any(shape(bzk) /= [nr, n]) .or. &
            any(shape(bw) /= [nr, nw]) .or. any(shape(z) /= [n, k + 1]) .or. &
            size(w) /= nw) then
            info = CM_BAD_INPUT
            return
        end if
        if (.not. (la_finite(reshape(d, [n*k])) .and. la_finite(brhs))) then
            info = CM_NONFINITE
            return
        end if
        allocate (hp(n, k), v(2*n, 1))
        call dormqr('L', 'T', 2*n, 1, n, ch%qv(:, :, 1), 2*n, ch%qtau(:, 1), v, 2*n, wq, &
                    -1, info)
        lwork = max(1, int(wq(1)), n)
        allocate (work(lwork))
        h = d(:, 1)
        do j = 2, k
            v(1:n, 1) = h
            v(n + 1:, 1) = d(:, j)
            call dormqr('L', 'T', 2*n, 1, n, ch%qv(:, :, j), 2*n, ch%qtau(:, j), v, 2*n, &
                        work, lwork, info)
            hp(:, j) = v(1:n, 1)
            h = v(n + 1:, 1)
        end do
        ! the final system in (z_1, z_(K+1), w)
        nu = 2*n + nw
        allocate (m(n + nr, nu), rhs(n + nr), sol(nu))
        m(1:n, 1:n) = ch%e
        m(1:n, n + 1:2*n) = ch%f
        m(1:n, 2*n + 1:) = ch%g
        m(n + 1:, 1:n) = bz1
        m(n + 1:, n + 1:2*n) = bzk
        m(n + 1:, 2*n + 1:) = bw
        rhs(1:n) = h
        rhs(n + 1:) = brhs
        call lstsq_solve(m, rhs, sol, rank, info, rcond)
        if (info /= CM_SUCCESS) return
        z(:, 1) = sol(1:n)
        z(:, k + 1) = sol(n + 1:2*n)
        w = sol(2*n + 1:)
        ! back substitution: R_j z_j = h'_j - E'_j z_1 - F'_j z_(j+1) - G'_j w
        allocate (r(n, n))
        do j = k, 2, -1
            v(1:n, 1) = hp(:, j) - matmul(ch%pe(:, :, j), z(:, 1)) &
                        - matmul(ch%pf(:, :, j), z(:, j + 1))
            if (nw > 0) v(1:n, 1) = v(1:n, 1) - matmul(ch%pg(:, :, j), w)
            r = ch%qv(1:n, :, j)
            call dtrtrs('U', 'N', 'N', n, 1, r, n, v, 2*n, info)
            if (info /= 0) then
                info = CM_SINGULAR
                return
            end if
            z(:, j) = v(1:n, 1)
        end do
        info = CM_SUCCESS
    end subroutine chain_solve

    !> Minimum-norm least-squares solution of a x = b (dgelsd); rank returned.
    subroutine lstsq_solve(a, b, x, rank, info, rcond)
        real(dp), intent(in) :: a(:, :), b(:)
        real(dp), intent(out) :: x(:)
        integer, intent(out) :: rank, info
        real(dp), intent(in) :: rcond
        real(dp), allocatable :: aa(:, :), bb(:, :), s(:), work(:)
        integer, allocatable :: iwork(:)
        real(dp) :: wq(1)
        integer :: m, n, ldb, lwork
        m = size(a, 1)
        n = size(a, 2)
        ldb = max(m, n)
        if (.not. (la_finite(a) .and. la_finite(b))) then
            rank = 0
            x = 0.0_dp
            info = CM_NONFINITE
            return
        end if
        allocate (aa(m, n), bb(ldb, 1), s(min(m, n)), iwork(64*max(m, n) + 64))
        aa = a
        bb = 0.0_dp
        bb(1:m, 1) = b
        call dgelsd(m, n, 1, aa, m, bb, ldb, s, rcond, rank, wq, -1, iwork, info)
        lwork = max(1, int(wq(1)))
        allocate (work(lwork))
        call dgelsd(m, n, 1, aa, m, bb, ldb, s, rcond, rank, work, lwork, iwork, info)
        if (info /= 0) then
            info = CM_NO_CONVERGENCE
            return
        end if
        x = bb(1:n, 1)
        info = CM_SUCCESS
    end subroutine lstsq_solve

end module conmech_block_chain
