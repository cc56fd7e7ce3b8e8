!> An N-trailer: the scaling test of constrained systems with Pfaffian constraints.
!!
!! N points in the plane, q = [x1, y1, ..., xN, yN], mass m each; the first is pulled by
!! a rotating force f (cos w t, sin w t) (the train winds along a curve); rods of length
!! l join consecutive points (N - 1 holonomic constraints
!! phi_i = (|p_i - p_{i-1}|^2 - l^2)/2, i = 2..N) and each point i >= 2 rides on a knife
!! edge along its rod: perp(p_i - p_{i-1}) . v_i = 0 (N - 1 Pfaffian
!! constraints, b = 0). Row i of G has its nonzeros in the columns 2i-3 .. 2i (width 4),
!! row i of A in 2i-1 .. 2i (width 2): the system declares `diagonal_mass`, `jac_width`
!! = 4 and `nh_width` = 2, the rows of G and A interleave along the chain, and the
!! banded KKT path costs O(N) per evaluation. No energy is conserved (the force works).
!! Set n = 2N, n_hol = n_nh = N - 1 and the flags, or use `trailer_chain_of(N)`.
module conmech_systems_trailer
    use conmech_kinds, only: dp
    use conmech_systems_constrained, only: constrained_diagonal_mass
    use conmech_constrained_band, only: band_dense
    implicit none
    private
    public :: trailer_chain, trailer_chain_of, trailer_initial_state

    !> N points in the plane (n = 2N), the first pulled by a rotating force: rods between
    !! consecutive points (N - 1 holonomic rows, windows of width 4) and a knife edge at
    !! each point i >= 2 along its link, perp(p_i - p_{i-1}) . v_i = 0 (N - 1 Pfaffian
    !! rows, windows of width 2): an N-trailer. Rows of G and A interleave along the chain.
    type, extends(constrained_diagonal_mass) :: trailer_chain
        real(dp) :: m = 1.0_dp       !! mass of each point
        real(dp) :: l = 1.0_dp       !! length of each rod
        real(dp) :: f = 1.0_dp       !! magnitude of the force on the first point
        real(dp) :: w = 1.0_dp       !! its angular rate: direction (cos w t, sin w t)
    contains
        procedure :: mass_diagonal => tr_mass_diagonal
        procedure :: forces => tr_forces
        procedure :: phi => tr_phi
        procedure :: phi_jac => tr_jac
        procedure :: phi_jac_band => tr_jac_band
        procedure :: phi_gamma => tr_gamma
        procedure :: nh_matrix => tr_nh
        procedure :: nh_matrix_band => tr_nh_band
        procedure :: nh_gamma => tr_nh_gamma
    end type trailer_chain

contains

    !> An N-trailer with its structure declared (N >= 2).
    function trailer_chain_of(nl) result(s)
        integer, intent(in) :: nl
        type(trailer_chain) :: s
        s%n = 2*max(nl, 2)
        s%n_hol = max(nl, 2) - 1
        s%n_nh = max(nl, 2) - 1
        s%diagonal_mass = .true.
        s%constant_mass = .true.
        s%jac_width = 4
        s%nh_width = 2
    end function trailer_chain_of

    !> A consistent state of N points: a straight line of rods of length l at the angle
    !! 0.3 from the x axis, every point moving along it with unit speed (consistent with
    !! the rods and the knife edges).
    subroutine trailer_initial_state(nl, l, q0, v0)
        integer, intent(in) :: nl
        real(dp), intent(in) :: l
        real(dp), allocatable, intent(out) :: q0(:), v0(:)
        real(dp), parameter :: ang = 0.3_dp
        integer :: i
        allocate (q0(2*nl), v0(2*nl))
        do i = 1, nl
            q0(2*i - 1) = -real(i - 1, dp)*l*cos(ang)
            q0(2*i) = -real(i - 1, dp)*l*sin(ang)
            v0(2*i - 1) = cos(ang)
            v0(2*i) = sin(ang)
        end do
    end subroutine trailer_initial_state

    subroutine tr_mass_diagonal(self, t, q, d)
        class(trailer_chain), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: d(:)
        d = self%m
    end subroutine tr_mass_diagonal
    subroutine tr_forces(self, t, q, v, f)
        class(trailer_chain), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = 0.0_dp
        f(1) = self%f*cos(self%w*t)
        f(2) = self%f*sin(self%w*t)
    end subroutine tr_forces
    subroutine tr_phi(self, t, q, c)
        class(trailer_chain), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        integer :: i
        do i = 2, size(q)/2
            c(i - 1) = 0.5_dp*((q(2*i - 1) - q(2*i - 3))**2 + (q(2*i) - q(2*i - 2))**2 - self%l**2)
        end do
    end subroutine tr_phi
    subroutine tr_jac_band(self, t, q, gb, first)
        class(trailer_chain), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: gb(:, :)
        integer, intent(out) :: first(:)
        real(dp) :: dx, dy
        integer :: i
        do i = 2, size(q)/2
            dx = q(2*i - 1) - q(2*i - 3)
            dy = q(2*i) - q(2*i - 2)
            first(i - 1) = 2*i - 3
            gb(i - 1, :) = [-dx, -dy, dx, dy]
        end do
    end subroutine tr_jac_band
    subroutine tr_jac(self, t, q, g)
        class(trailer_chain), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        real(dp) :: gb(self%n_hol, 4)
        integer :: first(self%n_hol)
        call tr_jac_band(self, t, q, gb, first)
        call band_dense(gb, first, g)
    end subroutine tr_jac
    subroutine tr_gamma(self, t, q, v, gam)
        class(trailer_chain), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        integer :: i
        do i = 2, size(q)/2
            gam(i - 1) = -((v(2*i - 1) - v(2*i - 3))**2 + (v(2*i) - v(2*i - 2))**2)
        end do
    end subroutine tr_gamma
    subroutine tr_nh_band(self, t, q, ab, b, first)
        class(trailer_chain), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: ab(:, :), b(:)
        integer, intent(out) :: first(:)
        integer :: i
        do i = 2, size(q)/2
            first(i - 1) = 2*i - 1
            ab(i - 1, :) = [-(q(2*i) - q(2*i - 2)), q(2*i - 1) - q(2*i - 3)]
        end do
        b = 0.0_dp
    end subroutine tr_nh_band
    subroutine tr_nh(self, t, q, a, b)
        class(trailer_chain), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: a(:, :), b(:)
        real(dp) :: ab(self%n_nh, 2)
        integer :: first(self%n_nh)
        call tr_nh_band(self, t, q, ab, b, first)
        call band_dense(ab, first, a)
    end subroutine tr_nh
    !> gamma_n = -(dA/dt) v: d/dt of perp(p_i - p_{i-1}) . v_i with v fixed.
    subroutine tr_nh_gamma(self, t, q, v, gam)
        class(trailer_chain), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        integer :: i
        do i = 2, size(q)/2
            gam(i - 1) = (v(2*i) - v(2*i - 2))*v(2*i - 1) - (v(2*i - 1) - v(2*i - 3))*v(2*i)
        end do
    end subroutine tr_nh_gamma

end module conmech_systems_trailer
