!> Event functions and step hooks used by the integrator tests.
module ode_test_events
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_events, ode_step_hook
    implicit none
    private
    public :: radial_events, circle_projection, sine_event

    !> Both components: the radial velocity r.v of a planar orbit (zero at the apsides).
    type, extends(ode_events) :: radial_events
    contains
        procedure :: eval => radial_eval
    end type radial_events

    !> sin(50 y_1) + level: with y_1 = t and the default level 0.9, 32 zeros on [0, 2], the
    !! closest 0.018 apart; with level 0, zero at t = 0 and every pi/50.
    type, extends(ode_events) :: sine_event
        real(dp) :: level = 0.9_dp
    contains
        procedure :: eval => sine_eval
    end type sine_event

    !> Projects [x, v] back onto x^2 + v^2 = r2 after every step; stops after max_calls.
    type, extends(ode_step_hook) :: circle_projection
        real(dp) :: r2 = 1.0_dp
        integer :: calls = 0
        integer :: max_calls = huge(1)
    contains
        procedure :: after_step => circle_after_step
    end type circle_projection

contains

    subroutine radial_eval(self, t, y, g)
        class(radial_events), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: g(:)
        g = y(1)*y(3) + y(2)*y(4)
    end subroutine radial_eval

    subroutine sine_eval(self, t, y, g)
        class(sine_event), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: g(:)
        g(1) = sin(50.0_dp*y(1)) + self%level
    end subroutine sine_eval

    subroutine circle_after_step(self, t, y, changed, info)
        class(circle_projection), intent(inout) :: self
        real(dp), intent(in) :: t
        real(dp), intent(inout) :: y(:)
        logical, intent(out) :: changed
        integer, intent(out) :: info
        self%calls = self%calls + 1
        y(1:2) = y(1:2)*sqrt(self%r2/(y(1)**2 + y(2)**2))
        changed = .true.
        info = 0
        if (self%calls >= self%max_calls) info = 1
    end subroutine circle_after_step

end module ode_test_events
