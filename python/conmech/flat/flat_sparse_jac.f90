!> Flat f2py routines for a Python right-hand side fun(t, y) whose Jacobian is sparse:
!! jvals(t, y) returns the values of df/dy on a fixed pattern (nnz entries compressed by
!! columns: rows sp_idx(sp_ptr(j) : sp_ptr(j + 1) - 1) of column j, 1-based), the k-th
!! value for the k-th entry. Radau takes its sparse LUs with that pattern (n >= 100, at
!! most 10 % dense; else dense LUs from the scattered values) and reads the values
!! directly: no n x n array is formed (conmech_sparse_jacobian_system). Conventions as in
!! flat_ode.f90 (solve) and flat_stepper.f90 (the stepper's actions).

!> solve_ivp with a sparse Jacobian: flat_solve's arguments for a Python system, with
!! jvals and the pattern in place of the dense Jacobian.
subroutine flat_solve_sparse_jac(fun, jvals, events, store, n, t_span, y0, method, rtol, &
                                 atol, first_step, max_step, max_steps, dense, neval, &
                                 t_eval, ne, ev_dir, ev_term, ev_res, nnz, sp_ptr, sp_idx, &
                                 counts, dense_form, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_status, only: CM_SUCCESS
    use conmech_flat_ode_support, only: run_solve
    use conmech_flat_adapters, only: callback_sparse_jac_system, &
        make_sparse_jac_system
    implicit none
    include "flat_solve_args.inc"
    integer(c_int), intent(in) :: nnz, sp_ptr(n + 1), sp_idx(max(nnz, 1))
    integer(c_int), intent(out) :: counts(5), dense_form, info
    character(len=256), intent(out) :: message
    include "flat_sparse_jac_callbacks.inc"
    include "flat_solve_callbacks.inc"
    type(callback_sparse_jac_system) :: sys

    counts = 0
    dense_form = 0
    call make_sparse_jac_system(fun, jvals, n, nnz, sp_ptr, sp_idx, sys, info, message)
    if (info /= CM_SUCCESS) return
    call run_solve(sys, n, t_span, y0, method, rtol, atol, first_step, max_step, max_steps, &
                   dense, neval, t_eval, ne, ev_dir, ev_term, ev_res, 0, nnz, sp_ptr, &
                   sp_idx, events, store, counts, dense_form, info, message, zero_at_t0=.true.)
end subroutine flat_solve_sparse_jac

!> One stepper action (flat_stepper_callback's) with a sparse Jacobian: jvals and the
!! pattern in place of the dense Jacobian; every action takes the full argument list (the
!! system's pattern is not in the packed state).
subroutine flat_stepper_sparse_jac(fun, jvals, action, n, nr, ni, nw, t0, t_bound, y0, &
                                   method, rtol, atol, first_step, max_step, max_steps, &
                                   nnz, sp_ptr, sp_idx, r, iv, w, sizes, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_status, only: CM_SUCCESS
    use conmech_flat_stepper_support, only: stepper_action
    use conmech_flat_adapters, only: callback_sparse_jac_system, &
        make_sparse_jac_system
    implicit none
    include "flat_stepper_args.inc"
    include "flat_sparse_jac_callbacks.inc"
    type(callback_sparse_jac_system) :: sys

    sizes = 0
    call make_sparse_jac_system(fun, jvals, n, nnz, sp_ptr, sp_idx, sys, info, message)
    if (info /= CM_SUCCESS) return
    call stepper_action(sys, action, n, nr, ni, nw, t0, t_bound, y0, method, rtol, atol, &
                        first_step, max_step, max_steps, 0, nnz, sp_ptr, sp_idx, r, iv, w, &
                        sizes, info, message)
end subroutine flat_stepper_sparse_jac
