!> Event functions used by the integrator tests.
module ode_test_events
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_events
    implicit none
    private
    public :: radial_events

    !> Both components: the radial velocity r.v of a planar orbit (zero at the apsides).
    type, extends(ode_events) :: radial_events
    contains
        procedure :: eval => radial_eval
    end type radial_events

contains

    subroutine radial_eval(self, t, y, g)
        class(radial_events), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: g(:)
        g = y(1)*y(3) + y(2)*y(4)
    end subroutine radial_eval

end module ode_test_events
