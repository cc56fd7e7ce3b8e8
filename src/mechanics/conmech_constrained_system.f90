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
!! Structure that makes large systems cheap (declared by the system; every built-in with a
!! diagonal mass sets it):
!! - `constant_mass`: M does not depend on (t, q); `prepare_mass` (called by
!!   constrained_solve on its copy of the system) keeps its Cholesky factor, and the KKT
!!   solves and projections use it instead of factorising M at every evaluation; when
!!   M^-1 is banded (M block diagonal, e.g. bodies with coupled coordinates) it also keeps
!!   M^-1 in band form for the banded path below;
!! - `diagonal_mass`: M is diagonal, given by `mass_diagonal` (default: the diagonal of
!!   `mass`); M^-1 is a division, no factorisation per evaluation;
!! - `jac_width` > 0: row i of G has its nonzeros in the jac_width consecutive columns
!!   first(i) .. first(i) + jac_width - 1 given by `phi_jac_band`; `nh_width` > 0: the same
!!   for the rows of A (`nh_matrix_band`). With a diagonal (or kept banded inverse) mass
!!   and every constraint row so declared, the rows of C = [G; A] are ordered by their
!!   first column (a stable counting sort), S = C M^-1 C^T is banded (bandwidth detected)
!!   and factorised by LAPACK's banded Cholesky (conmech_constrained_band): a chain of N
!!   links costs O(N) per evaluation and per projection, with or without Pfaffian rows.
!!   When the banded S is not positive definite (redundant constraints) the dense
!!   rank-revealing path above runs.
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
!!   difference, step eps^(1/5) max(|q|, |t|, 1)/max(|v|, 1) (error ~ 1e-12 relative);
!! - `forces_jacobian`, `constraint_hessian` (the exact Jacobian of Radau IIA on the
!!   constrained equations): central differences (submodule conmech_constrained_derivatives).
module conmech_constrained_system
    use conmech_kinds, only: dp
    use conmech_mechanical_system, only: mechanical_system
    use conmech_central_step, only: central_step
    use conmech_status
    use conmech_lapack, only: dpotrs, la_finite
    use conmech_schur, only: schur_solve
    use conmech_generalized, only: mass_cholesky
    use conmech_constrained_band, only: band_windows
    implicit none
    private

    public :: constrained_system, constrained_accel, constraint_matrix
    public :: project_position, project_velocity, constraint_residuals, prepare_mass
    public :: constraint_reaction
    !> Building blocks of the submodules (public: gfortran drops private module procedures
    !! that only a submodule calls): the symmetric positive semi-definite Schur solve and
    !! the test for a kept constant-mass factor; the Newton step of the position
    !! projections and its failure.
    public :: schur_solve, has_mass_factor
    public :: position_newton_step, position_not_converged
    public :: NEWTON_RUNNING, NEWTON_CONVERGED, NEWTON_DIVERGED
    !> The finite-difference defaults, for extensions that choose at run time (e.g. the
    !! Python layer) whether an analytic Jacobian / acceleration term exists.
    public :: fd_phi_jac, fd_phi_t, fd_phi_gamma, fd_nh_gamma
    public :: fd_forces_jacobian, fd_constraint_hessian

    type, abstract, extends(mechanical_system) :: constrained_system
        integer :: n = 0             !! number of (excessive) coordinates
        integer :: n_hol = 0         !! number of holonomic constraints phi(t, q) = 0
        integer :: n_nh = 0          !! number of non-holonomic constraints A q' + b = 0
        logical :: rheonomic = .false.  !! phi depends explicitly on t
        logical :: diagonal_mass = .false.  !! M is diagonal (see mass_diagonal)
        logical :: constant_mass = .false.  !! M is constant (see prepare_mass)
        real(dp), allocatable :: mass_factor(:, :)  !! Cholesky factor kept by prepare_mass
        integer :: jac_width = 0     !! > 0: row-window width of G (see phi_jac_band)
        integer :: nh_width = 0      !! > 0: row-window width of A (see nh_matrix_band)
        !> M^-1 in band form mass_inv_band(j, k) = M^-1(j, j + k), k = -bm..bm, kept by
        !! prepare_mass for a constant mass whose inverse is banded
        real(dp), allocatable :: mass_inv_band(:, :)
    contains
        procedure :: phi => cs_no_phi
        procedure :: phi_jac => fd_phi_jac
        procedure :: phi_t => fd_phi_t
        procedure :: phi_gamma => fd_phi_gamma
        procedure :: nh_matrix => cs_no_nh
        procedure :: nh_gamma => fd_nh_gamma
        procedure :: mass_diagonal => cs_mass_diagonal
        procedure :: phi_jac_band => cs_phi_jac_band
        procedure :: nh_matrix_band => cs_nh_matrix_band
        procedure :: forces_jacobian => fd_forces_jacobian
        procedure :: has_forces_jacobian => cs_not_given
        procedure :: constraint_hessian => fd_constraint_hessian
        procedure :: has_constraint_hessian => cs_not_given
    end type constrained_system

    ! Reactions, residuals and projections (submodule conmech_constrained_projection).
    interface
        !> Reaction force r = C(t, q)^T lam (n): O(n) for a row-window G.
        module subroutine constraint_reaction(sys, t, q, lam, r)
            class(constrained_system), intent(in) :: sys
            real(dp), intent(in) :: t
            real(dp), intent(in) :: q(:), lam(:)
            real(dp), intent(out) :: r(:)
        end subroutine constraint_reaction
        !> Residuals at (t, q, v): rpos = max |phi|, rvel = max |C v + c0|.
        module subroutine constraint_residuals(sys, t, q, v, rpos, rvel)
            class(constrained_system), intent(in) :: sys
            real(dp), intent(in) :: t
            real(dp), intent(in) :: q(:), v(:)
            real(dp), intent(out) :: rpos, rvel
        end subroutine constraint_residuals
        !> Mass-weighted projection of q onto phi(t, q) = 0 (Hairer-Lubich-Wanner):
        !! q = q~ + M(q~)^{-1} G(q~)^T mu by simplified Newton with M, G and the Schur
        !! complement frozen at q~. Converged when max|phi| <= tol, or when the Newton
        !! correction is below the round-off of q (4 eps max|q|); at most max_iter
        !! iterations (CM_NO_CONVERGENCE otherwise, q is then left unchanged). With
        !! `newton` = .true. G is refreshed at every iterate (Gauss-Newton, quadratic
        !! convergence from far away; used for the consistent initial values).
        module subroutine project_position(sys, t, q, tol, max_iter, iters, info, msg, newton)
            class(constrained_system), intent(in) :: sys
            real(dp), intent(in) :: t
            real(dp), intent(inout) :: q(:)
            real(dp), intent(in) :: tol
            integer, intent(in) :: max_iter
            integer, intent(out) :: iters, info
            character(len=:), allocatable, intent(out) :: msg
            logical, intent(in), optional :: newton
        end subroutine project_position
        !> Mass-weighted projection of v onto C(t, q) v + c0 = 0 (linear, one solve):
        !! v = v~ - M^{-1} C^T S^+ (C v~ + c0). CM_NO_CONVERGENCE if the projected residual
        !! is not small (inconsistent velocity constraints).
        module subroutine project_velocity(sys, t, q, v, info, msg)
            class(constrained_system), intent(in) :: sys
            real(dp), intent(in) :: t
            real(dp), intent(in) :: q(:)
            real(dp), intent(inout) :: v(:)
            integer, intent(out) :: info
            character(len=:), allocatable, intent(out) :: msg
        end subroutine project_velocity
    end interface

    ! Derivatives for implicit integrators (submodule conmech_constrained_derivatives):
    ! the defaults are central differences; compiled systems override them.
    interface
        !> r = [dQ/dq - d(M a)/dq, dQ/dv] at (t, q, v) with a held fixed (n x 2n): the
        !! Jacobian of the force balance M(q) a - Q(t, q, v). Default: central differences
        !! of `forces` and `mass` (steps eps^(1/3) max(|x_j|, 1)).
        module subroutine fd_forces_jacobian(self, t, q, v, a, r)
            class(constrained_system), intent(in) :: self
            real(dp), intent(in) :: t
            real(dp), intent(in) :: q(:), v(:), a(:)
            real(dp), intent(out) :: r(:, :)
        end subroutine fd_forces_jacobian
        !> The second derivatives of the constraints that a Newton iteration on the
        !! constrained equations needs, at (t, q, v) and multipliers lam (n_hol + n_nh):
        !! hl = d(C^T lam)/dq (n x n) and hv = d(C v + c0)/dq ((n_hol + n_nh) x n).
        !! Default: central differences of the constraint matrix and offset.
        module subroutine fd_constraint_hessian(self, t, q, v, lam, hl, hv)
            class(constrained_system), intent(in) :: self
            real(dp), intent(in) :: t
            real(dp), intent(in) :: q(:), v(:), lam(:)
            real(dp), intent(out) :: hl(:, :), hv(:, :)
        end subroutine fd_constraint_hessian
    end interface

    !> The states of a position projection after a Newton step.
    integer, parameter :: NEWTON_RUNNING = 0     !! |phi| > tol: iterate on
    integer, parameter :: NEWTON_CONVERGED = 1   !! |phi| <= tol: q holds the iterate
    integer, parameter :: NEWTON_DIVERGED = -1   !! |phi| not finite: give up

    ! The Newton iteration shared by the dense and banded position projections (submodule
    ! conmech_position_newton).
    interface
        !> qk <- qk - dq, then ph = phi(t, qk) and rnorm = max |ph|; q = qk once rnorm <=
        !! tol. state: NEWTON_RUNNING, NEWTON_CONVERGED or NEWTON_DIVERGED.
        module subroutine position_newton_step(sys, t, tol, dq, qk, ph, rnorm, q, state)
            class(constrained_system), intent(in) :: sys
            real(dp), intent(in) :: t, tol
            real(dp), intent(in) :: dq(:)
            real(dp), intent(inout) :: qk(:), q(:)
            real(dp), intent(out) :: ph(:), rnorm
            integer, intent(out) :: state
        end subroutine position_newton_step
        !> The failure of a projection after max_iter steps, with the last |phi| (rnorm).
        module subroutine position_not_converged(rnorm, max_iter, iters, info, msg)
            real(dp), intent(in) :: rnorm
            integer, intent(in) :: max_iter
            integer, intent(inout) :: iters
            integer, intent(out) :: info
            character(len=:), allocatable, intent(inout) :: msg
        end subroutine position_not_converged
    end interface

    ! The banded paths (submodule conmech_constrained_system_band). Each sets ok = .false.
    ! when it does not apply (mass not positive, windows not banded, S not positive
    ! definite): the caller then runs the dense path.
    interface
        !> Default row windows of A (and b) from the dense `nh_matrix`: ab(i, :) =
        !! A(i, first(i) + 0:w-1) (w = nh_width); a row that does not fit gives first = 0.
        module subroutine cs_nh_matrix_band(self, t, q, ab, b, first)
            class(constrained_system), intent(in) :: self
            real(dp), intent(in) :: t
            real(dp), intent(in) :: q(:)
            real(dp), intent(out) :: ab(:, :), b(:)
            integer, intent(out) :: first(:)
        end subroutine cs_nh_matrix_band
        !> Keep M^-1 in band form when it is banded and every constraint row has a declared
        !! window (mm: the Cholesky factor of M).
        module subroutine keep_mass_inverse(sys, mm)
            class(constrained_system), intent(inout) :: sys
            real(dp), intent(in) :: mm(:, :)
        end subroutine keep_mass_inverse
        !> r = C^T lam by the row windows.
        module subroutine band_reaction(sys, t, q, lam, r, ok)
            class(constrained_system), intent(in) :: sys
            real(dp), intent(in) :: t
            real(dp), intent(in) :: q(:), lam(:)
            real(dp), intent(out) :: r(:)
            logical, intent(out) :: ok
        end subroutine band_reaction
        !> rvel = max |C v + c0| by the row windows.
        module subroutine band_velocity_residual(sys, t, q, v, rvel, ok)
            class(constrained_system), intent(in) :: sys
            real(dp), intent(in) :: t
            real(dp), intent(in) :: q(:), v(:)
            real(dp), intent(out) :: rvel
            logical, intent(out) :: ok
        end subroutine band_velocity_residual
        !> Diagonal mass (or a kept banded M^-1) and row windows for every constraint row.
        pure module logical function band_ready(sys)
            class(constrained_system), intent(in) :: sys
        end function band_ready
        !> constrained_accel by the banded Schur complement.
        module subroutine band_accel(sys, t, q, v, a, lam, ok, alpha, beta)
            class(constrained_system), intent(in) :: sys
            real(dp), intent(in) :: t
            real(dp), intent(in) :: q(:), v(:)
            real(dp), intent(out) :: a(:), lam(:)
            logical, intent(out) :: ok
            real(dp), intent(in), optional :: alpha, beta
        end subroutine band_accel
        !> project_position by the banded Schur complement; ph = phi(t, q) on entry.
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
        end subroutine band_project_position
        !> project_velocity by the banded Schur complement.
        module subroutine band_project_velocity(sys, t, q, v, info, msg, ok)
            class(constrained_system), intent(in) :: sys
            real(dp), intent(in) :: t
            real(dp), intent(in) :: q(:)
            real(dp), intent(inout) :: v(:)
            integer, intent(out) :: info
            character(len=:), allocatable, intent(inout) :: msg
            logical, intent(out) :: ok
        end subroutine band_project_velocity
    end interface

