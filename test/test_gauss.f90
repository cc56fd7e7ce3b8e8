!> Gauss-Legendre through ode_solve: the harmonic oscillator's energy (a quadratic
!! invariant) kept to round-off over 1000 periods, orders 4 and 6, bad input.
program test_gauss
    use conmech
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    type(ode_function) :: f
    type(ode_options) :: opt
    type(ode_result) :: r, r2
    real(dp) :: err(2), tf, rs(GAUSS_NR), ws(2, GAUSS_NW)
    integer :: m, k, is(GAUSS_NI)
    logical :: same

    ts%name = "test_gauss"
    f%f => osc
    opt%method = METHOD_GAUSS6
    opt%first_step = 2.0_dp*pi/40.0_dp
    opt%save_steps = .false.
    tf = 2000.0_dp*pi
    call ode_solve(f, [0.0_dp, tf], [1.0_dp, 0.0_dp], opt, r)
    call ts%check(r%success .and. r%stats%naccept == 40000, "GAUSS6, 40000 steps: "//r%message)
    call ts%check_less(abs(sum(r%y(:, r%nt)**2) - 1.0_dp), 1.0e-13_dp, &
                       "x^2 + v^2 after 1000 periods")
    do m = METHOD_GAUSS4, METHOD_GAUSS6
        do k = 1, 2
            opt%method = m
            opt%first_step = 2.0_dp*pi/(10.0_dp*2**k)
            call ode_solve(f, [0.0_dp, 2.0_dp*pi], [1.0_dp, 0.0_dp], opt, r)
            err(k) = maxval(abs(r%y(:, r%nt) - [1.0_dp, 0.0_dp]))
        end do
        call ts%check_close(log(err(1)/err(2))/log(2.0_dp), real(2*(m - 4), dp), 0.3_dp, &
                            "observed order")
    end do
    ! step by step (packed state, action 0 then 1 per step): the steps of the whole run
    opt%method = METHOD_GAUSS6
    opt%first_step = 0.3_dp
    opt%save_steps = .true.
    call ode_solve(f, [0.0_dp, 10.0_dp], [1.0_dp, 0.0_dp], opt, r)
    call gauss_solve(f, 3, [0.0_dp, 10.0_dp], [1.0_dp, 0.0_dp], opt, r2, r_state=rs, &
                     i_state=is, w_state=ws, action=0)
    same = r2%status == CM_SUCCESS
    do k = 2, r%nt
        call gauss_solve(f, 3, [0.0_dp, 10.0_dp], [1.0_dp, 0.0_dp], opt, r2, r_state=rs, &
                         i_state=is, w_state=ws, action=1)
        same = same .and. r2%status == CM_SUCCESS .and. rs(3) == r%t(k) .and. &
               all(ws(:, 1) == r%y(:, k))
    end do
    call ts%check(same .and. is(5) == r%stats%nfev .and. is(6) == r%stats%naccept, &
                  "Gauss step by step = the whole run, bit for bit")
    opt%first_step = 0.0_dp
    call ode_solve(f, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], opt, r)
    call ts%check(r%status == CM_BAD_INPUT .and. index(r%message, "first_step") > 0, &
                  "no step: "//r%message)
    call ts%finish()

contains

    subroutine osc(t, y, dydt)
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        dydt = [y(2), -y(1)]
    end subroutine osc

end program test_gauss
