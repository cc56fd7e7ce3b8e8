!> Support of the flat control layer (compiled, not wrapped): the event functions of the
!! reduced dynamics (theta' = 0, E = 0); `callback_lq` (conmech_flat_callbacks, re-exported)
!! is the periodic linear system of Python callables afun(t, a, k), bfun(t, b, k, m).
module conmech_support_reduced
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_events
    use conmech_flat_callbacks, only: callback_lq
    implicit none
    private
    public :: velocity_zero, energy_zero, callback_lq

    !> g = theta' (the second component).
    type, extends(ode_events) :: velocity_zero
    contains
        procedure :: eval => vz_eval
    end type velocity_zero

    !> g = E (the first component).
    type, extends(ode_events) :: energy_zero
    contains
        procedure :: eval => ez_eval
    end type energy_zero

contains

    subroutine vz_eval(self, t, y, g)
        class(velocity_zero), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: g(:)
        g(1) = y(2)
    end subroutine vz_eval

    subroutine ez_eval(self, t, y, g)
        class(energy_zero), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: g(:)
        g(1) = y(1)
    end subroutine ez_eval

end module conmech_support_reduced
