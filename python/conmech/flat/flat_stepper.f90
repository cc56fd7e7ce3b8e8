!> Flat f2py layer of the steppers (conmech.DOP853, conmech.RK45, conmech.Radau,
!! conmech.Gauss6, ... in conmech/_stepper.py): one entry for every method of the method
!! table. The stepper's whole state lives in arrays owned by the Python object (r(nr),
!! iv(ni), w(n, nw); sizes from action 3, the common part at the positions
!! flat_stepper_layout gives), copied in and out by every call, so that nothing is kept in
!! Fortran between calls. action: 0 init at (t0, y0) and start, 1 one accepted step towards
!! t_bound, 2 dense coefficients of the last step (in w), 3 the sizes [nr, ni, nw] (init
!! only). jac_const /= 0: a constant Jacobian (read once, not counted in njev); nnz >= 0:
!! the sparsity pattern of df/dy by columns, sp_ptr(n + 1) and rows sp_idx(1:nnz)
!! (1-based), for differences by groups of columns (methods that use a Jacobian; kept in
!! the packed state; nnz = -1: none). Conventions as in flat_ode.f90.

!> Positions (1-based) of the common part of a packed state: layout = [r: t, t_old,
!! h_done; iv: nf, form, nfev, njev, nlu, naccept, nreject; w: y, first dense column].
subroutine flat_stepper_layout(layout)
    use, intrinsic :: iso_c_binding, only: c_int
    use conmech_ode_stepper, only: PACK_R_T, PACK_R_TOLD, PACK_R_HDONE, PACK_I_NF, &
        PACK_I_FORM, PACK_I_NFEV, PACK_I_NJEV, PACK_I_NLU, PACK_I_NACCEPT, PACK_I_NREJECT, &
        PACK_W_Y, PACK_W_FC
    implicit none
    integer(c_int), intent(out) :: layout(12)
    layout = [PACK_R_T, PACK_R_TOLD, PACK_R_HDONE, PACK_I_NF, PACK_I_FORM, PACK_I_NFEV, &
              PACK_I_NJEV, PACK_I_NLU, PACK_I_NACCEPT, PACK_I_NREJECT, PACK_W_Y, PACK_W_FC]
end subroutine flat_stepper_layout

!> One stepper action for a Python right-hand side fun(t, y) and, if has_jac /= 0, its
!! Jacobian jac(t, y) -> (n, n) (methods that use one; else finite differences).
subroutine flat_stepper_callback(fun, jac, action, n, nr, ni, nw, t0, t_bound, y0, method, &
                                 has_jac, rtol, atol, first_step, max_step, max_steps, &
                                 jac_const, nnz, sp_ptr, sp_idx, r, iv, w, sizes, info, &
                                 message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_flat_adapters, only: callback_jac_system
    use conmech_flat_stepper_support, only: stepper_action
    implicit none
    include "flat_stepper_args.inc"
    integer(c_int), intent(in) :: has_jac, jac_const
    include "flat_stepper_callbacks.inc"
    type(callback_jac_system) :: sys
    sys%f => fun
    sys%n = n
    if (has_jac /= 0) sys%jac => jac
    call stepper_action(sys, action, n, nr, ni, nw, t0, t_bound, y0, method, rtol, atol, &
                        first_step, max_step, max_steps, jac_const, nnz, sp_ptr, sp_idx, r, &
                        iv, w, sizes, info, message)
end subroutine flat_stepper_callback

!> One stepper action for the built-in (or compiled) system `name` with parameters
!! params(1:np) (its own Jacobian where the method uses one).
subroutine flat_stepper_builtin(name, np, params, nspec, spec, action, n, nr, ni, nw, t0, &
                                t_bound, y0, method, rtol, atol, first_step, max_step, &
                                max_steps, nnz, sp_ptr, sp_idx, r, iv, w, sizes, info, &
                                message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_status, only: CM_SUCCESS
    use conmech_ode_system, only: ode_system
    use conmech_flat_stepper_support, only: stepper_action, stepper_system
    implicit none
    include "flat_spec_args.inc"
    include "flat_stepper_args.inc"
    class(ode_system), allocatable :: sys
    sizes = 0
    call stepper_system(name, params(1:np), nspec, spec, n, sys, info, message)
    if (info /= CM_SUCCESS) return
    call stepper_action(sys, action, n, nr, ni, nw, t0, t_bound, y0, method, rtol, atol, &
                        first_step, max_step, max_steps, 0, nnz, sp_ptr, sp_idx, r, iv, w, &
                        sizes, info, message)
end subroutine flat_stepper_builtin

!> The Butcher tableau of an explicit Runge-Kutta method of the table (code; 12: SciPy's
!! RK45, DOPRI5's tableau): a(21, 21), b(21), c(21) (zero beyond its stages; DOP853's b is
!! its 8th-order weights, row 13 of a). Zero for a method without one.
subroutine flat_rk_tableau(code, a, b, c)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_ode_options, only: METHOD_DOPRI5, METHOD_DOP853, METHOD_VERNER98
    use conmech_rk_tableaus, only: rk_tableau, dopri5_tableau, dop853_tableau, &
        verner98_tableau
    use conmech_flat_ode_support, only: METHOD_RK45_SCIPY
    implicit none
    integer(c_int), intent(in) :: code
    real(c_double), intent(out) :: a(21, 21), b(21), c(21)
    type(rk_tableau) :: tb
    select case (code)
    case (METHOD_DOPRI5, METHOD_RK45_SCIPY)
        tb = dopri5_tableau()
    case (METHOD_DOP853)
        tb = dop853_tableau()
    case (METHOD_VERNER98)
        tb = verner98_tableau()
    end select
    a = tb%a
    b = tb%b
    c = tb%c
end subroutine flat_rk_tableau
