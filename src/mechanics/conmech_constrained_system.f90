!> Mechanical systems in excessive coordinates with constraints, their multipliers,
!! reaction forces and the projections onto the constraint manifold.
!!
!! The equations are
!!
!!     M(t, q) q'' = Q(t, q, q') + G(t, q)^T lambda_h + A(t, q)^T lambda_n
!!     phi(t, q) = 0                 (n_hol holonomic constraints, G = d phi / d q)
!!     A(t, q) q' + b(t, q) = 0      (n_nh non-holonomic Pfaffian constraints)
!!
!! so that the reaction force is C^T lambda with C = [G; A] (the seed's sign convention:
!! for the pendulum phi = (x^2 + y^2 - l^2)/2, lambda = m/l^2 (y g - x'^2 - y'^2)).
!! Differentiating the constraints gives the acceleration level C q'' = gamma with
!!
!!     gamma_h = - d/dt [G(t, q) v + phi_t(t, q)]  (v held fixed),
!!     gamma_n = - d/dt [A(t, q) v + b(t, q)]      (v held fixed).
!!
!! The accelerations and multipliers solve the KKT system [M C^T; C 0]; it is solved by
!! the Schur complement: Cholesky of M (dpotrf/dpotrs), then S = C M^{-1} C^T. S is
!! factorised by pivoted Cholesky (dpstrf) which reveals its rank; when the constraints are
!! redundant (rank < n_hol + n_nh) the minimum-norm multipliers come from dgelsd. The
!! reaction C^T lambda is unique either way.
!!
!! Users extend `constrained_system` and implement `mass` and `forces`, and, as needed,
!! `phi` and `phi_jac` (holonomic), `nh_matrix` (non-holonomic). Defaults:
!! - `phi_jac`: central differences, step eps^(1/3) max(|q_j|, 1);
!! - `phi_t`: zero unless `rheonomic`, then a central difference in t (step eps^(1/3)
!!   max(|t|, 1));
!! - `phi_gamma`: gamma_h = -d^2/ds^2 phi(t + s, q + s v) (for scleronomic phi the t-shift
!!   is dropped) by the five-point fourth-order second difference, step
!!   eps^(1/6) max(|q|, |t|, 1)/max(|v|, 1) (error ~ eps^(2/3), about 1e-10 relative);
!! - `nh_gamma`: -d/ds [A v + b](t + s, q + s v) by the five-point fourth-order first
!!   difference, step eps^(1/5) max(|q|, |t|, 1)/max(|v|, 1) (error ~ 1e-12 relative).
module conmech_constrained_system
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_lapack, only: dpotrs, dpstrf, dpstf2, dgelsd, la_finite
    use conmech_generalized, only: mass_cholesky
    implicit none
    private

    public :: constrained_system, constrained_accel, constraint_matrix
    public :: project_position, project_velocity, constraint_residuals
    !> The finite-difference defaults, for extensions that choose at run time (e.g. the
    !! Python layer) whether an analytic Jacobian / acceleration term exists.
    public :: fd_phi_jac, fd_phi_t, fd_phi_gamma, fd_nh_gamma

    interface fd_phi_jac
        module procedure cs_fd_phi_jac
    end interface fd_phi_jac
    interface fd_phi_t
        module procedure cs_fd_phi_t
    end interface fd_phi_t
    interface fd_phi_gamma
        module procedure cs_fd_phi_gamma
    end interface fd_phi_gamma
    interface fd_nh_gamma
        module procedure cs_fd_nh_gamma
    end interface fd_nh_gamma

    type, abstract :: constrained_system
        integer :: n = 0             !! number of (excessive) coordinates
        integer :: n_hol = 0         !! number of holonomic constraints phi(t, q) = 0
        integer :: n_nh = 0          !! number of non-holonomic constraints A q' + b = 0
        logical :: rheonomic = .false.  !! phi depends explicitly on t
    contains
        procedure(cs_mass), deferred :: mass
        procedure(cs_forces), deferred :: forces
        procedure :: phi => cs_no_phi
        procedure :: phi_jac => cs_fd_phi_jac
        procedure :: phi_t => cs_fd_phi_t
        procedure :: phi_gamma => cs_fd_phi_gamma
        procedure :: nh_matrix => cs_no_nh
        procedure :: nh_gamma => cs_fd_nh_gamma
        procedure :: energy => cs_no_energy
        procedure :: has_energy => cs_has_no_energy
    end type constrained_system

    abstract interface
        !> mm = M(t, q) (n x n, symmetric positive definite).
        subroutine cs_mass(self, t, q, mm)
            import :: constrained_system, dp
            class(constrained_system), intent(in) :: self
            real(dp), intent(in) :: t
            real(dp), intent(in) :: q(:)
            real(dp), intent(out) :: mm(:, :)
        end subroutine cs_mass
        !> f = Q(t, q, v) (applied forces, velocity terms included).
        subroutine cs_forces(self, t, q, v, f)
            import :: constrained_system, dp
            class(constrained_system), intent(in) :: self
            real(dp), intent(in) :: t
            real(dp), intent(in) :: q(:), v(:)
            real(dp), intent(out) :: f(:)
        end subroutine cs_forces
    end interface

contains

    ! ------------------------------------------------------------------ defaults

    !> The default has no holonomic constraints.
    subroutine cs_no_phi(self, t, q, c)
        class(constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c = 0.0_dp
    end subroutine cs_no_phi

    !> Default G = d phi/d q by central differences.
    subroutine cs_fd_phi_jac(self, t, q, g)
        class(constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        real(dp) :: qp(size(q)), cp(self%n_hol), cm(self%n_hol), h
        integer :: j
        qp = q
        do j = 1, size(q)
            h = epsilon(1.0_dp)**(1.0_dp/3.0_dp)*max(abs(q(j)), 1.0_dp)
            qp(j) = q(j) + h
            call self%phi(t, qp, cp)
            qp(j) = q(j) - h
            call self%phi(t, qp, cm)
            qp(j) = q(j)
            g(:, j) = (cp - cm)/(2.0_dp*h)
        end do
    end subroutine cs_fd_phi_jac

    !> Default phi_t: zero for scleronomic constraints, else a central difference in t.
    subroutine cs_fd_phi_t(self, t, q, pt)
        class(constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: pt(:)
        real(dp) :: cp(self%n_hol), cm(self%n_hol), h
        if (.not. self%rheonomic) then
            pt = 0.0_dp
            return
        end if
        h = epsilon(1.0_dp)**(1.0_dp/3.0_dp)*max(abs(t), 1.0_dp)
        call self%phi(t + h, q, cp)
        call self%phi(t - h, q, cm)
        pt = (cp - cm)/(2.0_dp*h)
    end subroutine cs_fd_phi_t

    !> Default gamma_h = -d^2/ds^2 phi(t + s, q + s v) at s = 0 (fourth-order five-point
    !! second difference; step eps^(1/6) times the scale of (t, q) over max(|v|, 1)).
    subroutine cs_fd_phi_gamma(self, t, q, v, gam)
        class(constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        real(dp) :: c2p(self%n_hol), cp(self%n_hol), c0(self%n_hol), cm(self%n_hol)
        real(dp) :: c2m(self%n_hol), s, tdir, scale
        if (self%n_hol == 0) return
        tdir = 0.0_dp
        scale = max(maxval(abs(q)), 1.0_dp)
        if (self%rheonomic) then
            tdir = 1.0_dp
            scale = max(scale, abs(t))
        end if
        if (maxval(abs(v)) == 0.0_dp .and. tdir == 0.0_dp) then
            gam = 0.0_dp
            return
        end if
        s = epsilon(1.0_dp)**(1.0_dp/6.0_dp)*scale/max(maxval(abs(v)), 1.0_dp)
        call self%phi(t + 2.0_dp*s*tdir, q + 2.0_dp*s*v, c2p)
        call self%phi(t + s*tdir, q + s*v, cp)
        call self%phi(t, q, c0)
        call self%phi(t - s*tdir, q - s*v, cm)
        call self%phi(t - 2.0_dp*s*tdir, q - 2.0_dp*s*v, c2m)
        gam = -(-c2p + 16.0_dp*cp - 30.0_dp*c0 + 16.0_dp*cm - c2m)/(12.0_dp*s**2)
    end subroutine cs_fd_phi_gamma

    !> The default has no non-holonomic constraints.
    subroutine cs_no_nh(self, t, q, a, b)
        class(constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: a(:, :)
        real(dp), intent(out) :: b(:)
        a = 0.0_dp
        b = 0.0_dp
    end subroutine cs_no_nh

    !> Default gamma_n = -d/dt [A v + b] (v fixed) along (1, v), by the fourth-order
    !! five-point first difference with step eps^(1/5) times the scale of (t, q).
    subroutine cs_fd_nh_gamma(self, t, q, v, gam)
        class(constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        real(dp) :: a(self%n_nh, size(q)), b(self%n_nh), w(self%n_nh), s
        integer :: j
        real(dp), parameter :: off(4) = [2.0_dp, 1.0_dp, -1.0_dp, -2.0_dp]
        real(dp), parameter :: wt(4) = [-1.0_dp, 8.0_dp, -8.0_dp, 1.0_dp]
        if (self%n_nh == 0) return
        s = epsilon(1.0_dp)**0.2_dp*max(maxval(abs(q)), abs(t), 1.0_dp) &
            /max(maxval(abs(v)), 1.0_dp)
        w = 0.0_dp
        do j = 1, 4
            call self%nh_matrix(t + off(j)*s, q + off(j)*s*v, a, b)
            w = w + wt(j)*(matmul(a, v) + b)
        end do
        gam = -w/(12.0_dp*s)
    end subroutine cs_fd_nh_gamma

    function cs_no_energy(self, t, q, v) result(e)
        class(constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.0_dp
    end function cs_no_energy

    logical function cs_has_no_energy(self)
        class(constrained_system), intent(in) :: self
        cs_has_no_energy = .false.
    end function cs_has_no_energy

    ! ------------------------------------------------------------------ linear algebra

    !> C = [G; A] (m x n) and the velocity-level offset c0 = [phi_t; b]: C v + c0 = 0.
    subroutine constraint_matrix(sys, t, q, c, c0)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:, :), c0(:)
        integer :: mh, mn
        mh = sys%n_hol
        mn = sys%n_nh
        if (mh > 0) then
            call sys%phi_jac(t, q, c(1:mh, :))
            call sys%phi_t(t, q, c0(1:mh))
        end if
        if (mn > 0) call sys%nh_matrix(t, q, c(mh + 1:mh + mn, :), c0(mh + 1:mh + mn))
    end subroutine constraint_matrix

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

    !> Accelerations a and multipliers lam (n_hol + n_nh) at (t, q, v) from the
    !! acceleration-level KKT system. With `alpha`, `beta` (Baumgarte) the acceleration
    !! constraint becomes C a = gamma - 2 alpha (C v + c0) - beta^2 [phi; 0].
    !! `rank` is the rank of the constraint set (< n_hol + n_nh when redundant).
    !! `msg` (optional: the hot path of the integrators omits it) explains a failure.
    subroutine constrained_accel(sys, t, q, v, a, lam, info, msg, rank, alpha, beta)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: a(:), lam(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out), optional :: msg
        integer, intent(out), optional :: rank
        real(dp), intent(in), optional :: alpha, beta
        real(dp) :: mm(sys%n, sys%n), x(sys%n, 1 + sys%n_hol + sys%n_nh)
        real(dp) :: c(sys%n_hol + sys%n_nh, sys%n), c0(sys%n_hol + sys%n_nh)
        real(dp) :: gam(sys%n_hol + sys%n_nh, 1), s(sys%n_hol + sys%n_nh, sys%n_hol + sys%n_nh)
        real(dp) :: ph(sys%n_hol)
        integer :: n, m, mh, lainfo, rk
        character(len=:), allocatable :: m2
        n = sys%n
        mh = sys%n_hol
        m = sys%n_hol + sys%n_nh
        if (n < 1 .or. mh < 0 .or. sys%n_nh < 0 .or. size(q) /= n .or. size(v) /= n &
            .or. size(a) /= n .or. size(lam) /= m) then
            info = CM_BAD_INPUT
            if (present(msg)) msg = "bad input: q, v, a need n elements and lambda n_hol + n_nh"
            return
        end if
        call sys%mass(t, q, mm)
        if (present(msg)) then
            ! (a local string: passing the optional deferred-length msg straight through
            ! loses its length with gfortran)
            call mass_cholesky(mm, info, m2)
            msg = m2
        else
            call mass_cholesky(mm, info)
        end if
        if (info /= CM_SUCCESS) return
        call sys%forces(t, q, v, x(:, 1))
        if (m > 0) then
            call constraint_matrix(sys, t, q, c, c0)
            x(:, 2:m + 1) = transpose(c)
        end if
        call dpotrs('U', n, m + 1, mm, n, x, n, lainfo)
        a = x(:, 1)
        rk = 0
        if (m > 0) then
            if (mh > 0) call sys%phi_gamma(t, q, v, gam(1:mh, 1))
            if (sys%n_nh > 0) call sys%nh_gamma(t, q, v, gam(mh + 1:m, 1))
            if (present(alpha)) then
                gam(:, 1) = gam(:, 1) - 2.0_dp*alpha*(matmul(c, v) + c0)
            end if
            if (present(beta) .and. mh > 0) then
                call sys%phi(t, q, ph)
                gam(1:mh, 1) = gam(1:mh, 1) - beta**2*ph
            end if
            s = matmul(c, x(:, 2:m + 1))
            gam(:, 1) = gam(:, 1) - matmul(c, a)
            call schur_solve(s, gam, rk, info)
            if (info /= CM_SUCCESS) then
                if (present(msg)) msg = "LAPACK failed in the constraint (Schur complement) solve"
                return
            end if
            lam = gam(:, 1)
            a = a + matmul(x(:, 2:m + 1), lam)
        end if
        if (present(rank)) rank = rk
        info = CM_SUCCESS
        if (present(msg)) msg = "success"
    end subroutine constrained_accel

    !> Residuals at (t, q, v): rpos = max |phi|, rvel = max |C v + c0|.
    subroutine constraint_residuals(sys, t, q, v, rpos, rvel)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: rpos, rvel
        real(dp) :: c(sys%n_hol + sys%n_nh, sys%n), c0(sys%n_hol + sys%n_nh), ph(sys%n_hol)
        rpos = 0.0_dp
        rvel = 0.0_dp
        if (sys%n_hol > 0) then
            call sys%phi(t, q, ph)
            rpos = maxval(abs(ph))
        end if
        if (sys%n_hol + sys%n_nh > 0) then
            call constraint_matrix(sys, t, q, c, c0)
            rvel = maxval(abs(matmul(c, v) + c0))
        end if
    end subroutine constraint_residuals

    !> Mass-weighted projection of q onto phi(t, q) = 0 (Hairer-Lubich-Wanner):
    !! q = q~ + M(q~)^{-1} G(q~)^T mu by simplified Newton with M, G and the Schur
    !! complement frozen at q~. Converged when max|phi| <= tol, or when the Newton
    !! correction is below the round-off of q (4 eps max|q|: large coordinates, where
    !! phi cannot reach an absolute tol); at most max_iter
    !! iterations (CM_NO_CONVERGENCE otherwise, q is then left unchanged). With
    !! `newton` = .true. G is refreshed at every iterate (Gauss-Newton, quadratic
    !! convergence from far away; used for the consistent initial values).
    subroutine project_position(sys, t, q, tol, max_iter, iters, info, msg, newton)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(inout) :: q(:)
        real(dp), intent(in) :: tol
        integer, intent(in) :: max_iter
        integer, intent(out) :: iters, info
        character(len=:), allocatable, intent(out) :: msg
        logical, intent(in), optional :: newton   !! refresh G at every iterate (far start)
        real(dp) :: mm(sys%n, sys%n), x(sys%n, sys%n_hol), g(sys%n_hol, sys%n)
        real(dp) :: s(sys%n_hol, sys%n_hol), ph(sys%n_hol, 1), qk(sys%n), dq(sys%n)
        real(dp) :: rnorm
        integer :: n, mh, lainfo, rk
        logical :: full
        character(len=32) :: buf
        n = sys%n
        mh = sys%n_hol
        iters = 0
        info = CM_SUCCESS
        msg = "success"
        if (mh == 0) return
        call sys%phi(t, q, ph(:, 1))
        rnorm = maxval(abs(ph(:, 1)))
        if (rnorm <= tol) return
        call sys%mass(t, q, mm)
        call mass_cholesky(mm, info, msg)
        if (info /= CM_SUCCESS) return
        call sys%phi_jac(t, q, g)
        x = transpose(g)
        call dpotrs('U', n, mh, mm, n, x, n, lainfo)
        s = matmul(g, x)
        full = .false.
        if (present(newton)) full = newton
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
            qk = qk - dq
            call sys%phi(t, qk, ph(:, 1))
            rnorm = maxval(abs(ph(:, 1)))
            if (.not. (rnorm < huge(1.0_dp))) exit
            if (rnorm <= tol) then
                q = qk
                return
            end if
        end do
        iters = min(iters, max_iter)
        info = CM_NO_CONVERGENCE
        write (buf, '(es10.3)') rnorm
        msg = "position projection did not converge: |phi| ="//trim(buf)// &
              " (inconsistent constraints, or too far from the manifold)"
    end subroutine project_position

    !> Mass-weighted projection of v onto C(t, q) v + c0 = 0 (linear, one solve):
    !! v = v~ - M^{-1} C^T S^+ (C v~ + c0). CM_NO_CONVERGENCE if the projected residual is
    !! not small (inconsistent velocity constraints).
    subroutine project_velocity(sys, t, q, v, info, msg)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(inout) :: v(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        real(dp) :: mm(sys%n, sys%n), x(sys%n, sys%n_hol + sys%n_nh)
        real(dp) :: c(sys%n_hol + sys%n_nh, sys%n), c0(sys%n_hol + sys%n_nh)
        real(dp) :: s(sys%n_hol + sys%n_nh, sys%n_hol + sys%n_nh), r(sys%n_hol + sys%n_nh, 1)
        real(dp) :: r0, vscale
        integer :: n, m, lainfo, rk
        n = sys%n
        m = sys%n_hol + sys%n_nh
        info = CM_SUCCESS
        msg = "success"
        if (m == 0) return
        call sys%mass(t, q, mm)
        call mass_cholesky(mm, info, msg)
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
    end subroutine project_velocity

end module conmech_constrained_system
