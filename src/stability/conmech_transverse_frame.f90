!> The data of a transverse linearisation (see conmech_transverse_general for the
!! construction): its options, the frame along the orbit with its monodromies, and the
!! augmented ODE [x; Q; Phi_red; Gramian; Phi] whose right-hand side transports the
!! invariant covectors by the adjoint equation and the frame without rotation inside the
!! section S; the Jacobian of a system without an analytic one by sixth-order central
!! differences.
module conmech_transverse_frame
    use conmech_kinds, only: dp, nan_dp
    use conmech_outcome, only: outcome
    use conmech_status
    use conmech_lapack, only: dpotrf, dpotrs, la_finite
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: METHOD_VERNER98
    use conmech_ode_dense, only: dense_solution
    use conmech_rotation_log, only: rotation_log
    use conmech_transverse_model, only: transverse_model
    implicit none
    private

    public :: transverse_options, transverse_frame, frame_ode, frame_derivative
    public :: transverse_jacobian, ENERGY_NONE, ENERGY_AUTO, ENERGY_REQUIRED

    integer, parameter :: ENERGY_NONE = 0      !! do not reduce by an energy
    integer, parameter :: ENERGY_AUTO = 1      !! reduce if the model's energy is conserved
    integer, parameter :: ENERGY_REQUIRED = 2  !! reduce, or fail if it cannot

    !> Options of `transverse_build`.
    type :: transverse_options
        !> integrator of the orbit and frame run (Verner 9(8): its global error on the
        !! frame is ~10x smaller than DOP853's at the same tolerance and fewer evaluations)
        integer :: method = METHOD_VERNER98
        real(dp) :: rtol = 1.0e-12_dp           !! integration tolerances
        real(dp) :: atol = 1.0e-12_dp
        integer :: energy = ENERGY_AUTO          !! ENERGY_NONE / _AUTO / _REQUIRED
        logical :: full_monodromy = .true.       !! also integrate the N x N monodromy
        !> H counts as conserved if max |grad H . f|/(|grad H| |f|) along the orbit is below
        real(dp) :: conservation_tol = 1.0e-7_dp
        !> |x(T) - x(0)| allowed (0: max(1e-8, 1e3 max(rtol, atol)) max(1, |x0|))
        real(dp) :: closure_tol = 0.0_dp
        integer :: max_steps = 1000000
    end type transverse_options

    !> The augmented system [x; Q; Phi_red; Gramian; Phi] (internal).
    type, extends(ode_system) :: frame_ode
        class(ode_system), allocatable :: sys
        class(transverse_model), allocatable :: model
        integer :: n = 0, k = 0, ny = 0, m = 0
        logical :: full = .false.
    contains
        procedure :: rhs => fo_rhs
    end type frame_ode

    !> A transverse linearisation: the frame along the orbit and its monodromies.
    type, extends(outcome) :: transverse_frame
        integer :: n = 0                    !! state dimension N
        integer :: k = 0                    !! transverse dimension
        integer :: nc = 0                   !! invariant-manifold normals removed
        integer :: m = 0                    !! inputs
        logical :: reduced = .false.        !! the energy was removed
        real(dp) :: period = 0.0_dp
        real(dp) :: closure = 0.0_dp        !! max |x(T) - x(0)| of the orbit
        real(dp) :: energy_drift = 0.0_dp   !! max |grad H . f|/(|grad H| |f|) (if H)
        real(dp) :: frame_defect = 0.0_dp   !! |Q(0)^T Q(T) - rotation| (integration error)
        integer :: nfev = 0
        real(dp), allocatable :: y0(:)
        real(dp), allocatable :: holonomy(:, :)        !! R = Q(0)^T Q(T)
        type(rotation_log) :: hlog
        real(dp), allocatable :: monodromy(:, :)       !! (k, k), periodic frame
        real(dp), allocatable :: mr(:), mi(:)          !! its multipliers
        real(dp), allocatable :: full_monodromy(:, :)  !! (N, N) if requested
        real(dp), allocatable :: fr(:), fi(:)
        real(dp), allocatable :: gramian(:, :)         !! (k, k) controllability, with inputs
        type(dense_solution) :: sol                    !! of the augmented state
        type(frame_ode) :: ode
    end type transverse_frame

contains


    !> f, A = df/dx, the frame q projected onto S (qs: the integrated frame drifts off S
    !! by the integration error, and the energy direction feeds that drift into the reduced
    !! dynamics; the projection removes it to first order), the frame derivative dq, the
    !! covector derivative dy = -y A and (with inputs) bx = dF/du at (t, x, y, q); y holds
    !! the invariant covectors (manifold normals, energy gradient) as rows. info /= 0 if
    !! [y^T, f] is numerically rank deficient (its Gram matrix fails Cholesky).
    subroutine frame_derivative(fo, t, x, y, q, f, a, qs, dq, dy, bx, info)
        class(frame_ode), intent(in) :: fo
        real(dp), intent(in) :: t, x(:), y(:, :), q(:, :)
        real(dp), intent(out) :: f(:), a(:, :), qs(:, :), dq(:, :), dy(:, :), bx(:, :)
        integer, intent(out) :: info
        real(dp) :: w(fo%n, fo%ny + 1), wdq(fo%ny + 1, fo%k), wq(fo%ny + 1, fo%k)
        real(dp) :: gm(fo%ny + 1, fo%ny + 1)
        integer :: p, lainfo
        call transverse_jacobian(fo%sys, t, x, f, a)
        p = fo%ny + 1
        if (fo%ny > 0) then
            dy = -matmul(y, a)
            w(:, 1:fo%ny) = transpose(y)
        end if
        w(:, p) = f
        gm = matmul(transpose(w), w)
        info = CM_SUCCESS
        if (.not. la_finite(gm)) then
            info = CM_NONFINITE
            dq = nan_dp
            return
        end if
        call dpotrf('U', p, gm, p, lainfo)
        if (lainfo /= 0) then
            info = CM_SINGULAR
            dq = nan_dp
            return
        end if
        wq = matmul(transpose(w), q)
        call dpotrs('U', p, fo%k, gm, p, wq, p, lainfo)
        qs = q - matmul(w, wq)
        if (fo%ny > 0) wdq(1:fo%ny, :) = matmul(dy, qs)
        wdq(p, :) = matmul(matmul(a, f), qs)
        call dpotrs('U', p, fo%k, gm, p, wdq, p, lainfo)
        dq = -matmul(w, wdq)
        if (fo%m > 0) call fo%model%input_matrix(t, x, bx)
    end subroutine frame_derivative

    !> f and A = df/dx: the system's own Jacobian when it has one, else sixth-order
    !! central differences (step eps^(1/7) max(|x_j|, 1), error ~1e-13 relative). The
    !! construction relies on f' = A f and on the adjoint of the same A carrying the
    !! invariant covectors; the second-order default differences (~1e-10) would make the
    !! transverse and the full multipliers disagree at that level.
    subroutine transverse_jacobian(sys, t, x, f, a)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t, x(:)
        real(dp), intent(out) :: f(:), a(:, :)
        real(dp), parameter :: off(6) = [3.0_dp, 2.0_dp, 1.0_dp, -1.0_dp, -2.0_dp, -3.0_dp]
        real(dp), parameter :: wt(6) = [1.0_dp, -9.0_dp, 45.0_dp, -45.0_dp, 9.0_dp, -1.0_dp]
        real(dp) :: xp(size(x)), fp(size(x)), h
        integer :: j, i
        if (sys%has_jacobian()) then
            call sys%rhs_jacobian(t, x, f, a)
            return
        end if
        call sys%rhs(t, x, f)
        xp = x
        do j = 1, size(x)
            h = epsilon(1.0_dp)**(1.0_dp/7.0_dp)*max(abs(x(j)), 1.0_dp)
            a(:, j) = 0.0_dp
            do i = 1, 6
                xp(j) = x(j) + off(i)*h
                call sys%rhs(t, xp, fp)
                a(:, j) = a(:, j) + wt(i)*fp
            end do
            a(:, j) = a(:, j)/(60.0_dp*h)
            xp(j) = x(j)
        end do
    end subroutine transverse_jacobian

    subroutine fo_rhs(self, t, y, dydt)
        class(frame_ode), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: f(self%n), a(self%n, self%n), q(self%n, self%k), dq(self%n, self%k)
        real(dp) :: qs(self%n, self%k)
        real(dp) :: cv(max(self%ny, 1), self%n), dcv(max(self%ny, 1), self%n)
        real(dp) :: ared(self%k, self%k), bx(self%n, max(self%m, 1)), br(self%k, max(self%m, 1))
        real(dp) :: ph(self%k, self%k), gw(self%k, self%k)
        integer :: n, k, o, ny, info
        n = self%n
        k = self%k
        ny = self%ny
        o = n
        if (ny > 0) cv(1:ny, :) = reshape(y(o + 1:o + ny*n), [ny, n])
        o = o + ny*n
        q = reshape(y(o + 1:o + n*k), [n, k])
        call frame_derivative(self, t, y(1:n), cv(1:ny, :), q, f, a, qs, dq, dcv(1:ny, :), bx, &
                              info)
        if (info /= CM_SUCCESS) then
            dydt = nan_dp
            return
        end if
        ared = matmul(transpose(qs), matmul(a, qs) - dq)
        dydt(1:n) = f
        if (ny > 0) dydt(n + 1:n + ny*n) = reshape(dcv(1:ny, :), [ny*n])
        dydt(o + 1:o + n*k) = reshape(dq, [n*k])
        o = o + n*k
        ph = reshape(y(o + 1:o + k*k), [k, k])
        dydt(o + 1:o + k*k) = reshape(matmul(ared, ph), [k*k])
        o = o + k*k
        if (self%m > 0) then
            gw = reshape(y(o + 1:o + k*k), [k, k])
            br = matmul(transpose(qs), bx)
            dydt(o + 1:o + k*k) = reshape(matmul(ared, gw) + matmul(gw, transpose(ared)) + &
                                          matmul(br, transpose(br)), [k*k])
            o = o + k*k
        end if
        if (self%full) then
            dydt(o + 1:o + n*n) = reshape(matmul(a, reshape(y(o + 1:o + n*n), [n, n])), [n*n])
        end if
    end subroutine fo_rhs

end module conmech_transverse_frame
