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
!!
!! Spatial motion (y = [r, r'], r in R^3: CR3BP, spatial Hill) has the same shape with the
!! symmetric potential Hessian H (packed Hxx, Hxy, Hxz, Hyy, Hyz, Hzz) in the rows below
!! the velocities and the Coriolis entries +-c in the x'-y' block: `spatial_frame_product`
!! and `spatial_frame_jacobian`.
module conmech_rotating_frame
    use conmech_kinds, only: dp
    implicit none
    private
    public :: rotating_frame_product, rotating_frame_jacobian
    public :: spatial_frame_product, spatial_frame_jacobian

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

    !> jx = J x for a 6 x k block x of spatial motion (packed Hessian h, Coriolis c): the
    !! velocity rows copied, H x_r + c [x_v2, -x_v1, 0] below.
    pure subroutine spatial_frame_product(k, h, c, x, jx)
        integer, intent(in) :: k
        real(dp), intent(in) :: h(6), c, x(6, k)
        real(dp), intent(out) :: jx(6, k)
        integer :: j
        do j = 1, k
            jx(1, j) = x(4, j)
            jx(2, j) = x(5, j)
            jx(3, j) = x(6, j)
            jx(4, j) = h(1)*x(1, j) + h(2)*x(2, j) + h(3)*x(3, j) + c*x(5, j)
            jx(5, j) = h(2)*x(1, j) + h(4)*x(2, j) + h(5)*x(3, j) - c*x(4, j)
            jx(6, j) = h(3)*x(1, j) + h(5)*x(2, j) + h(6)*x(3, j)
        end do
    end subroutine spatial_frame_product

    !> The dense 6 x 6 J of spatial motion (same entries).
    pure subroutine spatial_frame_jacobian(h, c, jac)
        real(dp), intent(in) :: h(6), c
        real(dp), intent(out) :: jac(6, 6)
        jac = 0.0_dp
        jac(1, 4) = 1.0_dp
        jac(2, 5) = 1.0_dp
        jac(3, 6) = 1.0_dp
        jac(4, 1:3) = [h(1), h(2), h(3)]
        jac(5, 1:3) = [h(2), h(4), h(5)]
        jac(6, 1:3) = [h(3), h(5), h(6)]
        jac(4, 5) = c
        jac(5, 4) = -c
    end subroutine spatial_frame_jacobian

end module conmech_rotating_frame
