!> Flat f2py layer of the integrators: plain subroutines with c_double/c_int arguments,
!! explicit-shape arrays, an `info` code and a fixed-length message (wrapped by numpy.f2py
!! into conmech._conmech; the Python API in conmech/_ivp.py is the user-facing side).
!!
!! Results are handed to the `store` callback once, at the end, with their actual sizes:
!! no capacities to guess, no re-runs, nothing saved between calls (thread-safe).
!! The Python layer catches an exception raised in a user's callback, returns NaN from
!! then on (the solver stops on the non-finite values and returns normally) and raises it
!! again after the call. Should an exception still cross a callback (e.g. f2py failing
!! to convert a returned value), f2py returns to Python at once (longjmp) with the
!! exception set: the Fortran arrays of that call leak, nothing is corrupted.
!! Nothing here stops or prints.
!!
!! Conventions of every flat file (python/conmech/flat/*.f90, all wrapped into the one
!! extension conmech._conmech by meson.build):
!! - plain subroutines only, no modules (Fortran modules of the flat layer go to
!!   python/conmech/flat/support/, compiled but not wrapped); real(c_double),
!!   integer(c_int), explicit-shape arrays, `info` + character(len=256) `message` outputs;
!! - f2py cannot pass empty arrays: an array that may be empty is declared with
!!   max(count, 1) elements and its count is a separate argument;
!! - a Python callback is a dummy procedure declared with `!f2py external name` and an
!!   interface block whose bodies `use, intrinsic :: iso_c_binding` (f2py does not
!!   understand `import`); intent(in) arguments reach Python, intent(out) ones are what
!!   the Python function returns. To hand it to a derived type, point a
!!   `procedure(), pointer, nopass` component at it (see conmech_flat_ode_support);
!! - results of unknown size go back through a `store` callback, called once at the end.

!> Method code from a name of the method table (case-insensitive: "RK4", "DOPRI5",
!! "RK45", "DOP853", "Radau", ...); 0 if unknown.
subroutine flat_method_code(name, code)
    use, intrinsic :: iso_c_binding, only: c_int
    use conmech_ode_methods, only: method_from_name
    implicit none
    character(len=*), intent(in) :: name
    integer(c_int), intent(out) :: code
    code = method_from_name(name)
end subroutine flat_method_code

!> The method table's entry of `code` (conmech_ode_methods): found = 0 if there is none;
!! its canonical name, aliases (space separated), order and flags = [fixed_step (first_step
!! is the step, required), uses_jacobian, constrained_only]. Codes run over
!! 1 .. max_code.
subroutine flat_method_info(code, found, name, aliases, order, flags, max_code)
    use, intrinsic :: iso_c_binding, only: c_int
    use conmech_ode_methods, only: method_info, method_entry, MAX_METHOD_CODE
    implicit none
    integer(c_int), intent(in) :: code
    integer(c_int), intent(out) :: found, order, flags(3), max_code
    character(len=16), intent(out) :: name
    character(len=48), intent(out) :: aliases
    type(method_info) :: mi
    call method_entry(code, mi)
    found = merge(1, 0, mi%code /= 0)
    name = mi%name
    aliases = mi%aliases
    order = mi%order
    flags = merge(1, 0, [mi%fixed_step, mi%uses_jacobian, mi%constrained_only])
    max_code = MAX_METHOD_CODE
end subroutine flat_method_info

!> State dimension of a built-in system (0 if the name is unknown).
subroutine flat_system_dimension(name, n)
    use, intrinsic :: iso_c_binding, only: c_int
    use conmech_systems, only: system_dimension
    implicit none
    character(len=*), intent(in) :: name
    integer(c_int), intent(out) :: n
    n = system_dimension(name)
end subroutine flat_system_dimension

!> Solve y' = f(t, y) with any method of the table for the system of the one flat argument
!! set (conmech_flat_system): a built-in system `name` with parameters `params` (see
!! conmech_systems::make_system; params has at least one element, np of them are used) or
!! a compiled one (`spec`), with its analytic Jacobian where the method uses one (no Python
!! in the loop unless there are events); or a Python right-hand side fun(t, y) (f2py
!! callback) with, for source 2, a Python Jacobian jfun(t, y) -> (n, n) (else forward
!! differences).
!! Tolerances are per component; first_step = 0: automatic; dense /= 0: dense output;
!! neval = 0: output at every accepted step; ne = 0: no events (`events` is not called).
!! ev_dir: +1 rising, -1 falling, 0 both; ev_term > 0: terminal, the run stops at that
!! occurrence (0: not terminal); an event exactly zero at t0 follows SciPy's rule (reported
!! at t0 when the first step moves it in its direction); ev_res: each event's resolution
!! (largest spacing of its samples inside a step; 0: the step's ends only, SciPy's rule).
!! jac_const /= 0: the Jacobian is constant (read once, njev 0); nnz >= 0: the
!! sparsity pattern of df/dy by columns, sp_ptr(n + 1) and rows sp_idx(1:nnz) (1-based), for
!! differences by groups of columns (methods that use a Jacobian; nnz = -1: none).
!! dense_form: form of the dense coefficients handed to `store` (1 Hairer's, 2 power basis,
!! 0 none). counts = [nfev, njev, nlu, naccept, nreject].
subroutine flat_solve(name, np, params, nspec, spec, fun, jfun, source, events, store, n, &
                      t_span, y0, method, rtol, atol, first_step, max_step, max_steps, &
                      dense, neval, t_eval, ne, ev_dir, ev_term, ev_res, jac_const, nnz, &
                      sp_ptr, sp_idx, counts, dense_form, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS
    use conmech_ode_system, only: ode_system
    use conmech_flat_spec, only: spec_system_of_size
    use conmech_flat_system, only: flat_system, SOURCE_SPEC
    use conmech_flat_ode_support, only: run_solve, copy_message
    implicit none
    include "flat_solve_args.inc"
    integer(c_int), intent(in) :: jac_const, nnz, sp_ptr(n + 1), sp_idx(max(nnz, 1))
    integer(c_int), intent(out) :: counts(5), dense_form, info
    character(len=256), intent(out) :: message
    include "flat_system_args.inc"
    include "flat_solve_callbacks.inc"
    class(ode_system), allocatable :: sys
    character(len=:), allocatable :: msg

    counts = 0
    dense_form = 0
    if (source == SOURCE_SPEC) then     ! y0 must have the built-in or compiled system's size
        call spec_system_of_size(name, real(params(1:np), dp), nspec, spec, n, "", sys, &
                                 info, msg)
        call copy_message(msg, message)
    else
        call flat_system(name, real(params(1:np), dp), nspec, spec, fun, jfun, source, n, &
                         sys, info, message)
    end if
    if (info /= CM_SUCCESS) return
    call run_solve(sys, n, t_span, y0, method, rtol, atol, first_step, max_step, max_steps, &
                   dense, neval, t_eval, ne, ev_dir, ev_term, ev_res, jac_const, nnz, sp_ptr, &
                   sp_idx, events, store, counts, dense_form, info, message, zero_at_t0=.true.)
end subroutine flat_solve
