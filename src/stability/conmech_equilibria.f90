!> Equilibria (linearisation, eigenvalues, classification) and the Lagrange-Dirichlet test.
!!
!! `linearize` returns A = df/dy at (t, y): the system's analytic Jacobian when it has one
!! (`has_jacobian()`), otherwise the documented central finite difference of
!! `ode_system%jacobian` (step h_j = eps^(1/3) max(|y_j|, 1), error O(h^2) ~ 1e-11 relative).
!!
!! `analyze_equilibrium` computes the eigenvalues of A with LAPACK (dgeev) and classifies the
!! equilibrium from them (Lyapunov's first method):
!! - EQ_ASYMPTOTICALLY_STABLE: every Re(lambda) < -tol;
!! - EQ_UNSTABLE: some Re(lambda) > tol (`saddle` is set when others have Re < -tol);
!! - EQ_CENTRE: every Re(lambda) within tol of zero, no zero eigenvalue and no repeated
!!   eigenvalue (linearly stable; nonlinear stability is not decided by the linearisation,
!!   use an integral or the Lagrange-Dirichlet test);
!! - EQ_DEGENERATE: anything else (a zero eigenvalue, a repeated imaginary pair, or
!!   Re = 0 mixed with Re < 0): the linearisation is inconclusive.
!! tol is relative to max(1, max |lambda|).
!!
!! `lagrange_dirichlet` tests whether a symmetric Hessian of the potential energy is
!! positive definite (dsyev): a strict minimum of the potential of a conservative system
!! with holonomic constraints is a stable equilibrium (Lagrange 1788, Dirichlet 1846).
module conmech_equilibria
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_lapack, only: la_eig, la_sym_eig, la_solve
    implicit none
    private

    integer, parameter, public :: EQ_ASYMPTOTICALLY_STABLE = 1 !! all Re(lambda) < 0
    integer, parameter, public :: EQ_CENTRE = 2                !! all on the imaginary axis
    integer, parameter, public :: EQ_UNSTABLE = 3              !! some Re(lambda) > 0
    integer, parameter, public :: EQ_DEGENERATE = 4            !! linearisation inconclusive

    public :: equilibrium_result, linearize, analyze_equilibrium, classify_eigenvalues
    public :: classification_name, lagrange_dirichlet, find_equilibrium, potential_hessian
    public :: potential_fun

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

    !> Linearise at (t, y), compute the eigenvalues and classify.
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
        allocate (res%jacobian(n, n), res%wr(n), res%wi(n), f(n))
        res%y = y
        call sys%rhs(tt, y, f)
        res%residual = maxval(abs(f))
        res%analytic = sys%has_jacobian()
        call linearize(sys, tt, y, res%jacobian)
        call la_eig(res%jacobian, res%wr, res%wi, res%info)
        if (res%info /= CM_SUCCESS) then
            res%message = "eigenvalues: "//status_message(res%info)
            return
        end if
        call classify_eigenvalues(res%wr, res%wi, tl, res%kind, res%saddle)
        res%message = classification_name(res%kind)
    end subroutine analyze_equilibrium

    !> Classification of an equilibrium from the eigenvalues of its linearisation.
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
        select case (kind)
        case (EQ_ASYMPTOTICALLY_STABLE)
            s = "asymptotically stable"
        case (EQ_CENTRE)
            s = "centre (linearly stable)"
        case (EQ_UNSTABLE)
            s = "unstable"
        case default
            s = "degenerate (linearisation inconclusive)"
        end select
    end function classification_name

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

    !> Newton's method for f(t, y) = 0 from the guess y (overwritten by the root).
    !! info: CM_SUCCESS, CM_SINGULAR (singular Jacobian), CM_NO_CONVERGENCE.
    subroutine find_equilibrium(sys, y, info, message, t, tol, max_iter)
        class(ode_system), intent(in) :: sys
        real(dp), intent(inout) :: y(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: message
        real(dp), intent(in), optional :: t
        real(dp), intent(in), optional :: tol       !! on max|dy| and max|f| (default 1e-12)
        integer, intent(in), optional :: max_iter   !! default 50
        real(dp) :: tt, tl, a(size(y), size(y)), f(size(y), 1), dy(size(y), 1)
        integer :: it, mx
        tt = 0.0_dp
        if (present(t)) tt = t
        tl = 1.0e-12_dp
        if (present(tol)) tl = tol
        mx = 50
        if (present(max_iter)) mx = max_iter
        do it = 1, mx
            call sys%rhs(tt, y, f(:, 1))
            call sys%jacobian(tt, y, a)
            call la_solve(a, f, dy, info)
            if (info /= CM_SUCCESS) then
                message = "find_equilibrium: singular Jacobian (Newton system)"
                return
            end if
            y = y - dy(:, 1)
            if (maxval(abs(dy)) <= tl*max(1.0_dp, maxval(abs(y)))) then
                call sys%rhs(tt, y, f(:, 1))
                info = CM_SUCCESS
                message = "success"
                return
            end if
        end do
        info = CM_NO_CONVERGENCE
        message = "find_equilibrium: Newton did not converge"
    end subroutine find_equilibrium

end module conmech_equilibria
