!> Built-in seed systems in generalized coordinates, M(t, q) q'' = Q(t, q, q').
!!
!! Angles of pendulums are measured from the downward vertical, except the pendulum on a
!! cart, which follows seed 000 (theta from the upward vertical, M = m = l = 1 gives
!! 2 x'' + cos(th) th'' - sin(th) th'^2 = 0, cos(th) x'' + th'' - g sin(th) = 0).
!! The Atwood machine follows seed 001 (y measured downward, y1 + y2 = L).
module conmech_systems_generalized
    use conmech_kinds, only: dp
    use conmech_generalized, only: generalized_system
    implicit none
    private

    public :: gen_pendulum, cart_pendulum, gen_double_pendulum, gen_atwood
    public :: spring_pendulum, double_spring_pendulum, three_springs, bead_hoop
    public :: polar_particle, gen_pendulum_moving, gen_yoyo

    !> Pendulum, q = [theta]: m l^2 th'' = -m g l sin th.
    type, extends(generalized_system) :: gen_pendulum
        real(dp) :: m = 1.0_dp, g = 9.81_dp, l = 1.0_dp
    contains
        procedure :: mass => gp_mass
        procedure :: forces => gp_forces
        procedure :: energy => gp_energy
        procedure :: has_energy => yes_energy_gp
    end type gen_pendulum

    !> Pendulum on a cart, q = [x, theta] (theta from upright), cart mass mc, bob m.
    type, extends(generalized_system) :: cart_pendulum
        real(dp) :: mc = 1.0_dp, m = 1.0_dp, l = 1.0_dp, g = 9.81_dp
    contains
        procedure :: mass => cp_mass
        procedure :: forces => cp_forces
        procedure :: energy => cp_energy
        procedure :: has_energy => yes_energy_cp
    end type cart_pendulum

    !> Double pendulum, q = [theta1, theta2] (absolute angles from downward).
    type, extends(generalized_system) :: gen_double_pendulum
        real(dp) :: m1 = 1.0_dp, m2 = 1.0_dp, l1 = 1.0_dp, l2 = 1.0_dp, g = 9.81_dp
    contains
        procedure :: mass => dp_mass
        procedure :: forces => dp_forces
        procedure :: energy => dp_energy
        procedure :: has_energy => yes_energy_dp
        procedure :: forces_jacobian => dp_forces_jacobian
        procedure :: has_forces_jacobian => yes_forces_jacobian_dp
    end type gen_double_pendulum

    !> Atwood machine, q = [y1] (downward): (m1 + m2) y1'' = (m1 - m2) g.
    type, extends(generalized_system) :: gen_atwood
        real(dp) :: m1 = 2.0_dp, m2 = 1.0_dp, g = 9.81_dp
    contains
        procedure :: mass => at_mass
        procedure :: forces => at_forces
    end type gen_atwood

    !> Spring pendulum (polar), q = [r, theta].
    type, extends(generalized_system) :: spring_pendulum
        real(dp) :: m = 1.0_dp, k = 40.0_dp, l0 = 1.0_dp, g = 9.81_dp
    contains
        procedure :: mass => sp_mass
        procedure :: forces => sp_forces
        procedure :: energy => sp_energy
        procedure :: has_energy => yes_energy_sp
    end type spring_pendulum

    !> Double spring pendulum in Cartesian coordinates q = [x1, y1, x2, y2]:
    !! spring k1 (rest l1) from the origin to mass 1, spring k2 (rest l2) from 1 to 2.
    type, extends(generalized_system) :: double_spring_pendulum
        real(dp) :: m1 = 1.0_dp, m2 = 1.0_dp, k1 = 40.0_dp, k2 = 40.0_dp
        real(dp) :: l1 = 1.0_dp, l2 = 1.0_dp, g = 9.81_dp
    contains
        procedure :: mass => dsp_mass
        procedure :: forces => dsp_forces
        procedure :: energy => dsp_energy
        procedure :: has_energy => yes_energy_dsp
    end type double_spring_pendulum

    !> Three equal masses joined pairwise by springs (k, rest l0), in the plane,
    !! q = [x1, y1, x2, y2, x3, y3], no gravity.
    type, extends(generalized_system) :: three_springs
        real(dp) :: m = 1.0_dp, k = 10.0_dp, l0 = 1.0_dp
    contains
        procedure :: mass => ts_mass
        procedure :: forces => ts_forces
        procedure :: energy => ts_energy
        procedure :: has_energy => yes_energy_ts
    end type three_springs

    !> Bead on a hoop of radius R spinning at omega: th'' = (omega^2 cos th - g/R) sin th.
    !! `energy` is the conserved Jacobi integral m R^2 (th'^2 - omega^2 sin^2 th)/2 - m g R cos th.
    type, extends(generalized_system) :: bead_hoop
        real(dp) :: m = 1.0_dp, r = 1.0_dp, omega = 5.0_dp, g = 9.81_dp
    contains
        procedure :: mass => bh_mass
        procedure :: forces => bh_forces
        procedure :: energy => bh_energy
        procedure :: has_energy => yes_energy_bh
    end type bead_hoop

    !> Particle in the plane in polar coordinates q = [r, theta], U = -m mu / r.
    type, extends(generalized_system) :: polar_particle
        real(dp) :: m = 1.0_dp, mu = 1.0_dp
    contains
        procedure :: mass => pp_mass
        procedure :: forces => pp_forces
        procedure :: energy => pp_energy
        procedure :: has_energy => yes_energy_pp
    end type polar_particle

    !> Pendulum with a suspension point moving horizontally, s(t) = a t^2/2 + b sin(w t):
    !! l th'' + g sin th + s''(t) cos th = 0 (rheonomic), q = [theta].
    type, extends(generalized_system) :: gen_pendulum_moving
        real(dp) :: m = 1.0_dp, g = 9.81_dp, l = 1.0_dp
        real(dp) :: a = 0.0_dp, b = 0.1_dp, w = 3.0_dp
    contains
        procedure :: mass => pm_mass
        procedure :: forces => pm_forces
    end type gen_pendulum_moving

    !> Yo-yo (disk m, radius r, inertia i) unwinding from a string whose end moves as
    !! y_h(t) = h0 + vh t + ah t^2/2; q = [y] (centre height, up):
    !! (m + i/r^2) y'' = -m g + (i/r^2) ah.
    type, extends(generalized_system) :: gen_yoyo
        real(dp) :: m = 1.0_dp, r = 0.05_dp, i = 1.25e-3_dp, g = 9.81_dp
        real(dp) :: ah = 0.0_dp, vh = 0.0_dp, h0 = 0.0_dp
    contains
        procedure :: mass => yy_mass
        procedure :: forces => yy_forces
    end type gen_yoyo

contains

    logical function yes_energy_gp(self)
        class(gen_pendulum), intent(in) :: self
        yes_energy_gp = .true.
    end function yes_energy_gp
    logical function yes_energy_cp(self)
        class(cart_pendulum), intent(in) :: self
        yes_energy_cp = .true.
    end function yes_energy_cp
    logical function yes_energy_dp(self)
        class(gen_double_pendulum), intent(in) :: self
        yes_energy_dp = .true.
    end function yes_energy_dp
    logical function yes_energy_sp(self)
        class(spring_pendulum), intent(in) :: self
        yes_energy_sp = .true.
    end function yes_energy_sp
    logical function yes_energy_dsp(self)
        class(double_spring_pendulum), intent(in) :: self
        yes_energy_dsp = .true.
    end function yes_energy_dsp
    logical function yes_energy_ts(self)
        class(three_springs), intent(in) :: self
        yes_energy_ts = .true.
    end function yes_energy_ts
    logical function yes_energy_bh(self)
        class(bead_hoop), intent(in) :: self
        yes_energy_bh = .true.
    end function yes_energy_bh
    logical function yes_energy_pp(self)
        class(polar_particle), intent(in) :: self
        yes_energy_pp = .true.
    end function yes_energy_pp

    ! ---------------------------------------------------------------- pendulum
    subroutine gp_mass(self, t, q, mm)
        class(gen_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm(1, 1) = self%m*self%l**2
    end subroutine gp_mass
    subroutine gp_forces(self, t, q, v, f)
        class(gen_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f(1) = -self%m*self%g*self%l*sin(q(1))
    end subroutine gp_forces
    function gp_energy(self, t, q, v) result(e)
        class(gen_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*self%m*self%l**2*v(1)**2 - self%m*self%g*self%l*cos(q(1))
    end function gp_energy

    ! ---------------------------------------------------------------- cart pendulum
    subroutine cp_mass(self, t, q, mm)
        class(cart_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm(1, 1) = self%mc + self%m
        mm(1, 2) = self%m*self%l*cos(q(2))
        mm(2, 1) = mm(1, 2)
        mm(2, 2) = self%m*self%l**2
    end subroutine cp_mass
    subroutine cp_forces(self, t, q, v, f)
        class(cart_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f(1) = self%m*self%l*sin(q(2))*v(2)**2
        f(2) = self%m*self%g*self%l*sin(q(2))
    end subroutine cp_forces
    function cp_energy(self, t, q, v) result(e)
        class(cart_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*((self%mc + self%m)*v(1)**2 + 2.0_dp*self%m*self%l*cos(q(2))*v(1)*v(2) &
                    + self%m*self%l**2*v(2)**2) + self%m*self%g*self%l*cos(q(2))
    end function cp_energy

    ! ---------------------------------------------------------------- double pendulum
    !> Exact r = [dQ/dq - d(M a)/dq, dQ/dv]: the variational equations (monodromy,
    !! transverse linearisation) then need no difference quotients (~1e-10 accurate).
    subroutine dp_forces_jacobian(self, t, q, v, a, r)
        class(gen_double_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:), a(:)
        real(dp), intent(out) :: r(:, :)
        real(dp) :: k, s, c
        k = self%m2*self%l1*self%l2
        s = sin(q(1) - q(2))
        c = cos(q(1) - q(2))
        r(1, 1) = -k*c*v(2)**2 - (self%m1 + self%m2)*self%g*self%l1*cos(q(1)) + k*s*a(2)
        r(1, 2) = k*c*v(2)**2 - k*s*a(2)
        r(2, 1) = k*c*v(1)**2 + k*s*a(1)
        r(2, 2) = -k*c*v(1)**2 - self%m2*self%g*self%l2*cos(q(2)) - k*s*a(1)
        r(1, 3) = 0.0_dp
        r(1, 4) = -2.0_dp*k*s*v(2)
        r(2, 3) = 2.0_dp*k*s*v(1)
        r(2, 4) = 0.0_dp
    end subroutine dp_forces_jacobian
    logical function yes_forces_jacobian_dp(self)
        class(gen_double_pendulum), intent(in) :: self
        yes_forces_jacobian_dp = .true.
    end function yes_forces_jacobian_dp

    subroutine dp_mass(self, t, q, mm)
        class(gen_double_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm(1, 1) = (self%m1 + self%m2)*self%l1**2
        mm(1, 2) = self%m2*self%l1*self%l2*cos(q(1) - q(2))
        mm(2, 1) = mm(1, 2)
        mm(2, 2) = self%m2*self%l2**2
    end subroutine dp_mass
    subroutine dp_forces(self, t, q, v, f)
        class(gen_double_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        real(dp) :: s12
        s12 = sin(q(1) - q(2))
        f(1) = -self%m2*self%l1*self%l2*s12*v(2)**2 - (self%m1 + self%m2)*self%g*self%l1*sin(q(1))
        f(2) = self%m2*self%l1*self%l2*s12*v(1)**2 - self%m2*self%g*self%l2*sin(q(2))
    end subroutine dp_forces
    function dp_energy(self, t, q, v) result(e)
        class(gen_double_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*(self%m1 + self%m2)*self%l1**2*v(1)**2 + 0.5_dp*self%m2*self%l2**2*v(2)**2 &
            + self%m2*self%l1*self%l2*cos(q(1) - q(2))*v(1)*v(2) &
            - (self%m1 + self%m2)*self%g*self%l1*cos(q(1)) - self%m2*self%g*self%l2*cos(q(2))
    end function dp_energy

    ! ---------------------------------------------------------------- Atwood
    subroutine at_mass(self, t, q, mm)
        class(gen_atwood), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm(1, 1) = self%m1 + self%m2
    end subroutine at_mass
    subroutine at_forces(self, t, q, v, f)
        class(gen_atwood), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f(1) = (self%m1 - self%m2)*self%g
    end subroutine at_forces

    ! ---------------------------------------------------------------- spring pendulum
    subroutine sp_mass(self, t, q, mm)
        class(spring_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = 0.0_dp
        mm(1, 1) = self%m
        mm(2, 2) = self%m*q(1)**2
    end subroutine sp_mass
    subroutine sp_forces(self, t, q, v, f)
        class(spring_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f(1) = self%m*q(1)*v(2)**2 + self%m*self%g*cos(q(2)) - self%k*(q(1) - self%l0)
        f(2) = -2.0_dp*self%m*q(1)*v(1)*v(2) - self%m*self%g*q(1)*sin(q(2))
    end subroutine sp_forces
    function sp_energy(self, t, q, v) result(e)
        class(spring_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*self%m*(v(1)**2 + q(1)**2*v(2)**2) - self%m*self%g*q(1)*cos(q(2)) &
            + 0.5_dp*self%k*(q(1) - self%l0)**2
    end function sp_energy

    ! ---------------------------------------------------------------- double spring pendulum
    subroutine dsp_mass(self, t, q, mm)
        class(double_spring_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = 0.0_dp
        mm(1, 1) = self%m1
        mm(2, 2) = self%m1
        mm(3, 3) = self%m2
        mm(4, 4) = self%m2
    end subroutine dsp_mass
    subroutine dsp_forces(self, t, q, v, f)
        class(double_spring_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        real(dp) :: r1, r2, f1(2), f2(2)
        r1 = norm2(q(1:2))
        r2 = norm2(q(3:4) - q(1:2))
        f1 = -self%k1*(r1 - self%l1)*q(1:2)/r1            ! on mass 1 from spring 1
        f2 = -self%k2*(r2 - self%l2)*(q(3:4) - q(1:2))/r2  ! on mass 2 from spring 2
        f(1:2) = f1 - f2
        f(3:4) = f2
        f(2) = f(2) - self%m1*self%g
        f(4) = f(4) - self%m2*self%g
    end subroutine dsp_forces
    function dsp_energy(self, t, q, v) result(e)
        class(double_spring_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*self%m1*sum(v(1:2)**2) + 0.5_dp*self%m2*sum(v(3:4)**2) &
            + self%m1*self%g*q(2) + self%m2*self%g*q(4) &
            + 0.5_dp*self%k1*(norm2(q(1:2)) - self%l1)**2 &
            + 0.5_dp*self%k2*(norm2(q(3:4) - q(1:2)) - self%l2)**2
    end function dsp_energy

    ! ---------------------------------------------------------------- three springs
    subroutine ts_mass(self, t, q, mm)
        class(three_springs), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        integer :: i
        mm = 0.0_dp
        do i = 1, 6
            mm(i, i) = self%m
        end do
    end subroutine ts_mass
    subroutine ts_forces(self, t, q, v, f)
        class(three_springs), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        integer :: i, j
        real(dp) :: d(2), r, fij(2)
        f = 0.0_dp
        do i = 1, 2
            do j = i + 1, 3
                d = q(2*j - 1:2*j) - q(2*i - 1:2*i)
                r = norm2(d)
                fij = self%k*(r - self%l0)*d/r          ! on i, towards j when stretched
                f(2*i - 1:2*i) = f(2*i - 1:2*i) + fij
                f(2*j - 1:2*j) = f(2*j - 1:2*j) - fij
            end do
        end do
    end subroutine ts_forces
    function ts_energy(self, t, q, v) result(e)
        class(three_springs), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        integer :: i, j
        e = 0.5_dp*self%m*sum(v**2)
        do i = 1, 2
            do j = i + 1, 3
                e = e + 0.5_dp*self%k*(norm2(q(2*j - 1:2*j) - q(2*i - 1:2*i)) - self%l0)**2
            end do
        end do
    end function ts_energy

    ! ---------------------------------------------------------------- bead on a hoop
    subroutine bh_mass(self, t, q, mm)
        class(bead_hoop), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm(1, 1) = self%m*self%r**2
    end subroutine bh_mass
    subroutine bh_forces(self, t, q, v, f)
        class(bead_hoop), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f(1) = self%m*self%r**2*(self%omega**2*cos(q(1)) - self%g/self%r)*sin(q(1))
    end subroutine bh_forces
    function bh_energy(self, t, q, v) result(e)
        class(bead_hoop), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*self%m*self%r**2*(v(1)**2 - self%omega**2*sin(q(1))**2) &
            - self%m*self%g*self%r*cos(q(1))
    end function bh_energy

    ! ---------------------------------------------------------------- polar particle
    subroutine pp_mass(self, t, q, mm)
        class(polar_particle), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = 0.0_dp
        mm(1, 1) = self%m
        mm(2, 2) = self%m*q(1)**2
    end subroutine pp_mass
    subroutine pp_forces(self, t, q, v, f)
        class(polar_particle), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f(1) = self%m*q(1)*v(2)**2 - self%m*self%mu/q(1)**2
        f(2) = -2.0_dp*self%m*q(1)*v(1)*v(2)
    end subroutine pp_forces
    function pp_energy(self, t, q, v) result(e)
        class(polar_particle), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*self%m*(v(1)**2 + q(1)**2*v(2)**2) - self%m*self%mu/q(1)
    end function pp_energy

    ! ---------------------------------------------------------------- moving suspension
    subroutine pm_mass(self, t, q, mm)
        class(gen_pendulum_moving), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm(1, 1) = self%m*self%l**2
    end subroutine pm_mass
    subroutine pm_forces(self, t, q, v, f)
        class(gen_pendulum_moving), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        real(dp) :: sdd
        sdd = self%a - self%b*self%w**2*sin(self%w*t)
        f(1) = -self%m*self%l*(self%g*sin(q(1)) + sdd*cos(q(1)))
    end subroutine pm_forces

    ! ---------------------------------------------------------------- yo-yo
    subroutine yy_mass(self, t, q, mm)
        class(gen_yoyo), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm(1, 1) = self%m + self%i/self%r**2
    end subroutine yy_mass
    subroutine yy_forces(self, t, q, v, f)
        class(gen_yoyo), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f(1) = -self%m*self%g + self%i/self%r**2*self%ah
    end subroutine yy_forces

end module conmech_systems_generalized
