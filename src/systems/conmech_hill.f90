!> Hill's lunar problem (the lecture notes): the restricted three-body problem in Hill's form,
!!
!!     x'' - 2 m y' = dF/dx,   y'' + 2 m x' = dF/dy,   F = kappa/r + (3/2) m^2 x^2,
!!
!! in the frame rotating with the Sun (time scaled so that the synodic period is 2 pi,
!! m = n'/(n - n')). State y = [x, y, x', y']. Jacobi integral I = x'^2 + y'^2 - 2 F
!! (constant along solutions). The analytic Jacobian makes the variational equations exact.
module conmech_hill
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_system
    use conmech_rotating_frame, only: rotating_frame_product, rotating_frame_jacobian
    implicit none
    private
    public :: hill_problem, hill_jacobi, hill_grad_f, hill_hess_f, hill_equilibrium_x

    type, extends(ode_system) :: hill_problem
        real(dp) :: m = 0.080848933808312_dp   !! n'/(n - n')
        real(dp) :: kappa = 1.0_dp             !! gravitational parameter
    contains
        procedure :: rhs => hill_rhs
        procedure :: jacobian => hill_jac
        procedure :: has_jacobian => hill_has_jac
        procedure :: has_jacobian_product => hill_has_jac
        procedure :: jacobian_product => hill_jac_prod
        procedure :: rhs_jacobian_product => hill_rhs_jac_prod
        procedure :: jacobi => hill_jacobi_tbp
    end type hill_problem

contains

    !> Gradient of F at (x, y).
    pure subroutine hill_grad_f(m, kappa, x, y, fx, fy)
        real(dp), intent(in) :: m, kappa, x, y
        real(dp), intent(out) :: fx, fy
        real(dp) :: r2, r3
        r2 = x*x + y*y
        r3 = r2*sqrt(r2)
        fx = -kappa*x/r3 + 3.0_dp*m*m*x
        fy = -kappa*y/r3
    end subroutine hill_grad_f

    !> Hessian of F at (x, y): fxx, fxy, fyy.
    pure subroutine hill_hess_f(m, kappa, x, y, fxx, fxy, fyy)
        real(dp), intent(in) :: m, kappa, x, y
        real(dp), intent(out) :: fxx, fxy, fyy
        real(dp) :: r2, r3, r5
        r2 = x*x + y*y
        r3 = r2*sqrt(r2)
        r5 = r3*r2
        fxx = kappa*(3.0_dp*x*x/r5 - 1.0_dp/r3) + 3.0_dp*m*m
        fxy = 3.0_dp*kappa*x*y/r5
        fyy = kappa*(3.0_dp*y*y/r5 - 1.0_dp/r3)
    end subroutine hill_hess_f

    !> Jacobi integral I = x'^2 + y'^2 - 2 F(x, y).
    pure real(dp) function hill_jacobi(m, kappa, s) result(c)
        real(dp), intent(in) :: m, kappa, s(4)
        c = s(3)**2 + s(4)**2 - 2.0_dp*(kappa/sqrt(s(1)**2 + s(2)**2) &
                                         + 1.5_dp*m*m*s(1)**2)
    end function hill_jacobi

    !> The equilibria (+-x_e, 0): x_e = (kappa/(3 m^2))^(1/3) (Hill's libration points).
    pure real(dp) function hill_equilibrium_x(m, kappa) result(xe)
        real(dp), intent(in) :: m, kappa
        xe = (kappa/(3.0_dp*m*m))**(1.0_dp/3.0_dp)
    end function hill_equilibrium_x

    real(dp) function hill_jacobi_tbp(self, y) result(c)
        class(hill_problem), intent(in) :: self
        real(dp), intent(in) :: y(:)
        c = hill_jacobi(self%m, self%kappa, y(1:4))
    end function hill_jacobi_tbp

    subroutine hill_rhs(self, t, y, dydt)
        class(hill_problem), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: fx, fy
        call hill_grad_f(self%m, self%kappa, y(1), y(2), fx, fy)
        dydt(1) = y(3)
        dydt(2) = y(4)
        dydt(3) = 2.0_dp*self%m*y(4) + fx
        dydt(4) = -2.0_dp*self%m*y(3) + fy
    end subroutine hill_rhs

    subroutine hill_jac(self, t, y, dfdy)
        class(hill_problem), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(dp) :: fxx, fxy, fyy, jac(4, 4)
        call hill_hess_f(self%m, self%kappa, y(1), y(2), fxx, fxy, fyy)
        call rotating_frame_jacobian(fxx, fxy, fyy, 2.0_dp*self%m, jac)
        dfdy = jac
    end subroutine hill_jac

    !> jx = J x for a 4 x k block (two rows copied, constant entries folded).
    subroutine hill_jac_prod(self, t, n, k, y, x, jx)
        class(hill_problem), intent(in) :: self
        real(dp), intent(in) :: t
        integer, intent(in) :: n, k
        real(dp), intent(in) :: y(n), x(n, k)
        real(dp), intent(out) :: jx(n, k)
        real(dp) :: fxx, fxy, fyy
        call hill_hess_f(self%m, self%kappa, y(1), y(2), fxx, fxy, fyy)
        call rotating_frame_product(k, fxx, fxy, fyy, 2.0_dp*self%m, x, jx)
    end subroutine hill_jac_prod

    !> f (as `hill_rhs`) and J x together.
    subroutine hill_rhs_jac_prod(self, t, n, k, y, dydt, x, jx)
        class(hill_problem), intent(in) :: self
        real(dp), intent(in) :: t
        integer, intent(in) :: n, k
        real(dp), intent(in) :: y(n), x(n, k)
        real(dp), intent(out) :: dydt(n), jx(n, k)
        real(dp) :: fx, fy, fxx, fxy, fyy
        call hill_grad_f(self%m, self%kappa, y(1), y(2), fx, fy)
        dydt(1) = y(3)
        dydt(2) = y(4)
        dydt(3) = 2.0_dp*self%m*y(4) + fx
        dydt(4) = -2.0_dp*self%m*y(3) + fy
        call hill_hess_f(self%m, self%kappa, y(1), y(2), fxx, fxy, fyy)
        if (n == 4 .and. k == 4) then
            call hill_stm_product(fxx, fxy, fyy, 2.0_dp*self%m, x, jx)
        else
            call rotating_frame_product(k, fxx, fxy, fyy, 2.0_dp*self%m, x, jx)
        end if
    end subroutine hill_rhs_jac_prod

    !> J x for the 4 x 4 STM (constant sizes, inline).
    pure subroutine hill_stm_product(uxx, uxy, uyy, c, x, jx)
        integer, parameter :: k = 4
        real(dp), intent(in) :: uxx, uxy, uyy, c, x(4, k)
        real(dp), intent(out) :: jx(4, k)
        integer :: j
        include "conmech_rotating_frame_product.inc"
    end subroutine hill_stm_product

    logical function hill_has_jac(self)
        class(hill_problem), intent(in) :: self
        hill_has_jac = .true.
    end function hill_has_jac

end module conmech_hill
