!> solve_ivp's common case through the flat layer at the smallest fixed cost: a built-in or
!! compiled system (no Python right-hand side), no events, no dense output. The points
!! are returned in output arrays of a capacity the caller chooses (t_eval's length, or a
!! guess), so that no call-back into Python is made when they fit; only a run with more
!! points than that hands its whole result to `store` (conventions of flat_solve). f2py's
!! cost per call grows with the number of arguments and above all with each call-back
!! argument (it inspects the Python function on every call), hence a routine of its own
!! with one call-back, rather than flat_solve's four.

!> Integrate y' = f(t, y) of the built-in (or compiled) system `name` with parameters
!! params(1:np) (spec: its function table, nspec = 0 for a built-in) from y0 over t_span
!! with method `method` (as flat_solve, METHOD_RK45_SCIPY included); output at the points
!! t_eval(1:neval), or at every step when neval = 0.
!! nt >= 0: the nt points are in t_out(1:nt), y_out(:, 1:nt); nt = -1: there were more
!! than cap and they were passed to `store` instead. counts = [nfev, njev, nlu, naccept,
!! nreject]; info the run's status (0 end reached, < 0 failure, CM_BAD_INPUT refused)
!! with its message.
subroutine flat_solve_native(name, np, params, nspec, spec, store, n, t0, tf, y0, method, &
                             rtol, atol, first_step, max_step, max_steps, neval, t_eval, &
                             cap, t_out, y_out, nt, counts, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_result
    use conmech_flat_spec, only: spec_system_of_size
    use conmech_flat_ode_support, only: solve_into, store_result, copy_message
    implicit none
    include "flat_spec_args.inc"
    integer(c_int), intent(in) :: n
    real(c_double), intent(in) :: t0, tf
    real(c_double), intent(in) :: y0(n)
    integer(c_int), intent(in) :: method
    real(c_double), intent(in) :: rtol(n), atol(n)
    real(c_double), intent(in) :: first_step, max_step
    integer(c_int), intent(in) :: max_steps, neval
    real(c_double), intent(in) :: t_eval(max(neval, 1))
    integer(c_int), intent(in) :: cap
    real(c_double), intent(out) :: t_out(max(cap, 1)), y_out(n, max(cap, 1))
    integer(c_int), intent(out) :: nt, counts(5), info
    character(len=256), intent(out) :: message
    include "flat_store_callback.inc"
    class(ode_system), allocatable :: sys
    type(ode_result) :: res
    character(len=:), allocatable :: msg
    integer(c_int) :: none(1), dense_form

    ! t_out and y_out are written up to nt only (f2py hands them over zero-filled)
    nt = 0
    counts = 0
    call spec_system_of_size(name, real(params(1:np), dp), nspec, spec, n, "", sys, info, msg)
    if (info /= CM_SUCCESS) then
        call copy_message(msg, message)
        return
    end if
    none = 0
    call solve_into(sys, n, [t0, tf], y0, method, rtol, atol, first_step, max_step, &
                    max_steps, 0, neval, t_eval, 0, none, none, [0.0_c_double], 0, -1, none, &
                    none, res, counts, info, message)
    if (.not. allocated(res%t)) return              ! refused before any integration
    if (res%nt <= cap) then
        nt = res%nt
        t_out(1:nt) = res%t(1:nt)
        y_out(:, 1:nt) = res%y(:, 1:nt)
    else
        nt = -1
        call store_result(res, n, .false., store, dense_form)
    end if
end subroutine flat_solve_native
