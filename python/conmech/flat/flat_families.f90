!> Flat f2py layer: continuation of equilibria, the first Lyapunov coefficient at a Hopf
!! point, the energy of a built-in or compiled system, the libration points of the
!! circular restricted three-body problem (conventions: see flat_ode.f90; the Python side
!! is conmech.stability.equilibrium_continuation, conmech.systems, conmech.cr3bp).

!> Continuation of the equilibrium y0 of the system of the parametric flat argument set
!! (conmech_flat_system: a built-in or compiled system in its parameter ip, 1-based, from
!! params(ip); or a Python fun(t, y, p, dydt, n) from p0); see
!! conmech_support_families::run_eq_continuation for ropt, iopt and the packed outputs.
subroutine flat_eq_continuation(name, np, params, nspec, spec, ip, fun, jfun, source, p0, n, &
                                y0, ropt, iopt, mp, npts, pp, ys, wr, wi, psi, nunst, res, &
                                iters, nsp, spi, spr, sp_y, sp_wr, sp_wi, sp_q, sp_a, info, &
                                message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_ode_system, only: ode_system
    use conmech_flat_system, only: flat_param_system
    use conmech_support_families, only: run_eq_continuation
    implicit none
    integer(c_int), intent(in) :: n, iopt(4), mp
    real(c_double), intent(in) :: y0(n), ropt(11)
    integer(c_int), intent(out) :: npts, nunst(mp), iters(mp), nsp, spi(5, 64), info
    real(c_double), intent(out) :: pp(mp), ys(n, mp), wr(n, mp), wi(n, mp), psi(3, mp)
    real(c_double), intent(out) :: res(mp), spr(8, 64), sp_y(n, 64), sp_wr(n, 64)
    real(c_double), intent(out) :: sp_wi(n, 64), sp_q(2*n, 64), sp_a(2*n, 64)
    character(len=256), intent(out) :: message
    include "flat_param_args.inc"
    class(ode_system), allocatable :: sys
    real(c_double) :: pstart
    npts = 0
    nsp = 0
    call flat_param_system(name, params(1:np), nspec, spec, ip, fun, jfun, source, n, p0, &
                           sys, pstart, info, message)
    if (info /= 0) return
    call run_eq_continuation(sys, n, y0, pstart, ropt, iopt, mp, npts, pp, ys, wr, wi, psi, &
                             nunst, res, iters, nsp, spi, spr, sp_y, sp_wr, sp_wi, sp_q, sp_a, &
                             info, message)
end subroutine flat_eq_continuation

!> The first Lyapunov coefficient at the equilibrium y (time t) of a built-in or compiled
!! system (ip < 0: no parameter) or of a Python fun(t, y, p, dydt, n) at the parameter p0
!! (the parametric flat argument set, conmech_flat_system): out = [omega, re_lambda, l1,
!! scale, l1_error, criticality, exact], q and adj as [real; imaginary] parts (see
!! conmech_support_families::run_hopf).
subroutine flat_hopf(name, np, params, nspec, spec, ip, fun, jfun, source, p0, n, t, y, &
                     l1_tol, out, q, adj, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_status, only: CM_SUCCESS
    use conmech_ode_system, only: ode_system
    use conmech_flat_system, only: flat_param_system
    use conmech_support_families, only: run_hopf
    implicit none
    integer(c_int), intent(in) :: n
    real(c_double), intent(in) :: t, y(n), l1_tol
    real(c_double), intent(out) :: out(7), q(2*n), adj(2*n)
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
    include "flat_param_args.inc"
    class(ode_system), allocatable :: sys
    real(c_double) :: pstart
    out = 0.0_c_double
    q = 0.0_c_double
    adj = 0.0_c_double
    call flat_param_system(name, params(1:np), nspec, spec, ip, fun, jfun, source, n, p0, &
                           sys, pstart, info, message)
    if (info /= CM_SUCCESS) return
    call run_hopf(sys, n, t, y, l1_tol, out, q, adj, info, message)
end subroutine flat_hopf

!> The energy (first integral) of a built-in or compiled system at (t, y); info -4 with a
!! message if it has none (conmech_system_energy).
subroutine flat_system_energy(name, np, params, nspec, spec, n, t, y, e, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS
    use conmech_ode_system, only: ode_system
    use conmech_flat_spec, only: spec_system
    use conmech_system_energy, only: system_energy
    implicit none
    include "flat_spec_args.inc"
    integer(c_int), intent(in) :: n
    real(c_double), intent(in) :: t, y(n)
    real(c_double), intent(out) :: e
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
    class(ode_system), allocatable :: sys
    character(len=:), allocatable :: msg
    real(dp) :: ev
    e = 0.0_c_double
    call spec_system(name, params(1:np), nspec, spec, sys, info, msg)
    if (info == CM_SUCCESS) call system_energy(sys, t, y, ev, info, msg)
    message = msg
    if (info == CM_SUCCESS) e = ev
end subroutine flat_system_energy

!> The libration points of the CR3BP: pos(:, k) of L_k and its Jacobi constant cj(k).
subroutine flat_cr3bp_libration(mu, pos, cj, info)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_cr3bp, only: cr3bp_libration_points
    implicit none
    real(c_double), intent(in) :: mu
    real(c_double), intent(out) :: pos(3, 5), cj(5)
    integer(c_int), intent(out) :: info
    call cr3bp_libration_points(mu, pos, cj, info)
end subroutine flat_cr3bp_libration
