!> The sparse LU (conmech_sparse_lu) and the reverse Cuthill-McKee order
!! (conmech_sparse_order): relative residuals of solves with random sparse real and complex
!! matrices that need row exchanges (a zero diagonal), with the natural and the RCM column
!! orders; a singular matrix reported at the step where no pivot exists; a tridiagonal
!! matrix with its unknowns shuffled: RCM recovers a band, so L and U stay within 4n
!! entries as the unshuffled band (without the order, the shuffled matrix fills in).
program test_sparse_lu
    use conmech_kinds, only: dp
    use conmech_sparse_lu, only: sparse_lu_real, sparse_lu_complex
    use conmech_sparse_order, only: rcm_order
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    integer, parameter :: N = 300, PER = 4
    integer, allocatable :: ap(:), ai(:), q(:), perm(:), zp(:), zi(:)
    real(dp), allocatable :: ax(:), a(:, :), b(:), x(:), u(:), r1(:)
    complex(dp), allocatable :: zx(:), za(:, :), zb(:), zs(:)
    type(sparse_lu_real) :: lu
    type(sparse_lu_complex) :: zlu
    integer :: info, j, k, nnz, i, pass, nnz_rcm
    real(dp) :: r

    ts%name = "test_sparse_lu"
    call random_seed_fixed()
    ! a random sparse matrix: PER random entries per column, the diagonal zero on odd columns
    allocate (a(N, N), u(N))
    a = 0.0_dp
    do j = 1, N
        do k = 1, PER
            call random_number(u(1:2))
            i = 1 + int(u(1)*N)
            i = min(i, N)
            a(i, j) = 2.0_dp*u(2) - 1.0_dp
        end do
        if (j < N) a(j + 1, j) = 1.0_dp
        if (j > 1) a(j - 1, j) = 0.5_dp
        if (mod(j, 2) == 0) then
            a(j, j) = 3.0_dp
        else
            a(j, j) = 0.0_dp
        end if
    end do
    call to_csc(a, ap, ai, ax)
    allocate (b(N), x(N), q(N))
    call random_number(b)
    do pass = 1, 2
        if (pass == 1) then
            q = [(j, j=1, N)]
        else
            call rcm_order(N, ap, ai, q)
            call ts%check(is_perm(q), "RCM order is a permutation")
        end if
        call lu%factor(ap, ai, ax, q, 0.1_dp, info)
        call ts%check(info == 0, "real factorisation succeeds")
        x = b
        call lu%solve(x)
        r = maxval(abs(matmul(a, x) - b))/(maxval(abs(a))*maxval(abs(x)))
        call ts%check_less(r, 1.0e-12_dp, "real relative residual")
        ! pure partial pivoting gives the same solution
        call lu%factor(ap, ai, ax, q, 1.0_dp, info)
        x = b
        call lu%solve(x)
        r = maxval(abs(matmul(a, x) - b))/(maxval(abs(a))*maxval(abs(x)))
        call ts%check_less(r, 1.0e-12_dp, "real relative residual (partial pivoting)")
        ! complex: (alpha + i beta) I - A
        za = cmplx(-a, 0.0_dp, kind=dp)
        do j = 1, N
            za(j, j) = za(j, j) + cmplx(0.7_dp, 1.3_dp, kind=dp)
        end do
        call to_csc(abs(za), zp, zi, r1)
        zx = [(za(zi(k), col_of(zp, k)), k=1, size(zi))]
        call zlu%factor(zp, zi, zx, q, 0.1_dp, info)
        call ts%check(info == 0, "complex factorisation succeeds")
        zb = cmplx(b, -2.0_dp*b, kind=dp)
        zs = zb
        call zlu%solve(zs)
        r = maxval(abs(matmul(za, zs) - zb))/(maxval(abs(za))*maxval(abs(zs)))
        call ts%check_less(r, 1.0e-12_dp, "complex relative residual")
    end do
    ! a singular matrix: a zero column
    a(:, 7) = 0.0_dp
    call to_csc(a, ap, ai, ax)
    q = [(j, j=1, N)]
    call lu%factor(ap, ai, ax, q, 0.1_dp, info)
    call ts%check(info == 7, "singular matrix: no pivot at step 7")
    ! a shuffled tridiagonal matrix: the band recovered by RCM
    deallocate (a)
    allocate (a(N, N), perm(N))
    call random_number(u)
    perm = [(j, j=1, N)]
    do j = N, 2, -1
        k = 1 + min(int(u(j)*j), j - 1)
        i = perm(j)
        perm(j) = perm(k)
        perm(k) = i
    end do
    a = 0.0_dp
    do j = 1, N
        a(perm(j), perm(j)) = 4.0_dp
        if (j > 1) a(perm(j - 1), perm(j)) = -1.0_dp
        if (j < N) a(perm(j + 1), perm(j)) = -1.0_dp
    end do
    call to_csc(a, ap, ai, ax)
    nnz = size(ai)
    call rcm_order(N, ap, ai, q)
    call lu%factor(ap, ai, ax, q, 0.1_dp, info)
    call ts%check(info == 0 .and. lu%factor_nnz() <= 4*N, "shuffled tridiagonal with RCM: "// &
                  "L and U within 4n entries (the band)")
    nnz_rcm = lu%factor_nnz()
    x = b
    call lu%solve(x)
    r = maxval(abs(matmul(a, x) - b))/(maxval(abs(a))*maxval(abs(x)))
    call ts%check_less(r, 1.0e-13_dp, "shuffled tridiagonal: relative residual")
    q = [(j, j=1, N)]
    call lu%factor(ap, ai, ax, q, 0.1_dp, info)
    call ts%check(info == 0 .and. 4*lu%factor_nnz() > 5*nnz_rcm, "shuffled tridiagonal without the "// &
                  "order fills in (L and U over 1.25 times the band)")
    call ts%finish()
    ! main-program allocatables are not freed at exit (the leak check would report them)
    if (allocated(ap)) deallocate (ap)
    if (allocated(ai)) deallocate (ai)
    if (allocated(q)) deallocate (q)
    if (allocated(perm)) deallocate (perm)
    if (allocated(zp)) deallocate (zp)
    if (allocated(zi)) deallocate (zi)
    if (allocated(ax)) deallocate (ax)
    if (allocated(a)) deallocate (a)
    if (allocated(b)) deallocate (b)
    if (allocated(x)) deallocate (x)
    if (allocated(u)) deallocate (u)
    if (allocated(r1)) deallocate (r1)
    if (allocated(zx)) deallocate (zx)
    if (allocated(za)) deallocate (za)
    if (allocated(zb)) deallocate (zb)
    if (allocated(zs)) deallocate (zs)

