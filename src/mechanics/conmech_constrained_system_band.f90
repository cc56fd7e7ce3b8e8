!> The banded paths of conmech_constrained_system: accelerations, multipliers, reactions,
!! residuals and projections when every constraint row has a row window (G by
!! `phi_jac_band`, A by `nh_matrix_band`) and the mass is diagonal or constant with a
!! banded inverse kept by `prepare_mass` (see the parent module and
!! conmech_constrained_band). The rows of C = [G; A] are ordered by their first column
!! (holonomic and Pfaffian rows interleave along a chain), so that S = C M^-1 C^T is
!! banded. Each costs O(n + m (w + kd)^2); when it does not apply it returns
!! ok = .false. and the parent's dense path runs.
submodule(conmech_constrained_system) conmech_constrained_system_band
    use conmech_lapack, only: dpotrs
    use conmech_constrained_band, only: band_width_of, band_schur, band_schur_minv, &
        band_gmul, band_gtmul, band_factor, band_solve, band_minv_mul, band_order, band_windows
    implicit none

    !> The constraint rows at (t, q) as windows ordered by their first column, and the
    !! mass operator (diagonal d, or the kept banded M^-1 of half-bandwidth bm).
    type :: band_rows
        integer :: m = 0            !! number of rows
        integer :: w = 0            !! window width (the larger of jac_width, nh_width)
        integer :: kd = -1          !! superdiagonals of S
        integer :: bm = 0           !! half-bandwidth of M^-1 (0: diagonal)
        logical :: diag = .true.    !! diagonal mass d
        real(dp), allocatable :: d(:)        !! diagonal of M
        real(dp), allocatable :: cb(:, :)    !! ordered windows (m x w)
        real(dp), allocatable :: c0(:)       !! [phi_t; b], original row order
        integer, allocatable :: first(:)     !! first column of each ordered window
        integer, allocatable :: perm(:)      !! original row of ordered row p
    end type band_rows

