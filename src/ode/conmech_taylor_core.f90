!> The arithmetic of one Taylor step, shared by the scalar stepper (conmech_taylor_stepper)
!! and the batch propagator (conmech_taylor_batch), so that a member of a batch takes
!! exactly the steps, bit for bit, of the same integration on its own.
!!
!! - `taylor_order`, `taylor_decay`: the order for the tolerance eps (Jorba and Zou's
!!   ceil(-ln(eps)/2 + 1) raised by 3, or a fifth above 19) and the step's fraction of
!!   the radius;
!! - `taylor_scales`: E_i = max(atol_i, rtol_i ||y||_inf) per block (state, Phi);
!! - `taylor_rho`: the step rho decay from the last two coefficients,
!!   rho = min over k = p - 1, p of (1/N_k)^(1/k), N_k = max_i eps |y_i^[k]|/E_i;
!! - `taylor_eval_step`: y(t + h) and the polynomial's derivative there (Horner);
!! - `taylor_check`: the safety-check ratio |h (P'(h) - f(t + h, P(h)))| / ((p + 1) E_i),
!!   about the local error over the tolerance (the next expansion gives f there for free);
!! - `taylor_add_time`: t + h in double length (Knuth's TwoSum);
!! - `taylor_eval_jet`, `taylor_check_jet`, `taylor_next_rho`: the same arithmetic, operation
!!   for operation, on the expansions themselves (the scalar stepper's path: the new state
!!   is written by Horner straight into the next expansion's zeroth coefficients, the check
!!   reads f there, and the scales and the norms of the last two coefficients are one pass).
module conmech_taylor_core
    use, intrinsic :: iso_fortran_env, only: int64
    use conmech_kinds, only: dp
    implicit none
    private
    public :: taylor_order, taylor_decay, taylor_scales, taylor_rho, taylor_eval_step, &
        taylor_check, taylor_add_time, taylor_shrink, TAYLOR_CHECK_MAX, taylor_eval_jet, &
        taylor_check_jet, taylor_next_rho

    real(dp), parameter :: TAYLOR_CHECK_MAX = 10.0_dp   !! rejected above 10 x the tolerance
    real(dp), parameter :: LOG_HUGE = log(huge(1.0_dp))
    integer, parameter :: NOT_NORMAL = -huge(1)

contains

    !> The order for the tolerance eps: Jorba and Zou's p0 = ceil(-ln(eps)/2 + 1) raised by
    !! max(3, p0/5) (18 at 1e-12, 24 at 1e-16). Jorba and Zou's p0 minimises the work of a
    !! step counted as p^2 products; but a step of a small system is a chain of dependent
    !! operations whose length grows like p, with a fixed part (Horner, the check, the step
    !! size) beside it, so a higher order with longer steps (taylor_decay) takes less time:
    !! on Kepler's problem at 1e-12, 54 steps of order 18 against 73 of order 15, 11% fewer
    !! instructions, a smaller error (bench/results/taylor_order.md).
    pure integer function taylor_order(eps)
        real(dp), intent(in) :: eps
        integer :: p0
        p0 = jorba_zou_order(eps)
        taylor_order = p0 + max(3, p0/5)
    end function taylor_order

    !> Jorba and Zou's order ceil(-ln(eps)/2 + 1), at least 2.
    pure integer function jorba_zou_order(eps)
        real(dp), intent(in) :: eps
        jorba_zou_order = max(2, ceiling(-0.5_dp*log(max(eps, tiny(1.0_dp))) + 1.0_dp))
    end function jorba_zou_order

    !> The step's fraction of the radius of convergence, h = rho decay, for the order
    !! taylor_order(eps). Jorba and Zou's step at their order p0 is rho exp(-lambda0),
    !! lambda0 = 2 + 0.7/(p0 - 1), so the first neglected term is (h/rho)^(p0 + 1) =
    !! exp(-lambda0 (p0 + 1)) of the solution's scale; at the order p the same bound on
    !! the first neglected term gives decay = exp(-lambda0 (p0 + 1)/(p + 1)).
    pure real(dp) function taylor_decay(eps)
        real(dp), intent(in) :: eps
        integer :: p0, p
        p0 = jorba_zou_order(eps)
        p = taylor_order(eps)
        taylor_decay = exp(-(2.0_dp + 0.7_dp/real(p0 - 1, dp))*real(p0 + 1, dp)/real(p + 1, dp))
    end function taylor_decay

    !> E_i = max(atol_i, rtol_i ||y||_inf) over the first nb components (the state) and
    !! over the rest (Phi) separately; at least the smallest normal number.
    pure subroutine taylor_scales(n, nb, y, rtol, atol, e)
        integer, intent(in) :: n, nb
        real(dp), intent(in) :: y(n), rtol(n), atol(n)
        real(dp), intent(out) :: e(n)
        real(dp) :: y1, y2
        integer :: i
        y1 = 0.0_dp
        do i = 1, nb
            y1 = max(y1, abs(y(i)))
        end do
        do i = 1, nb
            e(i) = max(atol(i), rtol(i)*y1, tiny(1.0_dp))
        end do
        if (n > nb) then
            y2 = 0.0_dp
            do i = nb + 1, n
                y2 = max(y2, abs(y(i)))
            end do
            do i = nb + 1, n
                e(i) = max(atol(i), rtol(i)*y2, tiny(1.0_dp))
            end do
        end if
    end subroutine taylor_scales

    !> Jorba and Zou's step (unsigned; huge when the last two coefficients vanish) from the
    !! coefficients c(0:p, 1:n) and the scales e; decay = taylor_decay(eps). The smaller
    !! of the two radii is taken in the logarithm: two logarithms and one exponential.
    pure real(dp) function taylor_rho(n, p, c, e, eps, decay) result(rho)
        integer, intent(in) :: n, p
        real(dp), intent(in) :: c(0:p, n), e(n), eps, decay
        real(dp) :: s1, s2, l
        integer :: i
        s1 = 0.0_dp
        s2 = 0.0_dp
        do i = 1, n
            s1 = max(s1, abs(c(p - 1, i))/e(i))
            s2 = max(s2, abs(c(p, i))/e(i))
        end do
        l = huge(1.0_dp)
        if (s1 > 0.0_dp) l = -log(s1*eps)/real(p - 1, dp)
        if (s2 > 0.0_dp) l = min(l, -log(s2*eps)/real(p, dp))
        rho = huge(1.0_dp)
        if (l < LOG_HUGE) rho = exp(l)*decay
    end function taylor_rho

    !> y(t + h) = sum_k c(k, i) h^k and its derivative dy (Horner; the derivative from the
    !! same pass, d_k = y_(k+1) + h d_(k+1): two multiply-adds per order, no weights).
    !! Explicit shapes (no stride arithmetic of an assumed-shape dummy). The two chains of
    !! one component are dependent (a multiply and an add per order each, latency-bound),
    !! so four components run interleaved in one pass over the orders: eight independent
    !! chains fill the pipeline and share the loop overhead. Every component gets the
    !! operations of its own Horner chain, so the result does not depend on the grouping.
    pure subroutine taylor_eval_step(n, p, c, h, ynew, dy)
        integer, intent(in) :: n, p
        real(dp), intent(in) :: c(0:p, n), h
        real(dp), intent(out) :: ynew(n), dy(n)
        real(dp) :: y1, y2, y3, y4, d1, d2, d3, d4
        integer :: i, k
        i = 1
        do while (i + 3 <= n)
            y1 = c(p, i)
            y2 = c(p, i + 1)
            y3 = c(p, i + 2)
            y4 = c(p, i + 3)
            d1 = 0.0_dp
            d2 = 0.0_dp
            d3 = 0.0_dp
            d4 = 0.0_dp
            do k = p - 1, 0, -1
                d1 = y1 + h*d1
                d2 = y2 + h*d2
                d3 = y3 + h*d3
                d4 = y4 + h*d4
                y1 = c(k, i) + h*y1
                y2 = c(k, i + 1) + h*y2
                y3 = c(k, i + 2) + h*y3
                y4 = c(k, i + 3) + h*y4
            end do
            ynew(i:i + 3) = [y1, y2, y3, y4]
            dy(i:i + 3) = [d1, d2, d3, d4]
            i = i + 4
        end do
        do while (i + 1 <= n)
            y1 = c(p, i)
            y2 = c(p, i + 1)
            d1 = 0.0_dp
            d2 = 0.0_dp
            do k = p - 1, 0, -1
                d1 = y1 + h*d1
                d2 = y2 + h*d2
                y1 = c(k, i) + h*y1
                y2 = c(k, i + 1) + h*y2
            end do
            ynew(i:i + 1) = [y1, y2]
            dy(i:i + 1) = [d1, d2]
            i = i + 2
        end do
        if (i == n) then
            y1 = c(p, i)
            d1 = 0.0_dp
            do k = p - 1, 0, -1
                d1 = y1 + h*d1
                y1 = c(k, i) + h*y1
            end do
            ynew(i) = y1
            dy(i) = d1
        end if
    end subroutine taylor_eval_step

    !> taylor_eval_step with the new state also written into w(0, 1:n) (the zeroth
    !! coefficients of the expansion about the step's end, which the system then
    !! completes): the same Horner chains. The chains' results go to the contiguous ynew
    !! and dy first (stored contiguously, the compiler pairs the chains into packed
    !! operations; a strided store into w keeps them scalar), then into w.
    pure subroutine taylor_eval_jet(n, p, c, h, w, ynew, dy)
        integer, intent(in) :: n, p
        real(dp), intent(in) :: c(0:p, n), h
        real(dp), intent(inout) :: w(0:p, n)
        real(dp), intent(out) :: ynew(n), dy(n)
        integer :: i
        call taylor_eval_step(n, p, c, h, ynew, dy)
        do i = 1, n
            w(0, i) = ynew(i)
        end do
    end subroutine taylor_eval_jet

    !> taylor_check (err) on the expansion about the step's end, w(0, :) = P(h) and
    !! w(1, :) = f(t + h, P(h)); finite: f there is finite (the next step's precondition), found in
    !! the same pass.
    pure subroutine taylor_check_jet(n, p, h, w, dy, e, err, finite)
        integer, intent(in) :: n, p
        real(dp), intent(in) :: h, w(0:p, n), dy(n), e(n)
        real(dp), intent(out) :: err
        logical, intent(out) :: finite
        real(dp) :: c, d
        integer :: i
        real(dp) :: z
        c = 16.0_dp*epsilon(1.0_dp)
        err = 0.0_dp
        z = 0.0_dp
        do i = 1, n
            d = abs(h*(dy(i) - w(1, i)))
            err = max(err, d/(e(i) + c*(abs(w(0, i)) + abs(h*dy(i)))))
            z = z + 0.0_dp*w(1, i)          ! NaN once an f_i is Inf or NaN (IEEE: 0 Inf)
        end do
        finite = z == z
        err = err/real(p + 1, dp)
    end subroutine taylor_check_jet

    !> taylor_scales of the state w(0, 1:n) (e) and taylor_rho of the expansion w (rho) in one pass
    !! over it (the same values, bit for bit). The two radii (1/N_k)^(1/k) of the last two
    !! coefficients need two logarithms only when their order is not already told by the
    !! binary exponents of N_k: ln N = (e + ln(f)/ln 2) ln 2 with N = f 2^e, f in [1/2, 1),
    !! so -ln(N_k)/k lies in an interval of width ln 2/k known from e alone; the radius whose
    !! interval lies entirely below the other's is the minimum, and its logarithm alone is
    !! taken. Then one exponential.
    pure subroutine taylor_next_rho(n, nb, p, w, rtol, atol, eps, decay, e, rho)
        integer, intent(in) :: n, nb, p
        real(dp), intent(in) :: w(0:p, n), rtol(n), atol(n), eps, decay
        real(dp), intent(out) :: e(n), rho
        real(dp) :: y1, y2, s1, s2, l, a1, a2
        integer :: i, e1, e2
        y1 = 0.0_dp
        do i = 1, nb
            y1 = max(y1, abs(w(0, i)))
        end do
        s1 = 0.0_dp
        s2 = 0.0_dp
        do i = 1, nb
            e(i) = max(atol(i), rtol(i)*y1, tiny(1.0_dp))
            s1 = max(s1, abs(w(p - 1, i))/e(i))
            s2 = max(s2, abs(w(p, i))/e(i))
        end do
        if (n > nb) then
            y2 = 0.0_dp
            do i = nb + 1, n
                y2 = max(y2, abs(w(0, i)))
            end do
            do i = nb + 1, n
                e(i) = max(atol(i), rtol(i)*y2, tiny(1.0_dp))
                s1 = max(s1, abs(w(p - 1, i))/e(i))
                s2 = max(s2, abs(w(p, i))/e(i))
            end do
        end if
        l = huge(1.0_dp)
        a1 = s1*eps
        a2 = s2*eps
        e1 = binary_exponent(a1)
        e2 = binary_exponent(a2)
        if (s1 > 0.0_dp .and. s2 > 0.0_dp .and. e1 /= NOT_NORMAL .and. e2 /= NOT_NORMAL) then
            ! l1 = -ln(a1)/(p - 1) in (-e1, -(e1 - 1)] ln 2/(p - 1), l2 likewise over p
            if ((e1 - 1)*p > e2*(p - 1)) then
                l = -log(a1)/real(p - 1, dp)             ! l1 < l2 for sure
            else if ((e2 - 1)*(p - 1) > e1*p) then
                l = -log(a2)/real(p, dp)                 ! l2 < l1 for sure
            else
                l = min(-log(a1)/real(p - 1, dp), -log(a2)/real(p, dp))
            end if
        else
            if (s1 > 0.0_dp) l = -log(a1)/real(p - 1, dp)
            if (s2 > 0.0_dp) l = min(l, -log(a2)/real(p, dp))
        end if
        rho = huge(1.0_dp)
        if (l < LOG_HUGE) rho = exp(l)*decay
    end subroutine taylor_next_rho

    !> e with a = f 2^e, f in [1/2, 1), for a positive normal finite a (from the bits, as
    !! the intrinsic exponent() gives it); NOT_NORMAL for zero, subnormal, Inf or NaN.
    pure integer function binary_exponent(a) result(ex)
        real(dp), intent(in) :: a
        integer(int64) :: bits
        bits = ishft(transfer(a, 0_int64), -52)       ! sign and biased exponent
        ex = NOT_NORMAL
        if (bits >= 1 .and. bits <= 2046) ex = int(bits) - 1022
    end function binary_exponent

    !> The safety-check ratio of a step: f1 = f(t + h, ynew) from the next expansion, e the
    !! scales at the step's start (a rounding floor of 16 eps |y| is added).
    pure real(dp) function taylor_check(n, p, h, ynew, dy, f1, e) result(err)
        integer, intent(in) :: n, p
        real(dp), intent(in) :: h, ynew(n), dy(n), e(n)
        real(dp), intent(in) :: f1(:)    ! assumed shape: a row of the expansion, no copy
        real(dp) :: c, d
        integer :: i
        c = 16.0_dp*epsilon(1.0_dp)
        err = 0.0_dp
        do i = 1, n
            d = abs(h*(dy(i) - f1(i)))
            err = max(err, d/(e(i) + c*(abs(ynew(i)) + abs(h*dy(i)))))
        end do
        err = err/real(p + 1, dp)
    end function taylor_check

    !> The shorter step after a rejected one (err > TAYLOR_CHECK_MAX, or not finite).
    pure real(dp) function taylor_shrink(h, err, p) result(hn)
        real(dp), intent(in) :: h, err
        integer, intent(in) :: p
        if (err == err .and. err <= huge(1.0_dp)) then
            hn = h*max(0.1_dp, min(0.5_dp, 0.8_dp*(TAYLOR_CHECK_MAX/err)** &
                                          (1.0_dp/real(p + 1, dp))))
        else
            hn = 0.1_dp*h
        end if
    end function taylor_shrink

    !> (t, t_lo) += h in double length (Knuth's TwoSum): the time of a long run keeps its
    !! last bits, so the state (propagated by the exact sum of the steps) and t agree.
    pure subroutine taylor_add_time(t, t_lo, h)
        real(dp), intent(inout) :: t, t_lo
        real(dp), intent(in) :: h
        real(dp) :: s, bb, lo
        s = t + h
        bb = s - t
        lo = (t - (s - bb)) + (h - bb)
        lo = lo + t_lo
        t = s + lo
        t_lo = lo - (t - s)
    end subroutine taylor_add_time

end module conmech_taylor_core
