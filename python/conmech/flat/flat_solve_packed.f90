!> solve_ivp's common case (a built-in or compiled system, no events, no dense output)
!! through the flat layer at the smallest fixed cost. f2py's cost per call grows with the
!! number of arguments, with every output array it creates (zero-filled) and above all
!! with a call-back argument (the Python function is inspected on every call), so this
!! routine has none of these: the arguments that do not change between calls with the
!! same method and tolerances come packed in two arrays the caller prepares once
!! (ipar, rpar), the outputs go into arrays the caller passes (out, iout), and a run with
!! more points than `out` holds leaves them in Fortran memory for flat_solve_take.
!!
!! The layout of the points in out (nt points, n components): out(1:nt) the times, then
!! the states by component, out(nt*i + 1 : nt*(i + 1)) = y(i, 1:nt): the caller reads
!! y as a C-ordered (n, nt) array without a copy.

!> Integrate y' = f(t, y) of the built-in (or compiled) system `name` (parameters
!! params(1:np), function table spec(1:nspec), nspec = 0 for a built-in) from y0 over
!! [t0, tf]. ipar = [np, nspec, method, max_steps, neval, with_t_eval] (method as
!! flat_solve, METHOD_RK45_SCIPY included; with_t_eval /= 0: the points are t_eval's); rpar = [first_step, max_step, rtol(1:n), atol(1:n),
!! t_eval(1:max(neval, 1))] (neval = 0: a point at every step, one unused number last).
!! On return iout(1:8) = [nt, nfev, njev, nlu, naccept, nreject, info, handle] and
!! iout(9:40) the message, its 256 characters as bytes (f2py's character output costs a
!! loop over every character on every call; this is read only when needed): nt > 0 points
!! in out (layout above); nt < 0: -nt points, more than out holds, kept at `handle` for
!! flat_solve_take (which must be called once, to take or to free them). Points as
!! solve_ivp returns them: a zero-length span without t_eval gives (t0, y0) twice (SciPy's
!! solver makes one empty step), a run that stored no point gives (t0, y0). info is the
!! run's status (0 end reached, < 0 failure, CM_BAD_INPUT refused) with its message.
subroutine flat_solve_packed(name, lp, params, ls, spec, ipar, lr, rpar, t0, tf, n, y0, &
                             nout, out, iout)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t, c_loc, c_intptr_t
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_result
    use conmech_flat_spec, only: spec_system_of_size
    use conmech_flat_ode_support, only: solve_into, copy_message
    implicit none
    character(len=*), intent(in) :: name
    integer(c_int), intent(in) :: lp, ls, lr, n, nout
    real(c_double), intent(in) :: params(lp)
    integer(c_int64_t), intent(in) :: spec(ls)
    integer(c_int), intent(in) :: ipar(6)
    real(c_double), intent(in) :: rpar(lr)
    real(c_double), intent(in) :: t0, tf
    real(c_double), intent(in) :: y0(n)
    real(c_double), intent(inout) :: out(nout)
    integer(c_int64_t), intent(inout) :: iout(40)
    character(len=256) :: message
    class(ode_system), allocatable :: sys
    type(ode_result) :: res
    type(ode_result), pointer :: kept
    character(len=:), allocatable :: msg
    integer(c_int) :: none(1), counts(5), info, np, nspec, neval, nt

    iout = 0
    np = ipar(1)
    nspec = ipar(2)
    neval = ipar(5)
    if (np < 0 .or. np > lp .or. nspec < 0 .or. nspec > ls .or. neval < 0 .or. n < 1 .or. &
        lr < 2 + 2*n + max(neval, 1) .or. nout < 2*(n + 1)) then
        iout(7) = CM_BAD_INPUT
        call copy_message("bad input: packed arguments of inconsistent sizes", message)
        iout(9:40) = transfer(message, iout(9:40))
        return
    end if
    message = ""
    counts = 0
    call spec_system_of_size(name, real(params(1:np), dp), nspec, spec, n, "", sys, info, msg)
    if (info /= CM_SUCCESS) then
        call copy_message(msg, message)
    else
        none = 0
        call solve_into(sys, n, [t0, tf], y0, ipar(3), rpar(3:2 + n), rpar(3 + n:2 + 2*n), &
                        rpar(1), rpar(2), ipar(4), 0, neval, rpar(3 + 2*n:), 0, none, none, &
                        [0.0_c_double], 0, -1, none, none, res, counts, info, message)
    end if
    iout(2:6) = counts
    iout(7) = info
    iout(9:40) = transfer(message, iout(9:40))
    if (info == CM_BAD_INPUT) return
    if (tf == t0 .and. ipar(6) == 0) then
        ! SciPy's solver makes one (empty) step: t = [t0, t0]
        call put_start(2)
    else if (.not. allocated(res%t)) then
        call put_start(1)               ! refused before its first step: the start only
    else if (res%nt == 0) then
        call put_start(1)
    else if (res%nt*(n + 1) <= nout) then
        nt = res%nt
        iout(1) = nt
        call put_points(res%t, res%y, nt)
    else
        ! more points than out holds: kept for flat_solve_take, which frees them
        allocate (kept)
        kept%nt = res%nt
        call move_alloc(res%t, kept%t)
        call move_alloc(res%y, kept%y)
        iout(1) = -kept%nt
        iout(8) = transfer(c_loc(kept), 0_c_intptr_t)
    end if

contains

    !> The start (t0, y0) as the only point, k times.
    subroutine put_start(k)
        integer(c_int), intent(in) :: k
        integer :: i
        iout(1) = k
        out(1:k) = t0
        do i = 1, n
            out(k*i + 1:k*(i + 1)) = y0(i)
        end do
    end subroutine put_start

    !> The points t(1:m), y(:, 1:m) in the layout of out.
    subroutine put_points(t, y, m)
        real(dp), intent(in) :: t(:), y(:, :)
        integer(c_int), intent(in) :: m
        integer :: i
        out(1:m) = t(1:m)
        do i = 1, n
            out(m*i + 1:m*(i + 1)) = y(i, 1:m)
        end do
    end subroutine put_points
end subroutine flat_solve_packed

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
    implicit none
    integer(c_int64_t), intent(in) :: handle
    integer(c_int), intent(in) :: n, nt, nout
    real(c_double), intent(inout) :: out(nout)
    integer(c_int), intent(out) :: info
    type(ode_result), pointer :: kept
    type(c_ptr) :: p
    integer :: i

    info = CM_BAD_INPUT
    if (handle == 0) return
    p = transfer(int(handle, c_intptr_t), p)
    call c_f_pointer(p, kept)
    if (nt == kept%nt .and. nt > 0 .and. size(kept%y, 1) == n .and. nout >= nt*(n + 1)) then
        out(1:nt) = kept%t(1:nt)
        do i = 1, n
            out(nt*i + 1:nt*(i + 1)) = kept%y(i, 1:nt)
        end do
        info = CM_SUCCESS
    end if
    deallocate (kept)
end subroutine flat_solve_take
