!> Hill's lunar problem in space: the planar equations of conmech_hill (frame rotating with
!! the Sun, time scaled so that the synodic month is 2 pi, m = n'/(n - n')) with the
!! out-of-plane motion,
!!
!!     x'' - 2 m y' = F_x,   y'' + 2 m x' = F_y,   z'' = F_z,
!!     F = kappa/r + (3/2) m^2 x^2 - (1/2) m^2 z^2,   r = |(x, y, z)|,
!!
!! i.e. z'' + m^2 z = -kappa z/r^3. State y = [x, y, z, x', y', z']; Jacobi integral
!! I = |v|^2 - 2 F (the convention of the planar problem). In the plane z = 0 the planar
!! problem is recovered exactly; along a planar orbit the out-of-plane variation obeys
!! dz'' + (m^2 + kappa/r^3) dz = 0, a Hill's equation whose characteristic exponent is the
!! motion of the node (Adams 1877). The Jacobian is exact and its product with a 6 x k
!! block never forms J.
module conmech_hill_spatial
    use conmech_kinds, only: dp
    use conmech_rotating_frame, only: spatial_frame_product, spatial_frame_jacobian
    use conmech_ode_system, only: ode_system
    implicit none
    private
    public :: hill_spatial, hill_spatial_jacobi

    !> Hill's problem in space; y = [x, y, z, x', y', z'].
    type, extends(ode_system) :: hill_spatial
        real(dp) :: m = 0.080848933808312_dp   !! n'/(n - n')
        real(dp) :: kappa = 1.0_dp             !! gravitational parameter
    contains
        procedure :: rhs => hs_rhs
        procedure :: jacobian => hs_jac
        procedure :: has_jacobian => hs_has
        procedure :: has_jacobian_product => hs_has
        procedure :: jacobian_product => hs_jac_prod
        procedure :: rhs_jacobian_product => hs_rhs_jac_prod
        procedure :: jacobi => hs_jacobi_tbp
    end type hill_spatial

contains

    !> Acceleration (F_x + 2 m y', F_y - 2 m x', F_z) and, if asked, the Hessian entries
    !! of F (hxx, hxy, hxz, hyy, hyz, hzz).
    pure subroutine hs_parts(m, kappa, s, acc, h)
        real(dp), intent(in) :: m, kappa, s(6)
        real(dp), intent(out) :: acc(3)
        real(dp), intent(out), optional :: h(6)
        real(dp) :: q, k3, k5, m2
        m2 = m*m
        q = s(1)**2 + s(2)**2 + s(3)**2
        k3 = kappa/(q*sqrt(q))              ! kappa/r^3
        acc(1) = -k3*s(1) + 3.0_dp*m2*s(1) + 2.0_dp*m*s(5)
        acc(2) = -k3*s(2) - 2.0_dp*m*s(4)
        acc(3) = -k3*s(3) - m2*s(3)
        if (present(h)) then
            k5 = 3.0_dp*k3/q                ! 3 kappa/r^5
            h(1) = k5*s(1)*s(1) - k3 + 3.0_dp*m2
            h(2) = k5*s(1)*s(2)
            h(3) = k5*s(1)*s(3)
            h(4) = k5*s(2)*s(2) - k3
            h(5) = k5*s(2)*s(3)
            h(6) = k5*s(3)*s(3) - k3 - m2
        end if
    end subroutine hs_parts

    !> Jacobi integral I = |v|^2 - 2 F of the state s.
    pure real(dp) function hill_spatial_jacobi(m, kappa, s) result(c)
        real(dp), intent(in) :: m, kappa, s(6)
        c = s(4)**2 + s(5)**2 + s(6)**2 &
            - 2.0_dp*(kappa/sqrt(s(1)**2 + s(2)**2 + s(3)**2) + 1.5_dp*m*m*s(1)**2 &
                      - 0.5_dp*m*m*s(3)**2)
    end function hill_spatial_jacobi

    real(dp) function hs_jacobi_tbp(self, y) result(c)
        class(hill_spatial), intent(in) :: self
        real(dp), intent(in) :: y(:)
        c = hill_spatial_jacobi(self%m, self%kappa, y(1:6))
    end function hs_jacobi_tbp

    subroutine hs_rhs(self, t, y, dydt)
        class(hill_spatial), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: acc(3)
        call hs_parts(self%m, self%kappa, y(1:6), acc)
        dydt(1:3) = y(4:6)
        dydt(4:6) = acc
    end subroutine hs_rhs

    logical function hs_has(self)
        class(hill_spatial), intent(in) :: self
        hs_has = .true.
    end function hs_has

    subroutine hs_jac(self, t, y, dfdy)
        class(hill_spatial), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(dp) :: acc(3), h(6), jac(6, 6)
        call hs_parts(self%m, self%kappa, y(1:6), acc, h)
        call spatial_frame_jacobian(h, 2.0_dp*self%m, jac)
        dfdy = jac
    end subroutine hs_jac

    subroutine hs_jac_prod(self, t, n, k, y, x, jx)
        class(hill_spatial), intent(in) :: self
        real(dp), intent(in) :: t
        integer, intent(in) :: n, k
        real(dp), intent(in) :: y(n), x(n, k)
        real(dp), intent(out) :: jx(n, k)
        real(dp) :: acc(3), h(6)
        call hs_parts(self%m, self%kappa, y(1:6), acc, h)
        call spatial_frame_product(k, h, 2.0_dp*self%m, x, jx)
    end subroutine hs_jac_prod

    subroutine hs_rhs_jac_prod(self, t, n, k, y, dydt, x, jx)
        class(hill_spatial), intent(in) :: self
        real(dp), intent(in) :: t
        integer, intent(in) :: n, k
        real(dp), intent(in) :: y(n), x(n, k)
        real(dp), intent(out) :: dydt(n), jx(n, k)
        real(dp) :: acc(3), h(6)
        call hs_parts(self%m, self%kappa, y(1:6), acc, h)
        dydt(1:3) = y(4:6)
        dydt(4:6) = acc
        call spatial_frame_product(k, h, 2.0_dp*self%m, x, jx)
    end subroutine hs_rhs_jac_prod

end module conmech_hill_spatial
