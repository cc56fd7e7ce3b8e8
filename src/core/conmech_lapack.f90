!> Explicit interfaces to the LAPACK routines conmech uses, and small safe wrappers.
!!
!! All linear algebra of the library goes through LAPACK (system LAPACK/BLAS, linked by
!! fpm.toml and meson.build). The wrappers allocate their own workspace (after a workspace
!! query where LAPACK offers one) and return an `info` code from `conmech_status`.
module conmech_lapack
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_size_t
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_SINGULAR, CM_LAPACK_ERROR, CM_BAD_INPUT, &
        CM_NO_CONVERGENCE, CM_NONFINITE
    implicit none
    private

    public :: dgesv, dgetrf, dgetrs, dgecon, dgeev, dpotrf, dpotrs, dsysv, dsyev, dgelsd, &
        dgelsy, dlange, dpstrf, dgesvd, dgeqp3, dgees
    public :: la_solve, la_eig, la_sym_eig, la_det, la_finite, la_status, la_input_status

    !> True if every entry is finite (call it before handing data to LAPACK: NaN input
    !! makes some routines report an illegal argument).
    interface la_finite
        module procedure la_finite_1, la_finite_2
    end interface la_finite
    public :: dpotf2, dpstf2   ! unblocked forms: no ilaenv call, fast for tiny matrices
    public :: dtrsv   ! BLAS triangular solve, one right-hand side
    public :: zgetrf, zgetrs   ! complex LU (Radau IIA's complex iteration matrix)
    public :: dgetf2, dpotri   ! unblocked LU, inverse from the Cholesky factor (RATTLE)

    interface
        subroutine dgesv(n, nrhs, a, lda, ipiv, b, ldb, info)
            import :: dp
            integer, intent(in) :: n, nrhs, lda, ldb
            real(dp), intent(inout) :: a(lda, *), b(ldb, *)
            integer, intent(out) :: ipiv(*), info
        end subroutine dgesv
        subroutine dgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
            import :: dp
            character(len=1), intent(in) :: trans
            integer, intent(in) :: n, nrhs, lda, ldb, ipiv(*)
            real(dp), intent(in) :: a(lda, *)
            real(dp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine dgetrs
        subroutine dgecon(norm, n, a, lda, anorm, rcond, work, iwork, info)
            import :: dp
            character(len=1), intent(in) :: norm
            integer, intent(in) :: n, lda
            real(dp), intent(in) :: a(lda, *), anorm
            real(dp), intent(out) :: rcond, work(*)
            integer, intent(out) :: iwork(*), info
        end subroutine dgecon
        function dlange(norm, m, n, a, lda, work) result(r)
            import :: dp
            character(len=1), intent(in) :: norm
            integer, intent(in) :: m, n, lda
            real(dp), intent(in) :: a(lda, *)
            real(dp), intent(inout) :: work(*)
            real(dp) :: r
        end function dlange
        subroutine dgeev(jobvl, jobvr, n, a, lda, wr, wi, vl, ldvl, vr, ldvr, work, lwork, info)
            import :: dp
            character(len=1), intent(in) :: jobvl, jobvr
            integer, intent(in) :: n, lda, ldvl, ldvr, lwork
            real(dp), intent(inout) :: a(lda, *)
            real(dp), intent(out) :: wr(*), wi(*), vl(ldvl, *), vr(ldvr, *), work(*)
            integer, intent(out) :: info
        end subroutine dgeev
        subroutine dpotrs(uplo, n, nrhs, a, lda, b, ldb, info)
            import :: dp
            character(len=1), intent(in) :: uplo
            integer, intent(in) :: n, nrhs, lda, ldb
            real(dp), intent(in) :: a(lda, *)
            real(dp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine dpotrs
        subroutine dsysv(uplo, n, nrhs, a, lda, ipiv, b, ldb, work, lwork, info)
            import :: dp
            character(len=1), intent(in) :: uplo
            integer, intent(in) :: n, nrhs, lda, ldb, lwork
            real(dp), intent(inout) :: a(lda, *), b(ldb, *)
            integer, intent(out) :: ipiv(*), info
            real(dp), intent(out) :: work(*)
        end subroutine dsysv
        subroutine dsyev(jobz, uplo, n, a, lda, w, work, lwork, info)
            import :: dp
            character(len=1), intent(in) :: jobz, uplo
            integer, intent(in) :: n, lda, lwork
            real(dp), intent(inout) :: a(lda, *)
            real(dp), intent(out) :: w(*), work(*)
            integer, intent(out) :: info
        end subroutine dsyev
        subroutine dgelsd(m, n, nrhs, a, lda, b, ldb, s, rcond, rank, work, lwork, iwork, info)
            import :: dp
            integer, intent(in) :: m, n, nrhs, lda, ldb, lwork
            real(dp), intent(inout) :: a(lda, *), b(ldb, *)
            real(dp), intent(out) :: s(*), work(*)
            real(dp), intent(in) :: rcond
            integer, intent(out) :: rank, iwork(*), info
        end subroutine dgelsd
        subroutine dgelsy(m, n, nrhs, a, lda, b, ldb, jpvt, rcond, rank, work, lwork, info)
            import :: dp
            integer, intent(in) :: m, n, nrhs, lda, ldb, lwork
            real(dp), intent(inout) :: a(lda, *), b(ldb, *)
            integer, intent(inout) :: jpvt(*)
            real(dp), intent(in) :: rcond
            integer, intent(out) :: rank, info
            real(dp), intent(out) :: work(*)
        end subroutine dgelsy
        subroutine dgesvd(jobu, jobvt, m, n, a, lda, s, u, ldu, vt, ldvt, work, lwork, info)
            import :: dp
            character(len=1), intent(in) :: jobu, jobvt
            integer, intent(in) :: m, n, lda, ldu, ldvt, lwork
            real(dp), intent(inout) :: a(lda, *)
            real(dp), intent(out) :: s(*), u(ldu, *), vt(ldvt, *), work(*)
            integer, intent(out) :: info
        end subroutine dgesvd
        subroutine dgeqp3(m, n, a, lda, jpvt, tau, work, lwork, info)
            import :: dp
            integer, intent(in) :: m, n, lda, lwork
            real(dp), intent(inout) :: a(lda, *)
            integer, intent(inout) :: jpvt(*)
            real(dp), intent(out) :: tau(*), work(*)
            integer, intent(out) :: info
        end subroutine dgeqp3
        !> Real Schur form A = Z T Z^T, optionally ordered: the eigenvalues for which
        !! select(wr, wi) is true lead (sdim of them).
        subroutine dgees(jobvs, sort, select, n, a, lda, sdim, wr, wi, vs, ldvs, work, &
                         lwork, bwork, info)
            import :: dp
            character(len=1), intent(in) :: jobvs, sort
            interface
                logical function select(wr, wi)
                    import :: dp
                    real(dp), intent(in) :: wr, wi
                end function select
            end interface
            integer, intent(in) :: n, lda, ldvs, lwork
            real(dp), intent(inout) :: a(lda, *)
            integer, intent(out) :: sdim, info
            real(dp), intent(out) :: wr(*), wi(*), vs(ldvs, *), work(*)
            logical, intent(out) :: bwork(*)
        end subroutine dgees
    end interface

    !> The signatures that several LAPACK routines share.
    abstract interface
        !> LU with partial pivoting of an m x n matrix (dgetrf; dgetf2 unblocked).
        subroutine la_lu_factor(m, n, a, lda, ipiv, info)
            import :: dp
            integer, intent(in) :: m, n, lda
            real(dp), intent(inout) :: a(lda, *)
            integer, intent(out) :: ipiv(*), info
        end subroutine la_lu_factor
        !> Cholesky factor in place (dpotrf; dpotf2 unblocked), or the inverse from it
        !! (dpotri).
        subroutine la_cholesky(uplo, n, a, lda, info)
            import :: dp
            character(len=1), intent(in) :: uplo
            integer, intent(in) :: n, lda
            real(dp), intent(inout) :: a(lda, *)
            integer, intent(out) :: info
        end subroutine la_cholesky
        !> Pivoted Cholesky factor of a semidefinite matrix, with its rank (dpstrf; dpstf2
        !! unblocked).
        subroutine la_pivoted_cholesky(uplo, n, a, lda, piv, rank, tol, work, info)
            import :: dp
            character(len=1), intent(in) :: uplo
            integer, intent(in) :: n, lda
            real(dp), intent(inout) :: a(lda, *)
            integer, intent(out) :: piv(*), rank, info
            real(dp), intent(in) :: tol
            real(dp), intent(out) :: work(*)
        end subroutine la_pivoted_cholesky
    end interface

    ! The unblocked forms (dgetf2, dpotf2, dpstf2) make no block-size query: fast for the
    ! small matrices of mechanical systems.
    procedure(la_lu_factor) :: dgetrf, dgetf2
    procedure(la_cholesky) :: dpotrf, dpotf2, dpotri
    procedure(la_pivoted_cholesky) :: dpstrf, dpstf2

    interface
        subroutine dtrsv(uplo, trans, diag, n, a, lda, x, incx)
            import :: dp
            character(len=1), intent(in) :: uplo, trans, diag
            integer, intent(in) :: n, lda, incx
            real(dp), intent(in) :: a(lda, *)
            real(dp), intent(inout) :: x(*)
        end subroutine dtrsv
    end interface

    ! Complex LU factorisation and solve.
    interface
        subroutine zgetrf(m, n, a, lda, ipiv, info)
            import :: dp
            integer, intent(in) :: m, n, lda
            complex(dp), intent(inout) :: a(lda, *)
            integer, intent(out) :: ipiv(*), info
        end subroutine zgetrf
        subroutine zgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
            import :: dp
            character(len=1), intent(in) :: trans
            integer, intent(in) :: n, nrhs, lda, ldb
            complex(dp), intent(in) :: a(lda, *)
            integer, intent(in) :: ipiv(*)
            complex(dp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine zgetrs
    end interface

contains

    !> conmech's replacement for LAPACK's error handler XERBLA (Fortran name `xerbla`).
    !!
    !! Reference LAPACK's XERBLA prints a line and executes STOP, which would end the
    !! program, and the Python interpreter that imported conmech, with exit status 0. LAPACK
    !! documents that users may supply their own XERBLA: this one does nothing, so the
    !! routine returns with its negative INFO, which the callers turn into a status
    !! (CM_LAPACK_ERROR) with a message. It lives in this module so that every program that
    !! uses conmech's LAPACK layer (la_* or la_finite) links it.
    subroutine conmech_xerbla(srname, info, srname_len) bind(c, name="xerbla_")
        character(kind=c_char), intent(in) :: srname(*)   !! routine name (not used)
        integer(c_int), intent(in) :: info                 !! bad argument (not used)
        integer(c_size_t), value :: srname_len             !! hidden length (not used)
    end subroutine conmech_xerbla

    pure logical function la_finite_1(a) result(ok)
        real(dp), intent(in) :: a(:)
        ok = all(abs(a) <= huge(1.0_dp))
    end function la_finite_1

    pure logical function la_finite_2(a) result(ok)
        real(dp), intent(in) :: a(:, :)
        ok = all(abs(a) <= huge(1.0_dp))
    end function la_finite_2

    !> Solve A X = B for a general square A by LU (dgesv). A and B are not changed.
    !! info = CM_SINGULAR if A is exactly singular or its reciprocal condition number
    !! (1-norm, dgecon) is below `rcond_min` (default 1e3*epsilon).
    subroutine la_solve(a, b, x, info, rcond_min)
        real(dp), intent(in) :: a(:, :), b(:, :)
        real(dp), intent(out) :: x(:, :)
        integer, intent(out) :: info
        real(dp), intent(in), optional :: rcond_min
        real(dp), allocatable :: lu(:, :), work(:)
        integer, allocatable :: ipiv(:), iwork(:)
        integer :: n, nrhs, lainfo
        real(dp) :: anorm, rcond, rmin
        n = size(a, 1)
        nrhs = size(b, 2)
        info = la_input_status(size(a, 2) == n .and. size(b, 1) == n .and. size(x, 1) == n &
                               .and. size(x, 2) == nrhs, a, b)
        if (info /= CM_SUCCESS) return
        rmin = 1.0e3_dp*epsilon(1.0_dp)
        if (present(rcond_min)) rmin = rcond_min
        allocate (lu(n, n), ipiv(n), work(4*n), iwork(n))
        lu = a
        anorm = dlange('1', n, n, lu, n, work)
        call dgetrf(n, n, lu, n, ipiv, lainfo)
        info = la_status(lainfo, CM_SINGULAR)
        if (info /= CM_SUCCESS) return
        call dgecon('1', n, lu, n, anorm, rcond, work, iwork, lainfo)
        if (rcond < rmin) then
            info = CM_SINGULAR
            return
        end if
        x = b
        call dgetrs('N', n, nrhs, lu, n, ipiv, x, n, lainfo)
        info = CM_SUCCESS
    end subroutine la_solve

    !> The status of a LAPACK return code: CM_SUCCESS for 0, CM_LAPACK_ERROR for an illegal
    !! argument (< 0), and `positive` for the routine's own failure (> 0: a singular
    !! factor, an iteration that did not converge, ...).
    elemental integer function la_status(lainfo, positive) result(info)
        integer, intent(in) :: lainfo, positive
        if (lainfo < 0) then
            info = CM_LAPACK_ERROR
        else if (lainfo > 0) then
            info = positive
        else
            info = CM_SUCCESS
        end if
    end function la_status

    !> The status of a wrapper's input: CM_BAD_INPUT unless `sizes_ok` (the caller's test
    !! that the arrays' shapes agree), then CM_NONFINITE if `a` (or `b`) holds a NaN or an
    !! Inf, else CM_SUCCESS.
    pure integer function la_input_status(sizes_ok, a, b) result(info)
        logical, intent(in) :: sizes_ok
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(in), optional :: b(:, :)
        info = CM_SUCCESS
        if (.not. sizes_ok) then
            info = CM_BAD_INPUT
        else if (.not. la_finite(a)) then
            info = CM_NONFINITE
        else if (present(b)) then
            if (.not. la_finite(b)) info = CM_NONFINITE
        end if
    end function la_input_status

    !> Eigenvalues (and optionally right eigenvectors) of a general real matrix (dgeev).
    subroutine la_eig(a, wr, wi, info, vr)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(out) :: wr(:), wi(:)
        integer, intent(out) :: info
        real(dp), intent(out), optional :: vr(:, :)
        real(dp), allocatable :: tmp(:, :), work(:), vl(:, :), v(:, :)
        real(dp) :: wq(1)
        integer :: n, lwork, lainfo
        character(len=1) :: jobvr
        n = size(a, 1)
        info = la_input_status(size(a, 2) == n .and. size(wr) == n .and. size(wi) == n, a)
        if (info /= CM_SUCCESS) return
        jobvr = 'N'
        if (present(vr)) jobvr = 'V'
        allocate (tmp(n, n), vl(1, 1), v(n, n))
        tmp = a
        call dgeev('N', jobvr, n, tmp, n, wr, wi, vl, 1, v, n, wq, -1, lainfo)
        lwork = max(1, int(wq(1)))
        allocate (work(lwork))
        call dgeev('N', jobvr, n, tmp, n, wr, wi, vl, 1, v, n, work, lwork, lainfo)
        info = la_status(lainfo, CM_NO_CONVERGENCE)
        if (info == CM_SUCCESS .and. present(vr)) vr = v
    end subroutine la_eig

    !> Eigenvalues (ascending) and optionally eigenvectors of a symmetric matrix (dsyev).
    subroutine la_sym_eig(a, w, info, v)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(out) :: w(:)
        integer, intent(out) :: info
        real(dp), intent(out), optional :: v(:, :)
        real(dp), allocatable :: tmp(:, :), work(:)
        real(dp) :: wq(1)
        integer :: n, lwork, lainfo
        character(len=1) :: jobz
        n = size(a, 1)
        info = la_input_status(size(a, 2) == n .and. size(w) == n, a)
        if (info /= CM_SUCCESS) return
        jobz = 'N'
        if (present(v)) jobz = 'V'
        allocate (tmp(n, n))
        tmp = a
        call dsyev(jobz, 'U', n, tmp, n, w, wq, -1, lainfo)
        lwork = max(1, int(wq(1)))
        allocate (work(lwork))
        call dsyev(jobz, 'U', n, tmp, n, w, work, lwork, lainfo)
        info = la_status(lainfo, CM_NO_CONVERGENCE)
        if (info == CM_SUCCESS .and. present(v)) v = tmp
    end subroutine la_sym_eig

    !> Determinant of a general square matrix from its LU factorisation (dgetrf).
    function la_det(a) result(d)
        real(dp), intent(in) :: a(:, :)
        real(dp) :: d
        real(dp), allocatable :: lu(:, :)
        integer, allocatable :: ipiv(:)
        integer :: n, i, lainfo
        n = size(a, 1)
        allocate (lu(n, n), ipiv(n))
        lu = a
        call dgetrf(n, n, lu, n, ipiv, lainfo)
        if (lainfo < 0) then
            d = 0.0_dp
            return
        end if
        d = 1.0_dp
        do i = 1, n
            d = d*lu(i, i)
            if (ipiv(i) /= i) d = -d
        end do
    end function la_det

end module conmech_lapack