contains

    pure logical function has_mass_inverse(sys)
        class(constrained_system), intent(in) :: sys
        has_mass_inverse = .false.
        if (.not. (sys%constant_mass .and. allocated(sys%mass_inv_band))) return
        has_mass_inverse = size(sys%mass_inv_band, 1) == sys%n
    end function has_mass_inverse

    module procedure band_ready
        band_ready = sys%n_hol >= 0 .and. sys%n_nh >= 0 .and. sys%n_hol + sys%n_nh > 0 &
                     .and. (sys%diagonal_mass .or. has_mass_inverse(sys))
        if (sys%n_hol > 0) band_ready = band_ready .and. sys%jac_width > 0 .and. &
                                        sys%jac_width <= sys%n
        if (sys%n_nh > 0) band_ready = band_ready .and. sys%nh_width > 0 .and. &
                                       sys%nh_width <= sys%n
    end procedure band_ready

    module procedure cs_nh_matrix_band
        real(dp) :: a(self%n_nh, self%n)
        call self%nh_matrix(t, q, a, b)
        call band_windows(a, ab, first)
    end procedure cs_nh_matrix_band

    module procedure keep_mass_inverse
        real(dp), allocatable :: x(:, :)
        integer :: n, i, j, bm, lainfo
        n = sys%n
        ! only where the banded path can use it (every row with a declared window)
        if (sys%n_hol > 0 .and. sys%jac_width <= 0) return
        if (sys%n_nh > 0 .and. sys%nh_width <= 0) return
        if (sys%n_hol + sys%n_nh == 0) return
        allocate (x(n, n))
        x = 0.0_dp
        do i = 1, n
            x(i, i) = 1.0_dp
        end do
        call dpotrs('U', n, n, mm, n, x, n, lainfo)
        if (lainfo /= 0 .or. .not. la_finite(x)) return
        bm = 0
        do j = 1, n
            do i = 1, n
                if (x(i, j) /= 0.0_dp) bm = max(bm, abs(i - j))
            end do
        end do
        if (4*(2*bm + 1) > n) return       ! not banded enough to pay: the dense path
        allocate (sys%mass_inv_band(n, -bm:bm))
        sys%mass_inv_band = 0.0_dp
        do j = 1, n
            do i = max(1, j - bm), min(n, j + bm)
                sys%mass_inv_band(i, j - i) = x(i, j)
            end do
        end do
    end procedure keep_mass_inverse

    !> The mass operator at (t, q); ok = .false. if a diagonal mass is not positive.
    subroutine setup_mass(sys, t, q, br, ok)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        type(band_rows), intent(inout) :: br
        logical, intent(out) :: ok
        br%diag = sys%diagonal_mass
        if (br%diag) then
            br%bm = 0
            allocate (br%d(sys%n))
            call sys%mass_diagonal(t, q, br%d)
            ok = all(br%d > 0.0_dp .and. br%d < huge(1.0_dp))
        else
            br%bm = -lbound(sys%mass_inv_band, 2)
            ok = .true.
        end if
    end subroutine setup_mass

    !> The ordered row windows of G (and of A unless hol_only) at (t, q), kd of S; c0 =
    !! [phi_t; b] with offsets. ok = .false. if a window leaves 1..n or is not finite.
    subroutine setup_rows(sys, t, q, hol_only, offsets, br, ok)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        logical, intent(in) :: hol_only, offsets
        type(band_rows), intent(inout) :: br
        logical, intent(out) :: ok
        real(dp), allocatable :: gh(:, :), an(:, :), bn(:)
        integer, allocatable :: fr(:), key(:)
        integer :: mh, mn, m, n, w, p, r, off, wr
        n = sys%n
        mh = sys%n_hol
        mn = sys%n_nh
        if (hol_only) mn = 0
        m = mh + mn
        w = 0
        if (mh > 0) w = sys%jac_width
        if (mn > 0) w = max(w, sys%nh_width)
        br%m = m
        br%w = w
        if (allocated(br%cb)) deallocate (br%cb, br%c0, br%first, br%perm)
        allocate (br%cb(m, w), br%c0(m), br%first(m), br%perm(m), fr(m), key(m))
        br%c0 = 0.0_dp
        if (mh > 0) then
            allocate (gh(mh, sys%jac_width))
            call sys%phi_jac_band(t, q, gh, fr(1:mh))
            if (offsets) call sys%phi_t(t, q, br%c0(1:mh))
        end if
        if (mn > 0) then
            allocate (an(mn, sys%nh_width), bn(mn))
            call sys%nh_matrix_band(t, q, an, bn, fr(mh + 1:m))
            br%c0(mh + 1:m) = bn
        end if
        ok = .false.
        do r = 1, m
            wr = sys%jac_width
            if (r > mh) wr = sys%nh_width
            if (fr(r) < 1 .or. fr(r) + wr - 1 > n) return
            key(r) = min(fr(r), n - w + 1)
        end do
        call band_order(key, n, br%perm)
        br%cb = 0.0_dp
        do p = 1, m
            r = br%perm(p)
            br%first(p) = key(r)
            off = fr(r) - key(r)
            if (r <= mh) then
                br%cb(p, off + 1:off + sys%jac_width) = gh(r, :)
            else
                br%cb(p, off + 1:off + sys%nh_width) = an(r - mh, :)
            end if
        end do
        br%kd = band_width_of(br%first, w, n, br%bm)
        ok = br%kd >= 0 .and. la_finite(br%cb)
    end subroutine setup_rows

    !> z = M^-1 x.
    subroutine minv_mul(sys, br, x, z)
        class(constrained_system), intent(in) :: sys
        type(band_rows), intent(in) :: br
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: z(:)
        if (br%diag) then
            z = x/br%d
        else
            call band_minv_mul(sys%mass_inv_band, br%bm, x, z)
        end if
    end subroutine minv_mul

    !> Banded S = C M^-1 C^T (ordered rows), factorised; ok = .false. if not positive
    !! definite.
    subroutine schur_factor(sys, br, ab, ok)
        class(constrained_system), intent(in) :: sys
        type(band_rows), intent(in) :: br
        real(dp), intent(out) :: ab(:, :)
        logical, intent(out) :: ok
        integer :: lainfo
        if (br%diag) then
            call band_schur(br%cb, br%first, 1.0_dp/br%d, br%kd, ab)
        else
            call band_schur_minv(br%cb, br%first, sys%mass_inv_band, br%bm, br%kd, ab)
        end if
        ok = la_finite(ab)
        if (.not. ok) return
        call band_factor(ab, br%kd, lainfo)
        ok = lainfo == 0
    end subroutine schur_factor

    !> Solve S x = r for r in the original row order (x overwrites r).
    subroutine schur_apply(br, ab, r)
        type(band_rows), intent(in) :: br
        real(dp), intent(in) :: ab(:, :)
        real(dp), intent(inout) :: r(:)
        real(dp) :: rs(br%m)
        integer :: lainfo
        rs = r(br%perm)
        call band_solve(ab, br%kd, rs, lainfo)
        r(br%perm) = rs
    end subroutine schur_apply

    !> y = C x in the original row order.
    subroutine cmul(br, x, y)
        type(band_rows), intent(in) :: br
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: y(:)
        real(dp) :: ys(br%m)
        call band_gmul(br%cb, br%first, x, ys)
        y(br%perm) = ys
    end subroutine cmul

    !> z = C^T lam, lam in the original row order.
    subroutine ctmul(br, lam, z)
        type(band_rows), intent(in) :: br
        real(dp), intent(in) :: lam(:)
        real(dp), intent(out) :: z(:)
        call band_gtmul(br%cb, br%first, lam(br%perm), z)
    end subroutine ctmul

    module procedure band_accel
        type(band_rows) :: br
        real(dp) :: r(sys%n_hol + sys%n_nh), w(sys%n_hol + sys%n_nh), ph(sys%n_hol)
        real(dp) :: z(sys%n), f(sys%n)
        integer :: mh, m
        mh = sys%n_hol
        m = mh + sys%n_nh
        call setup_mass(sys, t, q, br, ok)
        if (.not. ok) return
        call setup_rows(sys, t, q, .false., present(alpha), br, ok)
        if (.not. ok) return
        block
            real(dp) :: ab(br%kd + 1, m)
            call schur_factor(sys, br, ab, ok)
            if (.not. ok) return
            call sys%forces(t, q, v, f)
            call minv_mul(sys, br, f, a)
            if (mh > 0) call sys%phi_gamma(t, q, v, r(1:mh))
            if (m > mh) call sys%nh_gamma(t, q, v, r(mh + 1:m))
            if (present(alpha)) then
                call cmul(br, v, w)
                r = r - 2.0_dp*alpha*w
                r = r - 2.0_dp*alpha*br%c0
            end if
            if (present(beta) .and. mh > 0) then
                call sys%phi(t, q, ph)
                r(1:mh) = r(1:mh) - beta**2*ph
            end if
            call cmul(br, a, w)
            r = r - w
            ok = la_finite(r)
            if (.not. ok) return
            call schur_apply(br, ab, r)
            lam = r
            call ctmul(br, lam, z)
            call minv_mul(sys, br, z, f)
            a = a + f
        end block
    end procedure band_accel

    module procedure band_project_position
        type(band_rows) :: br
        real(dp) :: r(sys%n_hol), qk(sys%n), dq(sys%n), z(sys%n), rnorm
        integer :: kd, state
        iters = 0
        info = CM_SUCCESS
        ok = sys%n_hol > 0
        if (.not. ok) return
        call setup_mass(sys, t, q, br, ok)
        if (.not. ok) return
        call setup_rows(sys, t, q, .true., .false., br, ok)
        if (.not. ok) return
        kd = br%kd
        block
            real(dp) :: ab(kd + 1, sys%n_hol)
            call schur_factor(sys, br, ab, ok)
            if (.not. ok) return
            r = ph
            rnorm = maxval(abs(r))
            qk = q
            do iters = 1, max_iter
                if (full .and. iters > 1) then
                    ! Gauss-Newton: G at the iterate (same band: the structure is fixed)
                    call setup_rows(sys, t, qk, .true., .false., br, ok)
                    if (ok) ok = br%kd == kd
                    if (.not. ok) return
                    call schur_factor(sys, br, ab, ok)
                    if (.not. ok) return
                end if
                call schur_apply(br, ab, r)
                call ctmul(br, r, z)
                call minv_mul(sys, br, z, dq)
                if (maxval(abs(dq)) <= 4.0_dp*epsilon(1.0_dp)*max(maxval(abs(qk)), &
                                                                   tiny(1.0_dp))) then
                    q = qk
                    return
                end if
                call position_newton_step(sys, t, tol, dq, qk, r, rnorm, q, state)
                if (state == NEWTON_DIVERGED) exit
                if (state == NEWTON_CONVERGED) return
            end do
        end block
        call position_not_converged(rnorm, max_iter, iters, info, msg)
    end procedure band_project_position

    module procedure band_project_velocity
        type(band_rows) :: br
        real(dp) :: r(sys%n_hol + sys%n_nh), z(sys%n), dv(sys%n), r0, vscale
        info = CM_SUCCESS
        call setup_mass(sys, t, q, br, ok)
        if (.not. ok) return
        call setup_rows(sys, t, q, .false., .true., br, ok)
        if (.not. ok) return
        call cmul(br, v, r)
        r = r + br%c0
        r0 = maxval(abs(r))
        if (r0 == 0.0_dp) return
        block
            real(dp) :: ab(br%kd + 1, br%m)
            call schur_factor(sys, br, ab, ok)
            if (.not. ok) return
            call schur_apply(br, ab, r)
        end block
        call ctmul(br, r, z)
        call minv_mul(sys, br, z, dv)
        v = v - dv
        call cmul(br, v, r)
        vscale = max(maxval(abs(v)), 1.0_dp)*max(maxval(abs(br%cb)), 1.0_dp)
        if (maxval(abs(r + br%c0)) > 1.0e-8_dp*vscale + 1.0e-10_dp*r0) then
            info = CM_NO_CONVERGENCE
            msg = "velocity projection failed: the velocity constraints are inconsistent"
        end if
    end procedure band_project_velocity

    module procedure band_reaction
        type(band_rows) :: br
        br%bm = 0
        if (.not. sys%diagonal_mass) br%bm = -lbound(sys%mass_inv_band, 2)
        call setup_rows(sys, t, q, .false., .false., br, ok)
        if (ok) call ctmul(br, lam, r)
    end procedure band_reaction

    module procedure band_velocity_residual
        type(band_rows) :: br
        real(dp) :: r(sys%n_hol + sys%n_nh)
        rvel = 0.0_dp
        br%bm = 0
        if (.not. sys%diagonal_mass) br%bm = -lbound(sys%mass_inv_band, 2)
        call setup_rows(sys, t, q, .false., .true., br, ok)
        if (.not. ok) return
        call cmul(br, v, r)
        rvel = maxval(abs(r + br%c0))
    end procedure band_velocity_residual

end submodule conmech_constrained_system_band
