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
!! additions per column instead of a dense 4 x 4 product. The loop is written once
!! (conmech_rotating_frame_product.inc): `rotating_frame_product` includes it for any k,
!! and a built-in's `rhs_jacobian_product` includes it for k = 4 (the STM), where the
!! compiler unrolls it and no call is made.
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
        include "conmech_rotating_frame_product.inc"
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
