!> Variational equations: the state together with its state transition matrix (STM).
!!
!! For y' = f(t, y) the STM Phi(t) = dy(t)/dy(t0) solves Phi' = J(t, y(t)) Phi, Phi(t0) = I,
!! with J = df/dy the system's Jacobian (analytic when the system has one, else its
!! finite-difference default). `variational_system` is the ode_system of the extended
!! state z = [y; vec(Phi)] (n + n^2 components, Phi stored column by column), so every
!! conmech integrator (and its step control) applies to it.
!!
!! `integrate_stm` advances (y, Phi) from t0 to t1. By default the error of every component
!! of z is controlled (same step control on the state and on the STM). With
!! `state_only = .true.` the STM components get an infinite tolerance and the state's
!! tolerances are scaled by sqrt(n/(n + n^2)), so that the RMS error norm over z equals the
!! RMS norm over the state alone: the steps are those of the state's integration.
module conmech_variational
    use, intrinsic :: iso_fortran_env, only: int64
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_stats, ode_integrate
    use conmech_ode_options, only: METHOD_TAYLOR
    use conmech_taylor_stepper, only: taylor_propagate
    implicit none
    private

    public :: variational_system, variational_product_system, integrate_stm

    integer, parameter :: NSMALL = 16   !! largest n with J on the stack
    integer(int64), parameter :: ONE_BITS = transfer(1.0_dp, 0_int64)  !! bits of 1.0

    interface
        subroutine dgemm(transa, transb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc)
            import :: dp
            character(len=1), intent(in) :: transa, transb
            integer, intent(in) :: m, n, k, lda, ldb, ldc
            real(dp), intent(in) :: alpha, beta
            real(dp), intent(in) :: a(lda, *), b(ldb, *)
            real(dp), intent(inout) :: c(ldc, *)
        end subroutine dgemm
    end interface

    !> z = [y; vec(Phi)], z' = [f(t, y); vec(J(t, y) Phi)].
    type, extends(ode_system) :: variational_system
        class(ode_system), allocatable :: base   !! the underlying system
        integer :: n = 0                         !! its dimension
    contains
        procedure :: rhs => var_rhs
    end type variational_system

    !> The same z' through the base system's own `rhs_jacobian_product` (J never formed):
    !! `integrate_stm` uses it when the system has one. A type of its own, so that its
    !! `rhs` is a small routine (no test, no frame of the dense kernels).
    type, extends(variational_system) :: variational_product_system
    contains
        procedure :: rhs => var_rhs_product
    end type variational_product_system

