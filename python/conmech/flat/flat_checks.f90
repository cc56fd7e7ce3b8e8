!> Flat f2py layer (conventions in flat_ode.f90): the independent residual check of Hill's
!! variation orbits.
!! Nothing is saved between calls; nothing stops or prints.

!> Independent check of Hill's variation orbits: each y0s(:, i) (for m = ms(i)) is
!! integrated over a quarter period with adaptive DOP853 (rtol = atol = 1e-12) and
!! res(i) = max(|x(pi/2)|, |y'(pi/2)|) (both vanish on the doubly symmetric orbit); res(i)
!! is huge(1) when the integration fails or y0s(:, i) is not finite.
subroutine flat_hill_residuals(nm, ms, kappa, y0s, res)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp, pi
    use conmech_status, only: CM_SUCCESS
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_integrate, METHOD_DOP853
    use conmech_systems, only: make_system
    implicit none
    integer(c_int), intent(in) :: nm
    real(c_double), intent(in) :: ms(nm), kappa, y0s(4, nm)
    real(c_double), intent(out) :: res(nm)
    class(ode_system), allocatable :: sys
    character(len=:), allocatable :: msg
    type(ode_options) :: opt
    real(dp) :: y(4)
    integer :: i, info
    opt%method = METHOD_DOP853
    opt%rtol = 1.0e-12_dp
    opt%atol = 1.0e-12_dp
    do i = 1, nm
        res(i) = huge(1.0_dp)
        if (.not. all(abs(y0s(:, i)) <= huge(1.0_dp))) cycle
        call make_system("hill", [ms(i), kappa], sys, info, msg)
        if (info /= CM_SUCCESS) cycle
        y = y0s(:, i)
        call ode_integrate(sys, 0.0_dp, 0.5_dp*pi, y, opt, info)
        if (info < 0 .or. .not. all(abs(y) <= huge(1.0_dp))) cycle
        res(i) = max(abs(y(1)), abs(y(4)))
    end do
end subroutine flat_hill_residuals
