!> DOP853 in quadruple precision for a reference solution: the right-hand side is the first
!! Taylor coefficient of the generated real128 routine at fnaddr (nw work columns); y0, the
!! parameters, t0, tf, rtol and atol as pairs of doubles (hi, lo: the value hi + lo), the
!! final state y1 likewise. fixed_steps > 0: that many equal steps without error control.
!! counts = [nfev, nsteps, naccept, nreject].
subroutine flat_dop853_quad(fnaddr, nw, np, params, n, y0, t_span, rtol, atol, max_steps, &
                            fixed_steps, y1, counts, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_status, only: CM_BAD_INPUT
    use conmech_taylor_quad, only: qp, taylor_qp_fn
    use conmech_flat_quad_pairs, only: from_pairs, from_pair, to_pairs, quad_routine
    use conmech_dop853_quad, only: dop853_propagate_qp, dop853_qp_counts
    use conmech_flat_ode_support, only: copy_message
    implicit none
    integer(8), intent(in) :: fnaddr
    integer(c_int), intent(in) :: nw, np, n, max_steps, fixed_steps
    real(c_double), intent(in) :: params(2, max(np, 1)), y0(2, n), t_span(2, 2), rtol(2)
    real(c_double), intent(in) :: atol(2)
    real(c_double), intent(out) :: y1(2, n)
    integer(c_int), intent(out) :: counts(4), info
    character(len=256), intent(out) :: message
    procedure(taylor_qp_fn), pointer :: fn
    type(dop853_qp_counts) :: cnt
    real(qp) :: y(n), p(max(np, 1))
    character(len=:), allocatable :: msg
    integer :: inf
    y1 = y0
    counts = 0
    if (fnaddr == 0 .or. nw < n .or. n < 1 .or. np < 0) then
        info = CM_BAD_INPUT
        call copy_message("bad input: invalid quadruple-precision Taylor routine", message)
        return
    end if
    call quad_routine(fnaddr, fn)
    y = from_pairs(y0)
    p = from_pairs(params)
    call dop853_propagate_qp(fn, n, nw, p, from_pair(t_span(:, 1)), from_pair(t_span(:, 2)), &
                             y, from_pair(rtol), from_pair(atol), max_steps, inf, msg, cnt, &
                             fixed_steps=fixed_steps)
    call to_pairs(y, y1)
    counts = [cnt%nfev, cnt%nsteps, cnt%naccept, cnt%nreject]
    info = inf
    call copy_message(msg, message)
end subroutine flat_dop853_quad
