!> What the transverse construction needs to know about a system besides x' = f(x): the
!! normals of an invariant manifold the motion lies on (excessive coordinates), a conserved
!! energy, and an input matrix dF/du for control.
!!
!! The base type has none of them; extensions override what they have. The energy
!! gradient defaults to sixth-order central differences of `energy`,
!! g_j = (H(x+3h) - 9 H(x+2h) + 45 H(x+h) - 45 H(x-h) + 9 H(x-2h) - H(x-3h))/(60 h),
!! h = eps^(1/7) max(|x_j|, 1): error ~ h^6 + eps/h ~ 1e-14 relative, so that the energy
!! level used by the reduction is exact to well below the integration tolerance.
module conmech_transverse_model
    use conmech_kinds, only: dp
    implicit none
    private
    public :: transverse_model, fd_energy_gradient

    !> Invariants and inputs of a system for `transverse_build` (defaults: none).
    type :: transverse_model
        integer :: n_inputs = 0   !! number of inputs m of `input_matrix` (0: none)
    contains
        procedure :: n_normals => tm_n_normals
        procedure :: normals => tm_normals
        procedure :: manifold_residual => tm_manifold_residual
        procedure :: has_energy => tm_has_energy
        procedure :: energy => tm_energy
        procedure :: energy_gradient => tm_energy_gradient
        procedure :: input_matrix => tm_input_matrix
    end type transverse_model

contains

    !> Number of rows of `normals` (0: no invariant manifold).
    integer function tm_n_normals(self)
        class(transverse_model), intent(in) :: self
        tm_n_normals = 0
    end function tm_n_normals

    !> c(1:n_normals, :) = the normals (rows) of the invariant manifold at x.
    subroutine tm_normals(self, t, x, c)
        class(transverse_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        real(dp), intent(out) :: c(:, :)
        c = 0.0_dp
    end subroutine tm_normals

    !> How far x is from the invariant manifold (0 without one).
    real(dp) function tm_manifold_residual(self, t, x) result(r)
        class(transverse_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        r = 0.0_dp
    end function tm_manifold_residual

    logical function tm_has_energy(self)
        class(transverse_model), intent(in) :: self
        tm_has_energy = .false.
    end function tm_has_energy

    !> The energy H(x) (0 when there is none).
    real(dp) function tm_energy(self, t, x) result(e)
        class(transverse_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        e = 0.0_dp
    end function tm_energy

    !> grad H (default: `fd_energy_gradient`).
    subroutine tm_energy_gradient(self, t, x, g)
        class(transverse_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        real(dp), intent(out) :: g(:)
        call fd_energy_gradient(self, t, x, g)
    end subroutine tm_energy_gradient

    !> bx = dF/du at x (N x n_inputs); zero by default.
    subroutine tm_input_matrix(self, t, x, bx)
        class(transverse_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        real(dp), intent(out) :: bx(:, :)
        bx = 0.0_dp
    end subroutine tm_input_matrix

    !> Sixth-order central differences of self%energy (see the module notes).
    subroutine fd_energy_gradient(self, t, x, g)
        class(transverse_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        real(dp), intent(out) :: g(:)
        real(dp), parameter :: off(6) = [3.0_dp, 2.0_dp, 1.0_dp, -1.0_dp, -2.0_dp, -3.0_dp]
        real(dp), parameter :: wt(6) = [1.0_dp, -9.0_dp, 45.0_dp, -45.0_dp, 9.0_dp, -1.0_dp]
        real(dp) :: xp(size(x)), h
        integer :: j, i
        xp = x
        do j = 1, size(x)
            h = epsilon(1.0_dp)**(1.0_dp/7.0_dp)*max(abs(x(j)), 1.0_dp)
            g(j) = 0.0_dp
            do i = 1, 6
                xp(j) = x(j) + off(i)*h
                g(j) = g(j) + wt(i)*self%energy(t, xp)
            end do
            g(j) = g(j)/(60.0_dp*h)
            xp(j) = x(j)
        end do
    end subroutine fd_energy_gradient

end module conmech_transverse_model
