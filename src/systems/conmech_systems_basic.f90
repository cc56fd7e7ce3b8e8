!> Basic built-in first-order systems: harmonic oscillator, pendulum (theta), planar
!! two-body (Kepler) problem, Arenstorf's restricted three-body problem, Van der Pol.
!! Each has an analytic Jacobian (used by variational equations); Arenstorf's also a
!! structure-aware Jacobian product (conmech_rotating_frame) for `integrate_stm`.
module conmech_systems_basic
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_system
    use conmech_rotating_frame, only: rotating_frame_product, rotating_frame_jacobian
    implicit none
    private
    public :: harmonic_oscillator, pendulum_theta, kepler_2d, arenstorf, van_der_pol

    !> x'' = -omega^2 x; y = [x, v].
    type, extends(ode_system) :: harmonic_oscillator
        real(dp) :: omega = 1.0_dp
    contains
        procedure :: rhs => ho_rhs
        procedure :: jacobian => ho_jac
        procedure :: has_jacobian => ho_has_jac
    end type harmonic_oscillator

    !> theta'' = -(g/l) sin theta; y = [theta, theta'].
    type, extends(ode_system) :: pendulum_theta
        real(dp) :: g = 9.81_dp
        real(dp) :: l = 1.0_dp
    contains
        procedure :: rhs => pend_rhs
        procedure :: jacobian => pend_jac
        procedure :: has_jacobian => pend_has_jac
        procedure :: energy => pend_energy
    end type pendulum_theta

    !> r'' = -mu r/|r|^3 in the plane; y = [x, y, vx, vy].
    type, extends(ode_system) :: kepler_2d
        real(dp) :: mu = 1.0_dp
    contains
        procedure :: rhs => kep_rhs
        procedure :: jacobian => kep_jac
        procedure :: has_jacobian => kep_has_jac
        procedure :: energy => kep_energy
    end type kepler_2d

    !> Restricted three-body problem in Arenstorf's rotating frame; y = [x, y, vx, vy].
    type, extends(ode_system) :: arenstorf
        real(dp) :: mu = 0.012277471_dp
    contains
        procedure :: rhs => are_rhs
        procedure :: jacobian => are_jac
        procedure :: has_jacobian => are_has
        procedure :: has_jacobian_product => are_has
        procedure :: jacobian_product => are_jac_prod
        procedure :: rhs_jacobian_product => are_rhs_jac_prod
    end type arenstorf

    !> x'' = mu (1 - x^2) x' - x; y = [x, x'].
    type, extends(ode_system) :: van_der_pol
        real(dp) :: mu = 1.0_dp
    contains
        procedure :: rhs => vdp_rhs
        procedure :: jacobian => vdp_jac
        procedure :: has_jacobian => vdp_has_jac
    end type van_der_pol

