!> Flat f2py layer of the constrained mechanical systems (conventions: see flat_ode.f90).
!! The Python side is conmech/constrained.py.

!> Kind and dimensions of a mechanical system (built-in `name`, or compiled: spec):
!! kind 1 constrained (excessive coordinates; n, n_hol, n_nh), 2 generalized coordinates
!! (n = ndof), 0 unknown.
subroutine flat_mech_info(name, np, params, nspec, spec, kind, n, mh, mn, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS
    use conmech_constrained_system, only: constrained_system
    use conmech_generalized, only: generalized_system
    use conmech_flat_spec, only: spec_constrained, spec_generalized, spec_kind, KIND_BUILTIN, &
                                 KIND_CONSTRAINED
    use conmech_flat_ode_support, only: copy_message
    implicit none
    include "flat_spec_args.inc"
    integer(c_int), intent(out) :: kind, n, mh, mn, info
    character(len=256), intent(out) :: message
    class(constrained_system), allocatable :: cs
    class(generalized_system), allocatable :: gs
    character(len=:), allocatable :: msg
    integer :: sk
    kind = 0
    n = 0
    mh = 0
    mn = 0
    sk = spec_kind(nspec, spec)
    info = -1
    if (sk == KIND_BUILTIN .or. sk == KIND_CONSTRAINED) then
        call spec_constrained(name, real(params(1:np), dp), nspec, spec, cs, info, msg)
        if (info == CM_SUCCESS) then
            kind = 1
            n = cs%n
            mh = cs%n_hol
            mn = cs%n_nh
        end if
    end if
    if (info /= CM_SUCCESS .and. sk /= KIND_CONSTRAINED) then
        call spec_generalized(name, real(params(1:np), dp), nspec, spec, gs, info, msg)
        if (info == CM_SUCCESS) then
            kind = 2
            n = gs%ndof
        end if
    end if
    call copy_message(msg, message)
end subroutine flat_mech_info

!> Default initial state (q0, v0) of a built-in mechanical system with n coordinates.
subroutine flat_mech_initial_state(name, np, params, n, q0, v0, info)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_systems_mech, only: mech_initial_state
    implicit none
    character(len=*), intent(in) :: name
    integer(c_int), intent(in) :: np
    real(c_double), intent(in) :: params(max(np, 1))
    integer(c_int), intent(in) :: n
    real(c_double), intent(out) :: q0(n), v0(n)
    integer(c_int), intent(out) :: info
    real(dp), allocatable :: q(:), v(:)
    q0 = 0.0_dp
    v0 = 0.0_dp
    call mech_initial_state(name, real(params(1:np), dp), q, v, info)
    if (info /= CM_SUCCESS) return
    if (size(q) /= n) then
        info = CM_BAD_INPUT
        return
    end if
    q0 = q
    v0 = v
end subroutine flat_mech_initial_state

!> Solve a constrained system: built-in or compiled (source 0: `name` / `spec`, see
!! conmech_flat_spec; the Python callables are never called) or given by Python callables
!! (source 1; flat_constrained_callbacks.inc gives their conventions). has_jac, has_gamma,
!! has_nh_gamma, rheonomic: 0 or 1 (source 1); without an analytic Jacobian or
!! acceleration term the documented finite differences are used.
subroutine flat_constrained(name, np, params, nspec, spec, source, mass, forces, phi, jac, &
                            gamma, nh, nhgamma, has_jac, has_gamma, has_nh_gamma, rheonomic, &
                            mh, mn, store, events, evstore, n, t_span, q0, v0, method, rtol, &
                            atol, iopt, ropt, neval, t_eval, ne, ev_dir, ev_term, stats, moved, &
                            info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_constrained_system, only: constrained_system
    use conmech_flat_spec, only: spec_constrained
    use conmech_flat_ode_support, only: copy_message
    use conmech_flat_adapters, only: callback_constrained
    use conmech_flat_mech_support, only: run_constrained
    implicit none
    include "flat_spec_args.inc"
    integer(c_int), intent(in) :: source
    integer(c_int), intent(in) :: has_jac, has_gamma, has_nh_gamma, rheonomic, mh, mn
    integer(c_int), intent(in) :: ne
    integer(c_int), intent(in) :: ev_dir(max(ne, 1)), ev_term(max(ne, 1))
    include "flat_constrained_args.inc"
    character(len=256), intent(out) :: message
    include "flat_constrained_callbacks.inc"
    class(constrained_system), allocatable :: cs
    type(callback_constrained) :: cb
    character(len=:), allocatable :: msg
    stats = 0
    moved = 0.0_dp
    if (source == 0) then
        call spec_constrained(name, real(params(1:np), dp), nspec, spec, cs, info, msg)
        if (info /= CM_SUCCESS) then
            call copy_message(msg, message)
            return
        end if
    else
        if (n < 1 .or. mh < 0 .or. mn < 0) then
            info = CM_BAD_INPUT
            call copy_message("bad input: n must be >= 1, n_hol and n_nh >= 0", message)
            return
        end if
        cb%n = n
        cb%n_hol = mh
        cb%n_nh = mn
        cb%rheonomic = rheonomic /= 0
        cb%has_jac = has_jac /= 0
        cb%has_gamma = has_gamma /= 0
        cb%has_nh_gamma = has_nh_gamma /= 0
        cb%fmass => mass
        cb%fforces => forces
        cb%fphi => phi
        cb%fjac => jac
        cb%fgamma => gamma
        cb%fnh => nh
        cb%fnhgamma => nhgamma
        allocate (cs, source=cb)
    end if
    call run_constrained(cs, n, t_span, q0, v0, method, rtol, atol, iopt, ropt, neval, &
                         t_eval, store, stats, moved, info, message, ne, ev_dir, ev_term, &
                         events, evstore)
end subroutine flat_constrained
