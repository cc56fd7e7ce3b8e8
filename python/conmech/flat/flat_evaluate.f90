!> Flat f2py layer: a system's quantities at one state, for built-in and compiled systems
!! alike (conventions: see flat_ode.f90; the Python side is conmech.compiled.evaluate).

!> f(t, y) and df/dy of a first-order system (analytic = 1 if the Jacobian is exact).
subroutine flat_evaluate_ode(name, np, params, nspec, spec, n, t, y, f, jac, analytic, info, &
                             message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS
    use conmech_ode_system, only: ode_system
    use conmech_flat_spec, only: spec_system_of_size
    use conmech_flat_ode_support, only: copy_message
    implicit none
    include "flat_spec_args.inc"
    integer(c_int), intent(in) :: n
    real(c_double), intent(in) :: t, y(n)
    real(c_double), intent(out) :: f(n), jac(n, n)
    integer(c_int), intent(out) :: analytic, info
    character(len=256), intent(out) :: message
    class(ode_system), allocatable :: sys
    character(len=:), allocatable :: msg
    f = 0.0_dp
    jac = 0.0_dp
    analytic = 0
    call spec_system_of_size(name, real(params(1:np), dp), nspec, spec, n, &
                             "bad input: y has the wrong size for the system", sys, info, msg)
    if (info == CM_SUCCESS) then
        call sys%rhs(t, y, f)
        call sys%jacobian(t, y, jac)
        if (sys%has_jacobian()) analytic = 1
        msg = "success"
    end if
    call copy_message(msg, message)
end subroutine flat_evaluate_ode

!> Quantities of a mechanical system at (t, q, v): mass matrix, forces, energy (has_e = 1
!! if defined); for constrained systems also phi (mh), G (mh x n), gamma_h, A (mn x n), b,
!! gamma_n. kind 1 constrained, 2 generalized (as flat_mech_info); mh, mn >= 0.
subroutine flat_evaluate_mech(name, np, params, nspec, spec, kind, n, mh, mn, t, q, v, mm, &
                              qf, energy, has_e, phi, g, gam_h, a, b, gam_n, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_constrained_system, only: constrained_system
    use conmech_generalized, only: generalized_system
    use conmech_flat_spec, only: spec_constrained, spec_generalized
    use conmech_flat_ode_support, only: copy_message
    implicit none
    include "flat_spec_args.inc"
    integer(c_int), intent(in) :: kind, n, mh, mn
    real(c_double), intent(in) :: t, q(n), v(n)
    real(c_double), intent(out) :: mm(n, n), qf(n), energy
    integer(c_int), intent(out) :: has_e
    real(c_double), intent(out) :: phi(max(mh, 1)), g(max(mh, 1), n), gam_h(max(mh, 1))
    real(c_double), intent(out) :: a(max(mn, 1), n), b(max(mn, 1)), gam_n(max(mn, 1))
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
    class(constrained_system), allocatable :: cs
    class(generalized_system), allocatable :: gs
    character(len=:), allocatable :: msg
    mm = 0.0_dp
    qf = 0.0_dp
    energy = 0.0_dp
    has_e = 0
    phi = 0.0_dp
    g = 0.0_dp
    gam_h = 0.0_dp
    a = 0.0_dp
    b = 0.0_dp
    gam_n = 0.0_dp
    info = CM_BAD_INPUT
    msg = "bad input: unknown kind of mechanical system"
    if (kind == 1) then
        call spec_constrained(name, real(params(1:np), dp), nspec, spec, cs, info, msg)
        if (info == CM_SUCCESS) then
            if (cs%n /= n .or. cs%n_hol /= mh .or. cs%n_nh /= mn) then
                info = CM_BAD_INPUT
                msg = "bad input: dimensions do not match the system"
            else
                call cs%mass(t, q, mm)
                call cs%forces(t, q, v, qf)
                if (cs%has_energy()) then
                    energy = cs%energy(t, q, v)
                    has_e = 1
                end if
                if (mh > 0) then
                    call cs%phi(t, q, phi(1:mh))
                    call cs%phi_jac(t, q, g(1:mh, :))
                    call cs%phi_gamma(t, q, v, gam_h(1:mh))
                end if
                if (mn > 0) then
                    call cs%nh_matrix(t, q, a(1:mn, :), b(1:mn))
                    call cs%nh_gamma(t, q, v, gam_n(1:mn))
                end if
            end if
        end if
    else if (kind == 2) then
        call spec_generalized(name, real(params(1:np), dp), nspec, spec, gs, info, msg)
        if (info == CM_SUCCESS) then
            if (gs%ndof /= n) then
                info = CM_BAD_INPUT
                msg = "bad input: dimensions do not match the system"
            else
                call gs%mass(t, q, mm)
                call gs%forces(t, q, v, qf)
                if (gs%has_energy()) then
                    energy = gs%energy(t, q, v)
                    has_e = 1
                end if
            end if
        end if
    end if
    call copy_message(msg, message)
end subroutine flat_evaluate_mech
