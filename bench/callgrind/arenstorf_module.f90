!> Systems of the callgrind and STM benchmarks: the Arenstorf orbit with its analytic
!! Jacobian (for `integrate_stm`), and the same orbit with its 4x4 STM written out by hand
!! as a 20-equation system (the peer's arithmetic: jacobwilliams/dop853's benchmark).
module bench_arenstorf_systems
    use conmech
    implicit none
    private
    public :: are_jac, are_prod, are_stm, arenstorf_y0, arenstorf_period

    real(dp), parameter :: arenstorf_period = 17.0652165601579625588917206249_dp
    real(dp), parameter :: arenstorf_y0(4) = [0.994_dp, 0.0_dp, 0.0_dp, &
                                              -2.00158510637908252240537862224_dp]

    !> Arenstorf's orbit with an analytic Jacobian.
    type, extends(ode_system) :: are_jac
        real(dp) :: mu = 0.012277471_dp
    contains
        procedure :: rhs => aj_rhs
        procedure :: jacobian => aj_jac
        procedure :: has_jacobian => aj_has
        procedure :: rhs_jacobian => aj_rhs_jac
    end type are_jac

    !> The same orbit with its own J x product (what a user writes for integrate_stm to
    !! skip forming J): the hand-written system's arithmetic.
    type, extends(are_jac) :: are_prod
    contains
        procedure :: has_jacobian_product => ap_has
        procedure :: rhs_jacobian_product => ap_rhs_jac_prod
    end type are_prod

    !> Orbit + STM, 20 equations, J's structure written out.
    type, extends(ode_system) :: are_stm
        real(dp) :: mu = 0.012277471_dp
    contains
        procedure :: rhs => stm_rhs
    end type are_stm

