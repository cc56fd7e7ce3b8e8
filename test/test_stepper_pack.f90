!> The contract's packing for the methods not checked elsewhere: a stepper packed into
!! plain arrays after every step and unpacked into a fresh object before the next (nothing
!! kept between steps, as the Python objects do) makes the steps of the one driver loop,
!! bit for bit: the explicit Runge-Kutta methods on Kepler's problem, RATTLE on the
!! Cartesian pendulum (a constrained system, y = [q; v]). A packed state of another
!! method, or a never-started one, is refused with CM_BAD_INPUT.
program test_stepper_pack
    use conmech
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    type(kepler_2d) :: kep
    type(ode_options) :: opt
    type(ode_result) :: r
    type(state_packer) :: pk
    type(rk_stepper), allocatable :: rk, rk2
    type(rattle_stepper), allocatable :: ra, ra2
    type(constrained_ode) :: fo
    class(constrained_system), allocatable :: cs
    real(dp) :: tf, q0(2)
    integer :: m, k, info
    logical :: same
    character(len=:), allocatable :: msg

    ts%name = "test_stepper_pack"
    tf = 2.0_dp*acos(-1.0_dp)
    opt%rtol = 1.0e-8_dp
    opt%atol = 1.0e-8_dp
    do m = METHOD_RK4, METHOD_VERNER98
        opt%method = m
        opt%first_step = merge(0.01_dp, 0.0_dp, m == METHOD_RK4)
        call ode_solve(kep, [0.0_dp, tf], [0.4_dp, 0.0_dp, 0.0_dp, 2.0_dp], opt, r)
        allocate (rk)
        call rk%init(0.0_dp, tf, [0.4_dp, 0.0_dp, 0.0_dp, 2.0_dp], opt, info, msg)
        call rk%start(kep, info, msg)
        same = info == CM_SUCCESS
        do k = 2, r%nt
            call stepper_pack(rk, pk)
            allocate (rk2)
            call stepper_unpack(rk2, m, pk%r(1:pk%nr), pk%iv(1:pk%ni), pk%w(:, 1:pk%nw), &
                                info, msg)
            call move_alloc(rk2, rk)
            if (info == CM_SUCCESS) call rk%step(kep, tf, info, msg)
            same = same .and. info == CM_SUCCESS .and. rk%t == r%t(k) .and. &
                   all(rk%y == r%y(:, k))
        end do
        call ts%check(same .and. rk%last .and. rk%st%nfev == r%stats%nfev .and. &
                      rk%st%nreject == r%stats%nreject, &
                      "RK packed at every step = ode_solve, method "//achar(48 + m))
        call stepper_pack(rk, pk)
        allocate (rk2)
        call stepper_unpack(rk2, METHOD_RADAU5, pk%r(1:pk%nr), pk%iv(1:pk%ni), &
                            pk%w(:, 1:pk%nw), info, msg)
        call ts%check(info == CM_BAD_INPUT, "another method's state is refused: "//msg)
        deallocate (rk, rk2)
    end do
    pk%iv = 0
    allocate (rk2)
    call stepper_unpack(rk2, METHOD_DOP853, pk%r, pk%iv, pk%w, info, msg)
    call ts%check(info == CM_BAD_INPUT, "a state never started is refused")

    ! RATTLE: the constrained layer's run and the stepper packed at every step
    call make_constrained("pendulum_xy", [1.0_dp, 9.81_dp, 1.0_dp], cs, info, msg)
    q0 = [sin(1.0_dp), -cos(1.0_dp)]
    opt%method = METHOD_RATTLE
    opt%first_step = 0.01_dp
    allocate (fo%mech, source=cs)
    allocate (ra)
    allocate (ra%mech, source=cs)
    call ode_solve(fo, [0.0_dp, 1.0_dp], [q0, 0.0_dp, 0.0_dp], opt, r, stepper=ra)
    call ts%check(r%success .and. r%nt == 101, "RATTLE through ode_solve: "//r%message)
    deallocate (ra)
    allocate (ra)
    allocate (ra%mech, source=cs)
    call ra%init(0.0_dp, 1.0_dp, [q0, 0.0_dp, 0.0_dp], opt, info, msg)
    call ra%start(fo, info, msg)
    same = info == CM_SUCCESS
    do k = 2, r%nt
        call stepper_pack(ra, pk)
        allocate (ra2)
        allocate (ra2%mech, source=cs)          ! the system, as for any stepper's sys
        call stepper_unpack(ra2, METHOD_RATTLE, pk%r(1:pk%nr), pk%iv(1:pk%ni), &
                            pk%w(:, 1:pk%nw), info, msg)
        call move_alloc(ra2, ra)
        if (info == CM_SUCCESS) call ra%step(fo, 1.0_dp, info, msg)
        same = same .and. info == CM_SUCCESS .and. ra%t == r%t(k) .and. &
               all(ra%y == r%y(:, k))
    end do
    call ts%check(same .and. ra%last .and. ra%st%nfev == r%stats%nfev, &
                  "RATTLE packed at every step = ode_solve, bit for bit")
    call ts%finish()
    deallocate (ra, rk2, cs)   ! (main-program allocatables are not freed at exit)
    if (allocated(msg)) deallocate (msg)

end program test_stepper_pack
