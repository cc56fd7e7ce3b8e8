!> Flat f2py layer (conventions in flat_ode.f90): the stability routines for a Python
!! right-hand side with its exact Jacobian (a second callback jac(t, y, dfdy, n), SciPy's
!! `jac`), and the independent residual check of Hill's variation orbits.
!! Nothing is saved between calls; nothing stops or prints.

!> State and STM for a Python right-hand side fun(t, y, dydt, n) and Jacobian
!! jac(t, y, dfdy, n).
subroutine flat_stm_callback_jac(fun, jac, n, y0, t0, t1, rtol, atol, y1, phi, nfev, info, &
                                 message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_ode_solver, only: ode_options, ode_stats
    use conmech_flat_ode_support, only: callback_jac_system
    use conmech_variational, only: integrate_stm
    implicit none
    integer(c_int), intent(in) :: n
    real(c_double), intent(in) :: y0(n), t0, t1, rtol, atol
    real(c_double), intent(out) :: y1(n), phi(n, n)
    integer(c_int), intent(out) :: nfev, info
    character(len=256), intent(out) :: message
!f2py external fun, jac
    interface
        subroutine fun(t, y, dydt, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dydt(n)
        end subroutine fun
        subroutine jac(t, y, dfdy, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dfdy(n, n)
        end subroutine jac
    end interface
    type(callback_jac_system) :: sys
    type(ode_options) :: opt
    type(ode_stats) :: st
    character(len=:), allocatable :: msg
    integer :: i
    sys%f => fun
    sys%jac => jac
    sys%n = n
    y1 = y0
    phi = 0.0_c_double
    do i = 1, n
        phi(i, i) = 1.0_c_double
    end do
    opt%rtol = rtol
    opt%atol = atol
    call integrate_stm(sys, t0, t1, y1, phi, opt, info, msg, st)
    nfev = st%nfev
    message = msg
end subroutine flat_stm_callback_jac

!> Periodic orbit (see flat_orbit_builtin) for a Python right-hand side and Jacobian.
subroutine flat_orbit_callback_jac(fun, jac, n, y0, period, kind, mode, nfree, free_idx, ntg, &
                                   targets, free_time, period_factor, rtol, atol, max_iter, &
                                   y0_out, period_out, mono, mr, mi, residual, iterations, &
                                   info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_flat_ode_support, only: callback_jac_system
    use conmech_support_stab, only: run_orbit
    implicit none
    integer(c_int), intent(in) :: n, kind, mode, nfree, ntg, free_time, max_iter
    real(c_double), intent(in) :: y0(n), period, period_factor, rtol, atol
    integer(c_int), intent(in) :: free_idx(max(nfree, 1)), targets(max(ntg, 1))
    real(c_double), intent(out) :: y0_out(n), period_out, mono(n, n), mr(n), mi(n), residual
    integer(c_int), intent(out) :: iterations, info
    character(len=256), intent(out) :: message
!f2py external fun, jac
    interface
        subroutine fun(t, y, dydt, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dydt(n)
        end subroutine fun
        subroutine jac(t, y, dfdy, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dfdy(n, n)
        end subroutine jac
    end interface
    type(callback_jac_system) :: sys
    sys%f => fun
    sys%jac => jac
    sys%n = n
    call run_orbit(sys, n, y0, period, kind, mode, nfree, free_idx, ntg, targets, free_time, &
                   period_factor, rtol, atol, max_iter, y0_out, period_out, mono, mr, mi, &
                   residual, iterations, info, message)
end subroutine flat_orbit_callback_jac

!> Equilibrium analysis for a Python right-hand side and Jacobian.
subroutine flat_equilibrium_callback_jac(fun, jac, n, y, t, tol, dfdy, wr, wi, kind, saddle, &
                                         residual, analytic, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_flat_ode_support, only: callback_jac_system
    use conmech_equilibria, only: equilibrium_result, analyze_equilibrium
    use conmech_support_stab, only: unpack_eq
    implicit none
    integer(c_int), intent(in) :: n
    real(c_double), intent(in) :: y(n), t, tol
    real(c_double), intent(out) :: dfdy(n, n), wr(n), wi(n), residual
    integer(c_int), intent(out) :: kind, saddle, analytic, info
    character(len=256), intent(out) :: message
!f2py external fun, jac
    interface
        subroutine fun(t, y, dydt, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dydt(n)
        end subroutine fun
        subroutine jac(t, y, dfdy, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dfdy(n, n)
        end subroutine jac
    end interface
    type(callback_jac_system) :: sys
    type(equilibrium_result) :: e
    sys%f => fun
    sys%jac => jac
    sys%n = n
    call analyze_equilibrium(sys, y, e, t, tol)
    call unpack_eq(e, n, dfdy, wr, wi, kind, saddle, residual, analytic, info, message)
end subroutine flat_equilibrium_callback_jac

!> Independent check of Hill's variation orbits: each y0s(:, i) (for m = ms(i)) is
!! integrated over a quarter period with adaptive DOP853 (rtol = atol = 1e-12) and
!! res(i) = max(|x(pi/2)|, |y'(pi/2)|) (both vanish on the doubly symmetric orbit); res(i)
!! is huge(1) when the integration fails or y0s(:, i) is not finite.
subroutine flat_hill_residuals(nm, ms, kappa, y0s, res)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
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
        if (.not. all(ieee_is_finite(y0s(:, i)))) cycle
        call make_system("hill", [ms(i), kappa], sys, info, msg)
        if (info /= CM_SUCCESS) cycle
        y = y0s(:, i)
        call ode_integrate(sys, 0.0_dp, 0.5_dp*pi, y, opt, info)
        if (info < 0 .or. .not. all(ieee_is_finite(y))) cycle
        res(i) = max(abs(y(1)), abs(y(4)))
    end do
end subroutine flat_hill_residuals
