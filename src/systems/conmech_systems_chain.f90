!> A chain of N Cartesian pendulums (point masses on massless rods): the scaling test of
!! the constrained solvers.
!!
!! q = [x1, y1, ..., xN, yN] (2N coordinates), mass m each, rods of length l, the first
!! hinged at the origin, gravity -y; N holonomic constraints
!! phi_i = ((x_i - x_{i-1})^2 + (y_i - y_{i-1})^2 - l^2)/2 (x_0 = y_0 = 0), so that
!! lambda_i is the tension of rod i over l. The mass is diagonal and row i of G has its
!! nonzeros in the columns 2i-3 .. 2i: the system declares `diagonal_mass` and
!! `jac_width` = 4, and the KKT solve and the projections cost O(N) (S is tridiagonal;
!! the windows give a detected bandwidth of 2, as rows 1 and 2 share their window).
module conmech_systems_chain
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_constrained_system, only: constrained_system
    use conmech_systems_constrained, only: constrained_with_energy
    use conmech_constrained_band, only: band_dense
    implicit none
    private
    public :: pendulum_chain_xy, chain_initial_state, make_pendulum_chain, pendulum_chain_state

    !> N links; set n = 2N, n_hol = N, diagonal_mass, jac_width = min(4, n) (or use
    !! conmech_systems_mech::make_constrained("pendulum_chain_xy", [N, m, l, g]), which
    !! calls make_pendulum_chain).
    type, extends(constrained_with_energy) :: pendulum_chain_xy
        real(dp) :: m = 1.0_dp
        real(dp) :: l = 1.0_dp
        real(dp) :: g = 9.81_dp
    contains
        procedure :: mass_diagonal => ch_mass_diagonal
        procedure :: forces => ch_forces
        procedure :: phi => ch_phi
        procedure :: phi_jac => ch_jac
        procedure :: phi_jac_band => ch_jac_band
        procedure :: phi_gamma => ch_gamma
        procedure :: energy => ch_energy
    end type pendulum_chain_xy

