!> Flat f2py layer of the continuation of periodic orbits (conmech_continuation): built-in
!! and compiled systems continued in one of their parameters, Python right-hand sides
!! fun(t, y, p, dydt, n) with an optional Jacobian (the parametric argument set of
!! conmech_flat_system); single shooting, multiple shooting or collocation; an optional
!! Python energy(y, p, e, n) for the energy range. Options packed as in run_continuation
!! (conmech_support_cont); the branch in arrays of mp points (npts used) and at most 64
!! special points with their located flag, test value, closure and parameter bracket.

!> Continuation of a periodic orbit of the system of the parametric flat argument set
!! (conmech_flat_system: a built-in or compiled system in params(ip), or a Python
!! fun(t, y, p, dydt, n), with or without jfun, from p0).
subroutine flat_branch(name, np, params, nspec, spec, ip, fun, jfun, source, p0, n, y0, &
                       period, ropt, iopt, nfree, free_idx, ntg, targets, ntang, tang, mp, &
                       energy, npts, pp, per, ys, mr, mi, merr, acc, s, psi, res, iters, nsp, &
                       sp_kind, sp_index, sp_p, sp_per, sp_y, sp_mr, sp_mi, sp_s, sp_located, &
                       sp_test, sp_closure, sp_bracket, direction, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_ode_system, only: ode_system
    use conmech_flat_system, only: flat_param_system
    use conmech_support_cont, only: run_continuation, callback_energy
    implicit none
    integer(c_int), intent(in) :: n, iopt(17), nfree, ntg, mp
    real(c_double), intent(in) :: y0(n), period, ropt(15)
    integer(c_int), intent(in) :: free_idx(max(nfree, 1)), targets(max(ntg, 1)), ntang
    real(c_double), intent(inout) :: tang(max(ntang, 1))  ! in: old tangent; out: SV ratio
    integer(c_int), intent(out) :: npts, iters(mp), nsp, sp_kind(64), sp_index(64)
    integer(c_int), intent(out) :: sp_located(64), direction, info
    real(c_double), intent(out) :: pp(mp), per(mp), ys(n, mp), mr(n, mp), mi(n, mp)
    real(c_double), intent(out) :: merr(n, mp), acc(mp), s(mp), psi(4, mp), res(mp)
    real(c_double), intent(out) :: sp_p(64), sp_per(64), sp_y(n, 64), sp_mr(n, 64)
    real(c_double), intent(out) :: sp_mi(n, 64), sp_s(64), sp_test(64), sp_closure(64)
    real(c_double), intent(out) :: sp_bracket(2, 64)
    character(len=256), intent(out) :: message
    include "flat_param_args.inc"
!f2py external energy
    interface
        subroutine energy(y, p, e, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: y(n), p
            real(c_double), intent(out) :: e
        end subroutine energy
    end interface
    class(ode_system), allocatable :: sys
    type(callback_energy) :: en
    real(c_double) :: pstart
    npts = 0
    nsp = 0
    direction = 1
    call flat_param_system(name, params(1:np), nspec, spec, ip, fun, jfun, source, n, p0, &
                           sys, pstart, info, message)
    if (info /= 0) return
    en%f => energy
    en%n = n
    call run_continuation(sys, n, y0, period, pstart, ropt, iopt, nfree, free_idx, ntg, &
                          targets, ntang, tang, mp, en, npts, pp, per, ys, mr, mi, merr, acc, &
                          s, psi, res, iters, nsp, sp_kind, sp_index, sp_p, sp_per, sp_y, &
                          sp_mr, sp_mi, sp_s, sp_located, sp_test, sp_closure, sp_bracket, &
                          direction, info, message)
end subroutine flat_branch
