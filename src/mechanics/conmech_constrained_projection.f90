!> Reactions, residuals and the projections onto the constraint manifold of
!! conmech_constrained_system (see there): the dense paths, with the banded ones of
!! conmech_constrained_system_band tried first where the system's structure allows.
submodule(conmech_constrained_system) conmech_constrained_projection
    implicit none

contains

    !> Reaction force r = C(t, q)^T lam (n): O(n) for row windows.
    module procedure constraint_reaction
        real(dp), allocatable :: c(:, :), c0(:)
        logical :: ok
        r = 0.0_dp
        if (sys%n_hol + sys%n_nh == 0) return
        if (band_ready(sys)) then
            call band_reaction(sys, t, q, lam, r, ok)
            if (ok) return
        end if
        allocate (c(sys%n_hol + sys%n_nh, sys%n), c0(sys%n_hol + sys%n_nh))
        call constraint_matrix(sys, t, q, c, c0)
        r = matmul(lam, c)
    end procedure constraint_reaction

    !> Residuals at (t, q, v): rpos = max |phi|, rvel = max |C v + c0|.
    module procedure constraint_residuals
        real(dp), allocatable :: c(:, :), c0(:)
        real(dp) :: ph(sys%n_hol)
        logical :: ok
        rpos = 0.0_dp
        rvel = 0.0_dp
        if (sys%n_hol > 0) then
            call sys%phi(t, q, ph)
            rpos = maxval(abs(ph))
        end if
        if (band_ready(sys)) then
            call band_velocity_residual(sys, t, q, v, rvel, ok)
            if (ok) return
        end if
        if (sys%n_hol + sys%n_nh > 0) then
            allocate (c(sys%n_hol + sys%n_nh, sys%n), c0(sys%n_hol + sys%n_nh))
            call constraint_matrix(sys, t, q, c, c0)
            rvel = maxval(abs(matmul(c, v) + c0))
        end if
    end procedure constraint_residuals

    !> Mass-weighted projection of q onto phi(t, q) = 0 (Hairer-Lubich-Wanner):
    !! q = q~ + M(q~)^{-1} G(q~)^T mu by simplified Newton with M, G and the Schur
    !! complement frozen at q~. Converged when max|phi| <= tol, or when the Newton
    !! correction is below the round-off of q (4 eps max|q|: large coordinates, where
    !! phi cannot reach an absolute tol); at most max_iter
    !! iterations (CM_NO_CONVERGENCE otherwise, q is then left unchanged). With
    !! `newton` = .true. G is refreshed at every iterate (Gauss-Newton, quadratic
    !! convergence from far away; used for the consistent initial values).
    module procedure project_position
        real(dp) :: mm(sys%n, sys%n), x(sys%n, sys%n_hol), g(sys%n_hol, sys%n)
        real(dp) :: s(sys%n_hol, sys%n_hol), ph(sys%n_hol, 1), qk(sys%n), dq(sys%n)
        real(dp) :: rnorm
        integer :: n, mh, lainfo, rk, state
        logical :: full, ok
        n = sys%n
        mh = sys%n_hol
        iters = 0
        info = CM_SUCCESS
        msg = "success"
        if (mh == 0) return
        call sys%phi(t, q, ph(:, 1))
        rnorm = maxval(abs(ph(:, 1)))
        if (rnorm <= tol) return
        full = .false.
        if (present(newton)) full = newton
        if (band_ready(sys)) then
            call band_project_position(sys, t, q, ph(:, 1), tol, max_iter, full, iters, info, &
                                       msg, ok)
            if (ok) return
        end if
        call factored_mass(sys, t, q, mm, info, msg)
        if (info /= CM_SUCCESS) return
        call sys%phi_jac(t, q, g)
        x = transpose(g)
        call dpotrs('U', n, mh, mm, n, x, n, lainfo)
        s = matmul(g, x)
        qk = q
        do iters = 1, max_iter
            if (full .and. iters > 1) then
                call sys%phi_jac(t, qk, g)
                x = transpose(g)
                call dpotrs('U', n, mh, mm, n, x, n, lainfo)
                s = matmul(g, x)
            end if
            call schur_solve(s, ph, rk, info)
            if (info /= CM_SUCCESS) then
                msg = "LAPACK failed in the position projection"
                return
            end if
            dq = matmul(x, ph(:, 1))
            if (maxval(abs(dq)) <= 4.0_dp*epsilon(1.0_dp)*max(maxval(abs(qk)), tiny(1.0_dp))) &
                then
                ! the correction is below the round-off of q: phi is as small as it can get,
                ! if it is at the round-off level of its terms (~ |G| |q|); otherwise the
                ! Jacobian cannot reduce it (zero or rank-deficient G, incompatible
                ! constraints): a failure, not a converged projection
                if (rnorm > max(tol, 1.0e3_dp*epsilon(1.0_dp)*max(1.0_dp, &
                                maxval(abs(g))*maxval(abs(qk))))) exit
                q = qk
                return
            end if
            call position_newton_step(sys, t, tol, dq, qk, ph(:, 1), rnorm, q, state)
            if (state == NEWTON_DIVERGED) exit
            if (state == NEWTON_CONVERGED) return
        end do
        call position_not_converged(rnorm, max_iter, iters, info, msg)
    end procedure project_position

    !> Mass-weighted projection of v onto C(t, q) v + c0 = 0 (linear, one solve):
    !! v = v~ - M^{-1} C^T S^+ (C v~ + c0). CM_NO_CONVERGENCE if the projected residual is
    !! not small (inconsistent velocity constraints).
    module procedure project_velocity
        real(dp) :: mm(sys%n, sys%n), x(sys%n, sys%n_hol + sys%n_nh)
        real(dp) :: c(sys%n_hol + sys%n_nh, sys%n), c0(sys%n_hol + sys%n_nh)
        real(dp) :: s(sys%n_hol + sys%n_nh, sys%n_hol + sys%n_nh), r(sys%n_hol + sys%n_nh, 1)
        real(dp) :: r0, vscale
        integer :: n, m, lainfo, rk
        logical :: ok
        n = sys%n
        m = sys%n_hol + sys%n_nh
        info = CM_SUCCESS
        msg = "success"
        if (m == 0) return
        if (band_ready(sys)) then
            call band_project_velocity(sys, t, q, v, info, msg, ok)
            if (ok) return
        end if
        call factored_mass(sys, t, q, mm, info, msg)
        if (info /= CM_SUCCESS) return
        call constraint_matrix(sys, t, q, c, c0)
        r(:, 1) = matmul(c, v) + c0
        r0 = maxval(abs(r(:, 1)))
        if (r0 == 0.0_dp) return
        x = transpose(c)
        call dpotrs('U', n, m, mm, n, x, n, lainfo)
        s = matmul(c, x)
        call schur_solve(s, r, rk, info)
        if (info /= CM_SUCCESS) then
            msg = "LAPACK failed in the velocity projection"
            return
        end if
        v = v - matmul(x, r(:, 1))
        vscale = max(maxval(abs(v)), 1.0_dp)*max(maxval(abs(c)), 1.0_dp)
        if (maxval(abs(matmul(c, v) + c0)) > 1.0e-8_dp*vscale + 1.0e-10_dp*r0) then
            info = CM_NO_CONVERGENCE
            msg = "velocity projection failed: the velocity constraints are inconsistent"
        end if
    end procedure project_velocity

    !> The Cholesky factor of M(t, q) (upper): the one prepare_mass stored for a constant
    !! mass, else M factorised here; info /= CM_SUCCESS when M is not positive definite.
    subroutine factored_mass(sys, t, q, mm, info, msg)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t, q(:)
        real(dp), intent(out) :: mm(:, :)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(inout) :: msg
        info = CM_SUCCESS
        if (has_mass_factor(sys)) then
            mm = sys%mass_factor
        else
            call sys%mass(t, q, mm)
            call mass_cholesky(mm, info, msg)
        end if
    end subroutine factored_mass

end submodule conmech_constrained_projection
