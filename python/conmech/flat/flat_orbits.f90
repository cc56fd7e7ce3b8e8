!> Flat f2py layer of the periodic-orbit solvers with a choice of discretisation (single
!! shooting, multiple shooting, orthogonal collocation) and multipliers by the periodic
!! eigenvalue method with their error estimates: built-in/compiled systems (name + spec),
!! Python right-hand sides with or without a Python Jacobian. Plain subroutines, explicit
!! shapes, info + message (see conmech_support_orbits for the arguments).

!> Periodic orbit of a built-in or compiled system.
subroutine flat_po_builtin(name, np, params, nspec, spec, n, y0, period, kind, mode, nfree, &
                           free_idx, ntg, targets, free_time, period_factor, rtol, atol, &
                           max_iter, iopt, nk, y0_out, period_out, mono, mr, mi, merr, &
                           accuracy, deflated, nodes, node_times, nnodes, residual, &
                           iterations, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_ode_system, only: ode_system
    use conmech_flat_spec, only: spec_system
    use conmech_support_orbits, only: run_periodic_orbit
    implicit none
    character(len=*), intent(in) :: name
    integer(c_int), intent(in) :: np, n, kind, mode, nfree, ntg, free_time, max_iter, nk
    integer(c_int), intent(in) :: nspec
    integer(8), intent(in) :: spec(max(nspec, 1))  ! c_int64_t (f2py: long_long)
    real(c_double), intent(in) :: params(max(np, 1)), y0(n), period, period_factor, rtol, atol
    integer(c_int), intent(in) :: free_idx(max(nfree, 1)), targets(max(ntg, 1)), iopt(5)
    real(c_double), intent(out) :: y0_out(n), period_out, mono(n, n), mr(n), mi(n), merr(n)
    real(c_double), intent(out) :: accuracy, nodes(n, nk), node_times(nk), residual
    integer(c_int), intent(out) :: deflated, nnodes, iterations, info
    character(len=256), intent(out) :: message
    class(ode_system), allocatable :: sys
    character(len=:), allocatable :: msg
    call spec_system(name, params(1:np), nspec, spec, sys, info, msg)
    if (info /= 0) then
        message = msg
        nnodes = 0
        return
    end if
    call run_periodic_orbit(sys, n, y0, period, kind, mode, nfree, free_idx, ntg, targets, &
                            free_time, period_factor, rtol, atol, max_iter, iopt, nk, &
                            y0_out, period_out, mono, mr, mi, merr, accuracy, deflated, &
                            nodes, node_times, nnodes, residual, iterations, info, message)
end subroutine flat_po_builtin

!> As flat_po_builtin for a Python right-hand side fun(t, y, dydt, n) (FD Jacobian).
subroutine flat_po_callback(fun, n, y0, period, kind, mode, nfree, free_idx, ntg, targets, &
                            free_time, period_factor, rtol, atol, max_iter, iopt, nk, y0_out, &
                            period_out, mono, mr, mi, merr, accuracy, deflated, nodes, &
                            node_times, nnodes, residual, iterations, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_flat_ode_support, only: callback_system
    use conmech_support_orbits, only: run_periodic_orbit
    implicit none
    integer(c_int), intent(in) :: n, kind, mode, nfree, ntg, free_time, max_iter, nk
    real(c_double), intent(in) :: y0(n), period, period_factor, rtol, atol
    integer(c_int), intent(in) :: free_idx(max(nfree, 1)), targets(max(ntg, 1)), iopt(5)
    real(c_double), intent(out) :: y0_out(n), period_out, mono(n, n), mr(n), mi(n), merr(n)
    real(c_double), intent(out) :: accuracy, nodes(n, nk), node_times(nk), residual
    integer(c_int), intent(out) :: deflated, nnodes, iterations, info
    character(len=256), intent(out) :: message
!f2py external fun
    interface
        subroutine fun(t, y, dydt, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dydt(n)
        end subroutine fun
    end interface
    type(callback_system) :: sys
    sys%f => fun
    sys%n = n
    call run_periodic_orbit(sys, n, y0, period, kind, mode, nfree, free_idx, ntg, targets, &
                            free_time, period_factor, rtol, atol, max_iter, iopt, nk, &
                            y0_out, period_out, mono, mr, mi, merr, accuracy, deflated, &
                            nodes, node_times, nnodes, residual, iterations, info, message)
end subroutine flat_po_callback

!> As flat_po_callback with a Python Jacobian jac(t, y, dfdy, n).
subroutine flat_po_callback_jac(fun, jac, n, y0, period, kind, mode, nfree, free_idx, ntg, &
                                targets, free_time, period_factor, rtol, atol, max_iter, iopt, &
                                nk, y0_out, period_out, mono, mr, mi, merr, accuracy, &
                                deflated, nodes, node_times, nnodes, residual, iterations, &
                                info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_flat_ode_support, only: callback_jac_system
    use conmech_support_orbits, only: run_periodic_orbit
    implicit none
    integer(c_int), intent(in) :: n, kind, mode, nfree, ntg, free_time, max_iter, nk
    real(c_double), intent(in) :: y0(n), period, period_factor, rtol, atol
    integer(c_int), intent(in) :: free_idx(max(nfree, 1)), targets(max(ntg, 1)), iopt(5)
    real(c_double), intent(out) :: y0_out(n), period_out, mono(n, n), mr(n), mi(n), merr(n)
    real(c_double), intent(out) :: accuracy, nodes(n, nk), node_times(nk), residual
    integer(c_int), intent(out) :: deflated, nnodes, iterations, info
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
    call run_periodic_orbit(sys, n, y0, period, kind, mode, nfree, free_idx, ntg, targets, &
                            free_time, period_factor, rtol, atol, max_iter, iopt, nk, &
                            y0_out, period_out, mono, mr, mi, merr, accuracy, deflated, &
                            nodes, node_times, nnodes, residual, iterations, info, message)
end subroutine flat_po_callback_jac