contains

    subroutine aj_rhs(self, t, y, dydt)
        class(are_jac), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: mu, mp, x1, x2, yy, s1, s2, i13, i23
        mu = self%mu; mp = 1.0_dp - mu
        x1 = y(1) + mu; x2 = y(1) - mp; yy = y(2)
        s1 = x1*x1 + yy*yy; s2 = x2*x2 + yy*yy
        i13 = 1.0_dp/(s1*sqrt(s1)); i23 = 1.0_dp/(s2*sqrt(s2))
        dydt(1) = y(3); dydt(2) = y(4)
        dydt(3) = y(1) + 2.0_dp*y(4) - mp*x1*i13 - mu*x2*i23
        dydt(4) = yy - 2.0_dp*y(3) - mp*yy*i13 - mu*yy*i23
    end subroutine aj_rhs

    subroutine aj_jac(self, t, y, dfdy)
        class(are_jac), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(dp) :: mu, mp, x1, x2, yy, s1, s2, i13, i23, i15, i25, uxy
        mu = self%mu; mp = 1.0_dp - mu
        x1 = y(1) + mu; x2 = y(1) - mp; yy = y(2)
        s1 = x1*x1 + yy*yy; s2 = x2*x2 + yy*yy
        i13 = 1.0_dp/(s1*sqrt(s1)); i23 = 1.0_dp/(s2*sqrt(s2)); i15 = i13/s1; i25 = i23/s2
        uxy = 3.0_dp*(mp*x1*yy*i15 + mu*x2*yy*i25)
        dfdy(:, 1:2) = 0.0_dp
        dfdy(:, 3:4) = 0.0_dp
        dfdy(1, 3) = 1.0_dp
        dfdy(2, 4) = 1.0_dp
        dfdy(3, 1) = 1.0_dp - mp*(i13 - 3.0_dp*x1*x1*i15) - mu*(i23 - 3.0_dp*x2*x2*i25)
        dfdy(4, 2) = 1.0_dp - mp*(i13 - 3.0_dp*yy*yy*i15) - mu*(i23 - 3.0_dp*yy*yy*i25)
        dfdy(3, 2) = uxy
        dfdy(4, 1) = uxy
        dfdy(3, 4) = 2.0_dp
        dfdy(4, 3) = -2.0_dp
    end subroutine aj_jac

    !> f and J together, sharing the distances (as the hand-written 20 equations do).
    subroutine aj_rhs_jac(self, t, y, dydt, dfdy)
        class(are_jac), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:), dfdy(:, :)
        real(dp) :: mu, mp, x1, x2, yy, s1, s2, i13, i23, i15, i25, uxy
        mu = self%mu; mp = 1.0_dp - mu
        x1 = y(1) + mu; x2 = y(1) - mp; yy = y(2)
        s1 = x1*x1 + yy*yy; s2 = x2*x2 + yy*yy
        i13 = 1.0_dp/(s1*sqrt(s1)); i23 = 1.0_dp/(s2*sqrt(s2)); i15 = i13/s1; i25 = i23/s2
        dydt(1) = y(3); dydt(2) = y(4)
        dydt(3) = y(1) + 2.0_dp*y(4) - mp*x1*i13 - mu*x2*i23
        dydt(4) = yy - 2.0_dp*y(3) - mp*yy*i13 - mu*yy*i23
        uxy = 3.0_dp*(mp*x1*yy*i15 + mu*x2*yy*i25)
        dfdy(1, 1) = 0.0_dp; dfdy(2, 1) = 0.0_dp
        dfdy(1, 2) = 0.0_dp; dfdy(2, 2) = 0.0_dp
        dfdy(1, 3) = 1.0_dp; dfdy(2, 3) = 0.0_dp
        dfdy(1, 4) = 0.0_dp; dfdy(2, 4) = 1.0_dp
        dfdy(3, 1) = 1.0_dp - mp*(i13 - 3.0_dp*x1*x1*i15) - mu*(i23 - 3.0_dp*x2*x2*i25)
        dfdy(4, 2) = 1.0_dp - mp*(i13 - 3.0_dp*yy*yy*i15) - mu*(i23 - 3.0_dp*yy*yy*i25)
        dfdy(3, 2) = uxy; dfdy(4, 1) = uxy
        dfdy(3, 3) = 0.0_dp; dfdy(4, 4) = 0.0_dp
        dfdy(3, 4) = 2.0_dp; dfdy(4, 3) = -2.0_dp
    end subroutine aj_rhs_jac

    !> f and J x together (x: n x k; the orbit has n = 4).
    subroutine ap_rhs_jac_prod(self, t, n, k, y, dydt, x, jx)
        class(are_prod), intent(in) :: self
        real(dp), intent(in) :: t
        integer, intent(in) :: n, k
        real(dp), intent(in) :: y(n), x(n, k)
        real(dp), intent(out) :: dydt(n), jx(n, k)
        real(dp) :: mu, mp, x1, x2, yy, s1, s2, i13, i23, i15, i25, uxx, uxy, uyy
        integer :: j
        mu = self%mu; mp = 1.0_dp - mu
        x1 = y(1) + mu; x2 = y(1) - mp; yy = y(2)
        s1 = x1*x1 + yy*yy; s2 = x2*x2 + yy*yy
        i13 = 1.0_dp/(s1*sqrt(s1)); i23 = 1.0_dp/(s2*sqrt(s2)); i15 = i13/s1; i25 = i23/s2
        dydt(1) = y(3); dydt(2) = y(4)
        dydt(3) = y(1) + 2.0_dp*y(4) - mp*x1*i13 - mu*x2*i23
        dydt(4) = yy - 2.0_dp*y(3) - mp*yy*i13 - mu*yy*i23
        uxx = 1.0_dp - mp*(i13 - 3.0_dp*x1*x1*i15) - mu*(i23 - 3.0_dp*x2*x2*i25)
        uxy = 3.0_dp*(mp*x1*yy*i15 + mu*x2*yy*i25)
        uyy = 1.0_dp - mp*(i13 - 3.0_dp*yy*yy*i15) - mu*(i23 - 3.0_dp*yy*yy*i25)
        do j = 1, k
            jx(1, j) = x(3, j)
            jx(2, j) = x(4, j)
            jx(3, j) = uxx*x(1, j) + uxy*x(2, j) + 2.0_dp*x(4, j)
            jx(4, j) = uxy*x(1, j) + uyy*x(2, j) - 2.0_dp*x(3, j)
        end do
    end subroutine ap_rhs_jac_prod

    logical function ap_has(self)
        class(are_prod), intent(in) :: self
        ap_has = .true.
    end function ap_has

    logical function aj_has(self)
        class(are_jac), intent(in) :: self
        aj_has = .true.
    end function aj_has

    subroutine stm_rhs(self, t, y, dydt)
        class(are_stm), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: mu, mp, x1, x2, yy, s1, s2, i13, i23, i15, i25, uxx, uxy, uyy
        integer :: j, o
        mu = self%mu; mp = 1.0_dp - mu
        x1 = y(1) + mu; x2 = y(1) - mp; yy = y(2)
        s1 = x1*x1 + yy*yy; s2 = x2*x2 + yy*yy
        i13 = 1.0_dp/(s1*sqrt(s1)); i23 = 1.0_dp/(s2*sqrt(s2)); i15 = i13/s1; i25 = i23/s2
        dydt(1) = y(3); dydt(2) = y(4)
        dydt(3) = y(1) + 2.0_dp*y(4) - mp*x1*i13 - mu*x2*i23
        dydt(4) = yy - 2.0_dp*y(3) - mp*yy*i13 - mu*yy*i23
        uxx = 1.0_dp - mp*(i13 - 3.0_dp*x1*x1*i15) - mu*(i23 - 3.0_dp*x2*x2*i25)
        uxy = 3.0_dp*(mp*x1*yy*i15 + mu*x2*yy*i25)
        uyy = 1.0_dp - mp*(i13 - 3.0_dp*yy*yy*i15) - mu*(i23 - 3.0_dp*yy*yy*i25)
        do j = 1, 4
            o = 4*j
            dydt(o + 1) = y(o + 3)
            dydt(o + 2) = y(o + 4)
            dydt(o + 3) = uxx*y(o + 1) + uxy*y(o + 2) + 2.0_dp*y(o + 4)
            dydt(o + 4) = uxy*y(o + 1) + uyy*y(o + 2) - 2.0_dp*y(o + 3)
        end do
    end subroutine stm_rhs

end module bench_arenstorf_systems
