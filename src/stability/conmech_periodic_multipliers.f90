!> Floquet multipliers of a periodic orbit from its segment state transition matrices
!! Phi_K ... Phi_1 (multiple-shooting segments, pieces of a single-shooting monodromy or
!! the interval transfer matrices of a collocation), with an accuracy estimate.
!!
!! The product is never formed: its eigenvalues come from the periodic QR algorithm
!! (conmech_periodic_schur), backward stable factor by factor, so that the small
!! multipliers of a very unstable orbit keep their digits (|mu_min mu_max - 1| at the
!! level of the factors' own errors, not eps mu_max^2).
!!
!! The flow direction is deflated exactly. For an autonomous system the vector field is
!! carried along the orbit, Phi_k f(y_k) = f(y_{k+1}): with orthogonal Q_k whose first
!! column is f(y_k)/|f(y_k)| (a Householder reflector), Q_{k+1}^T Phi_k Q_k = [r_k, *; e_k,
!! C_k] with e_k ~ 0 (the integration error of the segment). Setting e_k = 0 is a
!! perturbation at that error level; the trivial multiplier is then prod r_k (1 to the
!! integration error), and the other n - 1 are those of the product of the C_k. A
!! conservative system's second trivial multiplier (the energy; a Jordan block with the
!! first, which eigenvalue methods split by sqrt(error)) becomes a simple eigenvalue of the
!! deflated product, accurate to the error level itself. A vector field that the factors
!! do not carry (defect above 1e-6: a forced system, whose f(t, y) is not a solution of
!! the variational equations) is not deflated.
!!
!! Accuracy estimate. Each factor carries a relative error level delta_k: the measured
!! defect |Phi_k f(y_k) - f(y_k(end))|/(|Phi_k| |f(y_k)|) of the carried vector field (a
!! direct sample of the segment's STM error), and at least `factor_tol` and 10 eps. The
!! multipliers' sensitivity to perturbations of that size is estimated statistically
!! (Kenney and Laub 1994, small-sample statistical condition estimation): the periodic
!! eigenvalues of the factors perturbed by delta_k |C_k| Z_k (Z_k pseudo-random, unit
!! Frobenius norm, a fixed seed) in three samples; err(i) is three times the largest
!! change of multiplier i. The deflated trivial multiplier's error is |prod r_k - 1| plus
!! the sum of the delta_k (its exact value 1 is known).
module conmech_periodic_multipliers
    use, intrinsic :: iso_fortran_env, only: int64
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_lapack, only: la_finite
    use conmech_lapack_qr, only: dlarfg
    use conmech_periodic_schur, only: periodic_eigenvalues
    implicit none
    private

    public :: multiplier_set, product_multipliers, unit_circle_tolerance

    integer, parameter :: NSAMPLES = 3
    !> Largest relative defect |Phi_k f_k - f_(k+1)|/(|Phi_k| |f_k|) for the deflation.
    real(dp), parameter :: DEFLATION_LIMIT = 1.0e-6_dp

    !> Multipliers of a product of segment STMs and their estimated errors.
    type :: multiplier_set
        integer :: info = CM_BAD_INPUT
        real(dp), allocatable :: mr(:), mi(:)  !! the n multipliers (real, imaginary parts)
        real(dp), allocatable :: err(:)        !! estimated absolute error of each
        logical :: deflated = .false.          !! mr(1) is the deflated flow multiplier
        real(dp) :: factor_error = 0.0_dp      !! largest relative error level of a factor
        real(dp) :: accuracy = 0.0_dp          !! largest err(i)/max(1, |mu_i|)
    end type multiplier_set

contains

    !> Multipliers of phi(:, :, K) ... phi(:, :, 1). With `f_start` and `f_end` (the vector
    !! field at the start and at the end of each segment, autonomous systems) the flow
    !! direction is deflated (see the module notes). `factor_tol`: the smallest relative
    !! error level assumed for the factors (e.g. the integrator's tolerance; default
    !! 10 eps).
    subroutine product_multipliers(phi, res, f_start, f_end, factor_tol)
        real(dp), intent(in) :: phi(:, :, :)
        type(multiplier_set), intent(out) :: res
        real(dp), intent(in), optional :: f_start(:, :), f_end(:, :)
        real(dp), intent(in), optional :: factor_tol
        real(dp), allocatable :: c(:, :, :), delta(:), wr(:), wi(:), pr(:), pim(:), dmax(:)
        real(dp), allocatable :: cp(:, :, :)
        real(dp) :: mu_f, ftol, nf
        integer :: n, k, m, s, l, info, off
        logical :: defl
        n = size(phi, 1)
        k = size(phi, 3)
        if (size(phi, 2) /= n .or. n < 1 .or. k < 1) then
            res%info = CM_BAD_INPUT
            return
        end if
        if (.not. la_finite(reshape(phi, [n*n*k]))) then
            res%info = CM_NONFINITE
            return
        end if
        ftol = 10.0_dp*epsilon(1.0_dp)
        if (present(factor_tol)) ftol = max(ftol, factor_tol)
        defl = present(f_start) .and. present(f_end) .and. n >= 2
        if (defl) then
            defl = size(f_start, 1) == n .and. size(f_start, 2) == k .and. &
                   size(f_end, 1) == n .and. size(f_end, 2) == k
        end if
        if (defl) then
            do l = 1, k
                if (.not. (norm2(f_start(:, l)) > 0.0_dp)) defl = .false.
            end do
        end if
        allocate (delta(k), res%mr(n), res%mi(n), res%err(n))
        delta = ftol
        if (defl) then
            call deflate_flow(phi, f_start, f_end, c, mu_f, delta)
            ! a vector field not carried by the STMs (a forced, non-autonomous system, or
            ! a collocation mesh too coarse): no deflation
            if (maxval(delta) > DEFLATION_LIMIT) then
                defl = .false.
                delta = ftol
            end if
        end if
        if (defl) then
            delta = max(delta, ftol)
            m = n - 1
            off = 1
        else
            c = phi
            m = n
            off = 0
        end if
        allocate (wr(m), wi(m), pr(m), pim(m), dmax(m))
        call periodic_eigenvalues(c, wr, wi, info)
        if (info /= CM_SUCCESS) then
            res%info = info
            return
        end if
        ! statistical condition estimate: periodic eigenvalues of perturbed factors
        dmax = 0.0_dp
        allocate (cp(m, m, k))
        do s = 1, NSAMPLES
            do l = 1, k
                call random_unit(cp(:, :, l), s, l)
                nf = norm2(c(:, :, l))
                cp(:, :, l) = c(:, :, l) + delta(l)*nf*cp(:, :, l)
            end do
            call periodic_eigenvalues(cp, pr, pim, info)
            if (info /= CM_SUCCESS) then
                dmax = huge(1.0_dp)
                exit
            end if
            call match_changes(wr, wi, pr, pim, dmax)
        end do
        res%mr(off + 1:n) = wr
        res%mi(off + 1:n) = wi
        res%err(off + 1:n) = min(3.0_dp*dmax, huge(1.0_dp))
        res%deflated = defl
        if (defl) then
            res%mr(1) = mu_f
            res%mi(1) = 0.0_dp
            res%err(1) = abs(mu_f - 1.0_dp) + sum(delta)
        end if
        res%factor_error = maxval(delta)
        res%accuracy = maxval(res%err/max(1.0_dp, sqrt(res%mr**2 + res%mi**2)))
        res%info = CM_SUCCESS
    end subroutine product_multipliers

    !> The factors in bases carried by the flow: c(:, :, l) = (Q_{l+1}^T Phi_l Q_l)(2:n,
    !! 2:n), mu_f = prod (Q_{l+1}^T Phi_l Q_l)(1, 1), and delta(l) the measured relative
    !! defect of the carried vector field.
    subroutine deflate_flow(phi, f_start, f_end, c, mu_f, delta)
        real(dp), intent(in) :: phi(:, :, :), f_start(:, :), f_end(:, :)
        real(dp), allocatable, intent(out) :: c(:, :, :)
        real(dp), intent(out) :: mu_f
        real(dp), intent(inout) :: delta(:)
        real(dp) :: q(size(phi, 1), size(phi, 1), size(phi, 3)), b(size(phi, 1), size(phi, 1))
        real(dp) :: pf(size(phi, 1))
        integer :: n, k, l, ln
        n = size(phi, 1)
        k = size(phi, 3)
        do l = 1, k
            call flow_basis(f_start(:, l), q(:, :, l))
        end do
        allocate (c(n - 1, n - 1, k))
        mu_f = 1.0_dp
        do l = 1, k
            ln = merge(1, l + 1, l == k)
            b = matmul(transpose(q(:, :, ln)), matmul(phi(:, :, l), q(:, :, l)))
            mu_f = mu_f*b(1, 1)
            c(:, :, l) = b(2:n, 2:n)
            pf = matmul(phi(:, :, l), f_start(:, l))
            delta(l) = norm2(pf - f_end(:, l))/(norm2(phi(:, :, l))*norm2(f_start(:, l)))
        end do
    end subroutine deflate_flow

    !> An orthogonal matrix whose first column is f/|f| (a Householder reflector).
    subroutine flow_basis(f, q)
        real(dp), intent(in) :: f(:)
        real(dp), intent(out) :: q(:, :)
        real(dp) :: v(size(f)), alpha, tau
        integer :: n, i
        n = size(f)
        alpha = f(1)
        v(1) = 1.0_dp
        v(2:n) = f(2:n)
        call dlarfg(n, alpha, v(2:n), 1, tau)
        ! H = I - tau v v^T with H f = alpha e1: H e1 = f/alpha
        q = 0.0_dp
        do i = 1, n
            q(i, i) = 1.0_dp
        end do
        do i = 1, n
            q(:, i) = q(:, i) - tau*v(i)*v
        end do
        if (alpha < 0.0_dp) q(:, 1) = -q(:, 1)
    end subroutine flow_basis

    !> Largest change of each multiplier (wr, wi) to its nearest unused perturbed one.
    pure subroutine match_changes(wr, wi, pr, pim, dmax)
        real(dp), intent(in) :: wr(:), wi(:), pr(:), pim(:)
        real(dp), intent(inout) :: dmax(:)
        logical :: used(size(pr))
        real(dp) :: d, best
        integer :: i, j, jb
        used = .false.
        do i = 1, size(wr)
            best = huge(1.0_dp)
            jb = 0
            do j = 1, size(pr)
                if (used(j)) cycle
                d = hypot(pr(j) - wr(i), pim(j) - wi(i))
                if (d < best) then
                    best = d
                    jb = j
                end if
            end do
            if (jb > 0) used(jb) = .true.
            dmax(i) = max(dmax(i), best)
        end do
    end subroutine match_changes

    !> A pseudo-random matrix of unit Frobenius norm, a fixed function of (sample, factor)
    !! (Park and Miller's minimal standard generator, 48271 x mod 2^31 - 1, in 64-bit
    !! integers without overflow; no state kept between calls).
    pure subroutine random_unit(z, sample, factor)
        real(dp), intent(out) :: z(:, :)
        integer, intent(in) :: sample, factor
        integer(int64), parameter :: m = 2147483647_int64, a = 48271_int64
        integer(int64) :: x
        integer :: i, j
        x = mod(int(sample, int64)*1000003_int64 + int(factor, int64)*7919_int64, m) + 1
        do j = 1, size(z, 2)
            do i = 1, size(z, 1)
                x = mod(a*x, m)
                z(i, j) = real(x, dp)/real(m, dp) - 0.5_dp
            end do
        end do
        if (norm2(z) > 0.0_dp) z = z/norm2(z)
    end subroutine random_unit

    !> The tolerance for |mu| <= 1 + tol (stability) of a multiplier set: ten times the
    !! largest error estimate of a multiplier near the unit circle
    !! (1/2 <= |mu| <= 2), and at least `floor`.
    pure real(dp) function unit_circle_tolerance(ms, floor) result(tol)
        type(multiplier_set), intent(in) :: ms
        real(dp), intent(in) :: floor
        real(dp) :: a
        integer :: i
        tol = floor
        if (.not. allocated(ms%err)) return
        do i = 1, size(ms%err)
            a = hypot(ms%mr(i), ms%mi(i))
            if (a >= 0.5_dp .and. a <= 2.0_dp) tol = max(tol, 10.0_dp*ms%err(i))
        end do
    end function unit_circle_tolerance

end module conmech_periodic_multipliers
