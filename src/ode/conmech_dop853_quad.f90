!> Hairer's DOP853 (the Dormand-Prince 8(5,3) pair, its error estimator combining the fifth-
!! and third-order embedded solutions, and its step-size control) in quadruple precision
!! (real128: 113-bit significand, unit round-off 9.6e-35), for reference solutions beside
!! Taylor's method in conmech_taylor_quad. The right-hand side of a generated system is the
!! first Taylor coefficient of its quadruple-precision recurrence routine (taylor_qp_fn called
!! at order 1: w(1, 1:n) = f(t, y)), so no second generated routine is needed. The same
!! algorithm as conmech_rk_stepper's DOP853 in double precision (Hairer's hinit initial step,
!! safety 0.9, step ratio in [1/6, 3], no step increase right after a rejection); the
!! coefficients' accuracy is stated in conmech_dop853_quad_coefficients.
module conmech_dop853_quad
    use, intrinsic :: iso_c_binding, only: c_int, c_loc
    use, intrinsic :: iso_fortran_env, only: qp => real128, real64
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT, CM_TOO_MANY_STEPS, &
                              CM_STEP_TOO_SMALL, CM_NONFINITE, status_message
    use conmech_taylor_quad, only: taylor_qp_fn
    use conmech_dop853_quad_coefficients
    implicit none
    private
    public :: dop853_qp_counts, dop853_propagate_qp

    !> Work counters of one dop853_propagate_qp run.
    type :: dop853_qp_counts
        integer :: nfev = 0     !! right-hand side evaluations
        integer :: nsteps = 0   !! attempted steps
        integer :: naccept = 0  !! accepted steps
        integer :: nreject = 0  !! rejected steps (after the first accepted one, as Hairer)
    end type dop853_qp_counts

    real(qp), parameter :: safe = 0.9_qp          !! safety factor of the step prediction
    real(qp), parameter :: facc1 = 1.0_qp/0.333_qp !! largest step decrease, 1/fac1
    real(qp), parameter :: facc2 = 1.0_qp/6.0_qp  !! largest step increase, 1/fac2
    !> tolerances below it are refused (compared in double precision, so that the decimal
    !! 1e-32 read to any precision is accepted)
    real(real64), parameter :: min_rtol = 1.0e-32_real64

