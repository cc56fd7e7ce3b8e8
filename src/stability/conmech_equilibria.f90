!> Equilibria (linearisation, eigenvalues, Jordan structure, families, classification),
!! Newton's method for equilibria (also on families) and the Lagrange-Dirichlet test.
!!
!! `linearize` returns A = df/dy at (t, y): the system's analytic Jacobian when it has one
!! (`has_jacobian()`), otherwise the documented central finite difference of
!! `ode_system%jacobian` (step h_j = eps^(1/3) max(|y_j|, 1), error O(h^2) ~ 1e-11 relative).
!!
!! `analyze_equilibrium` computes the eigenvalues of A with LAPACK (dgeev), the Jordan
!! structure of those on the imaginary axis (conmech_jordan: ranks of powers of
!! A - lambda I by SVD), and, when 0 is an eigenvalue, whether the equilibrium lies on a
!! family of equilibria (a cyclic coordinate, a symmetry): Newton (minimum-norm steps) from
!! y + s k for each kernel vector k of A (s = 1e-3 max(1, |y|)) must reach an equilibrium
!! displaced along k; the displacements span the family's tangent, of dimension
!! `family_dim`. The classification (Lyapunov's first method, completed by the Jordan
!! structure), with tol relative to max(1, max |lambda|):
!! - EQ_UNSTABLE: some Re(lambda) > tol (exponential growth; `saddle` when others have
!!   Re < -tol);
!! - EQ_SECULAR: no Re(lambda) > tol but a Jordan block of size s >= 2 on the imaginary
!!   axis: the linearisation has solutions growing like t^(s-1), a drift along the block's
!!   eigenvector at lambda = 0 (`drift`), a resonance at lambda = +-i w
!!   (`secular_frequency`). This is linear instability. It is the instability of the
!!   nonlinear equilibrium when the drift is carried by a first integral (the cart of the
!!   lecture notes: a momentum P /= 0, however small, gives the steady motion x = C0 + C1 t
!!   next to the equilibrium); without one the nonlinear terms may bound the drift
!!   (x'' = -x^3 has a Jordan block at 0 and a stable equilibrium);
!! - EQ_ASYMPTOTICALLY_STABLE: every Re(lambda) < -tol;
!! - EQ_STABLE_FAMILY: the equilibrium lies on a family of dimension d, 0 is a semisimple
!!   eigenvalue of multiplicity d and every other eigenvalue has Re < -tol: the family is
!!   normally attracting and each of its equilibria is stable, not asymptotically (a
!!   nearby solution settles on a nearby member: Aulbach 1984);
!! - EQ_CENTRE: every eigenvalue on the imaginary axis and semisimple, the zero eigenvalue
!!   (if any) only along a family of equilibria: the linearisation is bounded (linearly
!!   stable); nonlinear stability is not decided by it (use an integral or the
!!   Lagrange-Dirichlet test);
!! - EQ_DEGENERATE: the linearisation cannot decide: a zero eigenvalue not explained by a
!!   family, eigenvalues on the axis mixed with Re < 0 (a centre manifold), or a cluster of
!!   eigenvalues on the axis whose structure the tolerance cannot resolve.
!!
!! `find_equilibrium` is Newton's method with minimum-norm steps (dgelsd): on a family of
!! equilibria (a singular Jacobian everywhere on it) it converges to a member.
!!
!! `lagrange_dirichlet` tests whether a symmetric Hessian of the potential energy is
!! positive definite (dsyev): a strict minimum of the potential of a conservative system
!! with holonomic constraints is a stable equilibrium (Lagrange 1788, Dirichlet 1846).
module conmech_equilibria
    use conmech_kinds, only: dp
    use conmech_code_names, only: code_name
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_lapack, only: la_eig, la_sym_eig
    use conmech_rank, only: singular_values, null_space, range_basis, min_norm_solve
    use conmech_jordan, only: axis_cluster, jordan_structure, zero_drift
    implicit none
    private

    integer, parameter, public :: EQ_ASYMPTOTICALLY_STABLE = 1 !! all Re(lambda) < 0
    integer, parameter, public :: EQ_CENTRE = 2                !! all on the axis, bounded
    integer, parameter, public :: EQ_UNSTABLE = 3              !! some Re(lambda) > 0
    integer, parameter, public :: EQ_DEGENERATE = 4            !! linearisation inconclusive
    integer, parameter, public :: EQ_SECULAR = 5               !! Jordan block on the axis
    integer, parameter, public :: EQ_STABLE_FAMILY = 6         !! attracting family

    !> Newton's default: singular values below this fraction of the largest are dropped
    !! (the minimum-norm step of a rank-deficient Jacobian).
    real(dp), parameter, public :: NEWTON_RCOND = 1.0e-10_dp

    public :: equilibrium_result, linearize, analyze_equilibrium, classify_eigenvalues
    public :: classification_name, lagrange_dirichlet, find_equilibrium, potential_hessian
    public :: potential_fun, classify_matrix, equilibrium_family

    !> Result of `analyze_equilibrium`.
    type :: equilibrium_result
        integer :: info = CM_BAD_INPUT
        character(len=:), allocatable :: message
        real(dp), allocatable :: y(:)              !! the point
        real(dp), allocatable :: jacobian(:, :)    !! A = df/dy at the point
        real(dp), allocatable :: wr(:), wi(:)      !! eigenvalues of A (real, imaginary)
        integer :: kind = EQ_DEGENERATE            !! EQ_* classification
        logical :: saddle = .false.                !! eigenvalues on both sides
        real(dp) :: residual = 0.0_dp              !! max |f(t, y)| (0 at an equilibrium)
        logical :: analytic = .false.              !! the Jacobian was analytic
        integer :: zero_multiplicity = 0           !! algebraic multiplicity of lambda = 0
        integer :: largest_block = 1               !! largest Jordan block on the axis
        real(dp) :: secular_frequency = 0.0_dp     !! w > 0 of a Jordan block at +-i w
        integer :: family_dim = 0                  !! dimension of the family through y
        real(dp), allocatable :: family(:, :)      !! n x family_dim: its tangent, orthonormal
        real(dp), allocatable :: drift(:, :)       !! n x k: directions of secular drift
    end type equilibrium_result

    abstract interface
        !> Potential energy V(q).
        function potential_fun(q) result(v)
            import :: dp
            real(dp), intent(in) :: q(:)
            real(dp) :: v
        end function potential_fun
    end interface

