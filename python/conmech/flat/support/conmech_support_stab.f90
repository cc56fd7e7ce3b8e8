!> Support of the flat f2py layer of the stability modules (compiled, not wrapped: it
!! handles derived types). See python/conmech/flat/flat_stab.f90.
module conmech_support_stab
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options
    use conmech_variational, only: integrate_stm
    implicit none
    private
    public :: unpack_eq, run_orbit, callback_hill_solve

    !> Hill's equation y = [N, N'] with Phi from an external phi(t, p).
    type, extends(ode_system) :: callback_hill
        procedure(), pointer, nopass :: g => null()
    contains
        procedure :: rhs => callback_hill_rhs
        procedure :: jacobian => callback_hill_jac
        procedure :: has_jacobian => callback_hill_has_jac
    end type callback_hill

contains

    subroutine callback_hill_rhs(self, t, y, dydt)
        class(callback_hill), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(c_double) :: p
        call self%g(t, p)
        dydt(1) = y(2)
        dydt(2) = -p*y(1)
    end subroutine callback_hill_rhs

    subroutine callback_hill_jac(self, t, y, dfdy)
        class(callback_hill), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(c_double) :: p
        call self%g(t, p)
        dfdy = reshape([0.0_dp, -p, 1.0_dp, 0.0_dp], [2, 2])
    end subroutine callback_hill_jac

    logical function callback_hill_has_jac(self)
        class(callback_hill), intent(in) :: self
        callback_hill_has_jac = .true.
    end function callback_hill_has_jac

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

    subroutine unpack_eq(e, n, jac, wr, wi, kind, saddle, residual, analytic, info, message)
        use, intrinsic :: iso_c_binding, only: c_double, c_int
        use conmech_equilibria, only: equilibrium_result
        implicit none
        type(equilibrium_result), intent(in) :: e
        integer(c_int), intent(in) :: n
        real(c_double), intent(out) :: jac(n, n), wr(n), wi(n), residual
        integer(c_int), intent(out) :: kind, saddle, analytic, info
        character(len=256), intent(out) :: message
        info = e%info
        message = e%message
        jac = 0.0_c_double
        wr = 0.0_c_double
        wi = 0.0_c_double
        if (allocated(e%jacobian)) jac = e%jacobian
        if (allocated(e%wr)) wr = e%wr
        if (allocated(e%wi)) wi = e%wi
        kind = e%kind
        saddle = merge(1, 0, e%saddle)
        analytic = merge(1, 0, e%analytic)
        residual = e%residual
    end subroutine unpack_eq

    subroutine run_orbit(sys, n, y0, period, kind, mode, nfree, free_idx, ntg, targets, &
                         free_time, period_factor, rtol, atol, max_iter, y0_out, period_out, &
                         mono, mr, mi, &
                         residual, iterations, info, message)
        use, intrinsic :: iso_c_binding, only: c_double, c_int
        use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
        use conmech_ode_system, only: ode_system
        use conmech_shooting, only: shooting_options, periodic_orbit, find_periodic_orbit, &
                                    find_symmetric_orbit
        implicit none
        class(ode_system), intent(in) :: sys
        integer(c_int), intent(in) :: n, kind, mode, nfree, ntg, free_time, max_iter
        real(c_double), intent(in) :: y0(n), period, period_factor, rtol, atol
        integer(c_int), intent(in) :: free_idx(max(nfree, 1)), targets(max(ntg, 1))
        real(c_double), intent(out) :: y0_out(n), period_out, mono(n, n), mr(n), mi(n), residual
        integer(c_int), intent(out) :: iterations, info
        character(len=256), intent(out) :: message
        type(shooting_options) :: so
        type(periodic_orbit) :: o
        so%rtol = rtol
        so%atol = atol
        if (max_iter > 0) so%max_iter = max_iter
        y0_out = 0.0_c_double
        period_out = 0.0_c_double
        mono = 0.0_c_double
        mr = 0.0_c_double
        mi = 0.0_c_double
        residual = 0.0_c_double
        iterations = 0
        if (kind == 1) then
            call find_periodic_orbit(sys, y0, period, o, mode, so)
        else if (kind == 2) then
            if (.not. period_factor > 0.0_c_double) then
                info = CM_BAD_INPUT
                message = "period_factor must be positive"
                return
            end if
            call find_symmetric_orbit(sys, y0, free_idx(1:nfree), period/period_factor, &
                                      targets(1:ntg), o, so, free_time /= 0, period_factor)
        else
            info = CM_BAD_INPUT
            message = "unknown shooting kind"
            return
        end if
        info = o%info
        message = o%message
        residual = o%residual
        iterations = o%iterations
        if (info /= CM_SUCCESS) return
        y0_out = o%y0
        period_out = o%period
        mono = o%monodromy
        mr = o%floquet%mr
        mi = o%floquet%mi
    end subroutine run_orbit

end module conmech_support_stab
