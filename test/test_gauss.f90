!> Gauss-Legendre through ode_solve: the harmonic oscillator's energy (a quadratic
!! invariant) kept to round-off over 1000 periods, orders 4 and 6, the stepper packed and
!! unpacked at every step (the whole run, bit for bit), bad input.
program test_gauss
    use conmech
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    type(ode_function) :: f
    type(ode_options) :: opt
    type(ode_result) :: r
    type(gauss_stepper), allocatable :: gs
    type(state_packer) :: pk
    real(dp) :: err(2), tf
    integer :: m, k, info
    logical :: same
    character(len=:), allocatable :: msg

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
    ! step by step, the whole state packed into plain arrays after every step and unpacked
    ! into a fresh stepper before the next: the steps of the whole run, bit for bit
    opt%method = METHOD_GAUSS6
    opt%first_step = 0.3_dp
    opt%save_steps = .true.
    call ode_solve(f, [0.0_dp, 10.0_dp], [1.0_dp, 0.0_dp], opt, r)
    allocate (gs)
    call gs%init(0.0_dp, 10.0_dp, [1.0_dp, 0.0_dp], opt, info, msg)
    if (info == CM_SUCCESS) call gs%start(f, info, msg)
    same = info == CM_SUCCESS
    do k = 2, r%nt
        call stepper_pack(gs, pk)
        deallocate (gs)
        allocate (gs)
        call stepper_unpack(gs, METHOD_GAUSS6, pk%r(1:pk%nr), pk%iv(1:pk%ni), &
                            pk%w(:, 1:pk%nw), info, msg)
        if (info == CM_SUCCESS) call gs%step(f, 10.0_dp, info, msg)
        same = same .and. info == CM_SUCCESS .and. gs%t == r%t(k) .and. &
               all(gs%y == r%y(:, k))
    end do
    call ts%check(same .and. gs%last .and. gs%st%nfev == r%stats%nfev .and. &
                  gs%st%naccept == r%stats%naccept, &
                  "Gauss step by step (packed and unpacked) = the whole run, bit for bit")
    if (allocated(msg)) deallocate (msg)
    opt%first_step = 0.0_dp
    call ode_solve(f, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], opt, r)
    call ts%check(r%status == CM_BAD_INPUT .and. index(r%message, "first_step") > 0, &
                  "no step: "//r%message)
    call ts%finish()
    deallocate (gs)         ! (main-program allocatables are not freed at exit)

contains

    subroutine osc(t, y, dydt)
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        dydt = [y(2), -y(1)]
    end subroutine osc

end program test_gauss
