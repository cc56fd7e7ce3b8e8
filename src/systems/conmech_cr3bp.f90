!> The spatial circular restricted three-body problem in the rotating frame.
!!
!! Two primaries of masses 1 - mu and mu (0 < mu <= 1/2) move on circles about their
!! barycentre; in the frame rotating with them (unit distance, unit angular velocity) they
!! sit at (-mu, 0, 0) and (1 - mu, 0, 0), and a massless body obeys
!!
!!     x'' - 2 y' = Omega_x,   y'' + 2 x' = Omega_y,   z'' = Omega_z,
!!     Omega = (x^2 + y^2)/2 + (1 - mu)/r1 + mu/r2,
!!
!! r1, r2 its distances to the primaries. State y = [x, y, z, x', y', z']. The Jacobi
!! integral C = 2 Omega - (x'^2 + y'^2 + z'^2) is constant along solutions (it plays the
!! role of the energy, with the opposite sign and a factor -2). The Jacobian
!!
!!     J = [ 0  I ]     H the Hessian of Omega,
!!         [ H  K ]     K = [0 2 0; -2 0 0; 0 0 0] (Coriolis),
!!
!! is exact; its product with a 6 x k block copies three rows and applies the symmetric
!! 3 x 3 H and the two Coriolis entries, never forming J (the variational equations of
!! periodic orbits run through it).
!!
!! The five equilibria (libration points): L1 between the primaries, L2 beyond the
!! smaller one, L3 beyond the larger one (on the x axis, from the classical quintics in
!! the distance gamma to the nearer primary, solved by Newton's method to round-off), and
!! L4, L5 at the apexes of the equilateral triangles.
module conmech_cr3bp
    use conmech_kinds, only: dp
    use conmech_rotating_frame, only: spatial_frame_product, spatial_frame_jacobian
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT, CM_NO_CONVERGENCE
    use conmech_ode_system, only: ode_system
    implicit none
    private
    public :: cr3bp, cr3bp_jacobi, cr3bp_omega_hessian, cr3bp_libration_points

    !> The spatial CR3BP with mass parameter mu; y = [x, y, z, x', y', z'].
    type, extends(ode_system) :: cr3bp
        real(dp) :: mu = 0.012150585609624_dp   !! mass of the smaller primary (Earth-Moon)
    contains
        procedure :: rhs => cr_rhs
        procedure :: jacobian => cr_jac
        procedure :: has_jacobian => cr_has
        procedure :: has_jacobian_product => cr_has
        procedure :: jacobian_product => cr_jac_prod
        procedure :: rhs_jacobian_product => cr_rhs_jac_prod
        procedure :: jacobi => cr_jacobi_tbp
    end type cr3bp

contains

    !> The acceleration a = (Omega_x + 2 y', Omega_y - 2 x', Omega_z) and, if asked, the
    !! Hessian entries of Omega (hxx, hxy, hxz, hyy, hyz, hzz) at the state s.
    pure subroutine cr_parts(mu, s, acc, h)
        real(dp), intent(in) :: mu, s(6)
        real(dp), intent(out) :: acc(3)
        real(dp), intent(out), optional :: h(6)
        real(dp) :: mp, d1(3), d2(3), q1, q2, i13, i23, i15, i25
        mp = 1.0_dp - mu
        d1 = [s(1) + mu, s(2), s(3)]
        d2 = [s(1) - mp, s(2), s(3)]
        q1 = d1(1)**2 + d1(2)**2 + d1(3)**2
        q2 = d2(1)**2 + d2(2)**2 + d2(3)**2
        i13 = mp/(q1*sqrt(q1))          ! (1 - mu)/r1^3
        i23 = mu/(q2*sqrt(q2))          ! mu/r2^3
        acc(1) = s(1) - i13*d1(1) - i23*d2(1) + 2.0_dp*s(5)
        acc(2) = s(2) - i13*d1(2) - i23*d2(2) - 2.0_dp*s(4)
        acc(3) = -i13*d1(3) - i23*d2(3)
        if (present(h)) then
            i15 = 3.0_dp*i13/q1         ! 3 (1 - mu)/r1^5
            i25 = 3.0_dp*i23/q2
            h(1) = 1.0_dp - i13 - i23 + i15*d1(1)*d1(1) + i25*d2(1)*d2(1)
            h(2) = i15*d1(1)*d1(2) + i25*d2(1)*d2(2)
            h(3) = i15*d1(1)*d1(3) + i25*d2(1)*d2(3)
            h(4) = 1.0_dp - i13 - i23 + i15*d1(2)*d1(2) + i25*d2(2)*d2(2)
            h(5) = i15*d1(2)*d1(3) + i25*d2(2)*d2(3)
            h(6) = -i13 - i23 + i15*d1(3)*d1(3) + i25*d2(3)*d2(3)
        end if
    end subroutine cr_parts

    !> The Hessian of Omega at position (x, y, z) as a 3 x 3 matrix.
    pure subroutine cr3bp_omega_hessian(mu, r, hess)
        real(dp), intent(in) :: mu, r(3)
        real(dp), intent(out) :: hess(3, 3)
        real(dp) :: acc(3), h(6)
        call cr_parts(mu, [r, 0.0_dp, 0.0_dp, 0.0_dp], acc, h)
        hess = reshape([h(1), h(2), h(3), h(2), h(4), h(5), h(3), h(5), h(6)], [3, 3])
    end subroutine cr3bp_omega_hessian

    !> Jacobi integral C = 2 Omega - |v|^2 of the state s.
    pure real(dp) function cr3bp_jacobi(mu, s) result(c)
        real(dp), intent(in) :: mu, s(6)
        real(dp) :: r1, r2
        r1 = sqrt((s(1) + mu)**2 + s(2)**2 + s(3)**2)
        r2 = sqrt((s(1) - 1.0_dp + mu)**2 + s(2)**2 + s(3)**2)
        c = s(1)**2 + s(2)**2 + 2.0_dp*((1.0_dp - mu)/r1 + mu/r2) &
            - (s(4)**2 + s(5)**2 + s(6)**2)
    end function cr3bp_jacobi

    real(dp) function cr_jacobi_tbp(self, y) result(c)
        class(cr3bp), intent(in) :: self
        real(dp), intent(in) :: y(:)
        c = cr3bp_jacobi(self%mu, y(1:6))
    end function cr_jacobi_tbp

    !> The libration points: pos(:, k) the position of L_k (k = 1..5) and cj(k) its Jacobi
    !! constant. info CM_BAD_INPUT unless 0 < mu <= 1/2; CM_NO_CONVERGENCE if a Newton
    !! iteration on a collinear quintic did not reach round-off (it always does for such mu).
    pure subroutine cr3bp_libration_points(mu, pos, cj, info)
        real(dp), intent(in) :: mu
        real(dp), intent(out) :: pos(3, 5), cj(5)
        integer, intent(out) :: info
        real(dp) :: g, c(6)
        integer :: k
        pos = 0.0_dp
        cj = 0.0_dp
        info = CM_BAD_INPUT
        if (.not. (mu > 0.0_dp .and. mu <= 0.5_dp)) return
        ! gamma^5 + c(2) gamma^4 + ... + c(6) = 0 (Szebehely 1967, sec. 4.4)
        do k = 1, 3
            select case (k)
            case (1)     ! L1 = 1 - mu - gamma, gamma the distance to the smaller primary
                c = [1.0_dp, -(3.0_dp - mu), 3.0_dp - 2.0_dp*mu, -mu, 2.0_dp*mu, -mu]
                g = (mu/3.0_dp)**(1.0_dp/3.0_dp)
            case (2)     ! L2 = 1 - mu + gamma
                c = [1.0_dp, 3.0_dp - mu, 3.0_dp - 2.0_dp*mu, -mu, -2.0_dp*mu, -mu]
                g = (mu/3.0_dp)**(1.0_dp/3.0_dp)
            case (3)     ! L3 = -mu - gamma, gamma the distance to the larger primary
                c = [1.0_dp, 2.0_dp + mu, 1.0_dp + 2.0_dp*mu, -(1.0_dp - mu), &
                     -2.0_dp*(1.0_dp - mu), -(1.0_dp - mu)]
                g = 1.0_dp - 7.0_dp*mu/12.0_dp
            end select
            call quintic_root(c, g, info)
            if (info /= CM_SUCCESS) return
            select case (k)
            case (1)
                pos(1, 1) = 1.0_dp - mu - g
            case (2)
                pos(1, 2) = 1.0_dp - mu + g
            case (3)
                pos(1, 3) = -mu - g
            end select
        end do
        pos(1, 4) = 0.5_dp - mu
        pos(2, 4) = 0.5_dp*sqrt(3.0_dp)
        pos(1, 5) = 0.5_dp - mu
        pos(2, 5) = -0.5_dp*sqrt(3.0_dp)
        do k = 1, 5
            cj(k) = cr3bp_jacobi(mu, [pos(:, k), 0.0_dp, 0.0_dp, 0.0_dp])
        end do
        info = CM_SUCCESS
    end subroutine cr3bp_libration_points

    !> Newton's method on the quintic with coefficients c (highest first) from g, until the
    !! step stops decreasing below 1e-15 g (the root to round-off).
    pure subroutine quintic_root(c, g, info)
        real(dp), intent(in) :: c(6)
        real(dp), intent(inout) :: g
        integer, intent(out) :: info
        real(dp) :: p, dp_, step, last
        integer :: it, j
        info = CM_NO_CONVERGENCE
        last = huge(1.0_dp)
        do it = 1, 100
            p = c(1)
            dp_ = 0.0_dp
            do j = 2, 6
                dp_ = dp_*g + p
                p = p*g + c(j)
            end do
            if (.not. (abs(dp_) > 0.0_dp)) return
            step = p/dp_
            g = g - step
            if (abs(step) <= 1.0e-15_dp*abs(g) .or. &
                (abs(step) <= 1.0e-13_dp*abs(g) .and. abs(step) >= last)) then
                info = CM_SUCCESS
                return
            end if
            last = abs(step)
        end do
    end subroutine quintic_root

    subroutine cr_rhs(self, t, y, dydt)
        class(cr3bp), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: acc(3)
        call cr_parts(self%mu, y(1:6), acc)
        dydt(1:3) = y(4:6)
        dydt(4:6) = acc
    end subroutine cr_rhs

    logical function cr_has(self)
        class(cr3bp), intent(in) :: self
        cr_has = .true.
    end function cr_has

    subroutine cr_jac(self, t, y, dfdy)
        class(cr3bp), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(dp) :: acc(3), h(6), jac(6, 6)
        call cr_parts(self%mu, y(1:6), acc, h)
        call spatial_frame_jacobian(h, 2.0_dp, jac)
        dfdy = jac
    end subroutine cr_jac

    subroutine cr_jac_prod(self, t, n, k, y, x, jx)
        class(cr3bp), intent(in) :: self
        real(dp), intent(in) :: t
        integer, intent(in) :: n, k
        real(dp), intent(in) :: y(n), x(n, k)
        real(dp), intent(out) :: jx(n, k)
        real(dp) :: acc(3), h(6)
        call cr_parts(self%mu, y(1:6), acc, h)
        call spatial_frame_product(k, h, 2.0_dp, x, jx)
    end subroutine cr_jac_prod

    subroutine cr_rhs_jac_prod(self, t, n, k, y, dydt, x, jx)
        class(cr3bp), intent(in) :: self
        real(dp), intent(in) :: t
        integer, intent(in) :: n, k
        real(dp), intent(in) :: y(n), x(n, k)
        real(dp), intent(out) :: dydt(n), jx(n, k)
        real(dp) :: acc(3), h(6)
        call cr_parts(self%mu, y(1:6), acc, h)
        dydt(1:3) = y(4:6)
        dydt(4:6) = acc
        call spatial_frame_product(k, h, 2.0_dp, x, jx)
    end subroutine cr_rhs_jac_prod

end module conmech_cr3bp
