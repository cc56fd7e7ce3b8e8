!> Explicit interfaces to LAPACK's orthogonal factorisations and elementary reflectors:
!! QR (dgeqrf), applying its Q (dormqr), generating and applying one Householder reflector
!! (dlarfg, dlarf) and triangular solves (dtrtrs). The periodic eigenvalue method
!! (conmech_periodic_schur) and the structured elimination of periodic boundary-value
!! problems (conmech_block_chain) are built from them. Kept apart from conmech_lapack,
!! whose interfaces serve the dense solves and eigenproblems.
module conmech_lapack_qr
    use conmech_kinds, only: dp
    implicit none
    private

    public :: dgeqrf, dormqr, dlarfg, dlarf, dtrtrs

    interface
        subroutine dgeqrf(m, n, a, lda, tau, work, lwork, info)
            import :: dp
            integer, intent(in) :: m, n, lda, lwork
            real(dp), intent(inout) :: a(lda, *)
            real(dp), intent(out) :: tau(*), work(*)
            integer, intent(out) :: info
        end subroutine dgeqrf
        subroutine dormqr(side, trans, m, n, k, a, lda, tau, c, ldc, work, lwork, info)
            import :: dp
            character(len=1), intent(in) :: side, trans
            integer, intent(in) :: m, n, k, lda, ldc, lwork
            real(dp), intent(in) :: a(lda, *), tau(*)
            real(dp), intent(inout) :: c(ldc, *)
            real(dp), intent(out) :: work(*)
            integer, intent(out) :: info
        end subroutine dormqr
        subroutine dlarfg(n, alpha, x, incx, tau)
            import :: dp
            integer, intent(in) :: n, incx
            real(dp), intent(inout) :: alpha, x(*)
            real(dp), intent(out) :: tau
        end subroutine dlarfg
        subroutine dlarf(side, m, n, v, incv, tau, c, ldc, work)
            import :: dp
            character(len=1), intent(in) :: side
            integer, intent(in) :: m, n, incv, ldc
            real(dp), intent(in) :: v(*), tau
            real(dp), intent(inout) :: c(ldc, *)
            real(dp), intent(out) :: work(*)
        end subroutine dlarf
        subroutine dtrtrs(uplo, trans, diag, n, nrhs, a, lda, b, ldb, info)
            import :: dp
            character(len=1), intent(in) :: uplo, trans, diag
            integer, intent(in) :: n, nrhs, lda, ldb
            real(dp), intent(in) :: a(lda, *)
            real(dp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine dtrtrs
    end interface

end module conmech_lapack_qr
