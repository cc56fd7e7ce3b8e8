!> Support of the flat f2py layer for periodic orbits by single shooting, multiple shooting
!! or collocation (compiled, not wrapped): `run_periodic_orbit` runs find_periodic_orbit /
!! find_symmetric_orbit from plain arguments and unpacks the orbit, its multipliers with
!! their error estimates and the segment/mesh nodes into explicit-shape arrays.
module conmech_support_orbits
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: METHOD_DOP853
    use conmech_ode_options, only: METHOD_TAYLOR
    use conmech_shooting, only: shooting_options, periodic_orbit, find_periodic_orbit, &
                                find_symmetric_orbit
    implicit none
    private
    public :: run_periodic_orbit, stm_integrator_ok

contains

    !> kind 1: general shooting (mode 1 free period, 2 fixed period), kind 2: symmetric
    !! (free_idx, targets one-based; tau = period/period_factor, free_time /= 0).
    !! iopt = [discretisation (1 single, 2 multiple, 3 collocation), segments, degree,
    !! intervals, adapt, integrator (a method code: METHOD_DOP853 or METHOD_TAYLOR)];
    !! nk >= the number of nodes (segments or intervals + 1).
    !! Outputs: the orbit, the formed monodromy, multipliers (mr, mi) with error estimates
    !! merr and the set's accuracy, deflated (1: mr(1) is the deflated flow multiplier),
    !! the nnodes nodes and their times.
    subroutine run_periodic_orbit(sys, n, y0, period, kind, mode, nfree, free_idx, ntg, &
                                  targets, free_time, period_factor, rtol, atol, max_iter, &
                                  iopt, nk, y0_out, period_out, mono, mr, mi, merr, &
                                  accuracy, deflated, nodes, node_times, nnodes, residual, &
                                  iterations, info, message)
        class(ode_system), intent(in) :: sys
        integer(c_int), intent(in) :: n, kind, mode, nfree, ntg, free_time, max_iter, nk
        real(c_double), intent(in) :: y0(n), period, period_factor, rtol, atol
        integer(c_int), intent(in) :: free_idx(max(nfree, 1)), targets(max(ntg, 1)), iopt(6)
        real(c_double), intent(out) :: y0_out(n), period_out, mono(n, n), mr(n), mi(n)
        real(c_double), intent(out) :: merr(n), accuracy, nodes(n, nk), node_times(nk)
        real(c_double), intent(out) :: residual
        integer(c_int), intent(out) :: deflated, nnodes, iterations, info
        character(len=256), intent(out) :: message
        type(shooting_options) :: so
        type(periodic_orbit) :: o
        so%rtol = rtol
        so%atol = atol
        if (max_iter > 0) so%max_iter = max_iter
        so%discretisation = iopt(1)
        so%segments = iopt(2)
        so%degree = iopt(3)
        so%intervals = iopt(4)
        so%adapt = iopt(5)
        so%method = iopt(6)
        y0_out = 0.0_c_double
        period_out = 0.0_c_double
        mono = 0.0_c_double
        mr = 0.0_c_double
        mi = 0.0_c_double
        merr = 0.0_c_double
        accuracy = 0.0_c_double
        nodes = 0.0_c_double
        node_times = 0.0_c_double
        residual = 0.0_c_double
        deflated = 0
        nnodes = 0
        iterations = 0
        if (iopt(1) < 1 .or. iopt(1) > 3) then
            info = CM_BAD_INPUT
            message = "unknown discretisation"
            return
        end if
        if (.not. stm_integrator_ok(iopt(6), message)) then
            info = CM_BAD_INPUT
            return
        end if
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
        mr = o%multipliers%mr
        mi = o%multipliers%mi
        merr = o%multipliers%err
        accuracy = o%multipliers%accuracy
        deflated = merge(1, 0, o%multipliers%deflated)
        if (allocated(o%nodes)) then
            nnodes = min(size(o%nodes, 2), nk)
            nodes(:, 1:nnodes) = o%nodes(:, 1:nnodes)
            node_times(1:nnodes) = o%node_times(1:nnodes)
        end if
    end subroutine run_periodic_orbit

    !> Whether `code` names an integrator the orbit solvers offer for the state and its
    !! STM: DOP853, or Taylor's method on the variational system's own recurrences (a
    !! compiled system of conmech.symbolic); else false with the message.
    logical function stm_integrator_ok(code, message) result(ok)
        integer(c_int), intent(in) :: code
        character(len=*), intent(inout) :: message
        ok = code == METHOD_DOP853 .or. code == METHOD_TAYLOR
        if (.not. ok) message = "bad input: the integrator of the orbit and its STM must "// &
                                "be DOP853 or TAYLOR"
    end function stm_integrator_ok
end module conmech_support_orbits
