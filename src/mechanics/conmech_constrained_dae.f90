!> The equations of motion of a constrained system as an index-2 differential-algebraic
!! system in mass-matrix form (the stabilised formulation of Gear, Gupta and Leimkuhler),
!! y = [q, v, lambda, mu], for Radau IIA:
!!
!!     q' = v + G^T mu                     (mass rows I)
!!     M v' = Q(t, q, v) + C^T lambda      (mass rows M, constant)
!!     0 = C v + c0                        (velocity constraints, index 2)
!!     0 = phi(t, q)                       (position constraints, index 2)
!!
!! with C = [G; A], c0 = [phi_t; b] (holonomic and non-holonomic constraints) and the
!! extra multiplier mu (zero on exact solutions) that keeps the positions on phi = 0.
!! Both constraint levels hold at every step end to the Newton tolerance: no drift, no
!! projection. `ggl_setup` gives the system, its initial state and the Radau stepper with
!! the block-diagonal mass matrix diag(I, M, 0, 0) and lambda, mu as index-2 components;
!! events of (t, [q; v]) are seen through `ggl_events`. The mass matrix must be constant
!! (constrained_solve checks it at every output).
module conmech_constrained_dae
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_system, ode_events
    use conmech_radau_stepper, only: radau_stepper
    use conmech_constrained_system, only: constrained_system, constraint_matrix
    implicit none
    private

    public :: ggl_system, ggl_events, ggl_setup

    !> The stabilised index-2 right-hand side of a constrained system.
    type, extends(ode_system) :: ggl_system
        class(constrained_system), allocatable :: mech
    contains
        procedure :: rhs => ggl_rhs
    end type ggl_system

    !> Events of (t, [q; v]) seen from y = [q, v, lambda, mu].
    type, extends(ode_events) :: ggl_events
        class(ode_events), allocatable :: inner
        integer :: n = 0
    contains
        procedure :: eval => ggl_event_eval
    end type ggl_events

contains

    subroutine ggl_event_eval(self, t, y, g)
        class(ggl_events), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: g(:)
        call self%inner%eval(t, y(1:2*self%n), g)
    end subroutine ggl_event_eval

    subroutine ggl_rhs(self, t, y, dydt)
        class(ggl_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: c(self%mech%n_hol + self%mech%n_nh, self%mech%n)
        real(dp) :: c0(self%mech%n_hol + self%mech%n_nh)
        integer :: n, m, mh
        n = self%mech%n
        mh = self%mech%n_hol
        m = mh + self%mech%n_nh
        call self%mech%forces(t, y(1:n), y(n + 1:2*n), dydt(n + 1:2*n))
        dydt(1:n) = y(n + 1:2*n)
        if (m == 0) return
        call constraint_matrix(self%mech, t, y(1:n), c, c0)
        dydt(n + 1:2*n) = dydt(n + 1:2*n) + matmul(y(2*n + 1:2*n + m), c)
        if (mh > 0) dydt(1:n) = dydt(1:n) + matmul(y(2*n + m + 1:2*n + m + mh), c(1:mh, :))
        dydt(2*n + 1:2*n + m) = matmul(c, y(n + 1:2*n)) + c0
        if (mh > 0) call self%mech%phi(t, y(1:n), dydt(2*n + m + 1:2*n + m + mh))
    end subroutine ggl_rhs

    !> The GGL form of sys at (t0, q, v) with the multipliers lam: the system g, its state
    !! y0 = [q, v, lam, 0], the mass matrix M(t0, q) of the velocity rows (mass0) and the
    !! Radau stepper set up with diag(I, M, 0, 0) and the index-2 components.
    subroutine ggl_setup(sys, t0, q, v, lam, g, y0, mass0, stp)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t0, q(:), v(:), lam(:)
        type(ggl_system), intent(out) :: g
        real(dp), allocatable, intent(out) :: y0(:), mass0(:, :)
        type(radau_stepper), intent(inout) :: stp
        integer :: n, m, mh, nd, i
        n = sys%n
        mh = sys%n_hol
        m = mh + sys%n_nh
        nd = 2*n + m + mh
        allocate (mass0(n, n), y0(nd))
        call sys%mass(t0, q, mass0)
        y0 = 0.0_dp
        y0(1:n) = q
        y0(n + 1:2*n) = v
        y0(2*n + 1:2*n + m) = lam
        allocate (stp%mass(nd, nd), stp%index2(nd))
        stp%mass = 0.0_dp
        do i = 1, n
            stp%mass(i, i) = 1.0_dp
        end do
        stp%mass(n + 1:2*n, n + 1:2*n) = mass0
        stp%index2 = .false.
        stp%index2(2*n + 1:nd) = .true.
        allocate (g%mech, source=sys)
    end subroutine ggl_setup

end module conmech_constrained_dae
