!> Radau IIA (order 5) through ode_solve: Hairer's scaled Van der Pol (eps = 1e-6) against
!! a tight reference, counters, dense output, bad input; ode_integrate with the implicit
!! methods (the end point of ode_solve, bit for bit; its failure with the time); the
!! stepper packed and unpacked at every step (ode_solve's steps, bit for bit); Newton
!! failure (step reduced to the minimum, the time in the message) and a singular iteration
!! matrix (its message).
program test_radau
    use conmech
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    type(ode_function) :: f
    type(ode_options) :: opt
    type(ode_result) :: r
    real(dp) :: ref(2), y(2), yi(2)
    real(dp), parameter :: HS = 0.01_dp, GAM0 = 3.6378342527444957322_dp
    integer :: info, m
    type(ode_stats) :: st
    type(radau_stepper), allocatable :: rs
    type(state_packer) :: pk
    integer :: k
    logical :: same
    character(len=:), allocatable :: msg

    ts%name = "test_radau"
    f%f => vdp
    f%jac => vdp_jac
    call ts%check(method_from_name("Radau") == METHOD_RADAU5, "method name Radau")
    ! reference: SciPy's Radau at rtol = atol = 1e-12 (independent implementation)
    ref = [1.706167437543211_dp, -0.8928100165510839_dp]
    opt%method = METHOD_RADAU5
    opt%rtol = 1.0e-6_dp
    opt%atol = 1.0e-6_dp
    opt%dense_output = .true.
    call ode_solve(f, [0.0_dp, 2.0_dp], [2.0_dp, -0.66_dp], opt, r)
    call ts%check(r%success, "Van der Pol eps = 1e-6: "//r%message)
    call ts%check_less(maxval(abs(r%y(:, r%nt) - ref)), 3.0e-8_dp, "error at t = 2")
    call ts%check(r%stats%naccept > 500 .and. r%stats%naccept < 1100 .and. &
                  r%stats%njev > 0 .and. r%stats%nlu >= 2*r%stats%njev, "counters")
    call r%sol%eval(2.0_dp, y)
    call ts%check_less(maxval(abs(y - r%y(:, r%nt))), 1.0e-12_dp, "dense output at the end")
    call r%sol%eval(1.0_dp, y)
    call ts%check(abs(y(1)) < 2.1_dp .and. abs(y(1)) > 1.0_dp, "dense output inside")

    ! ode_integrate dispatches the implicit methods: the end point of ode_solve exactly
    opt%dense_output = .false.
    yi = [2.0_dp, -0.66_dp]
    call ode_integrate(f, 0.0_dp, 2.0_dp, yi, opt, info, st, msg)
    call ts%check(info == CM_SUCCESS, "ode_integrate Radau: "//msg)
    call ts%check(all(yi == r%y(:, r%nt)) .and. st%naccept == r%stats%naccept .and. &
                  st%nlu == r%stats%nlu, "ode_integrate Radau = ode_solve, bit for bit")
    opt%max_steps = 20
    yi = [2.0_dp, -0.66_dp]
    call ode_integrate(f, 0.0_dp, 2.0_dp, yi, opt, info, st, msg)
    call ts%check(info == CM_TOO_MANY_STEPS .and. index(msg, "t =") > 0 .and. &
                  all(yi /= [2.0_dp, -0.66_dp]), "ode_integrate Radau failure: "//msg)
    opt%max_steps = 100000
    ! step by step, the whole state packed into plain arrays after every step and unpacked
    ! into a fresh stepper before the next (nothing kept between steps, as the Python
    ! objects do): the steps and counters of ode_solve, bit for bit
    allocate (rs)
    call rs%init(0.0_dp, 2.0_dp, [2.0_dp, -0.66_dp], opt, info, msg)
    if (info == CM_SUCCESS) call rs%start(f, info, msg)
    call ts%check(info == CM_SUCCESS, "Radau stepper init, start: "//msg)
    same = .true.
    do k = 2, r%nt
        call stepper_pack(rs, pk)
        deallocate (rs)
        allocate (rs)
        call stepper_unpack(rs, METHOD_RADAU5, pk%r(1:pk%nr), pk%iv(1:pk%ni), &
                            pk%w(:, 1:pk%nw), info, msg)
        if (info /= CM_SUCCESS) exit
        call rs%step(f, 2.0_dp, info, msg)
        if (info /= CM_SUCCESS) exit
        same = same .and. rs%t == r%t(k) .and. all(rs%y == r%y(:, k))
    end do
    call ts%check(info == CM_SUCCESS .and. same .and. rs%t == 2.0_dp .and. rs%last .and. &
                  all([rs%st%nfev, rs%st%njev, rs%st%nlu, rs%st%naccept, rs%st%nreject] == &
                      [r%stats%nfev, r%stats%njev, r%stats%nlu, r%stats%naccept, &
                       r%stats%nreject]), &
                  "Radau stepper, packed and unpacked at every step: the steps and "// &
                  "counters of ode_solve")
    f%f => osc
    do m = METHOD_GAUSS4, METHOD_GAUSS6
        opt%method = m
        opt%first_step = 0.01_dp
        yi = [1.0_dp, 0.0_dp]
        call ode_integrate(f, 0.0_dp, 1.0_dp, yi, opt, info, st, msg)
        call ts%check(info == CM_SUCCESS .and. st%naccept == 100, "ode_integrate Gauss: "//msg)
        call ts%check_less(maxval(abs(yi - [cos(1.0_dp), -sin(1.0_dp)])), 1.0e-9_dp, &
                           "ode_integrate Gauss: y(1)")
    end do
    deallocate (msg)     ! (a main program's allocatables are not freed at its end)
    f%f => vdp
    opt%method = METHOD_RADAU5
    opt%first_step = 0.0_dp
    opt%dense_output = .true.

    ! the same with the finite-difference Jacobian
    f%jac => null()
    call ode_solve(f, [0.0_dp, 2.0_dp], [2.0_dp, -0.66_dp], opt, r)
    call ts%check_less(maxval(abs(r%y(:, r%nt) - ref)), 3.0e-8_dp, "FD Jacobian: error")

    ! mass-matrix form: y1' = y2, 0 = y2 + y1 (index 1), so y1 = exp(-t)
    f%f => dae
    f%jac => null()
    opt%dense_output = .false.
    opt%rtol = 1.0e-8_dp
    opt%atol = 1.0e-10_dp
    call radau_solve(f, [0.0_dp, 3.0_dp], [1.0_dp, -1.0_dp], opt, r, &
                     mass=reshape([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp], [2, 2]))
    call ts%check(r%success, "index-1 DAE: "//r%message)
    call ts%check_less(abs(r%y(1, r%nt) - exp(-3.0_dp)), 1.0e-8_dp, "DAE: y1(3) = exp(-3)")
    call ts%check_less(maxval(abs(r%y(1, :) + r%y(2, :))), 1.0e-12_dp, &
                       "DAE: algebraic equation at every step")
    f%f => vdp

    ! y' = y^2, y(0) = 1 blows up at t = 1: Newton stops converging, the step shrinks to the
    ! minimum, the run ends (CM_STEP_TOO_SMALL) near t = 1 with the time in the message
    f%f => blowup
    f%jac => blowup_jac
    opt%rtol = 1.0e-8_dp
    opt%atol = 1.0e-8_dp
    call ode_solve(f, [0.0_dp, 2.0_dp], [1.0_dp], opt, r)
    call ts%check(.not. r%success .and. r%status == CM_STEP_TOO_SMALL .and. &
                  index(r%message, "at t =") > 0, "y' = y^2: "//r%message)
    call ts%check_less(abs(r%t(r%nt) - 1.0_dp), 1.0e-3_dp, "y' = y^2: stops near t = 1")
    ! eigenvalues of J at gamma/h 2^k, k = 0..4: gamma/h I - J singular for h, h/2, ..., h/16
    f%f => lin5
    f%jac => lin5_jac
    opt%first_step = HS
    call ode_solve(f, [0.0_dp, 1.0_dp], [1.0_dp, 1.0_dp, 1.0_dp, 1.0_dp, 1.0_dp], opt, r)
    call ts%check(.not. r%success .and. r%status == CM_SINGULAR .and. &
                  index(r%message, "singular iteration matrix") > 0, "singular: "//r%message)
    opt%first_step = 0.0_dp
    f%f => vdp
    f%jac => vdp_jac

    ! bad input
    opt%rtol = -1.0_dp
    call ode_solve(f, [0.0_dp, 2.0_dp], [2.0_dp, -0.66_dp], opt, r)
    call ts%check(r%status == CM_BAD_INPUT .and. index(r%message, "rtol") > 0, &
                  "negative rtol: "//r%message)
    opt%rtol = 1.0e-6_dp
    call ode_solve(f, [0.0_dp, 2.0_dp], [2.0_dp, -0.66_dp], opt, r, t_eval=[3.0_dp])
    call ts%check(r%status == CM_BAD_INPUT, "t_eval outside t_span: "//r%message)
    opt%method = METHOD_RATTLE
    call ode_solve(f, [0.0_dp, 2.0_dp], [2.0_dp, -0.66_dp], opt, r)
    call ts%check(r%status == CM_BAD_INPUT .and. index(r%message, "constrained") > 0, &
                  "RATTLE in ode_solve: "//r%message)
    call ts%finish()
    deallocate (rs)         ! (main-program allocatables are not freed at exit)

contains

    subroutine vdp(t, y, dydt)
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        dydt = [y(2), ((1.0_dp - y(1)**2)*y(2) - y(1))/1.0e-6_dp]
    end subroutine vdp

    subroutine dae(t, y, dydt)
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        dydt = [y(2), y(2) + y(1)]
    end subroutine dae

    subroutine blowup(t, y, dydt)
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        dydt = y**2
    end subroutine blowup

    subroutine blowup_jac(t, y, dfdy)
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        dfdy(1, 1) = 2.0_dp*y(1)
    end subroutine blowup_jac

    subroutine lin5(t, y, dydt)
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        integer :: i
        do i = 1, 5
            dydt(i) = GAM0/HS*2.0_dp**(i - 1)*y(i)
        end do
    end subroutine lin5

    subroutine lin5_jac(t, y, dfdy)
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        integer :: i
        dfdy = 0.0_dp
        do i = 1, 5
            dfdy(i, i) = GAM0/HS*2.0_dp**(i - 1)
        end do
    end subroutine lin5_jac

    subroutine osc(t, y, dydt)
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        dydt = [y(2), -y(1)]
    end subroutine osc

    subroutine vdp_jac(t, y, dfdy)
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        dfdy(1, :) = [0.0_dp, 1.0_dp]
        dfdy(2, :) = [(-2.0_dp*y(1)*y(2) - 1.0_dp)/1.0e-6_dp, (1.0_dp - y(1)**2)/1.0e-6_dp]
    end subroutine vdp_jac

end program test_radau
