!> The restricted three-body problem in Arenstorf's rotating frame (the Earth-Moon mass
!! ratio mu), y = [x, y, x', y']:
!!
!!     x'' = x + 2 y' - (1 - mu)(x + mu)/r1^3 - mu (x - 1 + mu)/r2^3,
!!     y'' = y - 2 x' - (1 - mu) y/r1^3 - mu y/r2^3.
!!
!! Written by hand, not generated from a model like the other built-ins: the integrator
!! core's benchmark and acceptance figure (instructions per Arenstorf period) are measured on
!! it, and its Jacobian product is the structure-aware kernel of planar rotating-frame
!! problems (conmech_rotating_frame) with the 4 x 4 STM product written out
!! (conmech_rotating_frame_product.inc), which `integrate_stm` runs through.
module conmech_arenstorf
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_system
    use conmech_rotating_frame, only: rotating_frame_product, rotating_frame_jacobian
    implicit none
    private
    public :: arenstorf

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

contains

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

end module conmech_arenstorf
