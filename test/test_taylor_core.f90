!> The scalar stepper's fused step arithmetic (conmech_taylor_core: taylor_eval_jet,
!! taylor_check_jet, taylor_next_rho) against the separate routines the batch propagator
!! keeps (taylor_eval_step, taylor_check, taylor_scales + taylor_rho), bit for bit, on
!! expansions whose last two coefficients range over 40 decades each (so that the step-size
!! formula runs both its one-logarithm branches and its two-logarithm one), with the
!! edge cases: vanishing last coefficients (rho huge), a subnormal norm, an infinite
!! coefficient, a state and Phi block (nb < n). A member of a batch takes the steps of its
!! own scalar run only if these agree to the last bit.
program test_taylor_core
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_positive_inf
    use conmech_kinds, only: dp
    use conmech_taylor_core, only: taylor_scales, taylor_rho, taylor_eval_step, taylor_check, &
        taylor_eval_jet, taylor_check_jet, taylor_next_rho
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    integer, parameter :: p = 15, nmax = 7
    real(dp) :: c(0:p, nmax), w(0:p, nmax), rtol(nmax), atol(nmax), e1(nmax), e2(nmax)
    real(dp) :: ynew(nmax), dy1(nmax), dy2(nmax), f1(nmax), u(3), h, rho1, rho2, eps, decay
    real(dp) :: err1, err2, yj(nmax)
    integer :: trial, n, nb, k, i, nbad_rho, nbad_eval, nsep
    logical :: fin

    ts%name = "test_taylor_core"
    eps = 1.0e-12_dp
    decay = exp(-2.0_dp - 0.7_dp/real(p - 1, dp))
    nbad_rho = 0
    nbad_eval = 0
    nsep = 0
    call random_seed(put=[(12345 + 7*k, k=1, 64)])
    do trial = 1, 4000
        n = 1 + mod(trial, nmax)
        nb = n
        if (mod(trial, 3) == 0 .and. n > 2) nb = n - 2
        call random_number(c)
        c = c - 0.5_dp
        do i = 1, n
            call random_number(u)
            ! the last two coefficients over 1e-20 .. 1e20, independently
            c(p - 1, i) = c(p - 1, i)*10.0_dp**(40.0_dp*u(1) - 20.0_dp)
            c(p, i) = c(p, i)*10.0_dp**(40.0_dp*u(2) - 20.0_dp)
            c(0, i) = c(0, i)*10.0_dp**(4.0_dp*u(3) - 2.0_dp)
        end do
        select case (mod(trial, 97))
        case (1)
            c(p, 1:n) = 0.0_dp                      ! one radius only
        case (2)
            c(p - 1:p, 1:n) = 0.0_dp                ! no radius: rho huge
        case (3)
            c(p, 1:n) = 1.0e-300_dp*c(p, 1:n)       ! a subnormal norm times eps
        case (4)
            c(p - 1, 1) = ieee_value(1.0_dp, ieee_positive_inf)   ! an infinite coefficient
        end select
        rtol = 1.0e-12_dp
        atol = 1.0e-13_dp
        call random_number(h)
        h = (h - 0.5_dp)*0.3_dp
        ynew(1:n) = c(0, 1:n)
        call taylor_scales(n, nb, ynew(1:n), rtol, atol, e1)
        rho1 = taylor_rho(n, p, c(:, 1:n), e1, eps, decay)
        call taylor_next_rho(n, nb, p, c(:, 1:n), rtol, atol, eps, decay, e2, rho2)
        if (.not. (same(rho1, rho2) .and. all(same(e1(1:n), e2(1:n))))) nbad_rho = nbad_rho + 1
        if (separated(c(:, 1:n), e1(1:n), n)) nsep = nsep + 1
        ! the step: Horner into a separate state, or into the next expansion's zeroth
        ! coefficients; the check against f there
        call taylor_eval_step(n, p, c(:, 1:n), h, ynew, dy1)
        w = 0.0_dp
        call random_number(f1)
        w(1, 1:n) = f1(1:n)
        call taylor_eval_jet(n, p, c(:, 1:n), h, w(:, 1:n), yj, dy2)
        err1 = taylor_check(n, p, h, ynew, dy1, f1(1:n), e1)
        call taylor_check_jet(n, p, h, w(:, 1:n), dy2, e1, err2, fin)
        if (.not. (all(same(ynew(1:n), w(0, 1:n))) .and. all(same(dy1(1:n), dy2(1:n))) .and. &
                   same(err1, err2) .and. fin)) nbad_eval = nbad_eval + 1
    end do
    call ts%check(nbad_rho == 0, "taylor_next_rho = taylor_scales + taylor_rho, bit for bit")
    call ts%check(nbad_eval == 0, "taylor_eval_jet + taylor_check_jet = taylor_eval_step + "// &
                  "taylor_check, bit for bit")
    ! the one-logarithm branches were exercised (and the two-logarithm one: not all)
    call ts%check(nsep > 100 .and. nsep < 3900, "both step-size branches exercised")
    ! an infinite f at the step's end is reported
    w(1, 1) = ieee_value(1.0_dp, ieee_positive_inf)
    call taylor_check_jet(2, p, 0.1_dp, w(:, 1:2), dy2, e1, err2, fin)
    call ts%check(.not. fin, "an infinite f at the step's end is not finite")
    call ts%finish()

contains

    elemental logical function same(a, b)
        real(dp), intent(in) :: a, b
        same = a == b .or. (a /= a .and. b /= b)
    end function same

    !> The two radii's logarithms differ by more than the width of their binary-exponent
    !! intervals (the case where one logarithm suffices).
    logical function separated(cc, e, nn)
        integer, intent(in) :: nn
        real(dp), intent(in) :: cc(0:p, nn), e(nn)
        real(dp) :: s1, s2, l1, l2
        s1 = maxval(abs(cc(p - 1, :))/e)*eps
        s2 = maxval(abs(cc(p, :))/e)*eps
        separated = .false.
        if (s1 > tiny(1.0_dp) .and. s2 > tiny(1.0_dp) .and. s1 <= huge(1.0_dp) .and. &
            s2 <= huge(1.0_dp)) then
            l1 = -log(s1)/real(p - 1, dp)
            l2 = -log(s2)/real(p, dp)
            separated = abs(l1 - l2) > 2.0_dp*log(2.0_dp)/real(p - 1, dp)
        end if
    end function separated

end program test_taylor_core