contains

    !> The number of links N from the registry's first parameter: a whole number in
    !! 1..100000, else 0.
    pure integer function links_of(p) result(nl)
        real(dp), intent(in) :: p(:)
        nl = 0
        if (p(1) >= 1.0_dp .and. p(1) <= 1.0e5_dp .and. p(1) == aint(p(1))) nl = nint(p(1))
    end function links_of

    !> `sys`: a chain with the registry's parameters p = [N, m, l, g] and its structure
    !! declared (n = 2N, n_hol = N, diagonal mass, row windows of width 4); CM_BAD_INPUT
    !! unless N is a whole number in 1..100000.
    subroutine make_pendulum_chain(p, sys, info, msg)
        real(dp), intent(in) :: p(:)
        class(constrained_system), allocatable, intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(pendulum_chain_xy) :: s
        integer :: nl
        nl = links_of(p)
        if (nl == 0) then
            info = CM_BAD_INPUT
            msg = "bad input: pendulum_chain_xy needs a whole number of links N " &
                  //"(1 <= N <= 100000) as its first parameter"
            return
        end if
        info = CM_SUCCESS
        msg = "success"
        s%m = p(2); s%l = p(3); s%g = p(4)
        s%n = 2*nl; s%n_hol = nl
        s%diagonal_mass = .true.
        s%jac_width = min(4, s%n)
        allocate (sys, source=s)
    end subroutine make_pendulum_chain

    !> The registry's default initial state of the chain with the parameters p = [N, m, l, g]
    !! (chain_initial_state); CM_BAD_INPUT unless N is a whole number in 1..100000.
    subroutine pendulum_chain_state(p, q0, v0, info)
        real(dp), intent(in) :: p(:)
        real(dp), allocatable, intent(out) :: q0(:), v0(:)
        integer, intent(out) :: info
        integer :: nl
        nl = links_of(p)
        if (nl == 0) then
            info = CM_BAD_INPUT
            allocate (q0(0), v0(0))
            return
        end if
        info = CM_SUCCESS
        call chain_initial_state(nl, p(3), q0, v0)
    end subroutine pendulum_chain_state

    !> A consistent initial state of N links: link i at the angle 1 - 0.5 (i-1)/N from the
    !! downward vertical, at rest.
    subroutine chain_initial_state(nlinks, l, q0, v0)
        integer, intent(in) :: nlinks
        real(dp), intent(in) :: l
        real(dp), allocatable, intent(out) :: q0(:), v0(:)
        real(dp) :: x, y, th
        integer :: i
        allocate (q0(2*nlinks), v0(2*nlinks))
        x = 0.0_dp
        y = 0.0_dp
        do i = 1, nlinks
            th = 1.0_dp - 0.5_dp*real(i - 1, dp)/real(nlinks, dp)
            x = x + l*sin(th)
            y = y - l*cos(th)
            q0(2*i - 1) = x
            q0(2*i) = y
        end do
        v0 = 0.0_dp
    end subroutine chain_initial_state

    subroutine ch_mass_diagonal(self, t, q, d)
        class(pendulum_chain_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: d(:)
        d = self%m
    end subroutine ch_mass_diagonal

    subroutine ch_forces(self, t, q, v, f)
        class(pendulum_chain_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f(1::2) = 0.0_dp
        f(2::2) = -self%m*self%g
    end subroutine ch_forces

    !> Link vectors: d(:, i) = p_i - p_{i-1} of q (or of v for velocities).
    pure subroutine links(q, dx, dy)
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: dx(:), dy(:)
        integer :: nl
        nl = size(q)/2
        dx(1) = q(1)
        dy(1) = q(2)
        dx(2:nl) = q(3::2) - q(1:2*nl - 3:2)
        dy(2:nl) = q(4::2) - q(2:2*nl - 2:2)
    end subroutine links

    subroutine ch_phi(self, t, q, c)
        class(pendulum_chain_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        real(dp) :: dx(size(q)/2), dy(size(q)/2)
        call links(q, dx, dy)
        c = 0.5_dp*(dx**2 + dy**2 - self%l**2)
    end subroutine ch_phi

    subroutine ch_jac(self, t, q, g)
        class(pendulum_chain_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        real(dp) :: gb(size(q)/2, min(4, size(q)))
        integer :: first(size(q)/2)
        call ch_jac_band(self, t, q, gb, first)
        call band_dense(gb, first, g)
    end subroutine ch_jac

    !> Row i: columns 2i-3 .. 2i hold [-dx_i, -dy_i, dx_i, dy_i] (row 1: [dx_1, dy_1, 0, 0]
    !! from column 1).
    subroutine ch_jac_band(self, t, q, gb, first)
        class(pendulum_chain_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: gb(:, :)
        integer, intent(out) :: first(:)
        real(dp) :: dx(size(q)/2), dy(size(q)/2)
        integer :: i, nl
        nl = size(q)/2
        call links(q, dx, dy)
        gb = 0.0_dp
        first(1) = 1
        gb(1, 1) = dx(1)
        gb(1, 2) = dy(1)
        do i = 2, nl
            first(i) = 2*i - 3
            gb(i, :) = [-dx(i), -dy(i), dx(i), dy(i)]
        end do
    end subroutine ch_jac_band

    subroutine ch_gamma(self, t, q, v, gam)
        class(pendulum_chain_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        real(dp) :: du(size(v)/2), dw(size(v)/2)
        call links(v, du, dw)
        gam = -(du**2 + dw**2)
    end subroutine ch_gamma

    function ch_energy(self, t, q, v) result(e)
        class(pendulum_chain_xy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.5_dp*self%m*sum(v**2) + self%m*self%g*sum(q(2::2))
    end function ch_energy

end module conmech_systems_chain
