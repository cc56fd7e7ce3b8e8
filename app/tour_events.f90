!> Event functions used by the tour.
module tour_events
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_events
    implicit none
    private
    public :: theta_events

    !> g = theta': zero at the turning points of a pendulum.
    type, extends(ode_events) :: theta_events
    contains
        procedure :: eval => theta_eval
    end type theta_events

contains

    subroutine theta_eval(self, t, y, g)
        class(theta_events), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: g(:)
        g(1) = y(2)
    end subroutine theta_eval

end module tour_events
