!> The generated Kepler system with its Taylor recurrences written out for one order (the
!! module conmech_symbolic_taylor_fixed, made by bench/callgrind_taylor.sh from
!! conmech.symbolic.taylor.fixed_order_source for the same equations, mu = 1), the loop
!! version at any other order.
module kepler_fixed_jet
    use conmech
    use taylor_kepler_model, only: kepler_sym
    use conmech_symbolic_taylor_fixed, only: conmech_taylor_fixed
    implicit none
    private
    public :: kepler_fixed
    integer, parameter :: fixed_order = FIXED_ORDER_VALUE

    type, extends(kepler_sym) :: kepler_fixed
    contains
        procedure :: taylor_jet => fixed_jet
    end type kepler_fixed

contains

    subroutine fixed_jet(self, kind, t, order, nw, w)
        class(kepler_fixed), intent(in) :: self
        integer, intent(in) :: kind, order, nw
        real(dp), intent(in) :: t
        real(dp), intent(inout) :: w(0:order, nw)
        real(dp) :: p(1)
        p = 0.0_dp
        if (kind == 0 .and. order == fixed_order) then
            call conmech_taylor_fixed(t, order, w, p)
        else
            call self%kepler_sym%taylor_jet(kind, t, order, nw, w)
        end if
    end subroutine fixed_jet

end module kepler_fixed_jet