contains

    !> A = df/dy at (t, y): analytic if the system has a Jacobian, else central differences.
    subroutine linearize(sys, t, y, a)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: a(:, :)
        call sys%jacobian(t, y, a)
    end subroutine linearize

    !> Linearise at (t, y), compute the eigenvalues, their Jordan structure on the imaginary
    !! axis and the family of equilibria through y, and classify (see the module notes).
    subroutine analyze_equilibrium(sys, y, res, t, tol)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: y(:)
        type(equilibrium_result), intent(out) :: res
        real(dp), intent(in), optional :: t    !! time (default 0)
        real(dp), intent(in), optional :: tol  !! relative tolerance (default 1e-8)
        real(dp) :: tt, tl
        real(dp), allocatable :: f(:)
        integer :: n
        tt = 0.0_dp
        if (present(t)) tt = t
        tl = 1.0e-8_dp
        if (present(tol)) tl = tol
        n = size(y)
        if (n < 1) then
            res%info = CM_BAD_INPUT
            res%message = "bad input: empty state"
            return
        end if
        allocate (res%jacobian(n, n), res%wr(n), res%wi(n), f(n), res%family(n, 0), &
                  res%drift(n, 0))
        res%y = y
        call sys%rhs(tt, y, f)
        res%residual = maxval(abs(f))
        res%analytic = sys%has_jacobian()
        call linearize(sys, tt, y, res%jacobian)
        call structure(res, tl, sys, tt)
    end subroutine analyze_equilibrium

    !> Eigenvalues, Jordan structure and classification of a matrix A alone (no system, so
    !! no family test: a zero eigenvalue makes it EQ_DEGENERATE unless it is part of a
    !! Jordan block); e.g. a linearisation relative to first integrals.
    subroutine classify_matrix(a, res, tol)
        real(dp), intent(in) :: a(:, :)
        type(equilibrium_result), intent(out) :: res
        real(dp), intent(in), optional :: tol  !! relative tolerance (default 1e-8)
        real(dp) :: tl
        integer :: n
        tl = 1.0e-8_dp
        if (present(tol)) tl = tol
        n = size(a, 1)
        if (n < 1 .or. size(a, 2) /= n) then
            res%info = CM_BAD_INPUT
            res%message = "bad input: the matrix must be square and non-empty"
            return
        end if
        allocate (res%wr(n), res%wi(n), res%family(n, 0), res%drift(n, 0))
        res%jacobian = a
        res%y = [real(dp) ::]
        res%analytic = .true.
        call structure(res, tl)
    end subroutine classify_matrix

    !> The common part: eigenvalues, Jordan structure, family (with a system), drift, kind.
    subroutine structure(res, tl, sys, tt)
        type(equilibrium_result), intent(inout) :: res
        real(dp), intent(in) :: tl
        class(ode_system), intent(in), optional :: sys
        real(dp), intent(in), optional :: tt
        type(axis_cluster), allocatable :: cl(:)
        logical, allocatable :: on_axis(:)
        real(dp), allocatable :: drift(:, :)
        integer :: n, ncl, c, nd, m0
        n = size(res%wr)
        call la_eig(res%jacobian, res%wr, res%wi, res%info)
        if (res%info /= CM_SUCCESS) then
            res%message = "eigenvalues: "//status_message(res%info)
            return
        end if
        allocate (cl(n), on_axis(n))
        call jordan_structure(res%jacobian, res%wr, res%wi, tl, cl, ncl, on_axis, res%info)
        if (res%info /= CM_SUCCESS) then
            res%message = "Jordan structure: "//status_message(res%info)
            return
        end if
        m0 = 0
        do c = 1, ncl
            if (.not. cl(c)%resolved) cycle
            res%largest_block = max(res%largest_block, cl(c)%largest_block)
            if (cl(c)%omega == 0.0_dp) then
                m0 = cl(c)%multiplicity
                if (cl(c)%largest_block >= 2) then
                    allocate (drift(n, n))
                    call zero_drift(res%jacobian, cl(c)%largest_block, tl, drift, nd, &
                                    res%info)
                    if (res%info /= CM_SUCCESS) then
                        res%message = "secular drift: "//status_message(res%info)
                        return
                    end if
                    res%drift = drift(:, 1:nd)
                end if
            else if (cl(c)%largest_block >= 2) then
                res%secular_frequency = max(res%secular_frequency, cl(c)%omega)
            end if
        end do
        res%zero_multiplicity = m0
        if (m0 > 0 .and. present(sys) .and. present(tt)) then
            call equilibrium_family(sys, tt, res%y, res%jacobian, tl, res%family, &
                                    res%family_dim, res%info)
            if (res%info /= CM_SUCCESS) then
                res%message = "family of equilibria: "//status_message(res%info)
                return
            end if
        end if
        call classify_structure(res%wr, res%wi, cl(1:ncl), on_axis, tl, res%family_dim, &
                                res%kind, res%saddle)
        res%message = classification_name(res%kind)
    end subroutine structure

    !> Classification from the eigenvalues, their on-axis clusters and the dimension of the
    !! family of equilibria (see the module notes).
    pure subroutine classify_structure(wr, wi, cl, on_axis, tol, family_dim, kind, saddle)
        real(dp), intent(in) :: wr(:), wi(:)
        type(axis_cluster), intent(in) :: cl(:)
        logical, intent(in) :: on_axis(:)
        real(dp), intent(in) :: tol
        integer, intent(in) :: family_dim
        integer, intent(out) :: kind
        logical, intent(out) :: saddle
        real(dp) :: eps
        logical :: expo, neg, amb, secular, axis_nonzero
        integer :: c, m0
        eps = tol*max(1.0_dp, maxval(sqrt(wr**2 + wi**2)))
        expo = any(.not. on_axis .and. wr > eps)
        neg = any(.not. on_axis .and. wr < -eps)
        amb = any(.not. on_axis .and. abs(wr) <= eps)
        secular = .false.
        axis_nonzero = .false.
        m0 = 0
        do c = 1, size(cl)
            if (.not. cl(c)%resolved) cycle
            if (cl(c)%largest_block >= 2) secular = .true.
            if (cl(c)%omega == 0.0_dp) then
                m0 = cl(c)%multiplicity
            else
                axis_nonzero = .true.
            end if
        end do
        saddle = expo .and. neg
        if (expo) then
            kind = EQ_UNSTABLE
        else if (secular) then
            kind = EQ_SECULAR
        else if (amb) then
            kind = EQ_DEGENERATE
        else if (.not. any(on_axis)) then
            kind = EQ_ASYMPTOTICALLY_STABLE
        else if (m0 > family_dim) then
            kind = EQ_DEGENERATE        ! a zero eigenvalue the family does not explain
        else if (.not. axis_nonzero) then
            kind = EQ_STABLE_FAMILY     ! only the family's neutral directions on the axis
        else if (neg) then
            kind = EQ_DEGENERATE        ! a centre manifold: the nonlinear terms decide
        else
            kind = EQ_CENTRE
        end if
    end subroutine classify_structure

    !> Classification of an equilibrium from its eigenvalues alone (no Jordan structure, no
    !! family): unstable, asymptotically stable, centre (every eigenvalue on the axis,
    !! nonzero and simple) or degenerate.
    pure subroutine classify_eigenvalues(wr, wi, tol, kind, saddle)
        real(dp), intent(in) :: wr(:), wi(:)
        real(dp), intent(in) :: tol
        integer, intent(out) :: kind
        logical, intent(out) :: saddle
        real(dp) :: scale, eps
        integer :: i, j
        logical :: repeated
        scale = max(1.0_dp, maxval(sqrt(wr**2 + wi**2)))
        eps = tol*scale
        saddle = any(wr > eps) .and. any(wr < -eps)
        if (any(wr > eps)) then
            kind = EQ_UNSTABLE
        else if (all(wr < -eps)) then
            kind = EQ_ASYMPTOTICALLY_STABLE
        else if (all(abs(wr) <= eps) .and. all(abs(wi) > eps)) then
            repeated = .false.
            do i = 1, size(wr)
                do j = i + 1, size(wr)
                    if (abs(wi(i) - wi(j)) <= sqrt(eps)*scale) repeated = .true.
                end do
            end do
            kind = EQ_CENTRE
            if (repeated) kind = EQ_DEGENERATE
        else
            kind = EQ_DEGENERATE
        end if
    end subroutine classify_eigenvalues

    !> Name of an EQ_* classification.
    pure function classification_name(kind) result(s)
        integer, intent(in) :: kind
        character(len=:), allocatable :: s
        s = code_name(kind, [EQ_ASYMPTOTICALLY_STABLE, EQ_CENTRE, EQ_UNSTABLE, EQ_SECULAR, &
                             EQ_STABLE_FAMILY], &
                      [character(len=66) :: "asymptotically stable", "centre (linearly stable)", &
                       "unstable", &
                       "unstable (secular drift: a Jordan block on the imaginary axis)", &
                       "stable (on an attracting family of equilibria, not asymptotically)"], &
                      "degenerate (linearisation inconclusive)")
    end function classification_name

    !> The family of equilibria through the equilibrium y with Jacobian a: for each vector k
    !! of an orthonormal basis of ker A (singular values <= tol max(1, ||A||)), Newton with
    !! minimum-norm steps from y + s k (s = 1e-3 max(1, |y|)); a converged equilibrium
    !! displaced along k (|k . dy| >= s/4) confirms the direction. The displacements' range
    !! (singular values > s/10) is the family's tangent: family(:, 1:dim), orthonormal.
    subroutine equilibrium_family(sys, t, y, a, tol, family, dim, info)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(in) :: tol
        real(dp), allocatable, intent(out) :: family(:, :)
        integer, intent(out) :: dim
        integer, intent(out) :: info
        real(dp) :: ker(size(y), size(y)), disp(size(y), size(y)), yk(size(y)), s, sv(size(y))
        real(dp) :: basis(size(y), size(y))
        integer :: n, nk, j, nd, inf
        character(len=:), allocatable :: msg
        n = size(y)
        dim = 0
        allocate (family(n, 0))
        call singular_values(a, sv, info)
        if (info /= CM_SUCCESS) return
        call null_space(a, tol*max(1.0_dp, sv(1)), ker, nk, info)
        if (info /= CM_SUCCESS .or. nk == 0) return
        s = 1.0e-3_dp*max(1.0_dp, maxval(abs(y)))
        nd = 0
        do j = 1, nk
            yk = y + s*ker(:, j)
            call find_equilibrium(sys, yk, inf, msg, t, 1.0e-13_dp, 30)
            if (inf /= CM_SUCCESS) cycle
            if (abs(dot_product(ker(:, j), yk - y)) < 0.25_dp*s) cycle
            nd = nd + 1
            disp(:, nd) = yk - y
        end do
        if (nd == 0) return
        call range_basis(disp(:, 1:nd), 0.1_dp*s, basis, dim, info)
        if (info /= CM_SUCCESS) return
        deallocate (family)
        family = basis(:, 1:dim)
    end subroutine equilibrium_family

    !> Lagrange-Dirichlet test: is the symmetric Hessian of the potential positive definite?
    !! `w` returns its eigenvalues (ascending, dsyev); positive definite when
    !! w(1) > tol max(|w|) (tol default 1e-10).
    subroutine lagrange_dirichlet(hess, stable, w, info, tol)
        real(dp), intent(in) :: hess(:, :)
        logical, intent(out) :: stable
        real(dp), intent(out) :: w(:)
        integer, intent(out) :: info
        real(dp), intent(in), optional :: tol
        real(dp) :: tl
        tl = 1.0e-10_dp
        if (present(tol)) tl = tol
        stable = .false.
        if (size(hess, 1) /= size(hess, 2) .or. size(w) /= size(hess, 1)) then
            info = CM_BAD_INPUT
            return
        end if
        if (maxval(abs(hess - transpose(hess))) > 1.0e-8_dp*max(1.0_dp, maxval(abs(hess)))) &
            then
            info = CM_BAD_INPUT
            return
        end if
        call la_sym_eig(hess, w, info)
        if (info /= CM_SUCCESS) return
        stable = w(1) > tl*max(1.0e-300_dp, maxval(abs(w)))
    end subroutine lagrange_dirichlet

    !> Central-difference Hessian of a potential V(q) (step eps^(1/4) max(|q_i|, 1)).
    subroutine potential_hessian(v, q, hess)
        procedure(potential_fun) :: v
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: hess(:, :)
        real(dp) :: qq(size(q)), hi, hj, v0
        integer :: i, j, n
        n = size(q)
        qq = q
        v0 = v(q)
        do i = 1, n
            hi = epsilon(1.0_dp)**0.25_dp*max(abs(q(i)), 1.0_dp)
            qq(i) = q(i) + hi
            hess(i, i) = v(qq)
            qq(i) = q(i) - hi
            hess(i, i) = (hess(i, i) + v(qq) - 2.0_dp*v0)/hi**2
            qq(i) = q(i)
            do j = i + 1, n
                hj = epsilon(1.0_dp)**0.25_dp*max(abs(q(j)), 1.0_dp)
                qq(i) = q(i) + hi; qq(j) = q(j) + hj
                hess(i, j) = v(qq)
                qq(j) = q(j) - hj
                hess(i, j) = hess(i, j) - v(qq)
                qq(i) = q(i) - hi
                hess(i, j) = hess(i, j) + v(qq)
                qq(j) = q(j) + hj
                hess(i, j) = (hess(i, j) - v(qq))/(4.0_dp*hi*hj)
                qq(i) = q(i); qq(j) = q(j)
                hess(j, i) = hess(i, j)
            end do
        end do
    end subroutine potential_hessian

    !> Newton's method for f(t, y) = 0 from the guess y (overwritten by the root), with
    !! minimum-norm steps dy = A^+ f (dgelsd, singular values below rcond * sigma_max
    !! dropped, default NEWTON_RCOND): at a regular root it is Newton's method, on a family
    !! of equilibria (A singular everywhere on it) it converges to a member. Converged when
    !! max|dy| <= tol max(1, |y|) and, if A is rank-deficient there, max|f| <= sqrt(tol)
    !! max(1, |A| max(1, |y|)) (a minimum-norm step can vanish where f does not).
    !! info: CM_SUCCESS, CM_SINGULAR (rank-deficient A and f /= 0: no equilibrium reached),
    !! CM_NO_CONVERGENCE. `rank` (optional): the rank of A at the last iterate.
    subroutine find_equilibrium(sys, y, info, message, t, tol, max_iter, rcond, rank)
        class(ode_system), intent(in) :: sys
        real(dp), intent(inout) :: y(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: message
        real(dp), intent(in), optional :: t
        real(dp), intent(in), optional :: tol       !! on max|dy| (default 1e-12)
        integer, intent(in), optional :: max_iter   !! default 50
        real(dp), intent(in), optional :: rcond     !! default NEWTON_RCOND
        integer, intent(out), optional :: rank
        real(dp) :: tt, tl, rc, a(size(y), size(y)), f(size(y)), dy(size(y)), scale
        integer :: it, mx, rk, n
        tt = 0.0_dp
        if (present(t)) tt = t
        tl = 1.0e-12_dp
        if (present(tol)) tl = tol
        mx = 50
        if (present(max_iter)) mx = max_iter
        rc = NEWTON_RCOND
        if (present(rcond)) rc = rcond
        n = size(y)
        rk = n
        if (present(rank)) rank = n
        do it = 1, mx
            call sys%rhs(tt, y, f)
            call sys%jacobian(tt, y, a)
            call min_norm_solve(a, f, dy, rc, rk, info)
            if (present(rank)) rank = rk
            if (info /= CM_SUCCESS) then
                message = "find_equilibrium: the Newton step failed ("// &
                          status_message(info)//")"
                return
            end if
            y = y - dy
            if (maxval(abs(dy)) <= tl*max(1.0_dp, maxval(abs(y)))) then
                call sys%rhs(tt, y, f)
                scale = max(1.0_dp, maxval(abs(a))*max(1.0_dp, maxval(abs(y))))
                if (rk < n .and. maxval(abs(f)) > sqrt(tl)*scale) then
                    info = CM_SINGULAR
                    message = "find_equilibrium: singular Jacobian and f(y) /= 0 (Newton "// &
                              "stalled: no equilibrium reached from this guess)"
                    return
                end if
                info = CM_SUCCESS
                message = "success"
                return
            end if
        end do
        info = CM_NO_CONVERGENCE
        message = "find_equilibrium: Newton did not converge"
    end subroutine find_equilibrium

end module conmech_equilibria