contains

    subroutine random_seed_fixed()
        integer :: m
        integer, allocatable :: seed(:)
        call random_seed(size=m)
        allocate (seed(m))
        seed = 12345
        call random_seed(put=seed)
    end subroutine random_seed_fixed

    subroutine to_csc(m, p, ii, v)
        real(dp), intent(in) :: m(:, :)
        integer, allocatable, intent(out) :: p(:), ii(:)
        real(dp), allocatable, intent(out) :: v(:)
        integer :: c, rr, t
        allocate (p(size(m, 2) + 1), ii(count(m /= 0.0_dp)), v(count(m /= 0.0_dp)))
        t = 0
        p(1) = 1
        do c = 1, size(m, 2)
            do rr = 1, size(m, 1)
                if (m(rr, c) == 0.0_dp .and. rr /= c) cycle
                if (m(rr, c) == 0.0_dp) cycle
                t = t + 1
                ii(t) = rr
                v(t) = m(rr, c)
            end do
            p(c + 1) = t + 1
        end do
    end subroutine to_csc

    integer function col_of(p, pos)
        integer, intent(in) :: p(:), pos
        integer :: c
        col_of = 0
        do c = 1, size(p) - 1
            if (pos >= p(c) .and. pos < p(c + 1)) col_of = c
        end do
    end function col_of

    logical function is_perm(v)
        integer, intent(in) :: v(:)
        logical :: seen(size(v))
        integer :: t
        seen = .false.
        is_perm = .true.
        do t = 1, size(v)
            if (v(t) < 1 .or. v(t) > size(v)) then
                is_perm = .false.
                return
            end if
            if (seen(v(t))) is_perm = .false.
            seen(v(t)) = .true.
        end do
    end function is_perm

end program test_sparse_lu
