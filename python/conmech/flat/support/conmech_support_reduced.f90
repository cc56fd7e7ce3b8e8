!> Support of the flat control layer (compiled, not wrapped): the event functions of the
!! reduced dynamics (theta' = 0, E = 0) and a periodic linear system given by Python
!! callables afun(t, a, k), bfun(t, b, k, m) for the Riccati solver.
module conmech_support_reduced
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_NONFINITE
    use conmech_lapack, only: la_finite
    use conmech_ode_system, only: ode_events
    use conmech_periodic_riccati, only: periodic_lq
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

    !> A(t), B(t) from external procedures.
    type, extends(periodic_lq) :: callback_lq
        procedure(), pointer, nopass :: fa => null()
        procedure(), pointer, nopass :: fb => null()
    contains
        procedure :: coefficients => cb_coefficients
    end type callback_lq

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

    subroutine cb_coefficients(self, t, a, b, info)
        class(callback_lq), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(out) :: a(:, :), b(:, :)
        integer, intent(out) :: info
        real(c_double) :: tt, aa(self%k, self%k), bb(self%k, self%m)
        tt = t
        call self%fa(tt, aa, int(self%k, c_int))
        call self%fb(tt, bb, int(self%k, c_int), int(self%m, c_int))
        a = aa
        b(:, 1:self%m) = bb
        info = CM_SUCCESS
        if (.not. (la_finite(aa) .and. la_finite(bb))) info = CM_NONFINITE
    end subroutine cb_coefficients

end module conmech_support_reduced
