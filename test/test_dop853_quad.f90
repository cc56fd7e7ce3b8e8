!> DOP853 in quadruple precision: the tableau's order conditions in real128 (the quadrature
!! conditions sum b c^(q-1) = 1/q to q = 8, the row sums, the estimators' weights), order 8
!! observed with equal steps on y' = y cos t (y = exp(sin t)) down to errors of 1e-25, far
!! below double precision; Kepler's orbit (e = 0.5) returning to its initial state after one
!! period (2 pi) to 1e-22 at rtol 1e-26; the circular orbit at rtol 1e-32 to 1e-30 (the
!! accuracy floor the coefficients allow); bad input refused with a message.
program test_dop853_quad
    use, intrinsic :: iso_fortran_env, only: qp => real128
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_dop853_quad, only: dop853_propagate_qp, dop853_qp_counts
    use conmech_dop853_quad_coefficients
    use conmech_testing, only: test_suite
    use dop853_quad_test_models, only: kepler_qp, growth_qp
    implicit none
    type(test_suite) :: ts
    type(dop853_qp_counts) :: cnt
    real(qp), parameter :: pi_qp = 4.0_qp*atan(1.0_qp)
    real(qp) :: b(12), c(12), y(4), y0(4), err(4), ecc, mu(1), z(1), defect
    integer :: q, info, m
    character(len=:), allocatable :: msg

    ts%name = "test_dop853_quad"
    ! the quadrature conditions of order 8 in real128 (Hairer's decimals carry ~30 digits)
    b = [b1, 0.0_qp, 0.0_qp, 0.0_qp, 0.0_qp, b6, b7, b8, b9, b10, b11, b12]
    c = [0.0_qp, c2, c3, c4, c5, c6, c7, c8, c9, c10, c11, 1.0_qp]
    call ts%check_less(real(abs(sum(b) - 1.0_qp), dp), 1.0e-32_dp, "sum b = 1")
    do q = 2, 8
        defect = abs(sum(b*c**(q - 1)) - 1.0_qp/real(q, qp))
        call ts%check_less(real(defect, dp), 1.0e-29_dp, "sum b c^(q-1) = 1/q")
    end do
    call ts%check_less(real(abs(a12_1 + a12_4 + a12_5 + a12_6 + a12_7 + a12_8 + a12_9 &
                                + a12_10 + a12_11 - 1.0_qp), dp), 1.0e-32_dp, "row sum 12")
    call ts%check_less(real(abs(e1 + e6 + e7 + e8 + e9 + e10 + e11 + e12), dp), 1.0e-32_dp, &
                       "sum e = 0")
    call ts%check_less(real(abs(bh1 + bh9 + bh12 - 1.0_qp), dp), 1.0e-32_dp, "sum bh = 1")

    ! order 8 with equal steps: y' = y cos t on [0, 3], y(3) = exp(sin 3)
    do m = 1, 4
        z = 1.0_qp
        call dop853_propagate_qp(growth_qp, 1, 1, [1.0_qp], 0.0_qp, 3.0_qp, z, 1.0e-30_qp, &
                                 1.0e-30_qp, 10**6, info, msg, cnt, fixed_steps=40*2**m)
        call ts%check(info == CM_SUCCESS .and. cnt%naccept == 40*2**m, "equal steps: "//msg)
        err(m) = abs(z(1) - exp(sin(3.0_qp)))
    end do
    call ts%check_less(real(err(4), dp), 1.0e-24_dp, "error at 640 equal steps")
    call ts%check_less(1.0e-19_dp, real(err(1), dp), "at 80 steps the error is truncation")
    call ts%check_close(real(log(err(3)/err(4))/log(2.0_qp), dp), 8.0_dp, 0.3_dp, &
                        "observed order (320 -> 640 steps)")
    call ts%check_close(real(log(err(2)/err(3))/log(2.0_qp), dp), 8.0_dp, 0.3_dp, &
                        "observed order (160 -> 320 steps)")

    ! Kepler, e = 0.5, a = 1, mu = 1: back to the pericentre after 2 pi
    ecc = 0.5_qp
    y0 = [1.0_qp - ecc, 0.0_qp, 0.0_qp, sqrt((1.0_qp + ecc)/(1.0_qp - ecc))]
    y = y0
    mu = 1.0_qp
    call dop853_propagate_qp(kepler_qp, 4, 4, mu, 0.0_qp, 2.0_qp*pi_qp, y, 1.0e-26_qp, &
                             1.0e-26_qp, 10**6, info, msg, cnt)
    call ts%check(info == CM_SUCCESS, "Kepler: "//msg)
    call ts%check_less(real(maxval(abs(y - y0)), dp), 1.0e-22_dp, "Kepler closes over a period")
    ! 11 new stages an attempt, f at each accepted point, f(t0) and the starting step's probe
    call ts%check(cnt%nfev == 11*cnt%nsteps + cnt%naccept + 2, "evaluation count")
    ! the accuracy floor: the circular orbit over one period at rtol 1e-32 comes back to
    ! 1e-31 (the tableau with Hairer's printed first column stalls at 4e-29 with the same
    ! steps: its consistency defects, not the steps, set the floor)
    y0 = [1.0_qp, 0.0_qp, 0.0_qp, 1.0_qp]
    y = y0
    call dop853_propagate_qp(kepler_qp, 4, 4, mu, 0.0_qp, 2.0_qp*pi_qp, y, 1.0e-32_qp, &
                             1.0e-32_qp, 10**6, info, msg, cnt)
    call ts%check(info == CM_SUCCESS, "circular orbit at rtol 1e-32: "//msg)
    call ts%check_less(real(maxval(abs(y - y0)), dp), 1.0e-30_dp, &
                       "circular orbit at rtol 1e-32 closes to 1e-30")
    ! bad input
    y = y0
    call dop853_propagate_qp(kepler_qp, 4, 4, mu, 0.0_qp, 1.0_qp, y, 1.0e-33_qp, &
                             1.0e-26_qp, 10**6, info, msg, cnt)
    call ts%check(info == CM_BAD_INPUT .and. index(msg, "rtol") > 0, "tiny rtol: "//msg)
    call dop853_propagate_qp(kepler_qp, 4, 4, mu, 0.0_qp, 1.0_qp, y, 1.0e-20_qp, &
                             -1.0_qp, 10**6, info, msg, cnt)
    call ts%check(info == CM_BAD_INPUT .and. index(msg, "atol") > 0, "negative atol: "//msg)
    call dop853_propagate_qp(kepler_qp, 4, 2, mu, 0.0_qp, 1.0_qp, y, 1.0e-20_qp, &
                             1.0e-20_qp, 10**6, info, msg, cnt)
    call ts%check(info == CM_BAD_INPUT .and. index(msg, "nw") > 0, "nw < n: "//msg)
    call ts%check(all(y == y0), "the state is untouched on refusal")
    if (allocated(msg)) deallocate (msg)
    call ts%finish()
end program test_dop853_quad
