!> Flat f2py layer of the general transverse linearisation (conmech_transverse_general):
!! built-in and compiled systems (first-order, generalized, constrained) by name/spec, and
!! Python right-hand sides with an optional Jacobian and energy gradient (one argument
!! set, conmech_flat_system). Plain
!! subroutines, explicit shapes, info + message; nothing saved between calls.
!!
!! Outputs (kmax = N - 1 - n_normals, the largest possible k): k, reduced (1 if the energy
!! was removed), closure, drift (energy drift measure), defect (frame defect), nfev, the
!! transverse monodromy mono(1:k, 1:k) and its multipliers mr + i mi, the full monodromy
!! fmono (N, N) and its multipliers, the holonomy holo(1:k, 1:k), and at the nt times t:
!! the orbit xs (N, nt), the periodic frame qs (N, kmax, nt), A_perp as (kmax, kmax, nt) and
!! for two-degree-of-freedom systems with the energy removed the coefficients phis, psis of
!! N'' + psi N' + phi N = 0 (NaN when the state is not [q, q']).

!> The system of the one flat argument set (conmech_flat_system): a built-in or compiled
!! system (first-order, generalized, constrained; source 0) or a Python right-hand side
!! fun(t, y) with an optional Jacobian jfun (source 1 or 2), then with an optional energy
!! gradient egrad(t, y) (has_energy; never called for source 0). kind: the kind of the
!! built-in or compiled system (0 for Python functions).
subroutine flat_transverse_general(name, np, params, nspec, spec, fun, jfun, source, egrad, &
                                   has_energy, n, y0, period, rtol, atol, energy_mode, full, &
                                   nt, t, kmax, k, reduced, closure, drift, defect, mono, mr, &
                                   mi, fmono, fr_re, fr_im, holo, xs, qs, as, phis, psis, &
                                   nfev, kind, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_transverse_model, only: transverse_model
    use conmech_transverse_general, only: transverse_options, transverse_frame, transverse_build
    use conmech_flat_system, only: flat_system, SOURCE_SPEC
    use conmech_support_transverse_general, only: system_and_model, pack_frame, &
                                                  callback_energy_model
    implicit none
    integer(c_int), intent(in) :: has_energy, n, energy_mode, full, nt
    integer(c_int), intent(in) :: kmax
    real(c_double), intent(in) :: y0(n), period, rtol, atol, t(nt)
    integer(c_int), intent(out) :: k, reduced, nfev, kind, info
    real(c_double), intent(out) :: closure, drift, defect
    real(c_double), intent(out) :: mono(kmax, kmax), mr(kmax), mi(kmax), holo(kmax, kmax)
    real(c_double), intent(out) :: fmono(n, n), fr_re(n), fr_im(n)
    real(c_double), intent(out) :: xs(n, nt), qs(n, kmax, nt), as(kmax, kmax, nt)
    real(c_double), intent(out) :: phis(nt), psis(nt)
    character(len=256), intent(out) :: message
    include "flat_system_args.inc"
!f2py external egrad
    interface
        subroutine egrad(t, y, g, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: g(n)
        end subroutine egrad
    end interface
    class(ode_system), allocatable :: sys
    class(transverse_model), allocatable :: model
    type(callback_energy_model) :: cmodel
    type(transverse_options) :: opt
    type(transverse_frame) :: fr
    character(len=:), allocatable :: msg
    integer :: kd
    kd = 0
    if (source == SOURCE_SPEC) then
        call system_and_model(name, real(params(1:np), dp), nspec, spec, sys, model, kd, &
                              info, msg)
        message = msg
    else
        call flat_system(name, real(params(1:np), dp), nspec, spec, fun, jfun, source, n, &
                         sys, info, message)
        cmodel%egrad => egrad
        cmodel%present = has_energy /= 0
        cmodel%n = n
        allocate (model, source=cmodel)
    end if
    kind = kd
    if (info /= CM_SUCCESS) then
        fr%info = info
        call pack_frame(fr, nt, t, kmax, n, k, reduced, closure, drift, defect, mono, mr, mi, &
                        fmono, fr_re, fr_im, holo, xs, qs, as, phis, psis, nfev)
        return
    end if
    opt%rtol = rtol
    opt%atol = atol
    opt%energy = energy_mode
    opt%full_monodromy = full /= 0
    call transverse_build(sys, model, y0, period, opt, fr)
    info = fr%info
    message = fr%message
    if (info == CM_SUCCESS .and. fr%k > kmax) then
        info = CM_BAD_INPUT
        message = "transverse: internal size error (k > kmax)"
    end if
    call pack_frame(fr, nt, t, kmax, n, k, reduced, closure, drift, defect, mono, mr, mi, &
                    fmono, fr_re, fr_im, holo, xs, qs, as, phis, psis, nfev)
end subroutine flat_transverse_general
