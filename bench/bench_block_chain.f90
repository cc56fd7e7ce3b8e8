!> Cost of one Newton solve of multiple shooting / condensed collocation against the number
!! of segments K: the structured elimination of the block chain (conmech_block_chain:
!! chain_factor + chain_solve, O(K n^3)) against a dense LU solve (LAPACK dgesv) of the
!! same assembled ((K + 1) n + nw) square system, O((K n)^3), in one run.
!!
!!     fpm run --profile release --example bench_block_chain [-- --quick]
!!
!! Blocks: n = 6 (the spatial three-body problem's state), nw = 2 border unknowns (period
!! and parameter), A_k = exp-like transfer matrices with growth (I + h R_k, R_k random, so
!! that the product over the orbit grows as an unstable orbit's monodromy), B_k = -I,
!! C_k random; boundary rows: z_1 - z_(K+1) = e (periodicity, n rows) and two rows on
!! (z_1, w) (phase and pseudo-arclength). Prints a Markdown table: K, CPU time per solve
!! of each (best of 3), the growth exponent between successive K, and the relative
!! difference of the two solutions (both solve the same regular system).
program bench_block_chain
    use conmech_kinds, only: dp
    use conmech_block_chain, only: block_chain, chain_factor, chain_solve
    use conmech_lapack, only: dgesv
    implicit none
    integer, parameter :: n = 6, nw = 2, nr = n + nw
    integer, parameter :: ks(7) = [16, 32, 64, 128, 256, 512, 1024]
    integer, parameter :: kdense_max = 256
    real(dp) :: tc(size(ks)), td(size(ks)), diff(size(ks))
    integer :: i, kmax
    character(len=32) :: arg
    logical :: quick

    quick = .false.
    if (command_argument_count() >= 1) then
        call get_command_argument(1, arg)
        quick = trim(arg) == "--quick"
    end if
    kmax = size(ks)
    if (quick) kmax = 4
    tc = -1
    td = -1
    diff = -1
    do i = 1, kmax
        call run(ks(i), tc(i), td(i), diff(i))
    end do
    write (*, '(a)') "| K | unknowns | chain: us/solve | exponent | dense LU: us/solve | "// &
        "exponent | dense/chain | max rel. difference |"
    write (*, '(a)') "|---|---|---|---|---|---|---|---|"
    do i = 1, kmax
        write (*, '("| ",i0," | ",i0," | ",f0.1," | ",a," | ",a," | ",a," | ",a," | ",a," |")') &
            ks(i), (ks(i) + 1)*n + nw, 1e6_dp*tc(i), expo(tc, i), num(1e6_dp*td(i)), &
            expo(td, i), num(td(i)/tc(i)), merge(sci(diff(i)), "-         ", diff(i) >= 0)
    end do

contains

    function num(x) result(s)
        real(dp), intent(in) :: x
        character(len=:), allocatable :: s
        character(len=32) :: b
        if (x < 0) then
            s = "-"
        else
            write (b, '(f0.1)') x
            s = trim(b)
        end if
    end function num

    function sci(x) result(s)
        real(dp), intent(in) :: x
        character(len=:), allocatable :: s
        character(len=32) :: b
        write (b, '(es9.2)') x
        s = trim(b)
    end function sci

    function expo(t, i) result(s)
        real(dp), intent(in) :: t(:)
        integer, intent(in) :: i
        character(len=:), allocatable :: s
        character(len=32) :: b
        if (i == 1) then
            s = ""
        else if (t(i) <= 0 .or. t(i - 1) <= 0) then
            s = "-"
        else
            write (b, '(f0.2)') log(t(i)/t(i - 1))/log(real(ks(i), dp)/ks(i - 1))
            s = trim(b)
        end if
    end function expo

    subroutine run(k, tchain, tdense, rdiff)
        integer, intent(in) :: k
        real(dp), intent(out) :: tchain, tdense, rdiff
        real(dp), allocatable :: a(:, :, :), b(:, :, :), c(:, :, :), d(:, :), z(:, :), w(:)
        real(dp), allocatable :: bz1(:, :), bzk(:, :), bw(:, :), e(:), big(:, :), rhs(:)
        integer, allocatable :: ipiv(:)
        type(block_chain) :: ch
        real(dp) :: t0, t1, h
        integer :: j, rep, nrep, rank, info, nt, r0, c0, l
        allocate (a(n, n, k), b(n, n, k), c(n, nw, k), d(n, k), z(n, k + 1), w(nw))
        allocate (bz1(nr, n), bzk(nr, n), bw(nr, nw), e(nr))
        call random_seed_fixed()
        h = 4.0_dp/k          ! the product of the K transfer matrices grows like e^(4 |R|)
        do j = 1, k
            call random_number(a(:, :, j))
            a(:, :, j) = h*(2*a(:, :, j) - 1)
            do l = 1, n
                a(l, l, j) = a(l, l, j) + 1.0_dp
            end do
            b(:, :, j) = 0
            do l = 1, n
                b(l, l, j) = -1.0_dp
            end do
            call random_number(c(:, :, j))
            c(:, :, j) = h*c(:, :, j)
            call random_number(d(:, j))
        end do
        bz1 = 0
        bzk = 0
        do l = 1, n
            bz1(l, l) = 1.0_dp
            bzk(l, l) = -1.0_dp
        end do
        call random_number(bz1(n + 1:, :))
        call random_number(bw)
        call random_number(e)
        nrep = 3
        tchain = huge(1.0_dp)
        do rep = 1, nrep
            call cpu_time(t0)
            call chain_factor(ch, a, b, c, info)
            if (info /= 0) error stop "chain_factor failed"
            call chain_solve(ch, d, bz1, bzk, bw, e, z, w, rank, info, 1e-14_dp)
            if (info /= 0) error stop "chain_solve failed"
            call cpu_time(t1)
            tchain = min(tchain, t1 - t0)
        end do
        tdense = -1
        rdiff = -1
        if (k > kdense_max) return
        nt = (k + 1)*n + nw
        allocate (big(nt, nt), rhs(nt), ipiv(nt))
        tdense = huge(1.0_dp)
        do rep = 1, nrep
            ! assembly: block row j holds A_j z_j + B_j z_(j+1) + C_j w = d_j
            big = 0
            do j = 1, k
                r0 = (j - 1)*n
                c0 = (j - 1)*n
                big(r0 + 1:r0 + n, c0 + 1:c0 + n) = a(:, :, j)
                big(r0 + 1:r0 + n, c0 + n + 1:c0 + 2*n) = b(:, :, j)
                big(r0 + 1:r0 + n, (k + 1)*n + 1:) = c(:, :, j)
                rhs(r0 + 1:r0 + n) = d(:, j)
            end do
            big(k*n + 1:, 1:n) = bz1
            big(k*n + 1:, k*n + 1:(k + 1)*n) = bzk
            big(k*n + 1:, (k + 1)*n + 1:) = bw
            rhs(k*n + 1:) = e
            call cpu_time(t0)
            call dgesv(nt, 1, big, nt, ipiv, rhs, nt, info)
            call cpu_time(t1)
            if (info /= 0) error stop "dgesv failed"
            tdense = min(tdense, t1 - t0)
        end do
        rdiff = max(maxval(abs(reshape(z, [(k + 1)*n]) - rhs(1:(k + 1)*n))), &
                    maxval(abs(w - rhs((k + 1)*n + 1:)))) / max(1.0_dp, maxval(abs(rhs)))
    end subroutine run

    subroutine random_seed_fixed()
        integer :: sz
        integer, allocatable :: seed(:)
        call random_seed(size=sz)
        allocate (seed(sz))
        seed = 12345
        call random_seed(put=seed)
    end subroutine random_seed_fixed

end program bench_block_chain
