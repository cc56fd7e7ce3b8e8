!> The banded paths of conmech_constrained_system: accelerations, multipliers and
!! projections for a diagonal mass and a row-window constraint Jacobian (see the parent
!! module and conmech_constrained_band). Each costs O(n + m (w + kd)^2); when it does not
!! apply it returns ok = .false. and the parent's dense path runs.
submodule(conmech_constrained_system) conmech_constrained_system_band
    use conmech_constrained_band, only: band_width_of, band_schur, band_gmul, band_gtmul, &
        band_factor, band_solve
    implicit none

contains

    pure module logical function band_ready(sys)
        class(constrained_system), intent(in) :: sys
        band_ready = sys%diagonal_mass .and. sys%jac_width > 0 .and. sys%n_nh == 0 .and. &
                     sys%n_hol > 0 .and. sys%jac_width <= sys%n
    end function band_ready

    !> d = diag M, the windows of G and the bandwidth kd of S at (t, q); ok = .false. if the
    !! mass is not positive and finite or the windows are not banded.
    subroutine band_setup(sys, t, q, d, gb, first, kd, ok)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: d(:), gb(:, :)
        integer, intent(out) :: first(:), kd
        logical, intent(out) :: ok
        call sys%mass_diagonal(t, q, d)
        ok = all(d > 0.0_dp .and. d < huge(1.0_dp))
        kd = -1
        if (.not. ok) return
        call sys%phi_jac_band(t, q, gb, first)
        kd = band_width_of(first, sys%jac_width, sys%n)
        ok = kd >= 0 .and. la_finite(gb)
    end subroutine band_setup

    !> Banded S = G D^-1 G^T, factorised; ok = .false. if not positive definite.
    subroutine band_schur_factor(gb, first, d, kd, ab, ok)
        real(dp), intent(in) :: gb(:, :), d(:)
        integer, intent(in) :: first(:), kd
        real(dp), intent(out) :: ab(:, :)
        logical, intent(out) :: ok
        integer :: lainfo
        call band_schur(gb, first, 1.0_dp/d, kd, ab)
        ok = la_finite(ab)
        if (.not. ok) return
        call band_factor(ab, kd, lainfo)
        ok = lainfo == 0
    end subroutine band_schur_factor

    module subroutine band_accel(sys, t, q, v, a, lam, ok, alpha, beta)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: a(:), lam(:)
        logical, intent(out) :: ok
        real(dp), intent(in), optional :: alpha, beta
        real(dp) :: d(sys%n), gb(sys%n_hol, sys%jac_width), r(sys%n_hol), w(sys%n_hol)
        real(dp) :: z(sys%n)
        integer :: first(sys%n_hol), kd, lainfo
        call band_setup(sys, t, q, d, gb, first, kd, ok)
        if (.not. ok) return
        block
            real(dp) :: ab(kd + 1, sys%n_hol)
            call band_schur_factor(gb, first, d, kd, ab, ok)
            if (.not. ok) return
            call sys%forces(t, q, v, a)
            a = a/d
            call sys%phi_gamma(t, q, v, r)
            if (present(alpha)) then
                call band_gmul(gb, first, v, w)
                r = r - 2.0_dp*alpha*w
                call sys%phi_t(t, q, w)
                r = r - 2.0_dp*alpha*w
            end if
            if (present(beta)) then
                call sys%phi(t, q, w)
                r = r - beta**2*w
            end if
            call band_gmul(gb, first, a, w)
            r = r - w
            ok = la_finite(r)
            if (.not. ok) return
            call band_solve(ab, kd, r, lainfo)
            lam = r
            call band_gtmul(gb, first, lam, z)
            a = a + z/d
        end block
    end subroutine band_accel

    module subroutine band_project_position(sys, t, q, ph, tol, max_iter, full, iters, &
                                            info, msg, ok)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(inout) :: q(:)
        real(dp), intent(in) :: ph(:)
        real(dp), intent(in) :: tol
        integer, intent(in) :: max_iter
        logical, intent(in) :: full
        integer, intent(out) :: iters, info
        character(len=:), allocatable, intent(inout) :: msg
        logical, intent(out) :: ok
        real(dp) :: d(sys%n), gb(sys%n_hol, sys%jac_width), r(sys%n_hol), qk(sys%n)
        real(dp) :: dq(sys%n), rnorm
        integer :: first(sys%n_hol), kd, lainfo, kd_k
        character(len=32) :: buf
        iters = 0
        info = CM_SUCCESS
        call band_setup(sys, t, q, d, gb, first, kd, ok)
        if (.not. ok) return
        block
            real(dp) :: ab(kd + 1, sys%n_hol)
            call band_schur_factor(gb, first, d, kd, ab, ok)
            if (.not. ok) return
            r = ph
            rnorm = maxval(abs(r))
            qk = q
            do iters = 1, max_iter
                if (full .and. iters > 1) then
                    ! Gauss-Newton: G at the iterate (same band: the structure is fixed)
                    call sys%phi_jac_band(t, qk, gb, first)
                    kd_k = band_width_of(first, sys%jac_width, sys%n)
                    if (kd_k /= kd) then
                        ok = .false.
                        return
                    end if
                    call band_schur_factor(gb, first, d, kd, ab, ok)
                    if (.not. ok) return
                end if
                call band_solve(ab, kd, r, lainfo)
                call band_gtmul(gb, first, r, dq)
                dq = dq/d
                if (maxval(abs(dq)) <= 4.0_dp*epsilon(1.0_dp)*max(maxval(abs(qk)), &
                                                                   tiny(1.0_dp))) then
                    q = qk
                    return
                end if
                qk = qk - dq
                call sys%phi(t, qk, r)
                rnorm = maxval(abs(r))
                if (.not. (rnorm < huge(1.0_dp))) exit
                if (rnorm <= tol) then
                    q = qk
                    return
                end if
            end do
        end block
        iters = min(iters, max_iter)
        info = CM_NO_CONVERGENCE
        write (buf, '(es10.3)') rnorm
        msg = "position projection did not converge: |phi| ="//trim(buf)// &
              " (inconsistent constraints, or too far from the manifold)"
    end subroutine band_project_position

    module subroutine band_project_velocity(sys, t, q, v, info, msg, ok)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(inout) :: v(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(inout) :: msg
        logical, intent(out) :: ok
        real(dp) :: d(sys%n), gb(sys%n_hol, sys%jac_width), r(sys%n_hol), pt(sys%n_hol)
        real(dp) :: z(sys%n), r0, vscale
        integer :: first(sys%n_hol), kd, lainfo
        info = CM_SUCCESS
        call band_setup(sys, t, q, d, gb, first, kd, ok)
        if (.not. ok) return
        call band_gmul(gb, first, v, r)
        call sys%phi_t(t, q, pt)
        r = r + pt
        r0 = maxval(abs(r))
        if (r0 == 0.0_dp) return
        block
            real(dp) :: ab(kd + 1, sys%n_hol)
            call band_schur_factor(gb, first, d, kd, ab, ok)
            if (.not. ok) return
            call band_solve(ab, kd, r, lainfo)
        end block
        call band_gtmul(gb, first, r, z)
        v = v - z/d
        call band_gmul(gb, first, v, r)
        vscale = max(maxval(abs(v)), 1.0_dp)*max(maxval(abs(gb)), 1.0_dp)
        if (maxval(abs(r + pt)) > 1.0e-8_dp*vscale + 1.0e-10_dp*r0) then
            info = CM_NO_CONVERGENCE
            msg = "velocity projection failed: the velocity constraints are inconsistent"
        end if
    end subroutine band_project_velocity

end submodule conmech_constrained_system_band
