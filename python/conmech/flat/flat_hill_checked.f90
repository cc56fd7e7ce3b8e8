!> Hill's variation orbit and its independent closure check in one call, so that
!! conmech.hill.variation_orbit spends its time in Fortran: the orbit with its monodromy
!! (flat_hill_orbit, called here), then the true closure error of y0 from an
!! independent adaptive integration of a quarter period (flat_hill_residuals: DOP853,
!! rtol = atol = 1e-12, max(|x(pi/2)|, |y'(pi/2)|)), the scale max(1, |y0|) it is
!! compared against, and whether the monodromy and S are finite.
!!
!! Every number comes back in one array `out`, which Python unpacks by views (y0, the
!! monodromy, the multipliers as a complex view, the quarter-period state are slices of
!! it): f2py then allocates one array and converts one message instead of building six
!! arrays and eleven Python numbers, which was most of the call's cost outside Fortran.
!! The message travels in `out` too (its 256 bytes as 32 doubles, a bit copy): a
!! character output is allocated, padded and trimmed by f2py at every call, which cost
!! more than the rest of the wrapper.

!> As flat_hill_orbit, packed into out(76):
!!   out(1:4) y0, out(5:20) the monodromy (column-major 4 x 4), out(21:28) the multipliers
!!   as (real, imaginary) pairs (the memory of a complex array), out(29:32) the state at
!!   T/4, then period, jacobi, s, c, residual (33:37), true_res (the independent closure
!!   error; huge(1) if that integration fails) and scale = max(1, max |y0|) (38:39), and
!!   nsteps_used, iterations, nfev, finite (1 when the monodromy and S are finite) and
!!   info (40:44) as exact doubles, and out(45:76) the 256 bytes of the message (blank
!!   when info = 0; Python reads them as bytes, never as numbers).
subroutine flat_hill_orbit_checked(m, kappa, nsteps, full_period, use_guess, guess, &
                                   closure_tol, max_nsteps, out)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_status, only: CM_SUCCESS
    implicit none
    real(c_double), intent(in) :: m, kappa
    integer(c_int), intent(in) :: nsteps, full_period, use_guess
    real(c_double), intent(in) :: guess(2), closure_tol
    integer(c_int), intent(in) :: max_nsteps
    real(c_double), intent(out) :: out(76)
    interface
        subroutine flat_hill_orbit(m, kappa, nsteps, full_period, use_guess, guess, &
                                   closure_tol, max_nsteps, y0, period, jacobi, mono, mr, mi, &
                                   s, c, residual, quarter, nsteps_used, iterations, nfev, &
                                   info, message)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            include "flat_hill_orbit_args.inc"
        end subroutine flat_hill_orbit
        subroutine flat_hill_residuals(nm, ms, kappa, y0s, res)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: nm
            real(c_double), intent(in) :: ms(nm), kappa, y0s(4, nm)
            real(c_double), intent(out) :: res(nm)
        end subroutine flat_hill_residuals
    end interface
    real(c_double) :: r(1), y0(4), mono(4, 4), mr(4), mi(4), quarter(4)
    real(c_double) :: period, jacobi, s, c, residual, true_res, scale
    integer(c_int) :: nsteps_used, iterations, nfev, finite, info
    character(len=256) :: message
    call flat_hill_orbit(m, kappa, nsteps, full_period, use_guess, guess, closure_tol, &
                         max_nsteps, y0, period, jacobi, mono, mr, mi, s, c, residual, &
                         quarter, nsteps_used, iterations, nfev, info, message)
    true_res = huge(1.0_c_double)
    scale = 1.0_c_double
    finite = 0
    if (info == CM_SUCCESS) then
        call flat_hill_residuals(1_c_int, [m], kappa, reshape(y0, [4, 1]), r)
        true_res = r(1)
        scale = max(1.0_c_double, maxval(abs(y0)))
        if (all(abs(mono) <= huge(1.0_c_double)) .and. abs(s) <= huge(1.0_c_double)) finite = 1
    end if
    out(1:4) = y0
    out(5:20) = reshape(mono, [16])
    out(21:27:2) = mr
    out(22:28:2) = mi
    out(29:32) = quarter
    out(33:39) = [period, jacobi, s, c, residual, true_res, scale]
    out(40:44) = real([nsteps_used, iterations, nfev, finite, info], c_double)
    out(45:76) = transfer(message, out(45:76))
end subroutine flat_hill_orbit_checked