contains

    !> z' = [f(t, y); vec(J Phi)], f and J from the system's `rhs_jacobian` (one call, so a
    !! system may share their common work). No allocation per evaluation for n <= NSMALL:
    !! J lives in a contiguous local array, and Phi, dPhi are passed as explicit-shape
    !! n x n matrices (contiguous column sums). The product is structure-aware for the
    !! first-order form of a mechanical system (J = [0 I; A B], tested per call without
    !! branches: the top half of J Phi is then the bottom half of Phi, and only [A B] Phi
    !! is computed); constant-size kernels for n = 2, 4, 6; for n > NSMALL one dgemm.
    subroutine var_rhs(self, t, y, dydt)
        class(variational_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        integer :: n
        n = self%n
        select case (n)
        case (2)
            call var_rhs2(self%base, t, y, dydt)
        case (4)
            call var_rhs4(self%base, t, y, dydt)
        case (6)
            call var_rhs6(self%base, t, y, dydt)
        case default
            if (n <= NSMALL) then
                call var_rhs_small(self%base, n, t, y, dydt)
            else
                call var_rhs_big(self%base, n, t, y, dydt)
            end if
        end select
    end subroutine var_rhs

    !> z' = [f(t, y); vec(J Phi)] in one call of the system's `rhs_jacobian_product`.
    subroutine var_rhs_product(self, t, y, dydt)
        class(variational_product_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        call product_call(self%base, self%n, t, y, dydt)
    end subroutine var_rhs_product

    !> Explicit shapes: the state and Phi reach the system contiguous, without descriptors.
    subroutine product_call(base, n, t, y, dydt)
        class(ode_system), intent(in) :: base
        integer, intent(in) :: n
        real(dp), intent(in) :: t, y(n*(n + 1))
        real(dp), intent(out) :: dydt(n*(n + 1))
        call base%rhs_jacobian_product(t, n, n, y(1:n), dydt(1:n), y(n + 1:), dydt(n + 1:))
    end subroutine product_call

    subroutine var_rhs2(base, t, y, dydt)
        integer, parameter :: n = 2
        class(ode_system), intent(in) :: base
        real(dp), intent(in) :: t, y(n*(n + 1))
        real(dp), intent(out) :: dydt(n*(n + 1))
        real(dp) :: jac(n, n)
        call base%rhs_jacobian(t, y(1:n), dydt(1:n), jac)
        call product2(jac, y(n + 1:), dydt(n + 1:))
    end subroutine var_rhs2

    subroutine var_rhs4(base, t, y, dydt)
        integer, parameter :: n = 4
        class(ode_system), intent(in) :: base
        real(dp), intent(in) :: t, y(n*(n + 1))
        real(dp), intent(out) :: dydt(n*(n + 1))
        real(dp) :: jac(n, n)
        call base%rhs_jacobian(t, y(1:n), dydt(1:n), jac)
        call product4(jac, y(n + 1:), dydt(n + 1:))
    end subroutine var_rhs4

    subroutine var_rhs6(base, t, y, dydt)
        integer, parameter :: n = 6
        class(ode_system), intent(in) :: base
        real(dp), intent(in) :: t, y(n*(n + 1))
        real(dp), intent(out) :: dydt(n*(n + 1))
        real(dp) :: jac(n, n)
        call base%rhs_jacobian(t, y(1:n), dydt(1:n), jac)
        call product6(jac, y(n + 1:), dydt(n + 1:))
    end subroutine var_rhs6

    subroutine var_rhs_small(base, n, t, y, dydt)
        class(ode_system), intent(in) :: base
        integer, intent(in) :: n
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: jac(n, n)     ! n <= NSMALL: a small automatic array on the stack
        call base%rhs_jacobian(t, y(1:n), dydt(1:n), jac)
        call product_n(n, jac, y(n + 1:n + n*n), dydt(n + 1:n + n*n))
    end subroutine var_rhs_small

    !> n > NSMALL: J on the heap (its O(n^2) allocation is small beside the O(n^3)
    !! product), [A B] Phi or J Phi by one dgemm.
    subroutine var_rhs_big(base, n, t, y, dydt)
        class(ode_system), intent(in) :: base
        integer, intent(in) :: n
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp), allocatable :: jac(:, :)
        allocate (jac(n, n))
        call base%rhs_jacobian(t, y(1:n), dydt(1:n), jac)
        call product_blas(n, jac, y(n + 1:n + n*n), dydt(n + 1:n + n*n))
    end subroutine var_rhs_big

    !> dphi = jac phi (n x n each) for n = 2, 4, 6 (constant loop lengths) and any n.
    pure subroutine product2(jac, phi, dphi)
        integer, parameter :: n = 2, m = 1
        real(dp), intent(in) :: jac(n, n), phi(n, n)
        real(dp), intent(out) :: dphi(n, n)
        integer :: i, j, l
        integer(int64) :: dev
        include "conmech_stm_product_body.inc"
    end subroutine product2

    pure subroutine product4(jac, phi, dphi)
        integer, parameter :: n = 4, m = 2
        real(dp), intent(in) :: jac(n, n), phi(n, n)
        real(dp), intent(out) :: dphi(n, n)
        integer :: i, j, l
        integer(int64) :: dev
        include "conmech_stm_product_body.inc"
    end subroutine product4

    pure subroutine product6(jac, phi, dphi)
        integer, parameter :: n = 6, m = 3
        real(dp), intent(in) :: jac(n, n), phi(n, n)
        real(dp), intent(out) :: dphi(n, n)
        integer :: i, j, l
        integer(int64) :: dev
        include "conmech_stm_product_body.inc"
    end subroutine product6

    pure subroutine product_n(n, jac, phi, dphi)
        integer, intent(in) :: n
        real(dp), intent(in) :: jac(n, n), phi(n, n)
        real(dp), intent(out) :: dphi(n, n)
        integer :: i, j, l, m
        integer(int64) :: dev
        m = n/2
        include "conmech_stm_product_body.inc"
    end subroutine product_n

    !> dphi = jac phi by dgemm; for J = [0 I; A B] the top half is copied and only
    !! [A B] phi is multiplied.
    subroutine product_blas(n, jac, phi, dphi)
        integer, intent(in) :: n
        real(dp), intent(in) :: jac(n, n), phi(n, n)
        real(dp), intent(out) :: dphi(n, n)
        integer :: m, j
        m = n/2
        if (is_mech(n, m, jac)) then
            do j = 1, n
                dphi(1:m, j) = phi(m + 1:n, j)
            end do
            call dgemm('N', 'N', n - m, n, n, 1.0_dp, jac(m + 1, 1), n, phi, n, 0.0_dp, &
                       dphi(m + 1, 1), n)
        else
            call dgemm('N', 'N', n, n, n, 1.0_dp, jac, n, phi, n, 0.0_dp, dphi, n)
        end if
    end subroutine product_blas

    !> J = [0 I; A B] (n = 2m): the top m rows are exactly [0 I] (a NaN there gives
    !! .false.).
    pure logical function is_mech(n, m, jac)
        integer, intent(in) :: n, m
        real(dp), intent(in) :: jac(n, n)
        integer :: i, j
        is_mech = 2*m == n
        do j = 1, m
            do i = 1, m
                is_mech = is_mech .and. jac(i, j) == 0.0_dp .and. &
                          jac(i, m + j) == merge(1.0_dp, 0.0_dp, i == j)
            end do
        end do
    end function is_mech

    !> Advance the state y and the STM phi (n x n) from t0 to t1 in place.
    !! On entry phi is the STM at t0 (usually the identity); on exit the STM at t1.
    !! options%method = METHOD_TAYLOR integrates z = [y; Phi] by Taylor's method with the
    !! system's variational expansion (taylor_size(1) > 0, else CM_BAD_INPUT).
    subroutine integrate_stm(sys, t0, t1, y, phi, options, info, message, stats, state_only)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t0, t1
        real(dp), intent(inout) :: y(:)
        real(dp), intent(inout) :: phi(:, :)
        type(ode_options), intent(in) :: options
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out), optional :: message
        type(ode_stats), intent(out), optional :: stats
        logical, intent(in), optional :: state_only
        class(variational_system), allocatable :: vs
        type(ode_options) :: opt
        real(dp), allocatable :: z(:)
        character(len=:), allocatable :: msg
        real(dp) :: scl
        integer :: n, nz
        logical :: only
        n = size(y)
        nz = n + n*n
        if (size(phi, 1) /= n .or. size(phi, 2) /= n) then
            info = CM_BAD_INPUT
            if (present(message)) message = "integrate_stm: phi must be n x n"
            return
        end if
        only = .false.
        if (present(state_only)) only = state_only
        if (sys%has_jacobian_product()) then
            allocate (variational_product_system :: vs)
        else
            allocate (variational_system :: vs)
        end if
        allocate (vs%base, source=sys)
        vs%n = n
        opt = options
        if (only .or. allocated(options%atol_vec) .or. allocated(options%rtol_vec)) then
            opt%atol_vec = z_tolerance(options%atol, options%atol_vec, n, nz)
            opt%rtol_vec = z_tolerance(options%rtol, options%rtol_vec, n, nz)
            if (only) then
                scl = sqrt(real(n, dp)/real(nz, dp))
                opt%atol_vec(1:n) = opt%atol_vec(1:n)*scl
                opt%rtol_vec(1:n) = opt%rtol_vec(1:n)*scl
                opt%atol_vec(n + 1:) = huge(1.0_dp)*1.0e-10_dp
                opt%rtol_vec(n + 1:) = 0.0_dp
            end if
        end if
        allocate (z(nz))
        z(1:n) = y
        z(n + 1:) = reshape(phi, [n*n])
        if (options%method == METHOD_TAYLOR) then
            ! Taylor's method on the variational system's own expansion (the state and Phi
            ! by the same recurrences, conmech.symbolic's taylor_var)
            block
                type(ode_stats) :: st
                call taylor_propagate(sys, t0, t1, z, opt, info, st, msg, kind=1)
                if (present(stats)) stats = st
            end block
        else
            call ode_integrate(vs, t0, t1, z, opt, info, stats, msg)
        end if
        y = z(1:n)
        phi = reshape(z(n + 1:), [n, n])
        if (present(message)) message = msg
    end subroutine integrate_stm

    !> A tolerance of z = [y; vec(Phi)] per component: the scalar one, overridden by the
    !! options' vector where it is given for the state (size n) or for all of z (size nz).
    pure function z_tolerance(scalar, vec, n, nz) result(w)
        real(dp), intent(in) :: scalar
        real(dp), allocatable, intent(in) :: vec(:)
        integer, intent(in) :: n, nz
        real(dp) :: w(nz)
        w = scalar
        if (.not. allocated(vec)) return
        if (size(vec) == n) then
            w(1:n) = vec
        else if (size(vec) == nz) then
            w = vec
        end if
    end function z_tolerance

end module conmech_variational
