!> The Schur-complement solve of the constrained systems' KKT systems: S x = r for a
!! symmetric positive semi-definite S, by pivoted Cholesky when S has full rank and the
!! minimum-norm least-squares solution otherwise (redundant constraints).
module conmech_schur
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_lapack, only: dpotrs, dpstrf, dpstf2, dgelsd, la_finite
    implicit none
    private

    public :: schur_solve

contains

    !> Solve S x = r for the symmetric positive semi-definite S (m x m) and k right-hand
    !! sides: pivoted Cholesky (dpstrf) when S has full rank, else the minimum-norm
    !! solution by dgelsd. rank = numerical rank (relative tolerance 1e-11).
    subroutine schur_solve(s, r, rank, info)
        real(dp), intent(in) :: s(:, :)
        real(dp), intent(inout) :: r(:, :)
        integer, intent(out) :: rank, info
        real(dp) :: f(size(s, 1), size(s, 1)), work(2*size(s, 1)), tmp(size(r, 1), size(r, 2))
        real(dp) :: sv(size(s, 1)), tol, wq(1)
        real(dp), allocatable :: wk(:)
        integer :: piv(size(s, 1)), m, k, lainfo, i, lwork
        integer, allocatable :: iwork(:)
        m = size(s, 1)
        k = size(r, 2)
        info = CM_SUCCESS
        rank = 0
        if (m == 0) return
        if (.not. (la_finite(s) .and. la_finite(r))) then
            info = CM_NONFINITE
            return
        end if
        f = s
        tol = 1.0e-11_dp*maxval([(abs(s(i, i)), i=1, m)])
        if (m <= 32) then
            call dpstf2('U', m, f, m, piv, rank, tol, work, lainfo)
        else
            call dpstrf('U', m, f, m, piv, rank, tol, work, lainfo)
        end if
        if (lainfo < 0) then
            info = CM_LAPACK_ERROR
            return
        end if
        if (rank == m .and. lainfo == 0) then
            do i = 1, m
                tmp(i, :) = r(piv(i), :)
            end do
            call dpotrs('U', m, k, f, m, tmp, m, lainfo)
            do i = 1, m
                r(piv(i), :) = tmp(i, :)
            end do
            return
        end if
        ! rank deficient: minimum-norm least-squares solution
        f = s
        call dgelsd(m, m, k, f, m, r, m, sv, 1.0e-11_dp, rank, wq, -1, piv, lainfo)
        lwork = max(1, int(wq(1)))
        allocate (wk(lwork), iwork(max(1, 3*m*max(1, int(log(real(m, dp))/log(2.0_dp)) + 1) &
                                      + 11*m)))
        f = s
        call dgelsd(m, m, k, f, m, r, m, sv, 1.0e-11_dp, rank, wk, lwork, iwork, lainfo)
        if (lainfo /= 0) info = CM_LAPACK_ERROR
    end subroutine schur_solve

end module conmech_schur
