!> Event functions used by the apps.
module app_events
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_events
    implicit none
    private
    public :: theta_events, section_events

    !> g = theta': zero at the turning points of a pendulum.
    type, extends(ode_events) :: theta_events
    contains
        procedure :: eval => theta_eval
    end type theta_events

    !> g = y(k) - c: a Poincare section of the state space.
    type, extends(ode_events) :: section_events
        integer :: k = 1
        real(dp) :: c = 0.0_dp
    contains
        procedure :: eval => section_eval
    end type section_events

contains

    subroutine theta_eval(self, t, y, g)
        class(theta_events), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: g(:)
        g(1) = y(2)
    end subroutine theta_eval

    subroutine section_eval(self, t, y, g)
        class(section_events), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: g(:)
        g(1) = y(self%k) - self%c
    end subroutine section_eval

end module app_events
