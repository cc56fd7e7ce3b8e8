!> Support of the flat routines of solve_ivp's packed calls (flat_solve_packed,
!! flat_solve_rhs_packed): the run of a system from the packed arguments and the transfer
!! of its points into the caller's arrays, without a call-back (conventions in
!! flat_solve_packed.f90).
module conmech_flat_packed_support
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t, c_loc, c_intptr_t
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_result
    use conmech_flat_ode_support, only: solve_into, copy_message
    implicit none
    private
    public :: packed_sizes_ok, unpack_head, run_packed, put_message, put_points, put_result

contains

    !> Whether the packed arrays agree with the state's size n: ipar = [np, nspec, method,
    !! max_steps, neval, with_t_eval] against lp parameters and ls spec entries, rpar of
    !! size lr, out of size nout (room for two points at least); else a refusal in iout.
    logical function packed_sizes_ok(ipar, lp, ls, lr, n, nout, iout) result(ok)
        integer(c_int), intent(in) :: ipar(6), lp, ls, lr, n, nout
        integer(c_int64_t), intent(inout) :: iout(40)
        ok = .not. (ipar(1) < 0 .or. ipar(1) > lp .or. ipar(2) < 0 .or. ipar(2) > ls .or. &
                    ipar(5) < 0 .or. n < 1 .or. lr < 2 + 2*n + max(ipar(5), 1) .or. &
                    nout < 2*(n + 1))
        if (ok) return
        iout(7) = CM_BAD_INPUT
        call put_message("bad input: packed arguments of inconsistent sizes", iout)
    end function packed_sizes_ok

    !> The head of ipack (flat_solve_packed's layout: [np, nspec, method, max_steps, neval,
    !! with_t_eval, lname, the name's lname character codes]) checked against the sizes of
    !! the other packed arrays (packed_sizes_ok): ipar = ipack(1:6) and the system's name;
    !! else a refusal in iout (iout cleared first either way).
    logical function unpack_head(ipack, lp, ls, lr, n, nout, ipar, name, iout) result(ok)
        integer(c_int64_t), intent(in) :: ipack(:)
        integer(c_int), intent(in) :: lp, ls, lr, n, nout
        integer(c_int), intent(out) :: ipar(6)
        character(len=:), allocatable, intent(out) :: name
        integer(c_int64_t), intent(inout) :: iout(40)
        integer, parameter :: HEAD = 7
        integer :: lname, li, i
        iout = 0
        ipar = 0
        li = size(ipack)
        lname = -1
        if (li >= HEAD) lname = int(max(-1_c_int64_t, min(ipack(HEAD), int(li, c_int64_t))))
        ok = lname >= 0 .and. li - HEAD >= lname
        if (.not. ok) then
            iout(7) = CM_BAD_INPUT
            call put_message("bad input: packed arguments of inconsistent sizes", iout)
            return
        end if
        ipar = int(ipack(1:6), c_int)
        ok = packed_sizes_ok(ipar, lp, ls, lr, n, nout, iout)
        if (.not. ok) return
        allocate (character(len=lname) :: name)
        do i = 1, lname
            name(i:i) = achar(iand(ipack(HEAD + i), 127_c_int64_t))
        end do
    end function unpack_head

    !> The message into iout(9:40), its 256 characters as bytes.
    subroutine put_message(text, iout)
        character(len=*), intent(in) :: text
        integer(c_int64_t), intent(inout) :: iout(40)
        character(len=256) :: message
        integer :: i
        message = text
        ! eight characters at a time (a transfer of the whole message into the array
        ! section goes through an allocated temporary)
        do i = 1, 32
            iout(8 + i) = transfer(message(8*i - 7:8*i), 0_c_int64_t)
        end do
    end subroutine put_message

    !> Integrate `sys` (made by the caller: sinfo, smsg its status) from the packed
    !! arguments and put the points, counts, status and message into out and iout (or
    !! keep the points for flat_solve_take when they do not fit).
    subroutine run_packed(sys, sinfo, smsg, ipar, rpar, t0, tf, n, y0, out, iout)
        class(ode_system), intent(in) :: sys
        integer, intent(in) :: sinfo
        character(len=*), intent(in) :: smsg
        integer(c_int), intent(in) :: ipar(6), n
        real(c_double), intent(in) :: rpar(:), t0, tf, y0(n)
        real(c_double), intent(inout) :: out(:)
        integer(c_int64_t), intent(inout) :: iout(40)
        type(ode_result) :: res
        character(len=256) :: message
        integer(c_int) :: none(1), counts(5), info

        counts = 0
        info = sinfo
        message = smsg
        if (info == CM_SUCCESS) then
            none = 0
            call solve_into(sys, n, [t0, tf], y0, ipar(3), rpar(3:2 + n), &
                            rpar(3 + n:2 + 2*n), rpar(1), rpar(2), ipar(4), 0, ipar(5), &
                            rpar(3 + 2*n:), 0, none, none, [0.0_c_double], 0, -1, none, &
                            none, res, counts, info, message)
        end if
        iout(2:6) = counts
        iout(7) = info
        call put_message(message, iout)
        call put_result(res, info, t0, tf, ipar(6) /= 0, n, y0, out, iout)
    end subroutine run_packed

    !> The points of the run `res` from (t0, y0) to tf (status info; with_t_eval: its
    !! points are the output times') into out and iout(1), or kept for flat_solve_take
    !! (iout(1) = -their number, iout(8) the handle) when they do not fit: the start alone
    !! for a run refused or stopped before its first step, twice for a zero-length span
    !! without output times (SciPy's one empty step); nothing for a refusal.
    subroutine put_result(res, info, t0, tf, with_t_eval, n, y0, out, iout)
        type(ode_result), intent(inout) :: res
        integer(c_int), intent(in) :: info, n
        real(c_double), intent(in) :: t0, tf, y0(n)
        logical, intent(in) :: with_t_eval
        real(c_double), intent(inout) :: out(:)
        integer(c_int64_t), intent(inout) :: iout(40)
        type(ode_result), pointer :: kept
        if (info == CM_BAD_INPUT) return
        if (tf == t0 .and. .not. with_t_eval) then
            ! SciPy's solver makes one (empty) step: t = [t0, t0]
            call put_start(2)
        else if (.not. allocated(res%t)) then
            call put_start(1)               ! refused before its first step: the start only
        else if (res%nt == 0) then
            call put_start(1)
        else if (res%nt*(n + 1) <= size(out)) then
            call put_points(res%t, res%y, res%nt, n, out)
            iout(1) = res%nt
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
    end subroutine put_result

    !> The points t(1:m), y(:, 1:m) into out in the packed layout: the times, then the
    !! states by component (out(m*i + 1 : m*(i + 1)) = y(i, 1:m)).
    subroutine put_points(t, y, m, n, out)
        real(dp), intent(in) :: t(:), y(:, :)
        integer(c_int), intent(in) :: m, n
        real(c_double), intent(inout) :: out(:)
        integer :: i
        out(1:m) = t(1:m)
        do i = 1, n
            out(m*i + 1:m*(i + 1)) = y(i, 1:m)
        end do
    end subroutine put_points
end module conmech_flat_packed_support
