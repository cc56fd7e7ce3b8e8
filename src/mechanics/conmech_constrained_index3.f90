!> The equations of motion of a constrained system in the index-3 form of the Test Set for
!! IVP Solvers (Mazzia and Magherini, University of Bari; its Andrews squeezing mechanism
!! and car axis problem), with the accelerations and the multipliers as algebraic
!! variables, y = [q, v, w, lambda]:
!!
!!     q' = v                                   (index 1)
!!     v' = w                                   (index 2)
!!     0 = Q(t, q, v) + C^T lambda - M(t, q) w  (w: index 3)
!!     0 = phi(t, q),  0 = A v + b              (lambda_h: index 3, lambda_n: index 2 or 3)
!!
!! The DAE's mass matrix is diag(I, I, 0, 0) and no factorisation of M is needed (M w
!! is a product). Radau IIA with RADAU5's index-aware error scaling (the error of index-2
!! components weighted by h, of index-3 components by h^2; Hairer-Wanner, Solving ODEs II,
!! VII.4 and the RADAU5 code) gives q to order 5, v to order 3 and w, lambda to order 2.
!! Only the position constraints are imposed: the velocities satisfy G v + phi_t = 0 to
!! the accuracy of the method (no projection).
!!
!! The Jacobian is assembled as for the GGL form (conmech_constrained_dae): the force
!! balance's [dQ/dq - d(M w)/dq, dQ/dv] at w, d(C^T lambda)/dq and d(A v + b)/dq, exact
!! for compiled systems that provide them, central differences otherwise.
module conmech_constrained_index3
    use conmech_kinds, only: dp
    use conmech_radau_stepper, only: radau_stepper
    use conmech_constrained_system, only: constrained_system, constraint_matrix
    use conmech_constrained_dae, only: mech_dae, dae_start
    implicit none
    private

    public :: index3_system, index3_setup

    !> The index-3 right-hand side of a constrained system (y = [q, v, w, lambda]).
    type, extends(mech_dae) :: index3_system
    contains
        procedure :: rhs => index3_rhs
        procedure :: jacobian => index3_jacobian
    end type index3_system

contains

    subroutine index3_rhs(self, t, y, dydt)
        class(index3_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: c(self%mech%n_hol + self%mech%n_nh, self%mech%n)
        real(dp) :: c0(self%mech%n_hol + self%mech%n_nh), mm(self%mech%n, self%mech%n)
        integer :: n, m, mh
        n = self%mech%n
        mh = self%mech%n_hol
        m = mh + self%mech%n_nh
        associate (q => y(1:n), v => y(n + 1:2*n), w => y(2*n + 1:3*n))
            dydt(1:n) = v
            dydt(n + 1:2*n) = w
            call self%mech%forces(t, q, v, dydt(2*n + 1:3*n))
            call self%mech%mass(t, q, mm)
            dydt(2*n + 1:3*n) = dydt(2*n + 1:3*n) - matmul(mm, w)
            if (m == 0) return
            call constraint_matrix(self%mech, t, q, c, c0)
            dydt(2*n + 1:3*n) = dydt(2*n + 1:3*n) + matmul(y(3*n + 1:3*n + m), c)
            if (mh > 0) call self%mech%phi(t, q, dydt(3*n + 1:3*n + mh))
            if (m > mh) dydt(3*n + mh + 1:3*n + m) = matmul(c(mh + 1:m, :), v) + c0(mh + 1:m)
        end associate
    end subroutine index3_rhs

    !> The Jacobian of the index-3 right-hand side (see the module documentation).
    subroutine index3_jacobian(self, t, y, dfdy)
        class(index3_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(dp) :: c(self%mech%n_hol + self%mech%n_nh, self%mech%n)
        real(dp) :: c0(self%mech%n_hol + self%mech%n_nh)
        real(dp) :: hv(self%mech%n_hol + self%mech%n_nh, self%mech%n)
        real(dp) :: hl(self%mech%n, self%mech%n), r(self%mech%n, 2*self%mech%n)
        real(dp) :: mm(self%mech%n, self%mech%n)
        integer :: n, m, mh, i
        n = self%mech%n
        mh = self%mech%n_hol
        m = mh + self%mech%n_nh
        dfdy = 0.0_dp
        associate (q => y(1:n), v => y(n + 1:2*n), w => y(2*n + 1:3*n))
            do i = 1, 2*n
                dfdy(i, n + i) = 1.0_dp
            end do
            call self%mech%forces_jacobian(t, q, v, w, r)
            call self%mech%mass(t, q, mm)
            dfdy(2*n + 1:3*n, 1:2*n) = r
            dfdy(2*n + 1:3*n, 2*n + 1:3*n) = -mm
            if (m == 0) return
            call constraint_matrix(self%mech, t, q, c, c0)
            call self%mech%constraint_hessian(t, q, v, y(3*n + 1:3*n + m), hl, hv)
            dfdy(2*n + 1:3*n, 1:n) = dfdy(2*n + 1:3*n, 1:n) + hl
            dfdy(2*n + 1:3*n, 3*n + 1:3*n + m) = transpose(c)
            if (mh > 0) dfdy(3*n + 1:3*n + mh, 1:n) = c(1:mh, :)
            if (m > mh) then
                dfdy(3*n + mh + 1:3*n + m, 1:n) = hv(mh + 1:m, :)
                dfdy(3*n + mh + 1:3*n + m, n + 1:2*n) = c(mh + 1:m, :)
            end if
        end associate
    end subroutine index3_jacobian

    !> The index-3 form of sys at (q, v) with the accelerations acc and multipliers lam of
    !! the KKT system: the system g, its state y0 = [q, v, acc, lam] and the Radau stepper
    !! with the mass matrix diag(I, I, 0, 0) and RADAU5's index vector: 1 for q, 2 for v,
    !! 3 for w and the holonomic multipliers. The non-holonomic multipliers are of index 2
    !! alone, but with holonomic constraints beside them they are solved from one coupled
    !! system with the holonomic ones and carry their h^-2 round-off, so they are scaled as
    !! index 3 (as index 2, the Newton increments stall on that round-off at small steps);
    !! w is of index 2 when every constraint is non-holonomic.
    subroutine index3_setup(sys, q, v, acc, lam, g, y0, stp)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: q(:), v(:), acc(:), lam(:)
        type(index3_system), intent(out) :: g
        real(dp), allocatable, intent(out) :: y0(:)
        type(radau_stepper), intent(inout) :: stp
        integer :: n, m, mh, nd
        n = sys%n
        mh = sys%n_hol
        m = mh + sys%n_nh
        nd = 3*n + m
        call dae_start(q, v, nd, y0, stp)
        y0(2*n + 1:3*n) = acc
        y0(3*n + 1:nd) = lam
        stp%dae_index(1:n) = 1
        stp%dae_index(n + 1:2*n) = 2
        stp%dae_index(2*n + 1:3*n) = merge(3, 2, mh > 0)
        stp%dae_index(3*n + 1:3*n + mh) = 3
        stp%dae_index(3*n + mh + 1:nd) = merge(3, 2, mh > 0)
        allocate (g%mech, source=sys)
    end subroutine index3_setup

end module conmech_constrained_index3
