!> The arithmetic of one Taylor step, shared by the scalar stepper (conmech_taylor_stepper)
!! and the batch propagator (conmech_taylor_batch), so that a member of a batch takes
!! exactly the steps, bit for bit, of the same integration on its own.
!!
!! - `taylor_order`: Jorba and Zou's order ceil(-ln(eps)/2 + 1) for the tolerance eps;
!! - `taylor_scales`: E_i = max(atol_i, rtol_i ||y||_inf) per block (state, Phi);
!! - `taylor_rho`: the step rho exp(-2 - 0.7/(p - 1)) from the last two coefficients,
!!   rho = min over k = p - 1, p of (1/N_k)^(1/k), N_k = max_i eps |y_i^[k]|/E_i;
!! - `taylor_eval_step`: y(t + h) and the polynomial's derivative there (Horner);
!! - `taylor_check`: the safety-check ratio |h (P'(h) - f(t + h, P(h)))| / ((p + 1) E_i),
!!   about the local error over the tolerance (the next expansion gives f there for free);
!! - `taylor_add_time`: t + h in double length (Knuth's TwoSum).
module conmech_taylor_core
    use conmech_kinds, only: dp
    implicit none
    private
    public :: taylor_order, taylor_scales, taylor_rho, taylor_eval_step, taylor_check, &
        taylor_add_time, taylor_shrink, TAYLOR_CHECK_MAX

    real(dp), parameter :: TAYLOR_CHECK_MAX = 10.0_dp   !! rejected above 10 x the tolerance

contains

    !> Jorba and Zou's order for the tolerance eps: ceil(-ln(eps)/2 + 1), at least 2.
    pure integer function taylor_order(eps)
        real(dp), intent(in) :: eps
        taylor_order = max(2, ceiling(-0.5_dp*log(max(eps, tiny(1.0_dp))) + 1.0_dp))
    end function taylor_order

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
    !! coefficients c(0:p, 1:n) and the scales e; decay = exp(-2 - 0.7/(p - 1)). The smaller
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
        if (l < log(huge(1.0_dp))) rho = exp(l)*decay
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
