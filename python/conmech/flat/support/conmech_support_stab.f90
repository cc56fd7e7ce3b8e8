!> Support of the flat f2py layer of the stability modules (compiled, not wrapped: it
!! handles derived types): Hill's equation with a Python Phi(t). See
!! python/conmech/flat/flat_stab.f90.
module conmech_support_stab
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_flat_adapters, only: callback_hill
    use conmech_ode_solver, only: ode_options
    use conmech_variational, only: integrate_stm
    implicit none
    private
    public :: callback_hill_solve

contains

    !> Monodromy of N'' + Phi(t) N = 0 over one period, Phi from the external phi(t, p).
    subroutine callback_hill_solve(phi, period, rtol, mono, half_trace, det, info, message)
        external :: phi
        real(c_double), intent(in) :: period, rtol
        real(c_double), intent(out) :: mono(2, 2), half_trace, det
        integer(c_int), intent(out) :: info
        character(len=256), intent(out) :: message
        type(callback_hill) :: eq
        type(ode_options) :: opt
        real(dp) :: y(2), m(2, 2)
        character(len=:), allocatable :: msg
        mono = 0.0_c_double
        half_trace = 0.0_c_double
        det = 0.0_c_double
        if (.not. period > 0.0_c_double) then
            info = CM_BAD_INPUT
            message = "the period must be positive"
            return
        end if
        eq%g => phi
        opt%rtol = rtol
        opt%atol = rtol
        y = 0.0_dp
        m = reshape([1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2])
        call integrate_stm(eq, 0.0_dp, period, y, m, opt, info, msg)
        message = msg
        if (info < 0) return
        info = CM_SUCCESS
        mono = m
        half_trace = 0.5_dp*(m(1, 1) + m(2, 2))
        det = m(1, 1)*m(2, 2) - m(1, 2)*m(2, 1)
    end subroutine callback_hill_solve

end module conmech_support_stab
