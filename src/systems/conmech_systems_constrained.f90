!> Built-in seed systems in excessive coordinates with constraints (all with analytic
!! Jacobians and acceleration terms). The reaction force is C^T lambda, C = [G; A].
!! Holonomic constraints are scaled so that the multipliers are the physical ones:
!! pendulum phi = (x^2 + y^2 - l^2)/2 gives lambda = m/l^2 (y g - x'^2 - y'^2) (seed 000);
!! the Atwood machine phi = L - y1 - y2 gives lambda = the string tension.
!! The dimensions (n, n_hol, n_nh) are set by `make_constrained` in conmech_systems_mech,
!! or by hand: pendulum_xy (2,1,0), rod_two_masses (4,1,1), double_pendulum_xy (4,2,0),
!! atwood_xy (2,1,0), pendulum_moving_xy (2,1,0), yoyo (2,1,0), skate (3,0,1),
!! rolling_disk (4,0,2).
module conmech_systems_constrained
    use conmech_kinds, only: dp
    use conmech_constrained_system, only: constrained_system
    implicit none
    private

    public :: pendulum_xy, rod_two_masses, double_pendulum_xy, atwood_xy
    public :: pendulum_moving_xy, yoyo, skate, rolling_disk

    !> Point mass on a circle, q = [x, y], gravity -y.
    type, extends(constrained_system) :: pendulum_xy
        real(dp) :: m = 1.0_dp, g = 9.81_dp, l = 1.0_dp
    contains
        procedure :: mass => pxy_mass
        procedure :: forces => pxy_forces
        procedure :: phi => pxy_phi
        procedure :: phi_jac => pxy_jac
        procedure :: phi_gamma => pxy_gamma
        procedure :: energy => pxy_energy
        procedure :: has_energy => pxy_has_energy
    end type pendulum_xy

    !> Two unit masses on a massless rod of length l, q = [x1, y1, x2, y2]; the velocity of
    !! the rod's centre stays along the rod (seed 000):
    !! (x2 - x1)(y1' + y2') - (y2 - y1)(x1' + x2') = 0.
    type, extends(constrained_system) :: rod_two_masses
        real(dp) :: g = 9.81_dp, l = 1.0_dp
    contains
        procedure :: mass => rod_mass
        procedure :: forces => rod_forces
        procedure :: phi => rod_phi
        procedure :: phi_jac => rod_jac
        procedure :: phi_gamma => rod_gamma
        procedure :: nh_matrix => rod_nh
        procedure :: nh_gamma => rod_nh_gamma
        procedure :: energy => rod_energy
        procedure :: has_energy => rod_has_energy
    end type rod_two_masses

    !> Double pendulum in Cartesian coordinates q = [x1, y1, x2, y2].
    type, extends(constrained_system) :: double_pendulum_xy
        real(dp) :: m1 = 1.0_dp, m2 = 1.0_dp, l1 = 1.0_dp, l2 = 1.0_dp, g = 9.81_dp
    contains
        procedure :: mass => dxy_mass
        procedure :: forces => dxy_forces
        procedure :: phi => dxy_phi
        procedure :: phi_jac => dxy_jac
        procedure :: phi_gamma => dxy_gamma
        procedure :: energy => dxy_energy
        procedure :: has_energy => dxy_has_energy
    end type double_pendulum_xy

    !> Atwood machine, q = [y1, y2] measured downward, string L = y1 + y2.
    type, extends(constrained_system) :: atwood_xy
        real(dp) :: m1 = 2.0_dp, m2 = 1.0_dp, g = 9.81_dp, len = 2.0_dp
    contains
        procedure :: mass => axy_mass
        procedure :: forces => axy_forces
        procedure :: phi => axy_phi
        procedure :: phi_jac => axy_jac
        procedure :: phi_gamma => axy_gamma
        procedure :: energy => axy_energy
        procedure :: has_energy => axy_has_energy
    end type atwood_xy

    !> Pendulum whose suspension point moves as (s(t), 0), s = a t^2/2 + b sin(w t)
    !! (rheonomic), q = [x, y].
    type, extends(constrained_system) :: pendulum_moving_xy
        real(dp) :: m = 1.0_dp, g = 9.81_dp, l = 1.0_dp
        real(dp) :: a = 0.0_dp, b = 0.1_dp, w = 3.0_dp
    contains
        procedure :: mass => pmx_mass
        procedure :: forces => pmx_forces
        procedure :: phi => pmx_phi
        procedure :: phi_jac => pmx_jac
        procedure :: phi_t => pmx_phi_t
        procedure :: phi_gamma => pmx_gamma
    end type pendulum_moving_xy

    !> Yo-yo, q = [y, psi] (centre height up, unwound angle), string end at
    !! y_h(t) = h0 + vh t + ah t^2/2: phi = y + r psi - y_h(t) (rheonomic); lambda = tension.
    type, extends(constrained_system) :: yoyo
        real(dp) :: m = 1.0_dp, r = 0.05_dp, i = 1.25e-3_dp, g = 9.81_dp
        real(dp) :: ah = 0.0_dp, vh = 0.0_dp, h0 = 0.0_dp
    contains
        procedure :: mass => yo_mass
        procedure :: forces => yo_forces
        procedure :: phi => yo_phi
        procedure :: phi_jac => yo_jac
        procedure :: phi_t => yo_phi_t
        procedure :: phi_gamma => yo_gamma
    end type yoyo

    !> Ice-skate blade / knife edge on a plane inclined at alpha (downhill = +x),
    !! q = [x, y, theta]: -sin(th) x' + cos(th) y' = 0.
    type, extends(constrained_system) :: skate
        real(dp) :: m = 1.0_dp, i = 1.0_dp, g = 9.81_dp, alpha = 0.3_dp
    contains
        procedure :: mass => sk_mass
        procedure :: forces => sk_forces
        procedure :: nh_matrix => sk_nh
        procedure :: nh_gamma => sk_nh_gamma
        procedure :: energy => sk_energy
        procedure :: has_energy => sk_has_energy
    end type skate

    !> Vertical rolling disk (coin), q = [x, y, theta, phi] (heading, rolling angle):
    !! x' = R phi' cos th, y' = R phi' sin th.
    type, extends(constrained_system) :: rolling_disk
        real(dp) :: m = 1.0_dp, r = 1.0_dp, i_roll = 0.5_dp, i_turn = 0.25_dp
    contains
        procedure :: mass => rd_mass
        procedure :: forces => rd_forces
        procedure :: nh_matrix => rd_nh
        procedure :: nh_gamma => rd_nh_gamma
        procedure :: energy => rd_energy
        procedure :: has_energy => rd_has_energy
    end type rolling_disk