contains

    !> Advance y (real128) from t0 to tf in place by DOP853 with the error
    !! norm sqrt(mean((err_i/sk_i)^2)), sk_i = atol + rtol max(|y_i|, |ynew_i|); at most
    !! max_steps steps. The right-hand side is fn at order 1 on nw work columns with the
    !! parameters p. info: CM_SUCCESS, CM_BAD_INPUT (rtol below 1e-32, atol not positive, ...),
    !! CM_TOO_MANY_STEPS, CM_STEP_TOO_SMALL or CM_NONFINITE, with the message.
    subroutine dop853_propagate_qp(fn, n, nw, p, t0, tf, y, rtol, atol, max_steps, info, &
                                   message, counts, fixed_steps)
        procedure(taylor_qp_fn) :: fn
        integer, intent(in) :: n, nw, max_steps
        real(qp), intent(in) :: p(:)
        real(qp), intent(in) :: t0, tf, rtol, atol
        real(qp), intent(inout) :: y(n)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: message
        type(dop853_qp_counts), intent(out) :: counts
        !> if present and positive: that many equal steps, without error control (for
        !! measuring the order), instead of the adaptive steps
        integer, intent(in), optional :: fixed_steps
        real(qp), allocatable, target :: w(:, :), pp(:)
        real(qp), target :: tt
        real(qp) :: k(n, 12), ytmp(n), ynew(n), t, h, hnew, posneg, err, fac11, fac, facold
        logical :: last, reject
        integer :: m, nfixed
        info = CM_SUCCESS
        message = status_message(CM_SUCCESS)
        if (n < 1 .or. nw < n) then
            call refuse("bad input: n must be positive and nw at least n")
            return
        end if
        if (.not. (real(rtol, real64) >= min_rtol .and. rtol < 1.0_qp)) then
            call refuse("bad input: rtol must lie in [1e-32, 1) (the coefficients carry "// &
                        "about 30 digits, real128 34)")
            return
        end if
        if (.not. (atol > 0.0_qp .and. atol < huge(1.0_qp))) then
            call refuse("bad input: atol must be finite and positive (a zero component "// &
                        "would make the error scale zero)")
            return
        end if
        if (.not. (abs(t0) < huge(1.0_qp) .and. abs(tf) < huge(1.0_qp))) then
            call refuse("bad input: t0 and tf must be finite")
            return
        end if
        if (.not. all(abs(y) < huge(1.0_qp))) then
            call refuse("bad input: y0 must be finite")
            return
        end if
        if (max_steps < 1) then
            call refuse("bad input: max_steps must be positive")
            return
        end if
        nfixed = 0
        if (present(fixed_steps)) nfixed = fixed_steps
        if (tf == t0) return
        allocate (w(0:1, nw), pp(max(size(p), 1)))
        w = 0.0_qp
        pp = 0.0_qp
        pp(1:size(p)) = p
        posneg = sign(1.0_qp, tf - t0)
        t = t0
        call rhs(t, y, k(:, 1))
        if (nfixed > 0) then
            h = (tf - t0)/real(nfixed, qp)
            do m = 1, nfixed
                counts%nsteps = counts%nsteps + 1
                call attempt()
                counts%naccept = counts%naccept + 1
                y = ynew
                t = t0 + real(m, qp)*h
                if (m < nfixed) call rhs(t, y, k(:, 1))
            end do
            if (.not. all(abs(y) < huge(1.0_qp))) call fail(CM_NONFINITE)
            return
        end if
        h = initial_step()
        if (info /= CM_SUCCESS) return
        facold = 1.0e-4_qp
        last = .false.
        reject = .false.
        do
            if (counts%nsteps >= max_steps) then
                call fail(CM_TOO_MANY_STEPS)
                return
            end if
            if (.not. (0.1_qp*abs(h) > abs(t)*epsilon(1.0_qp))) then
                call fail(CM_STEP_TOO_SMALL)
                return
            end if
            if ((t + 1.01_qp*h - tf)*posneg > 0.0_qp) then
                h = tf - t
                last = .true.
            end if
            counts%nsteps = counts%nsteps + 1
            call attempt()
            if (.not. (err == err) .or. err > huge(1.0_qp)) then
                call fail(CM_NONFINITE)
                return
            end if
            fac11 = err**0.125_qp
            fac = max(facc2, min(facc1, fac11/safe))
            hnew = h/fac
            if (err <= 1.0_qp) then
                facold = max(err, 1.0e-4_qp)
                counts%naccept = counts%naccept + 1
                y = ynew
                t = t + h
                call rhs(t, y, k(:, 1))        ! first stage of the next step (FSAL)
                if (last) exit
                if (reject) hnew = posneg*min(abs(hnew), abs(h))
                reject = .false.
            else
                hnew = h/min(facc1, fac11/safe)
                reject = .true.
                if (counts%naccept >= 1) counts%nreject = counts%nreject + 1
                last = .false.
            end if
            h = hnew
        end do
        if (.not. all(abs(y) < huge(1.0_qp))) call fail(CM_NONFINITE)

    contains

        !> f(s, z) into dz: the first Taylor coefficient of the generated routine.
        subroutine rhs(s, z, dz)
            real(qp), intent(in) :: s, z(n)
            real(qp), intent(out) :: dz(n)
            w(0, 1:n) = z
            tt = s
            call fn(c_loc(tt), 1_c_int, c_loc(w), c_loc(pp))
            dz = w(1, 1:n)
            counts%nfev = counts%nfev + 1
        end subroutine rhs

        !> Hairer's starting step for an order-8 method: |h| with h^8 max(|f'|, |f|) = 0.01 in
        !! the tolerance's scale, at most 100 times the step sqrt(|y|/|f|)/100 (scaled norms).
        function initial_step() result(h0)
            real(qp) :: h0, sk(n), dnf, dny, der2, der12, h1
            h0 = 0.0_qp
            sk = atol + rtol*abs(y)
            dnf = sum((k(:, 1)/sk)**2)
            dny = sum((y/sk)**2)
            if (dnf <= 1.0e-10_qp .or. dny <= 1.0e-10_qp) then
                h1 = 1.0e-6_qp
            else
                h1 = sqrt(dny/dnf)*0.01_qp
            end if
            h0 = min(h1, abs(tf - t0))*posneg
            ytmp = y + h0*k(:, 1)
            call rhs(t + h0, ytmp, k(:, 2))
            der2 = sqrt(sum(((k(:, 2) - k(:, 1))/sk)**2))/abs(h0)
            der12 = max(der2, sqrt(dnf))
            if (.not. (der12 == der12)) then
                call fail(CM_NONFINITE)
                return
            end if
            if (der12 <= 1.0e-15_qp) then
                h1 = max(1.0e-6_qp, abs(h0)*1.0e-3_qp)
            else
                h1 = (0.01_qp/der12)**0.125_qp
            end if
            h0 = min(100.0_qp*abs(h0), h1, abs(tf - t0))*posneg
        end function initial_step

        !> One step of size h from (t, y) with k(:, 1) = f(t, y): ynew and the scaled error
        !! err (Hairer's combination of the fifth- and third-order estimators).
        subroutine attempt()
            real(qp) :: bs, sk, e3, e5, err3, err5, deno
            integer :: i
                do i = 1, n
                    ytmp(i) = y(i) + h*(a2_1*k(i, 1))
                end do
                call rhs(t + c2*h, ytmp, k(:, 2))
                do i = 1, n
                    ytmp(i) = y(i) + h*(a3_1*k(i, 1) + a3_2*k(i, 2))
                end do
                call rhs(t + c3*h, ytmp, k(:, 3))
                do i = 1, n
                    ytmp(i) = y(i) + h*(a4_1*k(i, 1) + a4_3*k(i, 3))
                end do
                call rhs(t + c4*h, ytmp, k(:, 4))
                do i = 1, n
                    ytmp(i) = y(i) + h*(a5_1*k(i, 1) + a5_3*k(i, 3) + a5_4*k(i, 4))
                end do
                call rhs(t + c5*h, ytmp, k(:, 5))
                do i = 1, n
                    ytmp(i) = y(i) + h*(a6_1*k(i, 1) + a6_4*k(i, 4) + a6_5*k(i, 5))
                end do
                call rhs(t + c6*h, ytmp, k(:, 6))
                do i = 1, n
                    ytmp(i) = y(i) + h*(a7_1*k(i, 1) + a7_4*k(i, 4) + a7_5*k(i, 5) + a7_6*k(i, 6))
                end do
                call rhs(t + c7*h, ytmp, k(:, 7))
                do i = 1, n
                    ytmp(i) = y(i) + h*(a8_1*k(i, 1) + a8_4*k(i, 4) + a8_5*k(i, 5) + a8_6*k(i, 6) &
                                        + a8_7*k(i, 7))
                end do
                call rhs(t + c8*h, ytmp, k(:, 8))
                do i = 1, n
                    ytmp(i) = y(i) + h*(a9_1*k(i, 1) + a9_4*k(i, 4) + a9_5*k(i, 5) + a9_6*k(i, 6) &
                                        + a9_7*k(i, 7) + a9_8*k(i, 8))
                end do
                call rhs(t + c9*h, ytmp, k(:, 9))
                do i = 1, n
                    ytmp(i) = y(i) + h*(a10_1*k(i, 1) + a10_4*k(i, 4) + a10_5*k(i, 5) &
                                        + a10_6*k(i, 6) + a10_7*k(i, 7) + a10_8*k(i, 8) &
                                        + a10_9*k(i, 9))
                end do
                call rhs(t + c10*h, ytmp, k(:, 10))
                do i = 1, n
                    ytmp(i) = y(i) + h*(a11_1*k(i, 1) + a11_4*k(i, 4) + a11_5*k(i, 5) &
                                        + a11_6*k(i, 6) + a11_7*k(i, 7) + a11_8*k(i, 8) &
                                        + a11_9*k(i, 9) + a11_10*k(i, 10))
                end do
                call rhs(t + c11*h, ytmp, k(:, 11))
                do i = 1, n
                    ytmp(i) = y(i) + h*(a12_1*k(i, 1) + a12_4*k(i, 4) + a12_5*k(i, 5) &
                                        + a12_6*k(i, 6) + a12_7*k(i, 7) + a12_8*k(i, 8) &
                                        + a12_9*k(i, 9) + a12_10*k(i, 10) + a12_11*k(i, 11))
                end do
                call rhs(t + h, ytmp, k(:, 12))
            err3 = 0.0_qp
            err5 = 0.0_qp
            do i = 1, n
                bs = b1*k(i, 1) + b6*k(i, 6) + b7*k(i, 7) + b8*k(i, 8) + b9*k(i, 9) &
                     + b10*k(i, 10) + b11*k(i, 11) + b12*k(i, 12)
                ynew(i) = y(i) + h*bs
                sk = atol + rtol*max(abs(y(i)), abs(ynew(i)))
                e3 = bs - bh1*k(i, 1) - bh9*k(i, 9) - bh12*k(i, 12)
                e5 = e1*k(i, 1) + e6*k(i, 6) + e7*k(i, 7) + e8*k(i, 8) + e9*k(i, 9) &
                     + e10*k(i, 10) + e11*k(i, 11) + e12*k(i, 12)
                err3 = err3 + (e3/sk)**2
                err5 = err5 + (e5/sk)**2
            end do
            deno = err5 + 0.01_qp*err3
            if (deno <= 0.0_qp) deno = 1.0_qp
            err = abs(h)*err5/sqrt(real(n, qp)*deno)
        end subroutine attempt

        !> A failure with the status' own message.
        subroutine fail(code)
            integer, intent(in) :: code
            info = code
            message = status_message(code)
        end subroutine fail

        !> Bad input with the message naming the argument.
        subroutine refuse(text)
            character(len=*), intent(in) :: text
            info = CM_BAD_INPUT
            message = text
        end subroutine refuse

    end subroutine dop853_propagate_qp

end module conmech_dop853_quad
