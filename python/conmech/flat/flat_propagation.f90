!> conmech.Propagator's route for a built-in or compiled system: the system, its stepper
!! and options made once (flat_propagation_new) and kept in Fortran memory at a handle the
!! caller owns, a propagation per call (flat_propagation_until: three small arguments and
!! the state), and the memory freed once (flat_propagation_free). See
!! support/conmech_flat_propagation.f90; iout's layout is flat_solve_packed's.

!> A kept propagation from the packed arguments of flat_solve_packed (ipack, params,
!! spec, rpar; the output times in them are not read) for a state of size n. On return
!! iout(7) = 0 and iout(8) the handle (for flat_propagation_until, and
!! flat_propagation_free once), or iout(7) = CM_BAD_INPUT with the message in iout(9:40)
!! and no handle (nothing to free).
subroutine flat_propagation_new(li, ipack, lp, params, ls, spec, lr, rpar, n, iout)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t, c_loc, c_intptr_t
    use conmech_status, only: CM_SUCCESS
    use conmech_flat_packed_support, only: unpack_head, put_message
    use conmech_flat_propagation, only: kept_propagation, propagation_make
    implicit none
    integer(c_int), intent(in) :: li, lp, ls, lr, n
    integer(c_int64_t), intent(in) :: ipack(li)
    real(c_double), intent(in) :: params(lp)
    integer(c_int64_t), intent(in) :: spec(ls)
    real(c_double), intent(in) :: rpar(lr)
    integer(c_int64_t), intent(inout) :: iout(40)
    type(kept_propagation), pointer :: p
    character(len=:), allocatable :: msg, name
    integer(c_int) :: ipar(6)
    integer :: info

    if (.not. unpack_head(ipack, lp, ls, lr, n, 2*(n + 1), ipar, name, iout)) return
    allocate (p)
    call propagation_make(name, params(1:ipar(1)), ipar(2), spec, ipar, rpar, n, p, info, msg)
    if (info /= CM_SUCCESS) then
        deallocate (p)
        iout(7) = info
        call put_message(msg, iout)
        return
    end if
    iout(8) = transfer(c_loc(p), 0_c_intptr_t)
end subroutine flat_propagation_new

!> One propagation of y (size n) from t0 to t1 by the kept propagation at `handle`, with
!! the parameters params (the propagation's number of them first; one unused number
!! when it has none; the system is made again when their values changed). On return
!! y is the state at t1 when the run reached it (iout(7) = 0), else as it was (iout(7) <
!! 0: the run's failure; CM_BAD_INPUT: refused); iout(2:6) = [nfev, njev, nlu, naccept,
!! nreject], the message in iout(9:40).
subroutine flat_propagation_until(handle, lp, params, t0, t1, n, y, iout)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t
    use conmech_flat_packed_support, only: put_message
    use conmech_flat_propagation, only: kept_propagation, propagation_at, propagation_run
    implicit none
    integer(c_int64_t), intent(in) :: handle
    integer(c_int), intent(in) :: lp, n
    real(c_double), intent(in) :: params(lp)
    real(c_double), intent(in) :: t0, t1
    real(c_double), intent(inout) :: y(n)
    integer(c_int64_t), intent(inout) :: iout(40)
    type(kept_propagation), pointer :: p
    character(len=:), allocatable :: msg
    integer(c_int) :: counts(5)
    integer :: info

    p => propagation_at(handle, n, lp, iout)
    if (.not. associated(p)) return
    call propagation_run(p, params(1:size(p%params)), t0, t1, y, counts, info, msg)
    iout(1) = merge(1, 0, info >= 0)
    iout(2:6) = counts
    iout(7) = info
    call put_message(msg, iout)
end subroutine flat_propagation_until

!> Free the kept propagation at `handle` (made by flat_propagation_new; once per handle).
subroutine flat_propagation_free(handle)
    use, intrinsic :: iso_c_binding, only: c_int64_t
    use conmech_flat_propagation, only: kept_propagation, propagation_at
    implicit none
    integer(c_int64_t), intent(in) :: handle
    type(kept_propagation), pointer :: p
    p => propagation_at(handle)
    if (associated(p)) deallocate (p)
end subroutine flat_propagation_free