contains

    ! ================================================================ pendulum_xy
    subroutine pxy_mass(self, t, q, mm)
        class(pendulum_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = 0.0_dp
        mm(1, 1) = self%m
        mm(2, 2) = self%m
    end subroutine pxy_mass
    subroutine pxy_forces(self, t, q, v, f)
        class(pendulum_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = [0.0_dp, -self%m*self%g]
    end subroutine pxy_forces
    subroutine pxy_phi(self, t, q, c)
        class(pendulum_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c(1) = 0.5_dp*(q(1)**2 + q(2)**2 - self%l**2)
    end subroutine pxy_phi
    subroutine pxy_jac(self, t, q, g)
        class(pendulum_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        g(1, :) = q(1:2)
    end subroutine pxy_jac
    subroutine pxy_gamma(self, t, q, v, gam)
        class(pendulum_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        gam(1) = -(v(1)**2 + v(2)**2)
    end subroutine pxy_gamma
    function pxy_energy(self, t, q, v) result(e)
        class(pendulum_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*self%m*sum(v**2) + self%m*self%g*q(2)
    end function pxy_energy
    logical function pxy_has_energy(self)
        class(pendulum_xy), intent(in) :: self
        pxy_has_energy = .true.
    end function pxy_has_energy

    ! ================================================================ rod_two_masses
    subroutine rod_mass(self, t, q, mm)
        class(rod_two_masses), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        integer :: i
        mm = 0.0_dp
        do i = 1, 4
            mm(i, i) = 1.0_dp
        end do
    end subroutine rod_mass
    subroutine rod_forces(self, t, q, v, f)
        class(rod_two_masses), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = [0.0_dp, -self%g, 0.0_dp, -self%g]
    end subroutine rod_forces
    subroutine rod_phi(self, t, q, c)
        class(rod_two_masses), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c(1) = 0.5_dp*((q(3) - q(1))**2 + (q(4) - q(2))**2 - self%l**2)
    end subroutine rod_phi
    subroutine rod_jac(self, t, q, g)
        class(rod_two_masses), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        g(1, :) = [q(1) - q(3), q(2) - q(4), q(3) - q(1), q(4) - q(2)]
    end subroutine rod_jac
    subroutine rod_gamma(self, t, q, v, gam)
        class(rod_two_masses), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        gam(1) = -((v(3) - v(1))**2 + (v(4) - v(2))**2)
    end subroutine rod_gamma
    subroutine rod_nh(self, t, q, a, b)
        class(rod_two_masses), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: a(:, :), b(:)
        real(dp) :: dx, dy
        dx = q(3) - q(1)
        dy = q(4) - q(2)
        a(1, :) = [-dy, dx, -dy, dx]
        b = 0.0_dp
    end subroutine rod_nh
    subroutine rod_nh_gamma(self, t, q, v, gam)
        class(rod_two_masses), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        gam(1) = -((v(3) - v(1))*(v(2) + v(4)) - (v(4) - v(2))*(v(1) + v(3)))
    end subroutine rod_nh_gamma
    function rod_energy(self, t, q, v) result(e)
        class(rod_two_masses), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*sum(v**2) + self%g*(q(2) + q(4))
    end function rod_energy
    logical function rod_has_energy(self)
        class(rod_two_masses), intent(in) :: self
        rod_has_energy = .true.
    end function rod_has_energy

    ! ================================================================ double_pendulum_xy
    subroutine dxy_mass(self, t, q, mm)
        class(double_pendulum_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = 0.0_dp
        mm(1, 1) = self%m1
        mm(2, 2) = self%m1
        mm(3, 3) = self%m2
        mm(4, 4) = self%m2
    end subroutine dxy_mass
    subroutine dxy_forces(self, t, q, v, f)
        class(double_pendulum_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = [0.0_dp, -self%m1*self%g, 0.0_dp, -self%m2*self%g]
    end subroutine dxy_forces
    subroutine dxy_phi(self, t, q, c)
        class(double_pendulum_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c(1) = 0.5_dp*(q(1)**2 + q(2)**2 - self%l1**2)
        c(2) = 0.5_dp*((q(3) - q(1))**2 + (q(4) - q(2))**2 - self%l2**2)
    end subroutine dxy_phi
    subroutine dxy_jac(self, t, q, g)
        class(double_pendulum_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        g(1, :) = [q(1), q(2), 0.0_dp, 0.0_dp]
        g(2, :) = [q(1) - q(3), q(2) - q(4), q(3) - q(1), q(4) - q(2)]
    end subroutine dxy_jac
    subroutine dxy_gamma(self, t, q, v, gam)
        class(double_pendulum_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        gam(1) = -(v(1)**2 + v(2)**2)
        gam(2) = -((v(3) - v(1))**2 + (v(4) - v(2))**2)
    end subroutine dxy_gamma
    function dxy_energy(self, t, q, v) result(e)
        class(double_pendulum_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*self%m1*sum(v(1:2)**2) + 0.5_dp*self%m2*sum(v(3:4)**2) &
            + self%g*(self%m1*q(2) + self%m2*q(4))
    end function dxy_energy
    logical function dxy_has_energy(self)
        class(double_pendulum_xy), intent(in) :: self
        dxy_has_energy = .true.
    end function dxy_has_energy

    ! ================================================================ atwood_xy
    subroutine axy_mass(self, t, q, mm)
        class(atwood_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = 0.0_dp
        mm(1, 1) = self%m1
        mm(2, 2) = self%m2
    end subroutine axy_mass
    subroutine axy_forces(self, t, q, v, f)
        class(atwood_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = [self%m1*self%g, self%m2*self%g]
    end subroutine axy_forces
    subroutine axy_phi(self, t, q, c)
        class(atwood_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c(1) = self%len - q(1) - q(2)
    end subroutine axy_phi
    subroutine axy_jac(self, t, q, g)
        class(atwood_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        g(1, :) = [-1.0_dp, -1.0_dp]
    end subroutine axy_jac
    subroutine axy_gamma(self, t, q, v, gam)
        class(atwood_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        gam = 0.0_dp
    end subroutine axy_gamma
    function axy_energy(self, t, q, v) result(e)
        class(atwood_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*(self%m1*v(1)**2 + self%m2*v(2)**2) - self%g*(self%m1*q(1) + self%m2*q(2))
    end function axy_energy
    logical function axy_has_energy(self)
        class(atwood_xy), intent(in) :: self
        axy_has_energy = .true.
    end function axy_has_energy

    ! ================================================================ pendulum_moving_xy
    subroutine pmx_mass(self, t, q, mm)
        class(pendulum_moving_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = 0.0_dp
        mm(1, 1) = self%m
        mm(2, 2) = self%m
    end subroutine pmx_mass
    subroutine pmx_forces(self, t, q, v, f)
        class(pendulum_moving_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = [0.0_dp, -self%m*self%g]
    end subroutine pmx_forces
    pure subroutine support(self, t, s, sd, sdd)
        class(pendulum_moving_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(out) :: s, sd, sdd
        s = 0.5_dp*self%a*t**2 + self%b*sin(self%w*t)
        sd = self%a*t + self%b*self%w*cos(self%w*t)
        sdd = self%a - self%b*self%w**2*sin(self%w*t)
    end subroutine support
    subroutine pmx_phi(self, t, q, c)
        class(pendulum_moving_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        real(dp) :: s, sd, sdd
        call support(self, t, s, sd, sdd)
        c(1) = 0.5_dp*((q(1) - s)**2 + q(2)**2 - self%l**2)
    end subroutine pmx_phi
    subroutine pmx_jac(self, t, q, g)
        class(pendulum_moving_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        real(dp) :: s, sd, sdd
        call support(self, t, s, sd, sdd)
        g(1, :) = [q(1) - s, q(2)]
    end subroutine pmx_jac
    subroutine pmx_phi_t(self, t, q, pt)
        class(pendulum_moving_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: pt(:)
        real(dp) :: s, sd, sdd
        call support(self, t, s, sd, sdd)
        pt(1) = -(q(1) - s)*sd
    end subroutine pmx_phi_t
    subroutine pmx_gamma(self, t, q, v, gam)
        class(pendulum_moving_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        real(dp) :: s, sd, sdd
        call support(self, t, s, sd, sdd)
        gam(1) = -((v(1) - sd)**2 + v(2)**2 - (q(1) - s)*sdd)
    end subroutine pmx_gamma

    ! ================================================================ yoyo
    subroutine yo_mass(self, t, q, mm)
        class(yoyo), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = 0.0_dp
        mm(1, 1) = self%m
        mm(2, 2) = self%i
    end subroutine yo_mass
    subroutine yo_forces(self, t, q, v, f)
        class(yoyo), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = [-self%m*self%g, 0.0_dp]
    end subroutine yo_forces
    subroutine yo_phi(self, t, q, c)
        class(yoyo), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c(1) = q(1) + self%r*q(2) - (self%h0 + self%vh*t + 0.5_dp*self%ah*t**2)
    end subroutine yo_phi
    subroutine yo_jac(self, t, q, g)
        class(yoyo), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        g(1, :) = [1.0_dp, self%r]
    end subroutine yo_jac
    subroutine yo_phi_t(self, t, q, pt)
        class(yoyo), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: pt(:)
        pt(1) = -(self%vh + self%ah*t)
    end subroutine yo_phi_t
    subroutine yo_gamma(self, t, q, v, gam)
        class(yoyo), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        gam(1) = self%ah
    end subroutine yo_gamma

    ! ================================================================ skate
    subroutine sk_mass(self, t, q, mm)
        class(skate), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = 0.0_dp
        mm(1, 1) = self%m
        mm(2, 2) = self%m
        mm(3, 3) = self%i
    end subroutine sk_mass
    subroutine sk_forces(self, t, q, v, f)
        class(skate), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = [self%m*self%g*sin(self%alpha), 0.0_dp, 0.0_dp]
    end subroutine sk_forces
    subroutine sk_nh(self, t, q, a, b)
        class(skate), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: a(:, :), b(:)
        a(1, :) = [-sin(q(3)), cos(q(3)), 0.0_dp]
        b = 0.0_dp
    end subroutine sk_nh
    subroutine sk_nh_gamma(self, t, q, v, gam)
        class(skate), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        gam(1) = v(3)*(cos(q(3))*v(1) + sin(q(3))*v(2))
    end subroutine sk_nh_gamma
    function sk_energy(self, t, q, v) result(e)
        class(skate), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*self%m*(v(1)**2 + v(2)**2) + 0.5_dp*self%i*v(3)**2 &
            - self%m*self%g*sin(self%alpha)*q(1)
    end function sk_energy
    logical function sk_has_energy(self)
        class(skate), intent(in) :: self
        sk_has_energy = .true.
    end function sk_has_energy

    ! ================================================================ rolling_disk
    subroutine rd_mass(self, t, q, mm)
        class(rolling_disk), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = 0.0_dp
        mm(1, 1) = self%m
        mm(2, 2) = self%m
        mm(3, 3) = self%i_turn
        mm(4, 4) = self%i_roll
    end subroutine rd_mass
    subroutine rd_forces(self, t, q, v, f)
        class(rolling_disk), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = 0.0_dp
    end subroutine rd_forces
    subroutine rd_nh(self, t, q, a, b)
        class(rolling_disk), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: a(:, :), b(:)
        a(1, :) = [1.0_dp, 0.0_dp, 0.0_dp, -self%r*cos(q(3))]
        a(2, :) = [0.0_dp, 1.0_dp, 0.0_dp, -self%r*sin(q(3))]
        b = 0.0_dp
    end subroutine rd_nh
    subroutine rd_nh_gamma(self, t, q, v, gam)
        class(rolling_disk), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        gam(1) = -self%r*sin(q(3))*v(3)*v(4)
        gam(2) = self%r*cos(q(3))*v(3)*v(4)
    end subroutine rd_nh_gamma
    function rd_energy(self, t, q, v) result(e)
        class(rolling_disk), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*(self%m*(v(1)**2 + v(2)**2) + self%i_turn*v(3)**2 + self%i_roll*v(4)**2)
    end function rd_energy
    logical function rd_has_energy(self)
        class(rolling_disk), intent(in) :: self
        rd_has_energy = .true.
    end function rd_has_energy

end module conmech_systems_constrained
