!> Support of the flat f2py layer for the continuation of periodic orbits (compiled, not
!! wrapped): the parameter of a built-in system or of a Python right-hand side
!! fun(t, y, p, dydt, n) made settable (`set_param_any`), and
!! `run_continuation`, which runs `continue_orbits` from plain arguments and packs the
!! branch into explicit-shape arrays.
module conmech_support_cont
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_flat_adapters, only: callback_system, callback_energy
    use conmech_param_system, only: builtin_param_system, set_builtin_param
    use conmech_shooting, only: set_parameter_proc
    use conmech_continuation, only: cont_options, branch, special_point, continue_orbits, &
                                    SP_PD, SP_BP, branch_energy
    use conmech_branch_switch, only: switch_period_doubling, switch_branch_point
    use conmech_support_orbits, only: stm_integrator_ok
    implicit none
    private
    public :: set_param_any, run_continuation, callback_energy
    public :: MAX_SPECIAL, NROPT, NIOPT

    integer, parameter :: MAX_SPECIAL = 64
    integer, parameter :: NROPT = 15, NIOPT = 17

contains

    !> set_param for both wrappers (a built-in system is rebuilt with the new parameter).
    subroutine set_param_any(sys, p)
        class(ode_system), intent(inout) :: sys
        real(dp), intent(in) :: p
        select type (sys)
        type is (builtin_param_system)
            call set_builtin_param(sys, p)
        class is (callback_system)
            sys%p = p
        end select
    end subroutine set_param_any

    !> Run the continuation and pack the branch. ropt = [ds, ds_min, ds_max, p_min, p_max,
    !! tol, res_tol, rtol, atol, locate_tol, period_factor, period_min, period_max,
    !! energy_min, energy_max]; iopt = [max_points, direction, max_iter, autonomous,
    !! fixed_period, conservative, locate, symmetric, free_time, switch, in_period,
    !! discretisation, segments, degree, intervals, has_energy, integrator (METHOD_DOP853
    !! or METHOD_TAYLOR)]: switch = 1 starts the
    !! doubled-period branch at the period-doubling point (p0, y0, period), switch = 2 the
    !! second branch at the branch point (p0, y0, period) whose old tangent is
    !! tang(1:ntang) (unknowns [y0, T, p]; its singular-value ratio is returned in
    !! tang(1)); switch = 3 starts at the solution (p0, y0, period) with the first tangent
    !! tang(1:ntang) in the unknowns of single shooting ([y0, T, p], T only if free; the
    !! reduced [z_1, T, p] for multiple shooting and collocation); in_period /= 0
    !! continues in the period. `en`: the energy (has_energy /= 0).
    !! Per point: multipliers with their error estimates (merr) and accuracy; per special
    !! point: located (1/0) + 10 * the reason the location stopped (SPR_*), the test
    !! function, the true closure and the p bracket.
    subroutine run_continuation(sys, n, y0, period, p0, ropt, iopt, nfree, free_idx, ntg, &
                                targets, ntang, tang, mp, en, npts, pp, per, ys, mr, mi, &
                                merr, acc, s, psi, res, iters, nsp, sp_kind, sp_index, sp_p, &
                                sp_per, sp_y, sp_mr, sp_mi, sp_s, sp_located, sp_test, &
                                sp_closure, sp_bracket, direction, info, message)
        class(ode_system), intent(inout) :: sys
        integer(c_int), intent(in) :: n, iopt(NIOPT), nfree, ntg, mp
        real(c_double), intent(in) :: y0(n), period, p0, ropt(NROPT)
        integer(c_int), intent(in) :: free_idx(max(nfree, 1)), targets(max(ntg, 1)), ntang
        real(c_double), intent(inout) :: tang(max(ntang, 1))
        type(callback_energy), intent(in) :: en
        integer(c_int), intent(out) :: npts, iters(mp), nsp, sp_kind(MAX_SPECIAL)
        integer(c_int), intent(out) :: sp_index(MAX_SPECIAL), sp_located(MAX_SPECIAL)
        integer(c_int), intent(out) :: direction, info
        real(c_double), intent(out) :: pp(mp), per(mp), ys(n, mp), mr(n, mp), mi(n, mp)
        real(c_double), intent(out) :: merr(n, mp), acc(mp), s(mp), psi(4, mp), res(mp)
        real(c_double), intent(out) :: sp_p(MAX_SPECIAL), sp_per(MAX_SPECIAL)
        real(c_double), intent(out) :: sp_y(n, MAX_SPECIAL), sp_mr(n, MAX_SPECIAL)
        real(c_double), intent(out) :: sp_mi(n, MAX_SPECIAL), sp_s(MAX_SPECIAL)
        real(c_double), intent(out) :: sp_test(MAX_SPECIAL), sp_closure(MAX_SPECIAL)
        real(c_double), intent(out) :: sp_bracket(2, MAX_SPECIAL)
        character(len=256), intent(out) :: message
        type(cont_options) :: o
        type(branch) :: br
        type(special_point) :: sp
        real(dp) :: ratio
        integer :: k
        logical :: sym, has_en
        npts = 0
        nsp = 0
        direction = 1
        pp = 0.0_dp; per = 0.0_dp; ys = 0.0_dp; mr = 0.0_dp; mi = 0.0_dp; s = 0.0_dp
        merr = 0.0_dp; acc = 0.0_dp
        psi = 0.0_dp; res = 0.0_dp; iters = 0
        sp_kind = 0; sp_index = 0; sp_p = 0.0_dp; sp_per = 0.0_dp; sp_y = 0.0_dp
        sp_mr = 0.0_dp; sp_mi = 0.0_dp; sp_s = 0.0_dp; sp_located = 0; sp_test = 0.0_dp
        sp_closure = 0.0_dp; sp_bracket = 0.0_dp
        if (.not. stm_integrator_ok(iopt(17), message)) then
            info = CM_BAD_INPUT
            return
        end if
        o%ds = ropt(1)
        o%ds_min = ropt(2)
        o%ds_max = ropt(3)
        o%p_min = ropt(4)
        o%p_max = ropt(5)
        o%tol = ropt(6)
        o%res_tol = ropt(7)
        o%rtol = ropt(8)
        o%atol = ropt(9)
        o%locate_tol = ropt(10)
        o%period_min = ropt(12)
        o%period_max = ropt(13)
        o%energy_min = ropt(14)
        o%energy_max = ropt(15)
        o%max_points = min(iopt(1), mp)
        o%direction = iopt(2)
        o%max_iter = iopt(3)
        o%autonomous = iopt(4) /= 0
        o%fixed_period = iopt(5) /= 0
        o%conservative = iopt(6) /= 0
        o%locate = iopt(7) /= 0
        o%in_period = iopt(11) /= 0
        o%discretisation = iopt(12)
        o%segments = iopt(13)
        o%degree = iopt(14)
        o%intervals = iopt(15)
        sym = iopt(8) /= 0
        has_en = iopt(16) /= 0
        o%integrator = iopt(17)
        call set_param_any(sys, p0)
        if (iopt(10) == 2) then
            sp%kind = SP_BP
            sp%point%p = p0
            sp%point%y0 = y0
            sp%point%period = period
            call switch_branch_point(sys, set_param_any, sp, tang(1:ntang), br, o, ratio)
            tang(1) = ratio
        else if (iopt(10) == 3 .and. sym) then
            call continue_orbits(sys, set_param_any, p0, y0, period, br, o, &
                                 free_idx(1:nfree), targets(1:ntg), iopt(9) /= 0, ropt(11), &
                                 tangent0=tang(1:ntang))
        else if (iopt(10) == 3) then
            call continue_orbits(sys, set_param_any, p0, y0, period, br, o, &
                                 tangent0=tang(1:ntang))
        else if (iopt(10) /= 0) then
            sp%kind = SP_PD
            sp%point%p = p0
            sp%point%y0 = y0
            sp%point%period = period
            call switch_period_doubling(sys, set_param_any, sp, br, o)
        else if (sym .and. has_en) then
            call continue_orbits(sys, set_param_any, p0, y0, period, br, o, &
                                 free_idx(1:nfree), targets(1:ntg), iopt(9) /= 0, ropt(11), &
                                 energy=en)
        else if (sym) then
            call continue_orbits(sys, set_param_any, p0, y0, period, br, o, &
                                 free_idx(1:nfree), targets(1:ntg), iopt(9) /= 0, ropt(11))
        else if (has_en) then
            call continue_orbits(sys, set_param_any, p0, y0, period, br, o, energy=en)
        else
            call continue_orbits(sys, set_param_any, p0, y0, period, br, o)
        end if
        info = br%info
        message = br%message
        npts = br%npoints
        direction = br%direction
        do k = 1, npts
            pp(k) = br%points(k)%p
            per(k) = br%points(k)%period
            ys(:, k) = br%points(k)%y0
            mr(:, k) = br%points(k)%mr
            mi(:, k) = br%points(k)%mi
            merr(:, k) = br%points(k)%merr
            acc(k) = br%points(k)%accuracy
            s(k) = br%points(k)%stability_index
            psi(:, k) = br%points(k)%psi
            res(k) = br%points(k)%residual
            iters(k) = br%points(k)%iterations
        end do
        nsp = min(br%nspecial, MAX_SPECIAL)
        do k = 1, nsp
            sp_kind(k) = br%special(k)%kind
            sp_index(k) = br%special(k)%index
            sp_p(k) = br%special(k)%point%p
            sp_per(k) = br%special(k)%point%period
            sp_y(:, k) = br%special(k)%point%y0
            if (allocated(br%special(k)%point%mr)) then
                sp_mr(:, k) = br%special(k)%point%mr
                sp_mi(:, k) = br%special(k)%point%mi
            end if
            sp_s(k) = br%special(k)%point%stability_index
            sp_located(k) = merge(1, 0, br%special(k)%located) + 10*br%special(k)%reason
            sp_test(k) = br%special(k)%test
            sp_closure(k) = br%special(k)%closure
            sp_bracket(:, k) = br%special(k)%p_bracket
        end do
    end subroutine run_continuation

end module conmech_support_cont
