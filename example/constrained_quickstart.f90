!> Constrained systems quickstart: a user-defined system in excessive coordinates (a bead on
!! a parabolic wire y = k x^2 under gravity), its multiplier and reaction force, and the
!! projected integrator against the plain index-1 form.
!!   fpm run --example constrained_quickstart
module quickstart_wire
    use conmech
    implicit none
    private
    public :: bead_on_wire

    !> q = [x, y], phi = y - k x^2 = 0. Only mass, forces and phi are required; the
    !! Jacobian and the acceleration term are given here for accuracy (the defaults are
    !! finite differences).
    type, extends(constrained_system) :: bead_on_wire
        real(dp) :: m = 1.0_dp, g = 9.81_dp, k = 0.5_dp
    contains
        procedure :: mass => wire_mass
        procedure :: forces => wire_forces
        procedure :: phi => wire_phi
        procedure :: phi_jac => wire_jac
        procedure :: phi_gamma => wire_gamma
    end type bead_on_wire

contains

    subroutine wire_mass(self, t, q, mm)
        class(bead_on_wire), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = 0.0_dp
        mm(1, 1) = self%m
        mm(2, 2) = self%m
    end subroutine wire_mass

    subroutine wire_forces(self, t, q, v, f)
        class(bead_on_wire), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = [0.0_dp, -self%m*self%g]
    end subroutine wire_forces

    subroutine wire_phi(self, t, q, c)
        class(bead_on_wire), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c(1) = q(2) - self%k*q(1)**2
    end subroutine wire_phi

    subroutine wire_jac(self, t, q, g)
        class(bead_on_wire), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        g(1, :) = [-2.0_dp*self%k*q(1), 1.0_dp]
    end subroutine wire_jac

    !> G q'' = gamma = -(dG/dt) v = 2 k x'^2.
    subroutine wire_gamma(self, t, q, v, gam)
        class(bead_on_wire), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        gam(1) = 2.0_dp*self%k*v(1)**2
    end subroutine wire_gamma

end module quickstart_wire

program constrained_quickstart
    use conmech
    use quickstart_wire, only: bead_on_wire
    implicit none
    type(bead_on_wire) :: wire
    type(constrained_options) :: opt
    type(constrained_result) :: res, plain
    real(dp) :: t_eval(5)
    integer :: i

    wire%n = 2          ! coordinates
    wire%n_hol = 1      ! holonomic constraints
    t_eval = [0.0_dp, 25.0_dp, 50.0_dp, 75.0_dp, 100.0_dp]
    opt%ode%rtol = 1.0e-8_dp
    opt%ode%atol = 1.0e-8_dp

    ! start at x = 1 slightly off the wire, moving: the start is projected first
    opt%projection = PROJ_POSITION_VELOCITY
    call constrained_solve(wire, [0.0_dp, 100.0_dp], [1.0_dp, 0.52_dp], [0.0_dp, 0.3_dp], &
                           opt, res, t_eval)
    opt%projection = PROJ_NONE
    call constrained_solve(wire, [0.0_dp, 100.0_dp], [1.0_dp, 0.52_dp], [0.0_dp, 0.3_dp], &
                           opt, plain, t_eval)
    if (.not. (res%success .and. plain%success)) then
        write (*, '(a)') "failed: "//res%message//" / "//plain%message
        stop 1
    end if
    write (*, '(a,es9.2,a,es9.2)') "initial state moved by |dq| =", res%dq0, &
        ", |dv| =", res%dv0
    write (*, '(a)') "     t          x          y     lambda  reaction_x  reaction_y" // &
        "   |phi| proj.   |phi| none    energy"
    do i = 1, res%nt
        write (*, '(f6.1,5f11.5,3es12.3)') res%t(i), res%q(:, i), res%lam(1, i), &
            res%reaction(:, i), res%res_pos(i), plain%res_pos(i), &
            0.5_dp*sum(res%v(:, i)**2) + wire%g*res%q(2, i)
    end do
    write (*, '(a,i0,a,i0,a,i0)') "steps ", res%naccept, ", nfev ", res%nfev, &
        ", projections ", res%nproj
end program constrained_quickstart
