!> Radau IIA of order 5 (three stages) for stiff systems y' = f(t, y) and M y' = f(t, y):
!! Hairer & Wanner's RADAU5 (Solving ODEs II, section IV.8), written anew as a stepper of
!! the integrator contract (conmech_ode_stepper).
!!
!! - Simplified Newton iteration on the transformed stage system: with the eigenvalues
!!   gamma and alpha +- i beta of the inverse Radau matrix, one real LU of
!!   (gamma/h M - J) and one complex LU of ((alpha + i beta)/h M - J), both of size n
!!   (LAPACK dgetrf/zgetrf; with a sparsity pattern in `jstruct`, n >= 100 and at most 10%
!!   of the entries in the pattern, or jstruct%lu = LU_SPARSE: sparse LUs with a reverse
!!   Cuthill-McKee column order, conmech_radau_sparse, and J kept on its pattern).
!!   Convergence control by the contraction rate theta as
!!   RADAU5: at most 7 iterations, stop when theta/(1 - theta) |dW| <= fnewt, a step
!!   reduction when the predicted error after the remaining iterations is too large.
!! - Error estimate (I - h gamma0 J)^{-1}(f0 + (e1 z1 + e2 z2 + e3 z3)/h), refined by one
!!   more solve after a rejection or at the first step, as RADAU5.
!! - Step size: h_new = h / max(1/8, min(5, err^(1/4)/fac)), fac = min(0.9, 0.9 (2 nit
!!   + 1)/(newt + 2 nit)), then the predictive controller of Gustafsson. The Jacobian is
!!   re-evaluated after an accepted step only when the Newton iteration was slow (more
!!   than two iterations and theta > 0.001; RADAU5 uses theta alone, SciPy this rule),
!!   and after a Newton failure if it is not current; a step rejected by the error test
!!   keeps it (SciPy; RADAU5 refreshes it there);
!!   otherwise the step and the LU are kept when the proposed ratio is below 1.2 (SciPy's
!!   window; RADAU5's default is [1, 1.2]). With these two choices the counts of steps,
!!   Jacobians and LUs are within a few per cent of SciPy's Radau (bench/bench_radau.py).
!! - Tolerances are used as given (SciPy's convention; RADAU5 itself transforms rtol to
!!   0.1 rtol^(2/3)): error norm sqrt(mean((err_i/sk_i)^2)), sk_i = atol_i + rtol_i |y_i|
!!   at the start of the step; Newton tolerance fnewt = max(10 eps/rtol, min(0.03,
!!   rtol^(1/2))) as SciPy and RADAU5.
!! - Initial step: the heuristic of SciPy's select_initial_step for an error estimator of
!!   order 3, unless first_step is given.
!! - Jacobian: the system's analytic `jacobian` if `has_jacobian()`, else forward
!!   differences with Hairer's steps sqrt(eps max(1e-5, |y_j|)) (n evaluations, counted in
!!   nfev; with a sparsity pattern in `jstruct`, one evaluation per Curtis-Powell-Reid
!!   group of columns). A Jacobian declared constant (`jstruct%constant`, SciPy's constant
!!   `jac`) is read once at the start and never re-evaluated; it counts no evaluation
!!   (njev 0, as SciPy).
!! - Smallest step: SciPy's (`min_step_at`, 10 spacings of t): a step proposed below it is
!!   raised to it once; an attempt below it ends the run.
!! - Continuous extension: the collocation polynomial (degree 3, power basis), on which the
!!   driver finds t_eval points and events.
!! - Failures: a Newton iteration that does not converge (or meets non-finite values)
!!   halves the step; 0.1 |h| <= eps |t| ends the run (CM_STEP_TOO_SMALL, with the time);
!!   a singular iteration matrix halves the step, five singular ones in a row end the run
!!   (CM_SINGULAR).
!! - Mass-matrix form M y' = f(t, y) with a constant, possibly singular M (differential-
!!   algebraic systems of index up to 3, RADAU5's IMAS = 1): the components `mass` and
!!   `dae_index` (or `index2`) set before `init`; the error (and the Newton increments) of
!!   an index-k component are weighted by |h|^(k-1), as RADAU5's NIND2, NIND3; the initial
!!   step is then 1e-6 unless given. The constrained layer uses it for the stabilised
!!   index-2 formulation (conmech_constrained_dae) and the index-3 formulation with the
!!   accelerations and multipliers as algebraic variables (conmech_constrained_index3).
!! Counters: nfev, njev, nlu (each LU counts once: two per factorisation, as SciPy counts).
!! This module holds the state and its packing; the step itself is the submodule
!! conmech_radau_step, on conmech_radau_newton (Jacobian, LU, Newton) and
!! conmech_radau_control (initial step, error estimate, step-size control).
module conmech_radau_stepper
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: ode_options
    use conmech_ode_stepper, only: ode_stepper
    use conmech_state_packer, only: state_packer
    use conmech_radau_collocation, only: radau_collocation_basis
    use conmech_radau_coefficients, only: GAM0, ALPH, BETA
    use conmech_jacobian_structure, only: jacobian_structure
    use conmech_radau_sparse, only: radau_sparse_lu
    implicit none
    private

    public :: radau_stepper, radau_allocate_work

    !> Everything a Radau IIA integration carries from step to step (beyond the contract's
    !! common state: t_old, h_done are the start and length of the last accepted step, fc
    !! its collocation polynomial), its work arrays, and the mass matrix of M y' = f.
    type, extends(ode_stepper) :: radau_stepper
        !> constant mass matrix M of M y' = f(t, y) (n x n, may be singular: a DAE), set by
        !! the caller before `init`; unallocated: M = I
        real(dp), allocatable :: mass(:, :)
        !> the index-2 algebraic components (their error is scaled by h, as RADAU5), set
        !! with `mass` (shorthand for `dae_index` = 2 on them)
        logical, allocatable :: index2(:)
        !> the differentiation index of each component (1, 2 or 3), set with `mass`: the
        !! error of an index-k component is weighted by |h|^(k-1) (RADAU5's NIND2, NIND3)
        integer, allocatable :: dae_index(:)
        !> what is known of df/dy: constant, or a sparsity pattern for grouped
        !! differences; set by the caller before `init`
        type(jacobian_structure) :: jstruct
        real(dp) :: hmax = 0, uround = 0, fnewt = 0   !! largest |h|, roundoff, Newton tol.
        real(dp) :: faccon = 1, theta = 0     !! Newton contraction memory and rate
        real(dp) :: hacc = 0, erracc = 1      !! last accepted step and error (Gustafsson)
        real(dp) :: safe = 0.9_dp             !! safety factor
        real(dp) :: facl = 5, facr = 0.125_dp !! bounds of h/h_new
        real(dp) :: cfac = 0                  !! safe (1 + 2 NIT)
        real(dp) :: err = 0                   !! scaled error estimate of the last attempt
        real(dp) :: hnew = 0                  !! proposed next step
        real(dp) :: first_step = 0            !! the option (0: heuristic)
        real(dp) :: pmat(3, 3) = 0, cvec(3) = 0   !! collocation basis (nodes, power basis)
        integer :: newt = 0                   !! Newton iterations of the last attempt
        integer :: nsteps = 0, nsing = 0, nfail = 0   !! steps, singular LUs, Newton failures
        integer :: max_steps = 100000
        logical :: first = .true.             !! no step accepted yet
        logical :: reject = .false.           !! the last attempt was rejected
        logical :: caljac = .false.           !! the Jacobian is current
        logical :: need_jac = .true.          !! evaluate the Jacobian before the step
        logical :: need_lu = .true.           !! factorise before the step
        logical :: have_cont = .false.        !! fc holds a polynomial
        logical :: newton_failed = .false.    !! the last Newton iteration failed
        logical :: converged = .false.        !! the last Newton iteration converged
        logical :: f_ok = .true.              !! f0 = f(t, y) is finite
        logical :: final_step = .false.       !! the step to attempt ends at tf
        logical :: h_capped = .false.         !! h was cut to hmax after the last step
        real(dp), allocatable :: f0(:), scal(:), scal0(:), rtolv(:), atolv(:)
        !> the sparse path: J on its pattern (jval) and sparse LUs (slu) instead of the
        !! dense jac, e1, e2 (conmech_radau_sparse; chosen in `init`)
        logical :: sparse = .false.
        real(dp), allocatable :: jval(:)                !! J's values on its pattern
        type(radau_sparse_lu) :: slu                    !! the sparse iteration matrices
        real(dp), allocatable :: jac(:, :), e1(:, :)    !! J and the LU of gamma/h M - J
        complex(dp), allocatable :: e2(:, :)            !! LU of (alpha + i beta)/h M - J
        integer, allocatable :: ip1(:), ip2(:)          !! pivots of e1, e2
        real(dp), allocatable :: z1(:), z2(:), z3(:), w1(:), w2(:), w3(:)
        real(dp), allocatable :: a1(:), a2(:), a3(:), b1(:), b2(:), b3(:), cont(:)
        complex(dp), allocatable :: zc(:)
    contains
        procedure :: setup => radau_setup
        procedure :: start => radau_start
        procedure :: step => radau_step
        procedure :: transfer_state => radau_transfer
        procedure :: refresh_f => radau_refresh_f
        procedure :: f_finite => radau_f_finite
    end type radau_stepper

    interface
        !> The options and the mass matrix checked; constants and arrays (no evaluation).
        module subroutine radau_setup(self, opt, info, msg)
            class(radau_stepper), intent(inout) :: self
            type(ode_options), intent(in) :: opt
            integer, intent(out) :: info
            character(len=:), allocatable, intent(out) :: msg
        end subroutine radau_setup
        !> f at t0, the scale and the initial step.
        module subroutine radau_start(self, sys, info, msg)
            class(radau_stepper), intent(inout) :: self
            class(ode_system), intent(in) :: sys
            integer, intent(out) :: info
            character(len=:), allocatable, intent(out) :: msg
        end subroutine radau_start
        !> One accepted step (Jacobian, LUs, Newton, error test, step control).
        module subroutine radau_step(self, sys, target, info, msg)
            class(radau_stepper), intent(inout) :: self
            class(ode_system), intent(in) :: sys
            real(dp), intent(in) :: target
            integer, intent(out) :: info
            character(len=:), allocatable, intent(out) :: msg
        end subroutine radau_step
    end interface

contains

    !> Allocate the work arrays (not part of the packed state) for dimension self%n.
    subroutine radau_allocate_work(self)
        class(radau_stepper), intent(inout) :: self
        integer :: n
        n = self%n
        if (allocated(self%z1)) then
            if (size(self%z1) == n) return
            deallocate (self%z1, self%z2, self%z3, self%w1, self%w2, self%w3, self%a1, &
                        self%a2, self%a3, self%scal, self%cont, self%zc, self%b1, self%b2, &
                        self%b3)
        end if
        allocate (self%z1(n), self%z2(n), self%z3(n), self%w1(n), self%w2(n), self%w3(n), &
                  self%a1(n), self%a2(n), self%a3(n), self%scal(n), self%cont(n), &
                  self%zc(n), self%b1(n), self%b2(n), self%b3(n))
    end subroutine radau_allocate_work

    !> The whole state (conmech_state_packer): the controller's memory, f(t, y), the scale,
    !! the tolerances, J, both LU factorisations with their pivots, the mass matrix if any.
    subroutine radau_transfer(self, p)
        class(radau_stepper), intent(inout) :: self
        type(state_packer), intent(inout) :: p
        logical :: has_mass
        integer :: n
        integer, allocatable :: idx(:)
        call self%transfer_base(p)
        n = self%n
        call p%item(self%hmax)
        call p%item(self%uround)
        call p%item(self%fnewt)
        call p%item(self%faccon)
        call p%item(self%theta)
        call p%item(self%hacc)
        call p%item(self%erracc)
        call p%item(self%safe)
        call p%item(self%facl)
        call p%item(self%facr)
        call p%item(self%cfac)
        call p%item(self%first_step)
        call p%item(self%nsteps)
        call p%item(self%nsing)
        call p%item(self%nfail)
        call p%item(self%max_steps)
        call p%item(self%first)
        call p%item(self%reject)
        call p%item(self%caljac)
        call p%item(self%need_jac)
        call p%item(self%need_lu)
        call p%item(self%have_cont)
        call p%item(self%newton_failed)
        call p%item(self%f_ok)
        call p%item(self%final_step)
        call p%item(self%h_capped)
        call self%jstruct%transfer(p)
        call p%column(self%f0)
        call p%column(self%scal0)
        call p%column(self%rtolv)
        call p%column(self%atolv)
        call p%item(self%sparse)
        if (self%sparse) then
            call transfer_sparse(self, p)
        else
            call p%columns(self%jac, 1, n)
            call p%columns(self%e1, 1, n)
            call p%complex_columns(self%e2, n)
            call p%ints(self%ip1, n)
            call p%ints(self%ip2, n)
            if (p%reading()) self%jval = [real(dp) ::]
        end if
        has_mass = allocated(self%mass)
        call p%item(has_mass)
        if (has_mass) then
            call p%columns(self%mass, 1, n)
            if (.not. p%reading()) idx = self%dae_index
            call p%ints(idx, n)
            if (p%reading()) self%dae_index = idx
        end if
        if (p%reading()) then
            call radau_allocate_work(self)
            call radau_collocation_basis(self%cvec, self%pmat)
        end if
    end subroutine radau_transfer

    !> The sparse path's state: J's values (in columns of length n); on reading, the
    !! pattern and, if the factors were current, the factorisations again (the same
    !! numbers: they depend on J and h only; not counted in nlu).
    subroutine transfer_sparse(self, p)
        class(radau_stepper), intent(inout) :: self
        type(state_packer), intent(inout) :: p
        real(dp), allocatable :: tmp(:, :)
        integer :: n, nnz, m, i1, i2
        n = self%n
        nnz = size(self%jstruct%row_idx)
        m = (nnz + n - 1)/n
        if (.not. p%reading()) then
            tmp = reshape(self%jval, [n, m], pad=[0.0_dp])
        end if
        if (m > 0) call p%columns(tmp, 1, m)
        if (p%reading()) then
            if (m > 0) then
                self%jval = reshape(tmp, [nnz])
            else
                allocate (self%jval(0))
            end if
            call self%slu%build(self%jstruct)
            if (.not. allocated(self%jac)) allocate (self%jac(0, 0), self%e1(0, 0), &
                                                     self%e2(0, 0), self%ip1(0), self%ip2(0))
            if (.not. self%need_lu) call self%slu%decompose(self%jval, GAM0/self%h, &
                cmplx(ALPH/self%h, BETA/self%h, kind=dp), i1, i2)
        end if
    end subroutine transfer_sparse

    !> f(t, y) and the scale again after a step hook changed y.
    subroutine radau_refresh_f(self, sys)
        class(radau_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        call sys%rhs(self%t, self%y, self%f0)
        self%st%nfev = self%st%nfev + 1
        self%f_ok = all(abs(self%f0) <= huge(1.0_dp))
        self%scal0 = self%atolv + self%rtolv*abs(self%y)
        self%f_stale = .false.
    end subroutine radau_refresh_f

    logical function radau_f_finite(self)
        class(radau_stepper), intent(in) :: self
        radau_f_finite = self%f_ok
    end function radau_f_finite

end module conmech_radau_stepper
