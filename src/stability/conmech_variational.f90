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
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_stats, ode_integrate
    implicit none
    private

    public :: variational_system, integrate_stm

    !> z = [y; vec(Phi)], z' = [f(t, y); vec(J(t, y) Phi)].
    type, extends(ode_system) :: variational_system
        class(ode_system), allocatable :: base   !! the underlying system
        integer :: n = 0                         !! its dimension
    contains
        procedure :: rhs => var_rhs
    end type variational_system

contains

    !> z' = [f(t, y); vec(J Phi)], f and J from the system's `rhs_jacobian` (one call, so a
    !! system may share their common work). J lives in a fixed-size stack buffer for
    !! n <= NSMALL (no allocation per evaluation). The product J Phi is one matrix product
    !! in column-axpy form, structure-aware for the first-order form of a mechanical system
    !! (J = [0 I; A B], detected per call: the top half of J Phi is then the bottom half of
    !! Phi, and only [A B] Phi is computed); loops of constant length for n = 2, 4, 6.
    subroutine var_rhs(self, t, y, dydt)
        class(variational_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        integer, parameter :: NSMALL = 16
        real(dp) :: jsmall(NSMALL, NSMALL)
        real(dp), allocatable :: jbig(:, :)
        integer :: n
        n = self%n
        if (n <= NSMALL) then
            call self%base%rhs_jacobian(t, y(1:n), dydt(1:n), jsmall(1:n, 1:n))
            select case (n)
            case (2)
                call product2(NSMALL, jsmall, y, dydt)
            case (4)
                call product4(NSMALL, jsmall, y, dydt)
            case (6)
                call product6(NSMALL, jsmall, y, dydt)
            case default
                call product_n(n, NSMALL, jsmall, y, dydt)
            end select
        else
            allocate (jbig(n, n))
            call self%base%rhs_jacobian(t, y(1:n), dydt(1:n), jbig)
            call product_n(n, n, jbig, y, dydt)
        end if
    end subroutine var_rhs

    !> dydt(n+1:) = vec(jac(1:n, 1:n) Phi), Phi = reshape(y(n+1:), [n, n]): n = 2, 4, 6, any.
    pure subroutine product2(ld, jac, y, dydt)
        integer, parameter :: n = 2
        integer, intent(in) :: ld
        real(dp), intent(in) :: jac(ld, n), y(:)
        real(dp), intent(inout) :: dydt(:)
        integer :: i, j, l, m
        logical :: mech
        include "conmech_stm_product_body.inc"
    end subroutine product2

    pure subroutine product4(ld, jac, y, dydt)
        integer, parameter :: n = 4
        integer, intent(in) :: ld
        real(dp), intent(in) :: jac(ld, n), y(:)
        real(dp), intent(inout) :: dydt(:)
        integer :: i, j, l, m
        logical :: mech
        include "conmech_stm_product_body.inc"
    end subroutine product4

    pure subroutine product6(ld, jac, y, dydt)
        integer, parameter :: n = 6
        integer, intent(in) :: ld
        real(dp), intent(in) :: jac(ld, n), y(:)
        real(dp), intent(inout) :: dydt(:)
        integer :: i, j, l, m
        logical :: mech
        include "conmech_stm_product_body.inc"
    end subroutine product6

    pure subroutine product_n(n, ld, jac, y, dydt)
        integer, intent(in) :: n, ld
        real(dp), intent(in) :: jac(ld, n), y(:)
        real(dp), intent(inout) :: dydt(:)
        integer :: i, j, l, m
        logical :: mech
        include "conmech_stm_product_body.inc"
    end subroutine product_n

    !> Advance the state y and the STM phi (n x n) from t0 to t1 in place.
    !! On entry phi is the STM at t0 (usually the identity); on exit the STM at t1.
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
        type(variational_system) :: vs
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
        allocate (vs%base, source=sys)
        vs%n = n
        opt = options
        if (only .or. allocated(options%atol_vec) .or. allocated(options%rtol_vec)) then
            allocate (opt%atol_vec(nz), opt%rtol_vec(nz))
            opt%atol_vec = options%atol
            opt%rtol_vec = options%rtol
            if (allocated(options%atol_vec)) then
                if (size(options%atol_vec) == n) then
                    opt%atol_vec(1:n) = options%atol_vec
                else if (size(options%atol_vec) == nz) then
                    opt%atol_vec = options%atol_vec
                end if
            end if
            if (allocated(options%rtol_vec)) then
                if (size(options%rtol_vec) == n) then
                    opt%rtol_vec(1:n) = options%rtol_vec
                else if (size(options%rtol_vec) == nz) then
                    opt%rtol_vec = options%rtol_vec
                end if
            end if
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
        call ode_integrate(vs, t0, t1, z, opt, info, stats, msg)
        y = z(1:n)
        phi = reshape(z(n + 1:), [n, n])
        if (present(message)) message = msg
    end subroutine integrate_stm

end module conmech_variational
