!> Support of the flat f2py layer for the transverse linearisation (compiled, not wrapped):
!! a planar natural system whose potential is a Python callback pot(q, v, g, h).
module conmech_support_transverse
    use, intrinsic :: iso_c_binding, only: c_double
    use conmech_kinds, only: dp
    use conmech_transverse, only: planar_natural_system
    implicit none
    private
    public :: callback_natural

    !> V, grad V, Hess V from pot(q(2), v, g(2), h(2, 2)).
    type, extends(planar_natural_system) :: callback_natural
        procedure(), pointer, nopass :: pot => null()
    contains
        procedure :: potential => cb_potential
    end type callback_natural

contains

    subroutine cb_potential(self, q, v, g, h)
        class(callback_natural), intent(in) :: self
        real(dp), intent(in) :: q(2)
        real(dp), intent(out) :: v, g(2), h(2, 2)
        call self%pot(q, v, g, h)
    end subroutine cb_potential

end module conmech_support_transverse
