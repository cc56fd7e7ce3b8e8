!> Flat f2py layer: continuation of equilibria and of periodic orbits of a Python right-hand
!! side fun(t, y, p, dydt, n) with its exact Jacobian jac(t, y, p, dfdy, n) (df/dy; the
!! parameter derivative by differences), as flat_eq_continuation_callback and
!! flat_branch_callback otherwise.

!> flat_eq_continuation_callback with the exact Jacobian.
subroutine flat_eq_continuation_callback_jac(fun, jac, n, y0, p0, ropt, iopt, mp, npts, pp, &
                                             ys, wr, wi, psi, nunst, res, iters, nsp, spi, &
                                             spr, sp_y, sp_wr, sp_wi, sp_q, sp_a, info, &
                                             message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_support_cont, only: callback_param_jac_system
    use conmech_support_families, only: run_eq_continuation
    implicit none
    integer(c_int), intent(in) :: n, iopt(4), mp
    real(c_double), intent(in) :: y0(n), p0, ropt(11)
    integer(c_int), intent(out) :: npts, nunst(mp), iters(mp), nsp, spi(5, 64), info
    real(c_double), intent(out) :: pp(mp), ys(n, mp), wr(n, mp), wi(n, mp), psi(3, mp)
    real(c_double), intent(out) :: res(mp), spr(8, 64), sp_y(n, 64), sp_wr(n, 64)
    real(c_double), intent(out) :: sp_wi(n, 64), sp_q(2*n, 64), sp_a(2*n, 64)
    character(len=256), intent(out) :: message
!f2py external fun, jac
    interface
        subroutine fun(t, y, p, dydt, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t, p
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dydt(n)
        end subroutine fun
        subroutine jac(t, y, p, dfdy, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t, p
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dfdy(n, n)
        end subroutine jac
    end interface
    type(callback_param_jac_system) :: sys
    sys%f => fun
    sys%jf => jac
    sys%n = n
    sys%p = p0
    call run_eq_continuation(sys, n, y0, p0, ropt, iopt, mp, npts, pp, ys, wr, wi, psi, &
                             nunst, res, iters, nsp, spi, spr, sp_y, sp_wr, sp_wi, sp_q, sp_a, &
                             info, message)
end subroutine flat_eq_continuation_callback_jac

!> flat_branch_callback with the exact Jacobian.
subroutine flat_branch_callback_jac(fun, jac, n, y0, period, p0, ropt, iopt, nfree, free_idx, &
                                    ntg, targets, ntang, tang, mp, energy, npts, pp, per, ys, &
                                    mr, mi, merr, acc, s, psi, res, iters, nsp, sp_kind, &
                                    sp_index, sp_p, sp_per, sp_y, sp_mr, sp_mi, sp_s, &
                                    sp_located, sp_test, sp_closure, sp_bracket, direction, &
                                    info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_support_cont, only: callback_param_jac_system, run_continuation, &
                                    callback_energy
    implicit none
    integer(c_int), intent(in) :: n, iopt(16), nfree, ntg, mp
    real(c_double), intent(in) :: y0(n), period, p0, ropt(15)
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
!f2py external fun, jac, energy
    interface
        subroutine fun(t, y, p, dydt, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t, p
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dydt(n)
        end subroutine fun
        subroutine jac(t, y, p, dfdy, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t, p
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dfdy(n, n)
        end subroutine jac
        subroutine energy(y, p, e, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: y(n), p
            real(c_double), intent(out) :: e
        end subroutine energy
    end interface
    type(callback_param_jac_system) :: sys
    type(callback_energy) :: en
    sys%f => fun
    sys%jf => jac
    sys%n = n
    sys%p = p0
    en%f => energy
    en%n = n
    call run_continuation(sys, n, y0, period, p0, ropt, iopt, nfree, free_idx, ntg, targets, &
                          ntang, tang, mp, en, npts, pp, per, ys, mr, mi, merr, acc, s, psi, &
                          res, iters, nsp, sp_kind, sp_index, sp_p, sp_per, sp_y, sp_mr, &
                          sp_mi, sp_s, sp_located, sp_test, sp_closure, sp_bracket, &
                          direction, info, message)
end subroutine flat_branch_callback_jac
