!> Test functions of the bifurcations of periodic orbits, from the Floquet multipliers.
!!
!! The monodromy of an autonomous system has the trivial multiplier 1 (the flow direction);
!! that of a conservative one a double trivial 1 (flow and energy: a Jordan block, only
!! accurate to ~sqrt(eps) as eigenvalues of the formed matrix). The multipliers come from
!! conmech_periodic_multipliers, where the flow direction is deflated exactly (its
!! multiplier is the first of the set, and a conservative system's second trivial one a
!! simple eigenvalue of the rest): a multiplier crossing 1 near the trivial one is not
!! mistaken for it. Without the deflation (a forced system), or for the second trivial
!! multiplier of a conservative system, `nontrivial_multipliers` drops the multipliers
!! nearest to 1. From the others (mu_i):
!! - branch point / period-preserving bifurcation (a real multiplier through +1):
!!   psi_bp = prod over the non-trivial mu_i of (mu_i - 1), real (a complex pair gives
!!   |mu - 1|^2 > 0) and continuous where a pair on the unit circle meets at +1 and
!!   leaves it along the real axis (mu, 1/mu: a negative factor), as at the halo
!!   bifurcation of a conservative family;
!! - period doubling (a real multiplier through -1): psi_pd = prod over the non-trivial
!!   mu_i of (mu_i + 1), likewise;
!! - Neimark-Sacker (a complex pair through the unit circle): psi_ns = prod over i < j of
!!   (mu_i mu_j - 1) (the eigenvalues of the bialternate product, Kuznetsov 2004, sec.
!!   10.2); it also vanishes at a neutral saddle (real mu, 1/mu), which the caller tells
!!   apart by `ns_is_complex`.
!! For a conservative planar orbit (4 x 4 monodromy) the trace gives the non-trivial pair
!! far more accurately: S = (trace M - 2)/2; psi_bp = S - 1, psi_pd = S + 1 (S through +1
!! or -1: the pair meets on the real axis at +1 or -1).
module conmech_multiplier_tests
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_periodic_multipliers, only: multiplier_set
    implicit none
    private

    public :: multiplier_tests, nontrivial_multipliers, ns_is_complex

contains

    !> The test functions psi(1:3) = (bp, pd, ns) of the multiplier set `ms` and the
    !! stability index: S = (trace - 2)/2 for a conservative 4 x 4 monodromy (`trace` of
    !! the monodromy), else the largest |mu| among the non-trivial multipliers.
    subroutine multiplier_tests(ms, ntrivial, conservative, trace, psi, s, info)
        type(multiplier_set), intent(in) :: ms
        integer, intent(in) :: ntrivial
        logical, intent(in) :: conservative
        real(dp), intent(in) :: trace
        real(dp), intent(out) :: psi(3), s
        integer, intent(out) :: info
        real(dp), allocatable :: nr(:), ni(:)
        integer :: n, k
        psi = 0.0_dp
        s = 0.0_dp
        info = ms%info
        if (info /= CM_SUCCESS) return
        n = size(ms%mr)
        allocate (nr(n), ni(n))
        if (ms%deflated .and. ntrivial >= 1) then
            call nontrivial_multipliers(ms%mr(2:), ms%mi(2:), ntrivial - 1, nr, ni, k)
        else
            call nontrivial_multipliers(ms%mr, ms%mi, ntrivial, nr, ni, k)
        end if
        if (conservative .and. n == 4) then
            s = 0.5_dp*(trace - 2.0_dp)
            psi(1) = s - 1.0_dp
            psi(2) = s + 1.0_dp
            psi(3) = 1.0_dp
            return
        end if
        psi(1) = real(product(cmplx(nr(1:k) - 1.0_dp, ni(1:k), dp)), dp)
        psi(2) = real(product(cmplx(nr(1:k) + 1.0_dp, ni(1:k), dp)), dp)
        psi(3) = ns_product(nr(1:k), ni(1:k))
        if (conservative) psi(3) = 1.0_dp
        s = 0.0_dp
        if (k > 0) s = maxval(sqrt(nr(1:k)**2 + ni(1:k)**2))
    end subroutine multiplier_tests

    !> Drop the ntrivial multipliers nearest to 1; the k others in (nr, ni).
    pure subroutine nontrivial_multipliers(mr, mi, ntrivial, nr, ni, k)
        real(dp), intent(in) :: mr(:), mi(:)
        integer, intent(in) :: ntrivial
        real(dp), intent(out) :: nr(:), ni(:)
        integer, intent(out) :: k
        logical :: keep(size(mr))
        real(dp) :: d(size(mr))
        integer :: j, i
        keep = .true.
        d = sqrt((mr - 1.0_dp)**2 + mi**2)
        do j = 1, min(ntrivial, size(mr))
            i = minloc(d, 1, mask=keep)
            keep(i) = .false.
        end do
        k = 0
        nr = 0.0_dp
        ni = 0.0_dp
        do i = 1, size(mr)
            if (keep(i)) then
                k = k + 1
                nr(k) = mr(i)
                ni(k) = mi(i)
            end if
        end do
    end subroutine nontrivial_multipliers

    !> prod over i < j of (mu_i mu_j - 1): real, since complex mu come in conjugate pairs.
    pure real(dp) function ns_product(nr, ni) result(p)
        real(dp), intent(in) :: nr(:), ni(:)
        complex(dp) :: acc, a, b
        integer :: i, j
        acc = (1.0_dp, 0.0_dp)
        do i = 1, size(nr)
            a = cmplx(nr(i), ni(i), dp)
            do j = i + 1, size(nr)
                b = cmplx(nr(j), ni(j), dp)
                acc = acc*(a*b - 1.0_dp)
            end do
        end do
        p = real(acc, dp)
    end function ns_product

    !> At a zero of psi_ns: is the pair with mu_i mu_j nearest 1 a complex pair (a
    !! Neimark-Sacker point) rather than a real pair mu, 1/mu (a neutral saddle)?
    pure logical function ns_is_complex(mr, mi, ntrivial) result(cplx)
        real(dp), intent(in) :: mr(:), mi(:)
        integer, intent(in) :: ntrivial
        real(dp) :: nr(size(mr)), ni(size(mr)), best, d
        complex(dp) :: a, b
        integer :: k, i, j
        call nontrivial_multipliers(mr, mi, ntrivial, nr, ni, k)
        best = huge(1.0_dp)
        cplx = .false.
        do i = 1, k
            a = cmplx(nr(i), ni(i), dp)
            do j = i + 1, k
                b = cmplx(nr(j), ni(j), dp)
                d = abs(a*b - 1.0_dp)
                if (d < best) then
                    best = d
                    cplx = ni(i) /= 0.0_dp .and. ni(j) /= 0.0_dp
                end if
            end do
        end do
    end function ns_is_complex

end module conmech_multiplier_tests