contains

    logical function ho_has_jac(self)
        class(harmonic_oscillator), intent(in) :: self
        ho_has_jac = .true.
    end function ho_has_jac

    logical function pend_has_jac(self)
        class(pendulum_theta), intent(in) :: self
        pend_has_jac = .true.
    end function pend_has_jac

    logical function kep_has_jac(self)
        class(kepler_2d), intent(in) :: self
        kep_has_jac = .true.
    end function kep_has_jac

    logical function vdp_has_jac(self)
        class(van_der_pol), intent(in) :: self
        vdp_has_jac = .true.
    end function vdp_has_jac

    subroutine ho_rhs(self, t, y, dydt)
        class(harmonic_oscillator), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        dydt(1) = y(2)
        dydt(2) = -self%omega**2*y(1)
    end subroutine ho_rhs

    subroutine ho_jac(self, t, y, dfdy)
        class(harmonic_oscillator), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dfdy(:, :)
        dfdy = reshape([0.0_dp, -self%omega**2, 1.0_dp, 0.0_dp], [2, 2])
    end subroutine ho_jac

    subroutine pend_rhs(self, t, y, dydt)
        class(pendulum_theta), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        dydt(1) = y(2)
        dydt(2) = -(self%g/self%l)*sin(y(1))
    end subroutine pend_rhs

    subroutine pend_jac(self, t, y, dfdy)
        class(pendulum_theta), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dfdy(:, :)
        dfdy = reshape([0.0_dp, -(self%g/self%l)*cos(y(1)), 1.0_dp, 0.0_dp], [2, 2])
    end subroutine pend_jac

    !> Energy per unit mass l^2: theta'^2/2 - (g/l) cos theta.
    pure real(dp) function pend_energy(self, y)
        class(pendulum_theta), intent(in) :: self
        real(dp), intent(in) :: y(:)
        pend_energy = 0.5_dp*y(2)**2 - (self%g/self%l)*cos(y(1))
    end function pend_energy

    subroutine kep_rhs(self, t, y, dydt)
        class(kepler_2d), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: r3
        r3 = y(1)**2 + y(2)**2
        r3 = r3*sqrt(r3)
        dydt(1) = y(3)
        dydt(2) = y(4)
        dydt(3) = -self%mu*y(1)/r3
        dydt(4) = -self%mu*y(2)/r3
    end subroutine kep_rhs

    subroutine kep_jac(self, t, y, dfdy)
        class(kepler_2d), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(dp) :: r2, r3, r5
        r2 = y(1)**2 + y(2)**2
        r3 = r2*sqrt(r2)
        r5 = r3*r2
        dfdy = 0.0_dp
        dfdy(1, 3) = 1.0_dp
        dfdy(2, 4) = 1.0_dp
        dfdy(3, 1) = self%mu*(3.0_dp*y(1)**2/r5 - 1.0_dp/r3)
        dfdy(3, 2) = self%mu*3.0_dp*y(1)*y(2)/r5
        dfdy(4, 1) = dfdy(3, 2)
        dfdy(4, 2) = self%mu*(3.0_dp*y(2)**2/r5 - 1.0_dp/r3)
    end subroutine kep_jac

    pure real(dp) function kep_energy(self, y)
        class(kepler_2d), intent(in) :: self
        real(dp), intent(in) :: y(:)
        kep_energy = 0.5_dp*(y(3)**2 + y(4)**2) - self%mu/sqrt(y(1)**2 + y(2)**2)
    end function kep_energy

    subroutine are_rhs(self, t, y, dydt)
        class(arenstorf), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: d1, d2, mp
        mp = 1.0_dp - self%mu
        d1 = (y(1) + self%mu)**2 + y(2)**2
        d1 = d1*sqrt(d1)
        d2 = (y(1) - mp)**2 + y(2)**2
        d2 = d2*sqrt(d2)
        dydt(1) = y(3)
        dydt(2) = y(4)
        dydt(3) = y(1) + 2.0_dp*y(4) - mp*(y(1) + self%mu)/d1 - self%mu*(y(1) - mp)/d2
        dydt(4) = y(2) - 2.0_dp*y(3) - mp*y(2)/d1 - self%mu*y(2)/d2
    end subroutine are_rhs

    logical function are_has(self)
        class(arenstorf), intent(in) :: self
        are_has = .true.
    end function are_has

    !> f (the same expressions as `are_rhs`, so the same bits) and the Hessian entries of
    !! the effective potential at (y1, y2).
    pure subroutine are_parts(mu, y, f, uxx, uxy, uyy)
        real(dp), intent(in) :: mu, y(4)
        real(dp), intent(out) :: f(4), uxx, uxy, uyy
        real(dp) :: mp, x1, x2, s1, s2, d1, d2, i13, i23, i15, i25
        mp = 1.0_dp - mu
        x1 = y(1) + mu
        x2 = y(1) - mp
        s1 = x1**2 + y(2)**2
        d1 = s1*sqrt(s1)
        s2 = x2**2 + y(2)**2
        d2 = s2*sqrt(s2)
        f(1) = y(3)
        f(2) = y(4)
        f(3) = y(1) + 2.0_dp*y(4) - mp*x1/d1 - mu*x2/d2
        f(4) = y(2) - 2.0_dp*y(3) - mp*y(2)/d1 - mu*y(2)/d2
        i15 = 1.0_dp/(d1*s1)     ! 1/r^5: one division per body, 1/r^3 from it
        i25 = 1.0_dp/(d2*s2)
        i13 = i15*s1
        i23 = i25*s2
        uxx = 1.0_dp - mp*(i13 - 3.0_dp*x1*x1*i15) - mu*(i23 - 3.0_dp*x2*x2*i25)
        uxy = 3.0_dp*y(2)*(mp*x1*i15 + mu*x2*i25)
        uyy = 1.0_dp - mp*(i13 - 3.0_dp*y(2)*y(2)*i15) - mu*(i23 - 3.0_dp*y(2)*y(2)*i25)
    end subroutine are_parts

    subroutine are_jac(self, t, y, dfdy)
        class(arenstorf), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(dp) :: f(4), uxx, uxy, uyy, jac(4, 4)
        call are_parts(self%mu, y(1:4), f, uxx, uxy, uyy)
        call rotating_frame_jacobian(uxx, uxy, uyy, 2.0_dp, jac)
        dfdy = jac
    end subroutine are_jac

    subroutine are_jac_prod(self, t, n, k, y, x, jx)
        class(arenstorf), intent(in) :: self
        real(dp), intent(in) :: t
        integer, intent(in) :: n, k
        real(dp), intent(in) :: y(n), x(n, k)
        real(dp), intent(out) :: jx(n, k)
        real(dp) :: f(4), uxx, uxy, uyy
        call are_parts(self%mu, y, f, uxx, uxy, uyy)
        call rotating_frame_product(k, uxx, uxy, uyy, 2.0_dp, x, jx)
    end subroutine are_jac_prod

    subroutine are_rhs_jac_prod(self, t, n, k, y, dydt, x, jx)
        class(arenstorf), intent(in) :: self
        real(dp), intent(in) :: t
        integer, intent(in) :: n, k
        real(dp), intent(in) :: y(n), x(n, k)
        real(dp), intent(out) :: dydt(n), jx(n, k)
        real(dp) :: uxx, uxy, uyy
        if (n == 4 .and. k == 4) then
            call are_rhs_stm(self%mu, y, dydt, x, jx)
        else
            call are_parts(self%mu, y, dydt, uxx, uxy, uyy)
            call rotating_frame_product(k, uxx, uxy, uyy, 2.0_dp, x, jx)
        end if
    end subroutine are_rhs_jac_prod

    !> f and J Phi for the 4 x 4 STM (constant sizes, the product inline).
    pure subroutine are_rhs_stm(mu, y, dydt, x, jx)
        integer, parameter :: k = 4
        real(dp), parameter :: c = 2.0_dp
        real(dp), intent(in) :: mu, y(4), x(4, k)
        real(dp), intent(out) :: dydt(4), jx(4, k)
        real(dp) :: uxx, uxy, uyy
        integer :: j
        call are_parts(mu, y, dydt, uxx, uxy, uyy)
        include "conmech_rotating_frame_product.inc"
    end subroutine are_rhs_stm

    subroutine vdp_rhs(self, t, y, dydt)
        class(van_der_pol), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        dydt(1) = y(2)
        dydt(2) = self%mu*(1.0_dp - y(1)**2)*y(2) - y(1)
    end subroutine vdp_rhs

    subroutine vdp_jac(self, t, y, dfdy)
        class(van_der_pol), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dfdy(:, :)
        dfdy(1, 1) = 0.0_dp
        dfdy(1, 2) = 1.0_dp
        dfdy(2, 1) = -2.0_dp*self%mu*y(1)*y(2) - 1.0_dp
        dfdy(2, 2) = self%mu*(1.0_dp - y(1)**2)
    end subroutine vdp_jac

end module conmech_systems_basic
