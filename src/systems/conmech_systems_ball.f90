!> The rolling rubber ball on a plane (seed 001: "a non-holonomic system: rubber ball on
!! plane, d.o.f. = 2"): a ball of mass m, radius R and central moment of inertia I (isotropic:
!! a homogeneous ball has I = 2/5 m R^2) rolls without slipping and without spinning about
!! the vertical on a plane inclined at alpha (downhill = +x; alpha = 0 is the seed's plane).
!!
!! Excessive coordinates q = [x, y, e0, e1, e2, e3]: the centre (x, y) and the orientation as
!! a unit quaternion e (no gimbal lock, unlike Euler angles). The angular velocity in space
!! is w = 2 H(e) e' with the rows
!!
!!     H_x = [-e1,  e0, -e3,  e2],  H_y = [-e2,  e3,  e0, -e1],  H_z = [-e3, -e2,  e1,  e0].
!!
!! T = m/2 (x'^2 + y'^2) + I/2 |w|^2 = m/2 (x'^2 + y'^2) + 2 I |e'|^2 on e.e' = 0, so
!! M = diag(m, m, 4I, 4I, 4I, 4I) (the difference to the exact quadratic form is a multiple
!! of e, taken up by the holonomic multiplier); U = -m g sin(alpha) x.
!! Constraints (n = 6, n_hol = 1, n_nh = 3):
!!
!!     phi = (|e|^2 - 1)/2                  (unit quaternion, holonomic)
!!     x' - R w_y = 0,  y' + R w_x = 0      (no slip at the contact point -R e_z)
!!     w_z = 0                              (no spin about the vertical: the rubber ball)
!!
!! gamma_h = -|e'|^2; gamma_n = -(dA/dt) v = 0 exactly, since H(e') e' = 0. The multipliers
!! of the non-holonomic rows are the contact force (F_x, F_y) and the vertical reaction
!! torque. Closed forms: on the plane the centre moves on a straight line at constant speed
!! and e(t) = [cos(|w| t/2), sin(|w| t/2) w/|w|] * e(0); on the incline the centre moves on a
!! parabola, x'' = g sin(alpha)/(1 + I/(m R^2)), y'' = 0, with F_x = -I x''/R^2.
module conmech_systems_ball
    use conmech_kinds, only: dp
    use conmech_constrained_system, only: constrained_system
    implicit none
    private

    public :: rolling_ball

    !> Rubber ball rolling without slip and spin on a plane inclined at alpha,
    !! q = [x, y, e0, e1, e2, e3] (set n = 6, n_hol = 1, n_nh = 3).
    type, extends(constrained_system) :: rolling_ball
        real(dp) :: m = 1.0_dp       !! mass
        real(dp) :: r = 1.0_dp       !! radius
        real(dp) :: i = 0.4_dp       !! central moment of inertia (isotropic)
        real(dp) :: g = 9.81_dp      !! gravity
        real(dp) :: alpha = 0.0_dp   !! inclination of the plane (downhill = +x)
    contains
        procedure :: mass => rb_mass
        procedure :: forces => rb_forces
        procedure :: phi => rb_phi
        procedure :: phi_jac => rb_phi_jac
        procedure :: phi_t => rb_phi_t
        procedure :: phi_gamma => rb_phi_gamma
        procedure :: nh_matrix => rb_nh
        procedure :: nh_gamma => rb_nh_gamma
        procedure :: energy => rb_energy
        procedure :: has_energy => rb_has_energy
    end type rolling_ball

contains

    !> M = diag(m, m, 4I, 4I, 4I, 4I).
    subroutine rb_mass(self, t, q, mm)
        class(rolling_ball), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        integer :: k
        mm = 0.0_dp
        mm(1, 1) = self%m
        mm(2, 2) = self%m
        do k = 3, 6
            mm(k, k) = 4.0_dp*self%i
        end do
    end subroutine rb_mass

    !> Gravity along the incline.
    subroutine rb_forces(self, t, q, v, f)
        class(rolling_ball), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = 0.0_dp
        f(1) = self%m*self%g*sin(self%alpha)
    end subroutine rb_forces

    !> phi = (|e|^2 - 1)/2.
    subroutine rb_phi(self, t, q, c)
        class(rolling_ball), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c(1) = 0.5_dp*(sum(q(3:6)**2) - 1.0_dp)
    end subroutine rb_phi

    !> G = [0, 0, e].
    subroutine rb_phi_jac(self, t, q, g)
        class(rolling_ball), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        g(1, 1:2) = 0.0_dp
        g(1, 3:6) = q(3:6)
    end subroutine rb_phi_jac

    !> Scleronomic: phi_t = 0.
    subroutine rb_phi_t(self, t, q, pt)
        class(rolling_ball), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: pt(:)
        pt = 0.0_dp
    end subroutine rb_phi_t

    !> gamma_h = -|e'|^2.
    subroutine rb_phi_gamma(self, t, q, v, gam)
        class(rolling_ball), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        gam(1) = -sum(v(3:6)**2)
    end subroutine rb_phi_gamma

    !> The rows of w = 2 H(e) e' (space-frame angular velocity), h(k, :) = H_k.
    pure function h_rows(e) result(h)
        real(dp), intent(in) :: e(4)
        real(dp) :: h(3, 4)
        h(1, :) = [-e(2), e(1), -e(4), e(3)]
        h(2, :) = [-e(3), e(4), e(1), -e(2)]
        h(3, :) = [-e(4), -e(3), e(2), e(1)]
    end function h_rows

    !> A = [1 0 -2R H_y; 0 1 2R H_x; 0 0 2 H_z], b = 0.
    subroutine rb_nh(self, t, q, a, b)
        class(rolling_ball), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: a(:, :), b(:)
        real(dp) :: h(3, 4)
        h = h_rows(q(3:6))
        a = 0.0_dp
        a(1, 1) = 1.0_dp
        a(1, 3:6) = -2.0_dp*self%r*h(2, :)
        a(2, 2) = 1.0_dp
        a(2, 3:6) = 2.0_dp*self%r*h(1, :)
        a(3, 3:6) = 2.0_dp*h(3, :)
        b = 0.0_dp
    end subroutine rb_nh

    !> gamma_n = -(dA/dt) v = -A(e -> e') v, which is 2 H(e') e' = 0 row by row; computed
    !! rather than assumed, so that it stays exact off the unit sphere too.
    subroutine rb_nh_gamma(self, t, q, v, gam)
        class(rolling_ball), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        real(dp) :: hd(3, 4), w(3)
        hd = h_rows(v(3:6))
        w = 2.0_dp*matmul(hd, v(3:6))
        gam(1) = self%r*w(2)
        gam(2) = -self%r*w(1)
        gam(3) = -w(3)
    end subroutine rb_nh_gamma

    !> E = m/2 (x'^2 + y'^2) + 2 I |e'|^2 - m g sin(alpha) x.
    function rb_energy(self, t, q, v) result(e)
        class(rolling_ball), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*self%m*(v(1)**2 + v(2)**2) + 2.0_dp*self%i*sum(v(3:6)**2) &
            - self%m*self%g*sin(self%alpha)*q(1)
    end function rb_energy

    logical function rb_has_energy(self)
        class(rolling_ball), intent(in) :: self
        rb_has_energy = .true.
    end function rb_has_energy

end module conmech_systems_ball
