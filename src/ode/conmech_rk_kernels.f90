!> One attempted step of each explicit Runge-Kutta method: stages, propagated solution and
!! error norm (Hairer's norms). Written for the compiler: explicit-shape arrays, one
!! contiguous loop over the components per stage with the tableau's nonzero coefficients
!! written out (no zero multiplied, no descriptor reloaded), the error norm fused into one
!! pass. The right-hand side counter is the caller's.
!!
!! Error norms: sqrt(mean((err_i/sk_i)^2)) with sk_i = atol_i + rtol_i max(|y_i|, |ynew_i|)
!! (DOP853 blends its 5th- and 3rd-order estimators as dop853.f does). A non-finite ynew
!! gives err = NaN (the step controller cuts the step).
module conmech_rk_kernels
    use conmech_kinds, only: dp, nan_dp
    use conmech_ode_system, only: ode_system
    use conmech_rk_tableaus, only: rk_tableau
    implicit none
    private
    public :: rk4_attempt, dopri5_attempt, dop853_attempt, verner_attempt, rk_stages

contains

    !> Classical RK4 step y -> ynew (k(:, 1) = f(t, y) on entry); err = 0 or NaN.
    subroutine rk4_attempt(sys, n, t, h, y, k, ynew, ytmp, err)
        class(ode_system), intent(in) :: sys
        integer, intent(in) :: n
        real(dp), intent(in) :: t, h, y(n)
        real(dp), intent(inout) :: k(n, 4)
        real(dp), intent(out) :: ynew(n), ytmp(n), err
        real(dp) :: h2, h6
        integer :: i
        h2 = 0.5_dp*h
        do i = 1, n
            ytmp(i) = y(i) + h2*k(i, 1)
        end do
        call sys%rhs(t + h2, ytmp, k(:, 2))
        do i = 1, n
            ytmp(i) = y(i) + h2*k(i, 2)
        end do
        call sys%rhs(t + h2, ytmp, k(:, 3))
        do i = 1, n
            ytmp(i) = y(i) + h*k(i, 3)
        end do
        call sys%rhs(t + h, ytmp, k(:, 4))
        h6 = h/6.0_dp
        do i = 1, n
            ynew(i) = y(i) + h6*(k(i, 1) + 2.0_dp*(k(i, 2) + k(i, 3)) + k(i, 4))
        end do
        err = 0.0_dp
        if (.not. all(abs(ynew) <= huge(1.0_dp))) err = nan_dp
    end subroutine rk4_attempt

    !> Dormand-Prince 5(4) step: stages 2..7 (stage 7 = f(t + h, ynew), FSAL).
    subroutine dopri5_attempt(sys, n, tb, t, h, y, k, ynew, ytmp, rtol, atol, err)
        class(ode_system), intent(in) :: sys
        integer, intent(in) :: n
        type(rk_tableau), intent(in) :: tb
        real(dp), intent(in) :: t, h, y(n), rtol(n), atol(n)
        real(dp), intent(inout) :: k(n, 7)
        real(dp), intent(out) :: ynew(n), ytmp(n), err
        real(dp) :: s, sk, e
        integer :: i
        do i = 1, n
            ytmp(i) = y(i) + h*(tb%a(2, 1)*k(i, 1))
        end do
        call sys%rhs(t + tb%c(2)*h, ytmp, k(:, 2))
        do i = 1, n
            ytmp(i) = y(i) + h*(tb%a(3, 1)*k(i, 1) + tb%a(3, 2)*k(i, 2))
        end do
        call sys%rhs(t + tb%c(3)*h, ytmp, k(:, 3))
        do i = 1, n
            ytmp(i) = y(i) + h*(tb%a(4, 1)*k(i, 1) + tb%a(4, 2)*k(i, 2) + tb%a(4, 3)*k(i, 3))
        end do
        call sys%rhs(t + tb%c(4)*h, ytmp, k(:, 4))
        do i = 1, n
            ytmp(i) = y(i) + h*(tb%a(5, 1)*k(i, 1) + tb%a(5, 2)*k(i, 2) &
                                + tb%a(5, 3)*k(i, 3) + tb%a(5, 4)*k(i, 4))
        end do
        call sys%rhs(t + tb%c(5)*h, ytmp, k(:, 5))
        do i = 1, n
            ytmp(i) = y(i) + h*(tb%a(6, 1)*k(i, 1) + tb%a(6, 2)*k(i, 2) &
                                + tb%a(6, 3)*k(i, 3) + tb%a(6, 4)*k(i, 4) + tb%a(6, 5)*k(i, 5))
        end do
        call sys%rhs(t + h, ytmp, k(:, 6))
        do i = 1, n     ! b2 = 0
            ynew(i) = y(i) + h*(tb%b(1)*k(i, 1) + tb%b(3)*k(i, 3) + tb%b(4)*k(i, 4) &
                                + tb%b(5)*k(i, 5) + tb%b(6)*k(i, 6))
        end do
        call sys%rhs(t + h, ynew, k(:, 7))
        do i = 1, n     ! e2 = 0; a non-finite ynew makes the norm NaN
            e = tb%e(1)*k(i, 1) + tb%e(3)*k(i, 3) + tb%e(4)*k(i, 4) + tb%e(5)*k(i, 5) &
                + tb%e(6)*k(i, 6) + tb%e(7)*k(i, 7)
            sk = atol(i) + rtol(i)*max(abs(y(i)), abs(ynew(i)))
            ytmp(i) = (e/sk)**2 + (ynew(i) - ynew(i))
        end do
        s = 0.0_dp
        do i = 1, n
            s = s + ytmp(i)
        end do
        if (s > huge(1.0_dp)) then     ! squares overflowed (huge states): h inside them
            s = 0.0_dp
            do i = 1, n
                e = tb%e(1)*k(i, 1) + tb%e(3)*k(i, 3) + tb%e(4)*k(i, 4) + tb%e(5)*k(i, 5) &
                    + tb%e(6)*k(i, 6) + tb%e(7)*k(i, 7)
                sk = atol(i) + rtol(i)*max(abs(y(i)), abs(ynew(i)))
                s = s + (h*e/sk)**2
            end do
            err = sqrt(s/real(n, dp))
        else
            err = abs(h)*sqrt(s/real(n, dp))
        end if
    end subroutine dopri5_attempt

    !> Dormand-Prince 8(5,3) step: stages 2..12; ynew; err (the FSAL stage 13 is the
    !! caller's, after acceptance).
    subroutine dop853_attempt(sys, n, tb, t, h, y, k, ynew, ytmp, w3, rtol, atol, err)
        class(ode_system), intent(in) :: sys
        integer, intent(in) :: n
        type(rk_tableau), intent(in) :: tb
        real(dp), intent(in) :: t, h, y(n), rtol(n), atol(n)
        real(dp), intent(inout) :: k(n, 12)
        real(dp), intent(out) :: ynew(n), ytmp(n), w3(n), err
        if (n == 4) then    ! a constant size: loops without overhead (one AVX2 vector)
            call dop853_kernel4(sys, tb, t, h, y, k, ynew, ytmp, w3, rtol, atol, err)
        else
            call dop853_kernel(sys, n, tb, t, h, y, k, ynew, ytmp, w3, rtol, atol, err)
        end if
    end subroutine dop853_attempt

    subroutine dop853_kernel4(sys, tb, t, h, y, k, ynew, ytmp, w3, rtol, atol, err)
        class(ode_system), intent(in) :: sys
        integer, parameter :: n = 4
        include "conmech_rk_dop853_body.inc"
    end subroutine dop853_kernel4

    subroutine dop853_kernel(sys, n, tb, t, h, y, k, ynew, ytmp, w3, rtol, atol, err)
        class(ode_system), intent(in) :: sys
        integer, intent(in) :: n
        include "conmech_rk_dop853_body.inc"
    end subroutine dop853_kernel

    !> Verner 9(8) step: stages 2..16, ynew from the 9th-order weights, err.
    subroutine verner_attempt(sys, n, tb, t, h, y, k, ynew, ytmp, rtol, atol, err)
        class(ode_system), intent(in) :: sys
        integer, intent(in) :: n
        type(rk_tableau), intent(in) :: tb
        real(dp), intent(in) :: t, h, y(n), rtol(n), atol(n)
        real(dp), intent(inout) :: k(n, 21)
        real(dp), intent(out) :: ynew(n), ytmp(n), err
        real(dp) :: s, sk
        integer :: i
        call rk_stages(sys, n, tb, t, h, y, k, ytmp, 2, 16)
        ynew = y
        call accumulate(n, h, tb%b, 15, k, ynew)
        ytmp = 0.0_dp
        call accumulate(n, 1.0_dp, tb%e, 16, k, ytmp)
        s = 0.0_dp
        do i = 1, n
            sk = atol(i) + rtol(i)*max(abs(y(i)), abs(ynew(i)))
            s = s + (ytmp(i)/sk)**2
        end do
        if (s > huge(1.0_dp)) then     ! squares overflowed (huge states): h inside them
            s = 0.0_dp
            do i = 1, n
                sk = atol(i) + rtol(i)*max(abs(y(i)), abs(ynew(i)))
                s = s + (h*ytmp(i)/sk)**2
            end do
            err = sqrt(s/real(n, dp))
        else
            err = abs(h)*sqrt(s/real(n, dp))
        end if
        if (.not. all(abs(ynew) <= huge(1.0_dp))) err = nan_dp
    end subroutine verner_attempt

    !> Stages s1..s2 of a tableau (stage s from a(s, 1:s-1), zero coefficients skipped).
    subroutine rk_stages(sys, n, tb, t, h, y, k, ytmp, s1, s2)
        class(ode_system), intent(in) :: sys
        integer, intent(in) :: n, s1, s2
        type(rk_tableau), intent(in) :: tb
        real(dp), intent(in) :: t, h, y(n)
        real(dp), intent(inout) :: k(n, 21)
        real(dp), intent(out) :: ytmp(n)
        integer :: s, j
        real(dp) :: ha
        do s = s1, s2
            ytmp = y
            do j = 1, s - 1
                if (tb%a(s, j) == 0.0_dp) cycle
                ha = h*tb%a(s, j)
                ytmp = ytmp + ha*k(:, j)
            end do
            call sys%rhs(t + tb%c(s)*h, ytmp, k(:, s))
        end do
    end subroutine rk_stages

    !> out = out + h sum_{j <= m} w(j) k(:, j), zero weights skipped, contiguous columns.
    pure subroutine accumulate(n, h, w, m, k, out)
        integer, intent(in) :: n, m
        real(dp), intent(in) :: h, w(21), k(n, 21)
        real(dp), intent(inout) :: out(n)
        integer :: i, j
        real(dp) :: hw
        do j = 1, m
            if (w(j) == 0.0_dp) cycle
            hw = h*w(j)
            do i = 1, n
                out(i) = out(i) + hw*k(i, j)
            end do
        end do
    end subroutine accumulate

end module conmech_rk_kernels
