!> Mechanical systems in generalized coordinates: M(t, q) q'' = Q(t, q, q').
!!
!! A user extends `generalized_system` with the parameters as components and implements
!! `mass` (the symmetric positive definite mass matrix M(t, q)) and `forces` (the
!! generalized forces Q(t, q, q'), including the velocity terms of the Euler-Lagrange
!! equations). `energy` is optional (`has_energy` says whether it is defined).
!!
!! `generalized_ode` wraps such a system as a first-order `ode_system` with y = [q, q']:
!! the accelerations come from a Cholesky factorisation of M (LAPACK dpotf2, or dpotrf
!! above 32 coordinates; solve with two BLAS dtrsv calls: the fastest of the LAPACK/BLAS
!! forms at small n, see bench/results/symbolic_pydy.md; M of up to 32 coordinates lives on
!! the stack, so a right-hand side evaluation allocates nothing). The
!! ODE interface has no status argument, so a mass matrix that is not positive definite
!! makes the right-hand side NaN (the integrators then stop with CM_NONFINITE);
!! `generalized_accel` and `generalized_solve` check M first and return CM_SINGULAR with a
!! message instead.
!!
!! A system that computes a = M^{-1} Q directly (e.g. a kinematic tree by the
!! articulated-body algorithm, O(n) without a matrix) overrides `accelerations` and
!! `has_accelerations`; `generalized_accel` (and with it the right-hand side) then calls it
!! instead of `mass_forces` and the Cholesky solve, and checks that the result is finite.
!! A system that also computes the Jacobian of its accelerations d a/d[q, v] directly
!! (e.g. from the derivatives of the recursive algorithms with a tree-sparse
!! factorisation) overrides `accelerations_jacobian` and `has_accelerations_jacobian`; the
!! Jacobian of the first-order form then uses it, with no factorisation of M.
module conmech_generalized
    use conmech_kinds, only: dp, nan_dp
    use conmech_mechanical_system, only: mechanical_system
    use conmech_status
    use conmech_text, only: itoa
    use conmech_lapack, only: dpotrf, dpotf2, dpotrs, dtrsv, la_finite
    use conmech_ode_system, only: ode_system, ode_events, ode_fd_jacobian
    use conmech_ode_solver, only: ode_options, ode_result, ode_solve
    implicit none
    private

    public :: generalized_system, generalized_ode, generalized_accel, generalized_solve
    public :: mass_cholesky

    !> Mass matrices up to this order are factorised in a stack buffer (no allocation).
    integer, parameter :: SMALL_NDOF = 32

    !> A system M(t, q) q'' = Q(t, q, q') with `ndof` generalized coordinates.
    type, abstract, extends(mechanical_system) :: generalized_system
        integer :: ndof = 0   !! number of generalized coordinates
    contains
        procedure :: forces_jacobian => gen_no_forces_jacobian
        procedure :: mass_forces => gen_mass_forces
        procedure :: has_forces_jacobian => gen_not_given
        procedure :: accelerations => gen_no_accelerations
        procedure :: has_accelerations => gen_not_given
        procedure :: accelerations_jacobian => gen_no_accelerations_jacobian
        procedure :: has_accelerations_jacobian => gen_not_given
    end type generalized_system

    !> First-order form y = [q, v], y' = [v, M^{-1} Q] of a generalized system.
    type, extends(ode_system) :: generalized_ode
        class(generalized_system), allocatable :: mech   !! the mechanical system
    contains
        procedure :: rhs => genode_rhs
        procedure :: jacobian => genode_jacobian
        procedure :: has_jacobian => genode_has_jacobian
    end type generalized_ode

contains

    !> The default of the has_* queries: the optional piece is not given.
    logical function gen_not_given(self)
        class(generalized_system), intent(in) :: self
        gen_not_given = .false.
    end function gen_not_given

    !> Exact derivatives of the accelerations, optional: r = [dQ/dq - d(M a)/dq, dQ/dv]
    !! (ndof x 2 ndof) at the accelerations a = M^{-1} Q, so that d a/d[q, v] = M^{-1} r.
    !! The default is not defined (`has_forces_jacobian` false: finite differences).
    subroutine gen_no_forces_jacobian(self, t, q, v, a, r)
        class(generalized_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:), a(:)
        real(dp), intent(out) :: r(:, :)
        r = 0.0_dp
    end subroutine gen_no_forces_jacobian

    !> Accelerations a = M^{-1} Q computed directly, optional (`has_accelerations`). The
    !! default is not defined (a = 0; `generalized_accel` factorises M instead). An
    !! override returns non-finite entries where it cannot compute a (e.g. a
    !! non-positive articulated inertia: M not positive definite).
    subroutine gen_no_accelerations(self, t, q, v, a)
        class(generalized_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: a(:)
        a = 0.0_dp
    end subroutine gen_no_accelerations

    !> The accelerations a and their Jacobian jac = d a/d[q, v] (ndof x 2 ndof) computed
    !! directly, optional (`has_accelerations_jacobian`). The default is not defined (zeros;
    !! the Jacobian then comes from `forces_jacobian` and a Cholesky factorisation of M).
    subroutine gen_no_accelerations_jacobian(self, t, q, v, a, jac)
        class(generalized_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: a(:), jac(:, :)
        a = 0.0_dp
        jac = 0.0_dp
    end subroutine gen_no_accelerations_jacobian

    !> mm = M(t, q) and f = Q(t, q, v) in one call (what the right-hand side needs). The
    !! default calls `mass` and `forces`; a system that computes both faster together
    !! (shared subexpressions, e.g. compiled systems with a `mass_forces` function)
    !! overrides it.
    subroutine gen_mass_forces(self, t, q, v, mm, f)
        class(generalized_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: mm(:, :), f(:)
        call self%mass(t, q, mm)
        call self%forces(t, q, v, f)
    end subroutine gen_mass_forces

    !> Cholesky factor (upper, in place) of an SPD matrix, with a clear status:
    !! CM_SINGULAR if dpotrf fails or the factor's diagonal ratio squared is below 1e-14
    !! (numerically singular mass matrix). `msg` (optional) explains a failure.
    subroutine mass_cholesky(mm, info, msg)
        real(dp), intent(inout) :: mm(:, :)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out), optional :: msg
        integer :: n, lainfo, i
        real(dp) :: dmin, dmax
        n = size(mm, 1)
        info = CM_SUCCESS
        if (size(mm, 2) /= n) then
            info = CM_BAD_INPUT
            if (present(msg)) msg = "bad input: the mass matrix is not square"
            return
        end if
        ! a finite sum means every entry is finite (a NaN or Inf entry makes it NaN or
        ! Inf); only when it is not (or overflows) are the entries tested one by one
        if (.not. (abs(sum(mm)) <= huge(1.0_dp))) then
            if (.not. la_finite(mm)) then
                info = CM_NONFINITE
                if (present(msg)) msg = "non-finite entries (NaN or Inf) in the mass matrix"
                return
            end if
        end if
        if (n <= SMALL_NDOF) then
            call dpotf2('U', n, mm, n, lainfo)   ! unblocked: no ilaenv overhead
        else
            call dpotrf('U', n, mm, n, lainfo)
        end if
        if (lainfo /= 0) then
            info = CM_SINGULAR
            if (present(msg)) msg = "singular mass matrix: not symmetric positive definite " &
                                    //"(dpotrf info="//itoa(lainfo)//")"
            return
        end if
        dmin = huge(1.0_dp)
        dmax = 0.0_dp
        do i = 1, n
            dmin = min(dmin, abs(mm(i, i)))
            dmax = max(dmax, abs(mm(i, i)))
        end do
        if ((dmin/dmax)**2 < 1.0e-14_dp) then
            info = CM_SINGULAR
            if (present(msg)) msg = "singular mass matrix: numerically singular (condition > 1e14)"
            return
        end if
        if (present(msg)) msg = "success"
    end subroutine mass_cholesky

    !> Accelerations a = M(t, q)^{-1} Q(t, q, v), with a status: from the system's own
    !! `accelerations` when it has them (CM_NONFINITE if they are not finite), else by a
    !! Cholesky factorisation of M (CM_SINGULAR if M is not positive definite).
    subroutine generalized_accel(mech, t, q, v, a, info, msg)
        class(generalized_system), intent(in) :: mech
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: a(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out), optional :: msg
        real(dp) :: small(SMALL_NDOF*SMALL_NDOF)
        real(dp), allocatable :: big(:)
        character(len=:), allocatable :: m2
        integer :: n
        n = mech%ndof
        if (n < 1 .or. size(q) /= n .or. size(v) /= n .or. size(a) /= n) then
            info = CM_BAD_INPUT
            if (present(msg)) msg = "bad input: q, v and a must have ndof elements (ndof >= 1)"
            return
        end if
        if (mech%has_accelerations()) then
            call mech%accelerations(t, q, v, a)
            if (abs(sum(a)) <= huge(1.0_dp)) then
                info = CM_SUCCESS
                if (present(msg)) msg = "success"
            else
                info = CM_NONFINITE
                if (present(msg)) msg = "non-finite accelerations from the system's " &
                    //"accelerations (mass matrix not positive definite, e.g. a zero or " &
                    //"negative articulated inertia, or non-finite forces)"
            end if
            return
        end if
        if (n > SMALL_NDOF) allocate (big(n*n))
        ! (a local string: passing the optional deferred-length msg straight through
        ! loses its length with gfortran)
        if (n <= SMALL_NDOF .and. present(msg)) then
            call accel_in(mech, n, t, q, v, a, small, info, m2)
        else if (n <= SMALL_NDOF) then
            call accel_in(mech, n, t, q, v, a, small, info)
        else if (present(msg)) then
            call accel_in(mech, n, t, q, v, a, big, info, m2)
        else
            call accel_in(mech, n, t, q, v, a, big, info)
        end if
        if (present(msg)) msg = m2
    end subroutine generalized_accel

    !> generalized_accel with the mass matrix in the caller's buffer mm (n x n).
    subroutine accel_in(mech, n, t, q, v, a, mm, info, msg)
        class(generalized_system), intent(in) :: mech
        integer, intent(in) :: n
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: a(:)
        real(dp), intent(out) :: mm(n, n)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out), optional :: msg
        character(len=:), allocatable :: m2
        call mech%mass_forces(t, q, v, mm, a)
        if (present(msg)) then
            call mass_cholesky(mm, info, m2)
            msg = m2
        else
            call mass_cholesky(mm, info)
        end if
        if (info /= CM_SUCCESS) return
        call chol_solve1(n, mm, a)
    end subroutine accel_in

    !> Solve U^T U x = b in place (U from mass_cholesky): two BLAS dtrsv calls, cheaper
    !! than dpotrs (dtrsm) for one right-hand side.
    subroutine chol_solve1(n, u, b)
        integer, intent(in) :: n
        real(dp), intent(in) :: u(n, n)
        real(dp), intent(inout) :: b(:)
        call dtrsv('U', 'T', 'N', n, u, n, b, 1)
        call dtrsv('U', 'N', 'N', n, u, n, b, 1)
    end subroutine chol_solve1

    subroutine genode_rhs(self, t, y, dydt)
        class(generalized_ode), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        integer :: n, info
        n = self%mech%ndof
        dydt(1:n) = y(n + 1:2*n)
        call generalized_accel(self%mech, t, y(1:n), y(n + 1:2*n), dydt(n + 1:2*n), info)
        if (info /= CM_SUCCESS) dydt(n + 1:2*n) = nan_dp
    end subroutine genode_rhs

    !> Jacobian of y' = [v, M^{-1} Q]: exact when the system has
    !! `accelerations_jacobian` ([0 I; d a/d[q, v]] directly) or `forces_jacobian`
    !! ([0 I; M^{-1} r], one Cholesky of M), else central differences.
    subroutine genode_jacobian(self, t, y, dfdy)
        class(generalized_ode), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(dp) :: mm(self%mech%ndof, self%mech%ndof), a(self%mech%ndof)
        real(dp) :: r(self%mech%ndof, 2*self%mech%ndof)
        integer :: n, info, j
        if (self%mech%has_accelerations_jacobian()) then
            n = self%mech%ndof
            dfdy = 0.0_dp
            do j = 1, n
                dfdy(j, n + j) = 1.0_dp
            end do
            call self%mech%accelerations_jacobian(t, y(1:n), y(n + 1:2*n), a, r)
            dfdy(n + 1:2*n, :) = r
            return
        end if
        if (.not. self%mech%has_forces_jacobian()) then
            call ode_fd_jacobian(self, t, y, dfdy)
            return
        end if
        n = self%mech%ndof
        dfdy = 0.0_dp
        do j = 1, n
            dfdy(j, n + j) = 1.0_dp
        end do
        call self%mech%mass(t, y(1:n), mm)
        call self%mech%forces(t, y(1:n), y(n + 1:2*n), a)
        call mass_cholesky(mm, info)
        if (info /= CM_SUCCESS) then
            dfdy(n + 1:2*n, :) = nan_dp
            return
        end if
        call chol_solve1(n, mm, a)
        call self%mech%forces_jacobian(t, y(1:n), y(n + 1:2*n), a, r)
        call dpotrs('U', n, 2*n, mm, n, r, n, info)
        dfdy(n + 1:2*n, :) = r
    end subroutine genode_jacobian

    logical function genode_has_jacobian(self)
        class(generalized_ode), intent(in) :: self
        genode_has_jacobian = self%mech%has_forces_jacobian() &
                              .or. self%mech%has_accelerations_jacobian()
    end function genode_has_jacobian

    !> Solve M q'' = Q from (q0, v0) on t_span with `ode_solve`; res%y = [q; v] (events
    !! see y = [q; v] too). Checks the dimensions and the mass matrix at the start first.
    subroutine generalized_solve(mech, t_span, q0, v0, options, res, t_eval, events)
        class(generalized_system), intent(in) :: mech
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: q0(:), v0(:)
        type(ode_options), intent(in) :: options
        type(ode_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        type(generalized_ode) :: sys
        real(dp), allocatable :: a(:)
        integer :: info
        character(len=:), allocatable :: msg
        if (mech%ndof < 1 .or. size(q0) /= mech%ndof .or. size(v0) /= mech%ndof) then
            res%status = CM_BAD_INPUT
            res%message = "bad input: q0 and v0 must have ndof elements"
            res%success = .false.
            return
        end if
        allocate (a(mech%ndof))
        call generalized_accel(mech, t_span(1), q0, v0, a, info, msg)
        if (info /= CM_SUCCESS) then
            res%status = info
            res%message = msg
            res%success = .false.
            return
        end if
        allocate (sys%mech, source=mech)
        call ode_solve(sys, t_span, [q0, v0], options, res, t_eval, events)
    end subroutine generalized_solve

end module conmech_generalized
