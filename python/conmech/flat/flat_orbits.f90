!> Flat f2py layer of the periodic-orbit solvers with a choice of discretisation (single
!! shooting, multiple shooting, orthogonal collocation) and multipliers by the periodic
!! eigenvalue method with their error estimates, for any system of the one flat argument
!! set (conmech_flat_system: built-in/compiled by name + spec, or a Python right-hand side
!! with or without a Python Jacobian). Plain subroutines, explicit shapes, info + message
!! (see conmech_support_orbits for the arguments).

!> Periodic orbit of the system given by the one flat argument set (conmech_flat_system).
subroutine flat_po(name, np, params, nspec, spec, fun, jfun, source, n, y0, period, kind, &
                   mode, nfree, free_idx, ntg, targets, free_time, period_factor, rtol, atol, &
                   max_iter, iopt, nk, y0_out, period_out, mono, mr, mi, merr, accuracy, &
                   deflated, nodes, node_times, nnodes, residual, iterations, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_ode_system, only: ode_system
    use conmech_flat_system, only: flat_system
    use conmech_support_orbits, only: run_periodic_orbit
    implicit none
    integer(c_int), intent(in) :: n, kind, mode, nfree, ntg, free_time
    integer(c_int), intent(in) :: max_iter, nk
    real(c_double), intent(in) :: y0(n), period, period_factor, rtol, atol
    integer(c_int), intent(in) :: free_idx(max(nfree, 1)), targets(max(ntg, 1)), iopt(6)
    real(c_double), intent(out) :: y0_out(n), period_out, mono(n, n), mr(n), mi(n), merr(n)
    real(c_double), intent(out) :: accuracy, nodes(n, nk), node_times(nk), residual
    integer(c_int), intent(out) :: deflated, nnodes, iterations, info
    character(len=256), intent(out) :: message
    include "flat_system_args.inc"
    class(ode_system), allocatable :: sys
    call flat_system(name, params(1:np), nspec, spec, fun, jfun, source, n, sys, info, message)
    if (info /= 0) then
        nnodes = 0
        return
    end if
    call run_periodic_orbit(sys, n, y0, period, kind, mode, nfree, free_idx, ntg, targets, &
                            free_time, period_factor, rtol, atol, max_iter, iopt, nk, &
                            y0_out, period_out, mono, mr, mi, merr, accuracy, deflated, &
                            nodes, node_times, nnodes, residual, iterations, info, message)
end subroutine flat_po
