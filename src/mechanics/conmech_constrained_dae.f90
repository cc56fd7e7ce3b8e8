!> The equations of motion of a constrained system as an index-2 differential-algebraic
!! system (the stabilised formulation of Gear, Gupta and Leimkuhler, GGL) for Radau IIA,
!! y = [q, v, lambda, mu]:
!!
!!     q' = v + G^T mu                               (differential, index 1)
!!     v' = M(t, q)^{-1} (Q(t, q, v) + C^T lambda)   (differential, index 1)
!!     0 = C v + c0                                  (velocity constraints: lambda index 2)
!!     0 = phi(t, q)                                 (position constraints: mu index 2)
!!
!! with C = [G; A], c0 = [phi_t; b] (holonomic and non-holonomic constraints) and the
!! extra multiplier mu (zero on exact solutions) that keeps the positions on phi = 0.
!! The mass matrix of the DAE is diag(I, I, 0, 0) (constant, whatever M(t, q)): the
!! configuration-dependent mass enters through M^{-1} in the velocity rows (Cholesky per
!! evaluation; a `constant_mass` system's factor is kept, a `diagonal_mass` costs a
!! division). Both constraint levels hold at every step end to the Newton tolerance: no
!! drift, no projection. Radau IIA gives q and v to order 5 and the multipliers to order
!! 3 (Hairer-Wanner, Solving ODEs II, VII.4); lambda and mu get the index-2 error scaling
!! (their error weighted by h, as RADAU5's NIND2). The extra multiplier mu vanishes on
!! the exact solution, so no relative tolerance sets its scale; it is measured by what it
!! moves: its absolute tolerance is that of the positions divided by the size of its
!! constraint's gradient, (atol + rtol max|q0|)/max|G_i(q0)|. (With atol alone, the
!! round-off of phi at the stages, ~ eps |q| |G|, divided by h G G^T, exceeds atol/h at
!! tight tolerances once the angles have grown: the Newton iteration then stalls.)
!!
!! The Jacobian is assembled from the system's pieces: the Jacobian of the force balance
!! [dQ/dq - d(M a)/dq, dQ/dv] at the current acceleration a (`forces_jacobian`) and the
!! constraint second derivatives d(C^T lambda)/dq, d(G^T mu)/dq, d(C v + c0)/dq
!! (`constraint_hessian`): exact for compiled systems that provide them (conmech.symbolic
!! generates both), central differences otherwise.
!!
!! `ggl_setup` gives the system, its initial state and the Radau stepper with its mass
!! matrix and index vector; `dae_events` sees events of (t, [q; v]) from any DAE state
!! whose first 2n components are [q; v] (this form and the index-3 form,
!! conmech_constrained_index3). `dae_mass_solve` is the M^{-1} of both; `mech_dae` their
!! common parent type and `dae_start` their common start (state and stepper mass matrix).
module conmech_constrained_dae
    use conmech_kinds, only: dp, nan_dp
    use conmech_status, only: CM_SUCCESS
    use conmech_lapack, only: dpotrs
    use conmech_generalized, only: mass_cholesky
    use conmech_ode_system, only: ode_system, ode_events
    use conmech_radau_stepper, only: radau_stepper
    use conmech_constrained_system, only: constrained_system, constraint_matrix, &
        prepare_mass, has_mass_factor
    implicit none
    private

    public :: mech_dae, ggl_system, dae_events, ggl_setup, dae_mass_solve, dae_start

    !> A DAE form of a constrained system, y = [q, v, ...]: its Jacobian is always
    !! assembled (from exact or finite-difference pieces).
    type, abstract, extends(ode_system) :: mech_dae
        class(constrained_system), allocatable :: mech
    contains
        procedure :: has_jacobian => mech_dae_has_jacobian
    end type mech_dae

    !> The stabilised index-2 right-hand side of a constrained system.
    type, extends(mech_dae) :: ggl_system
    contains
        procedure :: rhs => ggl_rhs
        procedure :: jacobian => ggl_jacobian
    end type ggl_system

    !> Events of (t, [q; v]) seen from a DAE state y = [q, v, ...].
    type, extends(ode_events) :: dae_events
        class(ode_events), allocatable :: inner
        integer :: n = 0
    contains
        procedure :: eval => dae_event_eval
    end type dae_events