!> The states at the m times `times` (sorted from t0 towards the last, finite) by the
!! kept propagation at `handle`, from one run from (t0, y) to the last time that evaluates
!! its steps' continuous extension at the others (solve_ivp's t_eval): out(:, j) the state
!! at times(j), NaN from the first time not reached; y (the state at t0 on entry) the
!! state at the last time reached. iout(1) the number of times reached, iout(2:6) the
!! run's counts, iout(7) its status (message in iout(9:40)), CM_BAD_INPUT for times out of
!! order (nothing run).
subroutine flat_propagation_grid(handle, lp, params, t0, m, times, n, y, out, iout)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t
    use conmech_kinds, only: nan_dp
    use conmech_status, only: CM_BAD_INPUT
    use conmech_flat_packed_support, only: put_message
    use conmech_flat_propagation, only: kept_propagation, propagation_at, propagation_grid
    implicit none
    integer(c_int64_t), intent(in) :: handle
    integer(c_int), intent(in) :: lp, m, n
    real(c_double), intent(in) :: params(lp)
    real(c_double), intent(in) :: t0
    real(c_double), intent(in) :: times(m)
    real(c_double), intent(inout) :: y(n)
    real(c_double), intent(inout) :: out(n, m)
    integer(c_int64_t), intent(inout) :: iout(40)
    type(kept_propagation), pointer :: p
    character(len=:), allocatable :: msg
    integer(c_int) :: counts(5)
    integer :: info, nt

    p => propagation_at(handle, n, lp, iout)
    if (.not. associated(p)) return
    if (m < 1 .or. .not. sorted_from(t0, times)) then
        iout(7) = CM_BAD_INPUT
        call put_message("bad input: the times must be finite and sorted strictly from "// &
                         "the propagator's time in one direction", iout)
        return
    end if
    out = nan_dp
    call propagation_grid(p, params(1:size(p%params)), t0, times, y, out, nt, counts, info, &
                          msg)
    iout(1) = nt
    iout(2:6) = counts
    iout(7) = info
    call put_message(msg, iout)

contains

    !> times finite, the first at or after t0 and each strictly after the one before, in
    !! the direction from t0 to the last
    logical function sorted_from(t0, times) result(ok)
        real(c_double), intent(in) :: t0, times(:)
        real(c_double) :: dir, before
        integer :: j
        dir = sign(1.0_c_double, times(size(times)) - t0)
        ok = (times(1) - t0)*dir >= 0.0_c_double
        before = times(1)
        do j = 1, size(times)
            ok = ok .and. abs(times(j)) <= huge(1.0_c_double)
            if (j > 1) ok = ok .and. (times(j) - before)*dir > 0.0_c_double
            before = times(j)
        end do
    end function sorted_from
end subroutine flat_propagation_grid

!> solve_ivp's run from (t0, y0) (size n) to tf by the kept propagation at `handle` (made
!! from the packed arguments of flat_solve_packed), with this call's step options and
!! output times: the first step h0 (0: the method's choice), the largest step hmax, the
!! step limit max_steps, and with_t_eval /= 0: the points at t_eval(1:neval) (neval = 0:
!! every step's, as flat_solve_packed; t_eval has one unused number then). The points,
!! counts, status and message in out and iout exactly as flat_solve_packed gives them for
!! the same arguments (the points kept for flat_solve_take when they do not fit), without
!! making the system and its stepper again.
subroutine flat_propagation_solve(handle, lp, params, t0, tf, n, y0, h0, hmax, max_steps, &
                                  with_t_eval, neval, lt, t_eval, nout, out, iout)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t
    use conmech_status, only: CM_BAD_INPUT
    use conmech_ode_result, only: ode_result
    use conmech_flat_packed_support, only: put_message, put_result
    use conmech_flat_propagation, only: kept_propagation, propagation_at, propagation_solve
    implicit none
    integer(c_int64_t), intent(in) :: handle
    integer(c_int), intent(in) :: lp, n, max_steps, with_t_eval, neval, lt, nout
    real(c_double), intent(in) :: params(lp)
    real(c_double), intent(in) :: t0, tf, h0, hmax
    real(c_double), intent(in) :: y0(n)
    real(c_double), intent(in) :: t_eval(lt)
    real(c_double), intent(inout) :: out(nout)
    integer(c_int64_t), intent(inout) :: iout(40)
    type(kept_propagation), pointer :: p
    type(ode_result) :: res
    character(len=:), allocatable :: msg
    integer(c_int) :: counts(5)
    integer :: info

    p => propagation_at(handle, n, lp, iout)
    if (.not. associated(p)) return
    if (nout < 2*(n + 1) .or. neval < 0 .or. neval > lt) then
        iout(7) = CM_BAD_INPUT
        call put_message("bad input: packed arguments of inconsistent sizes", iout)
        return
    end if
    if (neval > 0) then
        call propagation_solve(p, params(1:size(p%params)), t0, tf, y0, h0, hmax, max_steps, &
                               res, counts, info, msg, t_eval(1:neval))
    else
        call propagation_solve(p, params(1:size(p%params)), t0, tf, y0, h0, hmax, max_steps, &
                               res, counts, info, msg)
    end if
    iout(2:6) = counts
    iout(7) = info
    call put_message(msg, iout)
    call put_result(res, info, t0, tf, with_t_eval /= 0, n, y0, out, iout)
end subroutine flat_propagation_solve
