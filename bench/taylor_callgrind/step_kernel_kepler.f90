!> One Taylor step of the Kepler system written out by hand for n = 4 and p = 15 (order
!! at tolerance 1e-12), the prototype of a per-model step kernel: Horner into the next
!! expansion, the recurrences written out for the order (conmech_symbolic_taylor_fixed,
!! called directly), the safety check and, for an accepted step, the next scales and
!! radius: the operations of conmech_taylor_core's taylor_eval_jet, taylor_check_jet and
!! taylor_next_rho in the same order, so the steps are the same to the bit. Compiled with
!! the flags of the written-out recurrences (no contraction: no fused multiply-add).
module kepler_kernel
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use, intrinsic :: iso_fortran_env, only: int64
    use conmech_symbolic_taylor_fixed, only: conmech_taylor_fixed
    implicit none
    integer, parameter :: dp = c_double
    integer, parameter :: n = 4, p = 15, nw = 10
    real(dp), parameter :: LOG_HUGE = log(huge(1.0_dp))
    integer, parameter :: NOT_NORMAL = -huge(1)
contains
    !> c: the expansion at t, w: the work array of the next; err: the check's ratio, fin:
    !! f finite at t + h (1) or not (0); accepted (err <= 10): e and rho are those of the
    !! new expansion, else e is kept (the retry is checked against the same scales)
    subroutine kepler_step(t, h, c, w, rtol, atol, eps, decay, e, dy, err, fin, rho, par) &
            bind(C, name="kepler_step")
        real(dp), value :: t, h, eps, decay
        real(dp), intent(in) :: c(0:p, nw), rtol(n), atol(n), par(*)
        real(dp), intent(inout) :: w(0:p, nw), e(n)
        real(dp), intent(out) :: dy(n), err, rho
        integer(c_int), intent(out) :: fin
        real(dp) :: y(n), d(n), cc, dd, z, y1, s1, s2, l, a1, a2
        integer :: i, k, e1, e2
        do i = 1, n
            y(i) = c(p, i)
            d(i) = 0.0_dp
        end do
        do k = p - 1, 0, -1
            do i = 1, n
                d(i) = y(i) + h*d(i)
                y(i) = c(k, i) + h*y(i)
            end do
        end do
        do i = 1, n
            w(0, i) = y(i)
            dy(i) = d(i)
        end do
        call conmech_taylor_fixed(t + h, p, w, par)
        cc = 16.0_dp*epsilon(1.0_dp)
        err = 0.0_dp
        z = 0.0_dp
        do i = 1, n
            dd = abs(h*(dy(i) - w(1, i)))
            err = max(err, dd/(e(i) + cc*(abs(w(0, i)) + abs(h*dy(i)))))
            z = z + 0.0_dp*w(1, i)
        end do
        fin = 0
        if (z == z) fin = 1
        err = err/real(p + 1, dp)
        if (.not. err <= 10.0_dp) return
        y1 = 0.0_dp
        do i = 1, n
            y1 = max(y1, abs(w(0, i)))
        end do
        s1 = 0.0_dp
        s2 = 0.0_dp
        do i = 1, n
            e(i) = max(atol(i), rtol(i)*y1, tiny(1.0_dp))
            s1 = max(s1, abs(w(p - 1, i))/e(i))
            s2 = max(s2, abs(w(p, i))/e(i))
        end do
        l = huge(1.0_dp)
        a1 = s1*eps
        a2 = s2*eps
        e1 = bexp(a1)
        e2 = bexp(a2)
        if (s1 > 0.0_dp .and. s2 > 0.0_dp .and. e1 /= NOT_NORMAL .and. e2 /= NOT_NORMAL) then
            if ((e1 - 1)*p > e2*(p - 1)) then
                l = -log(a1)/real(p - 1, dp)
            else if ((e2 - 1)*(p - 1) > e1*p) then
                l = -log(a2)/real(p, dp)
            else
                l = min(-log(a1)/real(p - 1, dp), -log(a2)/real(p, dp))
            end if
        else
            if (s1 > 0.0_dp) l = -log(a1)/real(p - 1, dp)
            if (s2 > 0.0_dp) l = min(l, -log(a2)/real(p, dp))
        end if
        rho = huge(1.0_dp)
        if (l < LOG_HUGE) rho = exp(l)*decay
    end subroutine kepler_step
    pure integer function bexp(a) result(ex)
        real(dp), intent(in) :: a
        integer(int64) :: bits
        bits = ishft(transfer(a, 0_int64), -52)
        ex = NOT_NORMAL
        if (bits >= 1 .and. bits <= 2046) ex = int(bits) - 1022
    end function bexp
end module kepler_kernel
