!> solve_ivp's common cases (a built-in or compiled system, or a Python right-hand side
!! without a Jacobian; no events, no dense output) through the flat layer at the smallest
!! fixed cost. f2py's cost per call grows with the number of arguments, with every output
!! array it creates (zero-filled) and above all with a call-back argument (the Python
!! function is inspected on every call), so these routines have none of them but the
!! right-hand side itself: the arguments that do not change between calls with the same
!! method and tolerances come packed in two arrays the caller prepares once (ipack and
!! rpar, or ipar and rpar for a Python right-hand side), the outputs go into
!! arrays the caller passes (out, iout), and a run with more points than `out` holds
!! leaves them in Fortran memory for flat_solve_take.
!!
!! The layout of the points in out (nt points, n components): out(1:nt) the times, then
!! the states by component, out(nt*i + 1 : nt*(i + 1)) = y(i, 1:nt): the caller reads
!! y as a C-ordered (n, nt) array without a copy.

!> Integrate y' = f(t, y) of the built-in (or compiled) system named in ipack
!! (parameters params(1:np), function table spec(1:nspec), nspec = 0 for a built-in;
!! both read at every call, as the system holds them) from y0 over [t0, tf].
!! ipack = [np, nspec, method, max_steps, neval, with_t_eval, lname, the name's lname
!! characters (codes)] (method as flat_solve, METHOD_RK45_SCIPY included; with_t_eval
!! /= 0: the points are t_eval's; the name packed with the numbers: one f2py conversion
!! less than a string argument); rpar = [first_step, max_step, rtol(1:n), atol(1:n),
!! t_eval(1:max(neval, 1))] (neval = 0: a point at every step, one unused number last).
!! On return iout(1:8) = [nt, nfev, njev, nlu, naccept, nreject, info, handle] and
!! iout(9:40) the message, its 256 characters as bytes (f2py's character output costs a
!! loop over every character on every call; this is read only when needed). nt > 0 points
!! in out (layout above); nt < 0: -nt points, more than out holds, kept at `handle` for
!! flat_solve_take (which must be called once, to take or to free them). Points as
!! solve_ivp returns them: a zero-length span without t_eval gives (t0, y0) twice (SciPy's
!! solver makes one empty step), a run that stored no point gives (t0, y0). info is the
!! run's status (0 end reached, < 0 failure, CM_BAD_INPUT refused) with its message.
subroutine flat_solve_packed(li, ipack, lp, params, ls, spec, lr, rpar, t0, tf, n, y0, &
                             nout, out, iout)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t
    use conmech_ode_system, only: ode_system
    use conmech_c_system, only: c_ode_system
    use conmech_flat_spec, only: spec_system_of_size, spec_kind, spec_c_ode, check_spec_size, &
        KIND_ODE
    use conmech_flat_packed_support, only: unpack_head, run_packed
    implicit none
    integer(c_int), intent(in) :: li, lp, ls, lr, n, nout
    integer(c_int64_t), intent(in) :: ipack(li)
    real(c_double), intent(in) :: params(lp)
    integer(c_int64_t), intent(in) :: spec(ls)
    real(c_double), intent(in) :: rpar(lr)
    real(c_double), intent(in) :: t0, tf
    real(c_double), intent(in) :: y0(n)
    real(c_double), intent(inout) :: out(nout)
    integer(c_int64_t), intent(inout) :: iout(40)
    class(ode_system), allocatable :: sys
    ! a compiled system (the frequent case) in a local object of its own type: no
    ! polymorphic allocation, copy and finalization per call
    type(c_ode_system) :: csys
    character(len=:), allocatable :: msg, name
    integer(c_int) :: ipar(6)
    integer :: info

    if (.not. unpack_head(ipack, lp, ls, lr, n, nout, ipar, name, iout)) return
    if (spec_kind(ipar(2), spec) == KIND_ODE) then
        call spec_c_ode(params(1:ipar(1)), spec, csys, info, msg)
        call check_spec_size(name, ipar(2), spec, n, "", info, msg)
        call run_packed(csys, info, msg, ipar, rpar, t0, tf, n, y0, out, iout)
        return
    end if
    call spec_system_of_size(name, params(1:ipar(1)), ipar(2), spec, n, "", sys, info, msg)
    call run_packed(sys, info, msg, ipar, rpar, t0, tf, n, y0, out, iout)
end subroutine flat_solve_packed

!> flat_solve_packed for a Python right-hand side fun(t, y, dydt, n) (f2py's one
!! call-back; its Jacobian, where the method needs one, by differences): the same packed
!! arguments (ipar's np and nspec 0) and outputs. An exception in fun stops the run (the
!! caller's guard raises it).
subroutine flat_solve_rhs_packed(fun, ipar, lr, rpar, t0, tf, n, y0, nout, out, iout)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t
    use conmech_ode_system, only: ode_system
    use conmech_flat_system, only: flat_system, SOURCE_FUN
    use conmech_flat_packed_support, only: packed_sizes_ok, run_packed
    implicit none
    integer(c_int), intent(in) :: ipar(6), lr, n, nout
    real(c_double), intent(in) :: rpar(lr)
    real(c_double), intent(in) :: t0, tf
    real(c_double), intent(in) :: y0(n)
    real(c_double), intent(inout) :: out(nout)
    integer(c_int64_t), intent(inout) :: iout(40)
!f2py external fun
    interface
        subroutine fun(t, y, dydt, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dydt(n)
        end subroutine fun
    end interface
    class(ode_system), allocatable :: sys
    character(len=256) :: msg
    integer :: info
    integer(c_int64_t) :: nospec(1)

    iout = 0
    if (.not. packed_sizes_ok(ipar, 1, 1, lr, n, nout, iout)) return
    nospec = 0
    call flat_system("", [0.0_c_double], 0, nospec, fun, fun, SOURCE_FUN, n, sys, info, msg)
    call run_packed(sys, info, msg, ipar, rpar, t0, tf, n, y0, out, iout)
end subroutine flat_solve_rhs_packed

!> The points of a run of flat_solve_packed that did not fit its output array: the nt
!! points kept at `handle`, in the layout of flat_solve_packed into out(1:nt*(n + 1)),
!! and their memory freed. Called once per such handle. info: 0, or CM_BAD_INPUT when nt
!! or out do not match the kept points, nothing copied (the memory is freed all the same:
!! nt = 0 is the call that only frees them, when the caller could not make room).
subroutine flat_solve_take(handle, n, nt, nout, out, info)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t, c_ptr, c_f_pointer, &
        c_intptr_t
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_solver, only: ode_result
    use conmech_flat_packed_support, only: put_points
    implicit none
    integer(c_int64_t), intent(in) :: handle
    integer(c_int), intent(in) :: n, nt, nout
    real(c_double), intent(inout) :: out(nout)
    integer(c_int), intent(out) :: info
    type(ode_result), pointer :: kept
    type(c_ptr) :: p

    info = CM_BAD_INPUT
    if (handle == 0) return
    p = transfer(int(handle, c_intptr_t), p)
    call c_f_pointer(p, kept)
    if (nt == kept%nt .and. nt > 0 .and. size(kept%y, 1) == n .and. nout >= nt*(n + 1)) then
        call put_points(kept%t, kept%y, nt, n, out)
        info = CM_SUCCESS
    end if
    deallocate (kept)
end subroutine flat_solve_take