contains

    subroutine dae_event_eval(self, t, y, g)
        class(dae_events), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: g(:)
        call self%inner%eval(t, y(1:2*self%n), g)
    end subroutine dae_event_eval

    !> x = M(t, q)^{-1} x for the k columns of x: a division for a diagonal mass, the kept
    !! Cholesky factor of a constant one, else a Cholesky factorisation of M(t, q). ok is
    !! .false. (and x NaN) when M is not positive definite.
    subroutine dae_mass_solve(sys, t, q, x, ok)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(inout) :: x(:, :)
        logical, intent(out) :: ok
        real(dp) :: mm(sys%n, sys%n), dg(sys%n)
        integer :: n, info, j
        n = sys%n
        ok = .true.
        if (sys%diagonal_mass) then
            call sys%mass_diagonal(t, q, dg)
            ok = all(dg > 0.0_dp .and. dg < huge(1.0_dp))
            if (ok) then
                do j = 1, size(x, 2)
                    x(:, j) = x(:, j)/dg
                end do
            end if
        else if (has_mass_factor(sys)) then
            call dpotrs('U', n, size(x, 2), sys%mass_factor, n, x, n, info)
            ok = info == 0
        else
            call sys%mass(t, q, mm)
            call mass_cholesky(mm, info)
            ok = info == CM_SUCCESS
            if (ok) then
                call dpotrs('U', n, size(x, 2), mm, n, x, n, info)
                ok = info == 0
            end if
        end if
        if (.not. ok) x = nan_dp
    end subroutine dae_mass_solve

    subroutine ggl_rhs(self, t, y, dydt)
        class(ggl_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: c(self%mech%n_hol + self%mech%n_nh, self%mech%n)
        real(dp) :: c0(self%mech%n_hol + self%mech%n_nh), x(self%mech%n, 1)
        integer :: n, m, mh
        logical :: ok
        n = self%mech%n
        mh = self%mech%n_hol
        m = mh + self%mech%n_nh
        call self%mech%forces(t, y(1:n), y(n + 1:2*n), x(:, 1))
        dydt(1:n) = y(n + 1:2*n)
        if (m > 0) then
            call constraint_matrix(self%mech, t, y(1:n), c, c0)
            x(:, 1) = x(:, 1) + matmul(y(2*n + 1:2*n + m), c)
            if (mh > 0) dydt(1:n) = dydt(1:n) + matmul(y(2*n + m + 1:2*n + m + mh), &
                                                      c(1:mh, :))
            dydt(2*n + 1:2*n + m) = matmul(c, y(n + 1:2*n)) + c0
            if (mh > 0) call self%mech%phi(t, y(1:n), dydt(2*n + m + 1:2*n + m + mh))
        end if
        call dae_mass_solve(self%mech, t, y(1:n), x, ok)
        dydt(n + 1:2*n) = x(:, 1)
    end subroutine ggl_rhs

    !> The Jacobian of the GGL right-hand side (see the module documentation).
    subroutine ggl_jacobian(self, t, y, dfdy)
        class(ggl_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(dp) :: c(self%mech%n_hol + self%mech%n_nh, self%mech%n)
        real(dp) :: c0(self%mech%n_hol + self%mech%n_nh)
        real(dp) :: lam(self%mech%n_hol + self%mech%n_nh)
        real(dp) :: hv(self%mech%n_hol + self%mech%n_nh, self%mech%n)
        real(dp) :: hl(self%mech%n, self%mech%n), r(self%mech%n, 2*self%mech%n)
        real(dp) :: x(self%mech%n, 2*self%mech%n + self%mech%n_hol + self%mech%n_nh + 1)
        integer :: n, m, mh, i
        logical :: ok
        n = self%mech%n
        mh = self%mech%n_hol
        m = mh + self%mech%n_nh
        dfdy = 0.0_dp
        associate (q => y(1:n), v => y(n + 1:2*n))
            ! the acceleration a = M^{-1}(Q + C^T lambda) (last column of x)
            call self%mech%forces(t, q, v, x(:, 2*n + m + 1))
            if (m > 0) then
                call constraint_matrix(self%mech, t, q, c, c0)
                lam = y(2*n + 1:2*n + m)
                x(:, 2*n + m + 1) = x(:, 2*n + m + 1) + matmul(lam, c)
            end if
            call dae_mass_solve(self%mech, t, q, x(:, 2*n + m + 1:2*n + m + 1), ok)
            call self%mech%forces_jacobian(t, q, v, x(:, 2*n + m + 1), r)
            x(:, 1:2*n) = r
            if (m > 0) then
                call self%mech%constraint_hessian(t, q, v, lam, hl, hv)
                x(:, 1:n) = x(:, 1:n) + hl
                x(:, 2*n + 1:2*n + m) = transpose(c)
            end if
            call dae_mass_solve(self%mech, t, q, x(:, 1:2*n + m), ok)
            ! velocity rows
            dfdy(n + 1:2*n, 1:2*n + m) = x(:, 1:2*n + m)
            ! position rows: q' = v + G^T mu
            do i = 1, n
                dfdy(i, n + i) = 1.0_dp
            end do
            if (m == 0) return
            dfdy(2*n + 1:2*n + m, 1:n) = hv
            dfdy(2*n + 1:2*n + m, n + 1:2*n) = c
            if (mh == 0) return
            dfdy(1:n, 2*n + m + 1:2*n + m + mh) = transpose(c(1:mh, :))
            dfdy(2*n + m + 1:2*n + m + mh, 1:n) = c(1:mh, :)
            lam = 0.0_dp
            lam(1:mh) = y(2*n + m + 1:2*n + m + mh)
            call self%mech%constraint_hessian(t, q, v, lam, hl, hv)
            dfdy(1:n, 1:n) = hl
        end associate
    end subroutine ggl_jacobian

    logical function mech_dae_has_jacobian(self)
        class(mech_dae), intent(in) :: self
        mech_dae_has_jacobian = self%mech%n >= 1
    end function mech_dae_has_jacobian

    !> The start of a DAE form of size nd: y0 = [q, v, 0, ...] and the Radau stepper's
    !! mass matrix diag(I, I, 0, ...) (ones on the 2n components of q and v), with its
    !! index vector allocated (nd) for the caller to fill.
    subroutine dae_start(q, v, nd, y0, stp)
        real(dp), intent(in) :: q(:), v(:)
        integer, intent(in) :: nd
        real(dp), allocatable, intent(out) :: y0(:)
        type(radau_stepper), intent(inout) :: stp
        integer :: n, i
        n = size(q)
        allocate (y0(nd))
        y0 = 0.0_dp
        y0(1:n) = q
        y0(n + 1:2*n) = v
        if (allocated(stp%mass)) deallocate (stp%mass)
        if (allocated(stp%dae_index)) deallocate (stp%dae_index)
        allocate (stp%mass(nd, nd), stp%dae_index(nd))
        stp%mass = 0.0_dp
        do i = 1, 2*n
            stp%mass(i, i) = 1.0_dp
        end do
    end subroutine dae_start

    !> The GGL form of sys at (t0, q, v) with the multipliers lam: the system g (its copy
    !! of sys with a constant mass factorised once), its state y0 = [q, v, lam, 0] and the
    !! Radau stepper set up with the mass matrix diag(I, I, 0, 0) and the index vector
    !! (1 for q, v; 2 for lambda, mu).
    subroutine ggl_setup(sys, t0, q, v, lam, rtol, atol, g, y0, stp, rtol_vec, atol_vec)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t0, q(:), v(:), lam(:)
        !> the tolerances of the run (q, v, lambda); those of mu follow from them
        real(dp), intent(in) :: rtol, atol
        type(ggl_system), intent(out) :: g
        real(dp), allocatable, intent(out) :: y0(:)
        type(radau_stepper), intent(inout) :: stp
        !> the per-component tolerances of the DAE state
        real(dp), allocatable, intent(out) :: rtol_vec(:), atol_vec(:)
        real(dp) :: c(sys%n_hol + sys%n_nh, sys%n), c0(sys%n_hol + sys%n_nh), gi
        integer :: n, m, mh, nd, i
        n = sys%n
        mh = sys%n_hol
        m = mh + sys%n_nh
        nd = 2*n + m + mh
        call dae_start(q, v, nd, y0, stp)
        y0(2*n + 1:2*n + m) = lam
        stp%dae_index = 1
        stp%dae_index(2*n + 1:nd) = 2
        allocate (rtol_vec(nd), atol_vec(nd))
        rtol_vec = rtol
        atol_vec = atol
        if (mh > 0) then
            call constraint_matrix(sys, t0, q, c, c0)
            do i = 1, mh
                gi = maxval(abs(c(i, :)))
                if (gi > 0.0_dp) atol_vec(2*n + m + i) = (atol + rtol*maxval(abs(q)))/gi
            end do
        end if
        allocate (g%mech, source=sys)
        call prepare_mass(g%mech, t0, q)
    end subroutine ggl_setup

end module conmech_constrained_dae
