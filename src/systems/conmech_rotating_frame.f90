!> The Jacobian product of planar motion in a rotating frame (restricted three-body
!! problem, Hill's problem): for y = [x, y, x', y'] with x'' = U_x + c y',
!! y'' = U_y - c x',
!!
!!     J = [ 0    0    1  0 ]
!!         [ 0    0    0  1 ]
!!         [ Uxx  Uxy  0  c ]
!!         [ Uxy  Uyy -c  0 ],
!!
!! so J x copies two rows and folds the constant entries: 6 multiplications and 4
!! additions per column instead of a dense 4 x 4 product. Written once, used by the
!! built-ins' `jacobian_product` / `rhs_jacobian_product` and their dense `jacobian`.
module conmech_rotating_frame
    use conmech_kinds, only: dp
    implicit none
    private
    public :: rotating_frame_product, rotating_frame_jacobian

contains

    !> jx = J x for a 4 x k block x, J as above (Hessian entries uxx, uxy, uyy, Coriolis c).
    pure subroutine rotating_frame_product(k, uxx, uxy, uyy, c, x, jx)
        integer, intent(in) :: k
        real(dp), intent(in) :: uxx, uxy, uyy, c
        real(dp), intent(in) :: x(4, k)
        real(dp), intent(out) :: jx(4, k)
        integer :: j
        do j = 1, k
            jx(1, j) = x(3, j)
            jx(2, j) = x(4, j)
            jx(3, j) = uxx*x(1, j) + uxy*x(2, j) + c*x(4, j)
            jx(4, j) = uxy*x(1, j) + uyy*x(2, j) - c*x(3, j)
        end do
    end subroutine rotating_frame_product

    !> The dense 4 x 4 J (same entries).
    pure subroutine rotating_frame_jacobian(uxx, uxy, uyy, c, jac)
        real(dp), intent(in) :: uxx, uxy, uyy, c
        real(dp), intent(out) :: jac(4, 4)
        jac = 0.0_dp
        jac(1, 3) = 1.0_dp
        jac(2, 4) = 1.0_dp
        jac(3, 1) = uxx
        jac(3, 2) = uxy
        jac(4, 1) = uxy
        jac(4, 2) = uyy
        jac(3, 4) = c
        jac(4, 3) = -c
    end subroutine rotating_frame_jacobian

end module conmech_rotating_frame
