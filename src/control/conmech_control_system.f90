!> Systems with inputs, x' = F(t, x, u) (u in R^m), feedback laws u = k(t, x), and the
!! closed loop x' = F(t, x, k(t, x) + w).
!!
!! A `control_system` is an `ode_system` whose `rhs` is F with u = 0, so every integrator
!! and stability routine runs it open loop; `rhs_u` takes the input, `input_matrix` gives
!! dF/du at (t, x, u) (default: central differences in u; F is affine in u for mechanical
!! systems, where the differences are exact up to round-off).
!!
!! A `closed_loop` holds a plant and a law and is itself a control system in the additive
!! input w: its `rhs` (w = 0) is the closed-loop vector field, integrated like any system
!! (events, dense output, shooting, monodromy); its input matrix is the plant's at
!! u = k(t, x), which the transverse construction uses for B_perp(t).
!!
!! `control_model` is the `transverse_model` of a control system: its inputs (and nothing
!! else: a controlled system has no energy integral in general).
module conmech_control_system
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_system
    use conmech_transverse_model, only: transverse_model
    implicit none
    private
    public :: control_system, feedback_law, closed_loop, control_model

    !> x' = F(t, x, u) with n_inputs inputs.
    type, abstract, extends(ode_system) :: control_system
        integer :: n_inputs = 0
    contains
        procedure(rhs_u_proc), deferred :: rhs_u
        procedure :: rhs => cs_rhs
        procedure :: input_matrix => cs_input_matrix
    end type control_system

    !> u = k(t, x) (n_inputs values).
    type, abstract :: feedback_law
        integer :: n_inputs = 0
    contains
        procedure(law_proc), deferred :: eval
    end type feedback_law

    abstract interface
        !> dxdt = F(t, x, u).
        subroutine rhs_u_proc(self, t, x, u, dxdt)
            import :: control_system, dp
            class(control_system), intent(in) :: self
            real(dp), intent(in) :: t
            real(dp), intent(in) :: x(:), u(:)
            real(dp), intent(out) :: dxdt(:)
        end subroutine rhs_u_proc
        !> u = k(t, x).
        subroutine law_proc(self, t, x, u)
            import :: feedback_law, dp
            class(feedback_law), intent(in) :: self
            real(dp), intent(in) :: t
            real(dp), intent(in) :: x(:)
            real(dp), intent(out) :: u(:)
        end subroutine law_proc
    end interface

    !> x' = F(t, x, law(t, x) + w), a control system in w.
    type, extends(control_system) :: closed_loop
        class(control_system), allocatable :: plant
        class(feedback_law), allocatable :: law
    contains
        procedure :: rhs_u => cl_rhs_u
        procedure :: input_matrix => cl_input_matrix
    end type closed_loop

    !> The inputs of a control system, for `transverse_build` (B_perp).
    type, extends(transverse_model) :: control_model
        class(control_system), allocatable :: sys
    contains
        procedure :: input_matrix => cm_input_matrix
    end type control_model

contains

    subroutine cs_rhs(self, t, y, dydt)
        class(control_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: u(self%n_inputs)
        u = 0.0_dp
        call self%rhs_u(t, y, u, dydt)
    end subroutine cs_rhs

    !> bx = dF/du at (t, x, u), central differences (step 1e-6 max(|u_j|, 1)).
    subroutine cs_input_matrix(self, t, x, u, bx)
        class(control_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: x(:), u(:)
        real(dp), intent(out) :: bx(:, :)
        real(dp) :: up(size(u)), fp(size(x)), fm(size(x)), h
        integer :: j
        up = u
        do j = 1, size(u)
            h = 1.0e-6_dp*max(abs(u(j)), 1.0_dp)
            up(j) = u(j) + h
            call self%rhs_u(t, x, up, fp)
            up(j) = u(j) - h
            call self%rhs_u(t, x, up, fm)
            up(j) = u(j)
            bx(:, j) = (fp - fm)/(2.0_dp*h)
        end do
    end subroutine cs_input_matrix

    subroutine cl_rhs_u(self, t, x, u, dxdt)
        class(closed_loop), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: x(:), u(:)
        real(dp), intent(out) :: dxdt(:)
        real(dp) :: uk(self%plant%n_inputs)
        call self%law%eval(t, x, uk)
        call self%plant%rhs_u(t, x, uk + u, dxdt)
    end subroutine cl_rhs_u

    subroutine cl_input_matrix(self, t, x, u, bx)
        class(closed_loop), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: x(:), u(:)
        real(dp), intent(out) :: bx(:, :)
        real(dp) :: uk(self%plant%n_inputs)
        call self%law%eval(t, x, uk)
        call self%plant%input_matrix(t, x, uk + u, bx)
    end subroutine cl_input_matrix

    subroutine cm_input_matrix(self, t, x, bx)
        class(control_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        real(dp), intent(out) :: bx(:, :)
        real(dp) :: u(self%sys%n_inputs)
        u = 0.0_dp
        call self%sys%input_matrix(t, x, u, bx)
    end subroutine cm_input_matrix

end module conmech_control_system