contains

    ! ------------------------------------------------------------------ defaults

    !> The default d is the diagonal of `mass` (override it: O(n) instead of O(n^2)).
    subroutine cs_mass_diagonal(self, t, q, d)
        class(constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: d(:)
        real(dp) :: mm(self%n, self%n)
        integer :: i
        call self%mass(t, q, mm)
        do i = 1, self%n
            d(i) = mm(i, i)
        end do
    end subroutine cs_mass_diagonal

    !> Default row windows of G from the dense `phi_jac`: gb(i, :) = G(i, first(i) + 0:w-1)
    !! (w = jac_width). A row whose nonzeros do not fit in w columns gives first = 0 (then
    !! the dense path is used).
    subroutine cs_phi_jac_band(self, t, q, gb, first)
        class(constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: gb(:, :)
        integer, intent(out) :: first(:)
        real(dp) :: g(self%n_hol, self%n)
        call self%phi_jac(t, q, g)
        call band_windows(g, gb, first)
    end subroutine cs_phi_jac_band

    !> The default has no holonomic constraints.
    subroutine cs_no_phi(self, t, q, c)
        class(constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c = 0.0_dp
    end subroutine cs_no_phi

    !> Default G = d phi/d q by central differences.
    subroutine fd_phi_jac(self, t, q, g)
        class(constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        real(dp) :: qp(size(q)), cp(self%n_hol), cm(self%n_hol), h
        integer :: j
        qp = q
        do j = 1, size(q)
            h = central_step(q(j))
            qp(j) = q(j) + h
            call self%phi(t, qp, cp)
            qp(j) = q(j) - h
            call self%phi(t, qp, cm)
            qp(j) = q(j)
            g(:, j) = (cp - cm)/(2.0_dp*h)
        end do
    end subroutine fd_phi_jac

    !> Default phi_t: zero for scleronomic constraints, else a central difference in t.
    subroutine fd_phi_t(self, t, q, pt)
        class(constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: pt(:)
        real(dp) :: cp(self%n_hol), cm(self%n_hol), h
        if (.not. self%rheonomic) then
            pt = 0.0_dp
            return
        end if
        h = central_step(t)
        call self%phi(t + h, q, cp)
        call self%phi(t - h, q, cm)
        pt = (cp - cm)/(2.0_dp*h)
    end subroutine fd_phi_t

    !> Default gamma_h = -d^2/ds^2 phi(t + s, q + s v) at s = 0 (fourth-order five-point
    !! second difference; step eps^(1/6) times the scale of (t, q) over max(|v|, 1)).
    subroutine fd_phi_gamma(self, t, q, v, gam)
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
    end subroutine fd_phi_gamma

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
    subroutine fd_nh_gamma(self, t, q, v, gam)
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
    end subroutine fd_nh_gamma

    !> The default of the has_* queries: the optional piece is not given (the force and
    !! constraint derivatives by finite differences).
    logical function cs_not_given(self)
        class(constrained_system), intent(in) :: self
        cs_not_given = .false.
    end function cs_not_given

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

    !> For a system with `constant_mass`: factorise M(t, q) once and keep the factor in
    !! `mass_factor`, and M^-1 in band form in `mass_inv_band` when it is banded
    !! (otherwise, or if M is not positive definite, drop them: the per-evaluation path
    !! then runs and reports). Call it again after changing the system's mass parameters.
    subroutine prepare_mass(sys, t, q)
        class(constrained_system), intent(inout) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), allocatable :: mm(:, :)
        integer :: info
        if (allocated(sys%mass_factor)) deallocate (sys%mass_factor)
        if (allocated(sys%mass_inv_band)) deallocate (sys%mass_inv_band)
        if (.not. sys%constant_mass .or. sys%diagonal_mass .or. size(q) /= sys%n) return
        allocate (mm(sys%n, sys%n))
        call sys%mass(t, q, mm)
        call mass_cholesky(mm, info)
        if (info /= CM_SUCCESS) return
        call keep_mass_inverse(sys, mm)
        call move_alloc(mm, sys%mass_factor)
    end subroutine prepare_mass

    !> A constant mass with its factor kept by prepare_mass.
    pure logical function has_mass_factor(sys) result(yes)
        class(constrained_system), intent(in) :: sys
        yes = .false.
        if (.not. sys%constant_mass) return
        if (.not. allocated(sys%mass_factor)) return
        yes = size(sys%mass_factor, 1) == sys%n .and. size(sys%mass_factor, 2) == sys%n
    end function has_mass_factor

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
        real(dp) :: ph(sys%n_hol), dg(sys%n)
        integer :: n, m, mh, lainfo, rk, j
        logical :: ok, cached
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
        if (band_ready(sys)) then
            call band_accel(sys, t, q, v, a, lam, ok, alpha, beta)
            if (ok) then
                if (present(rank)) rank = m
                info = CM_SUCCESS
                if (present(msg)) msg = "success"
                return
            end if
        end if
        ok = .false.
        if (sys%diagonal_mass) then
            call sys%mass_diagonal(t, q, dg)
            ok = all(dg > 0.0_dp .and. dg < huge(1.0_dp))
        end if
        cached = .false.
        if (.not. ok) cached = has_mass_factor(sys)
        if (.not. (ok .or. cached)) then
            call sys%mass(t, q, mm)
            if (present(msg)) then
                ! (a local string: passing the optional deferred-length msg straight
                ! through loses its length with gfortran)
                call mass_cholesky(mm, info, m2)
                msg = m2
            else
                call mass_cholesky(mm, info)
            end if
            if (info /= CM_SUCCESS) return
        end if
        call sys%forces(t, q, v, x(:, 1))
        if (m > 0) then
            call constraint_matrix(sys, t, q, c, c0)
            x(:, 2:m + 1) = transpose(c)
        end if
        if (ok) then
            do j = 1, m + 1
                x(:, j) = x(:, j)/dg
            end do
        else if (cached) then
            call dpotrs('U', n, m + 1, sys%mass_factor, n, x, n, lainfo)
        else
            call dpotrs('U', n, m + 1, mm, n, x, n, lainfo)
        end if
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

end module conmech_constrained_system
