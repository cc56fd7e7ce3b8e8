!> Radau IIA's sparse path (sparse LUs of the iteration matrices, J kept on its pattern)
!! against the dense LAPACK path on the same problem with the same pattern:
!! - Robertson's chemical kinetics (Hairer & Wanner II, section IV.1) and Van der Pol at
!!   eps = 1e-6, with the analytic Jacobian and with grouped differences: the same steps,
!!   Jacobians and LUs, and end points equal to rounding;
!! - the one-dimensional Brusselator (Hairer & Wanner II, section IV.1; N = 500 points,
!!   n = 1000, the unknowns numbered u_1..u_N, v_1..v_N so that the pattern is not banded):
!!   the rule picks the sparse path, the same counts and end point as the dense one;
!! - the sparse stepper packed and unpacked at every step: the steps and counters of
!!   ode_solve, bit for bit.
program test_radau_sparse
    use conmech
    use conmech_jacobian_structure, only: LU_DENSE, LU_SPARSE, LU_AUTO
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    integer, parameter :: NB = 500
    real(dp), parameter :: ALPHA_B = 1.0_dp/50.0_dp
    type(ode_function) :: f
    type(ode_options) :: opt
    type(ode_result) :: rd, rs
    type(radau_stepper) :: sd, ss
    type(radau_stepper), allocatable :: st
    type(state_packer) :: pk
    integer, allocatable :: ptr(:), idx(:)
    real(dp), allocatable :: y0(:)
    integer :: info, k, pass
    logical :: same
    character(len=:), allocatable :: msg, what

    ts%name = "test_radau_sparse"
    opt%method = METHOD_RADAU5
    do pass = 1, 4
        select case (pass)
        case (1, 2)
            f%f => robertson
            f%jac => robertson_jac
            if (pass == 2) f%jac => null()
            what = "Robertson"
            opt%rtol = 1.0e-6_dp
            opt%atol = 1.0e-10_dp
            y0 = [1.0_dp, 0.0_dp, 0.0_dp]
            call full_pattern(3, ptr, idx)
            call compare([0.0_dp, 1.0e5_dp], y0)
        case (3, 4)
            f%f => vdp
            f%jac => vdp_jac
            if (pass == 4) f%jac => null()
            what = "Van der Pol"
            opt%rtol = 1.0e-6_dp
            opt%atol = 1.0e-6_dp
            y0 = [2.0_dp, -0.66_dp]
            call full_pattern(2, ptr, idx)
            call compare([0.0_dp, 2.0_dp], y0)
        end select
    end do
    ! the Brusselator: the rule takes the sparse path
    f%f => brusselator
    f%jac => null()
    what = "Brusselator N = 500"
    opt%rtol = 1.0e-6_dp
    opt%atol = 1.0e-6_dp
    y0 = brusselator_y0()
    call brusselator_pattern(ptr, idx)
    call compare([0.0_dp, 10.0_dp], y0, LU_AUTO)
    ! packed and unpacked at every step
    opt%rtol = 1.0e-4_dp
    opt%atol = 1.0e-4_dp
    call new_structure(ss, LU_SPARSE)
    call ode_solve(f, [0.0_dp, 2.0_dp], y0, opt, rs, stepper=ss)
    allocate (st)
    call new_structure(st, LU_SPARSE)
    call st%init(0.0_dp, 2.0_dp, y0, opt, info, msg)
    if (info == CM_SUCCESS) call st%start(f, info, msg)
    same = .true.
    do k = 2, rs%nt
        call stepper_pack(st, pk)
        deallocate (st)
        allocate (st)
        call stepper_unpack(st, METHOD_RADAU5, pk%r(1:pk%nr), pk%iv(1:pk%ni), &
                            pk%w(:, 1:pk%nw), info, msg)
        if (info /= CM_SUCCESS) exit
        call st%step(f, 2.0_dp, info, msg)
        if (info /= CM_SUCCESS) exit
        same = same .and. st%t == rs%t(k) .and. all(st%y == rs%y(:, k))
    end do
    call ts%check(info == CM_SUCCESS .and. same .and. st%sparse .and. &
                  all([st%st%nfev, st%st%njev, st%st%nlu, st%st%naccept] == &
                      [rs%stats%nfev, rs%stats%njev, rs%stats%nlu, rs%stats%naccept]), &
                  "sparse stepper packed and unpacked at every step: the steps and "// &
                  "counters of ode_solve")
    call ts%finish()
    ! main-program allocatables are not freed at exit (the leak check would report them)
    if (allocated(st)) deallocate (st)
    if (allocated(ptr)) deallocate (ptr)
    if (allocated(idx)) deallocate (idx)
    if (allocated(y0)) deallocate (y0)
    if (allocated(msg)) deallocate (msg)
    if (allocated(what)) deallocate (what)

contains

    !> The dense and the sparse path with the pattern (ptr, idx) on t_span from y.
    subroutine compare(tspan, y, sparse_mode)
        real(dp), intent(in) :: tspan(2), y(:)
        integer, intent(in), optional :: sparse_mode
        integer :: mode
        character(len=200) :: buf
        mode = LU_SPARSE
        if (present(sparse_mode)) mode = sparse_mode
        call new_structure(sd, LU_DENSE)
        call new_structure(ss, mode)
        call ode_solve(f, tspan, y, opt, rd, stepper=sd)
        call ode_solve(f, tspan, y, opt, rs, stepper=ss)
        write (buf, '(5i7,a,5i7)') rd%stats%nfev, rd%stats%njev, rd%stats%nlu, &
            rd%stats%naccept, rd%stats%nreject, " /", rs%stats%nfev, rs%stats%njev, &
            rs%stats%nlu, rs%stats%naccept, rs%stats%nreject
        call ts%check(rd%success .and. rs%success .and. ss%sparse .and. .not. sd%sparse, &
                      what//": both paths succeed, the sparse one taken")
        call ts%check(rd%stats%nfev == rs%stats%nfev .and. rd%stats%njev == rs%stats%njev &
                      .and. rd%stats%nlu == rs%stats%nlu .and. rd%stats%naccept == &
                      rs%stats%naccept .and. rd%stats%nreject == rs%stats%nreject, &
                      what//": the same nfev njev nlu naccept nreject"//trim(buf))
        call ts%check_less(maxval(abs(rd%y(:, rd%nt) - rs%y(:, rs%nt))/(1.0e-6_dp + &
                           abs(rd%y(:, rd%nt)))), 1.0e-8_dp, what//": the same end point")
    end subroutine compare

    subroutine new_structure(s, mode)
        type(radau_stepper), intent(inout) :: s
        integer, intent(in) :: mode
        integer :: i2
        character(len=:), allocatable :: m2
        s%jstruct%lu = mode
        call s%jstruct%set_pattern(size(ptr) - 1, ptr, idx, i2, m2)
    end subroutine new_structure

    subroutine full_pattern(n, p, ix)
        integer, intent(in) :: n
        integer, allocatable, intent(out) :: p(:), ix(:)
        integer :: j, i
        p = [(1 + n*j, j=0, n)]
        ix = [((i, i=1, n), j=1, n)]
    end subroutine full_pattern

    subroutine robertson(t, y, dydt)
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        dydt(1) = -0.04_dp*y(1) + 1.0e4_dp*y(2)*y(3)
        dydt(3) = 3.0e7_dp*y(2)**2
        dydt(2) = -dydt(1) - dydt(3)
    end subroutine robertson

    subroutine robertson_jac(t, y, dfdy)
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dfdy(:, :)
        dfdy(1, :) = [-0.04_dp, 1.0e4_dp*y(3), 1.0e4_dp*y(2)]
        dfdy(3, :) = [0.0_dp, 6.0e7_dp*y(2), 0.0_dp]
        dfdy(2, :) = -dfdy(1, :) - dfdy(3, :)
    end subroutine robertson_jac

    subroutine vdp(t, y, dydt)
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        dydt(1) = y(2)
        dydt(2) = ((1.0_dp - y(1)**2)*y(2) - y(1))/1.0e-6_dp
    end subroutine vdp

    subroutine vdp_jac(t, y, dfdy)
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dfdy(:, :)
        dfdy(1, :) = [0.0_dp, 1.0_dp]
        dfdy(2, :) = [(-2.0_dp*y(1)*y(2) - 1.0_dp)/1.0e-6_dp, (1.0_dp - y(1)**2)/1.0e-6_dp]
    end subroutine vdp_jac

    !> u_i = y(i), v_i = y(NB + i) on x_i = i/(NB + 1); u = 1, v = 3 at both ends.
    subroutine brusselator(t, y, dydt)
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: c, ul, ur, vl, vr, u, v
        integer :: i
        c = ALPHA_B*real(NB + 1, dp)**2
        do i = 1, NB
            u = y(i)
            v = y(NB + i)
            ul = 1.0_dp
            ur = 1.0_dp
            vl = 3.0_dp
            vr = 3.0_dp
            if (i > 1) ul = y(i - 1)
            if (i < NB) ur = y(i + 1)
            if (i > 1) vl = y(NB + i - 1)
            if (i < NB) vr = y(NB + i + 1)
            dydt(i) = 1.0_dp + u*u*v - 4.0_dp*u + c*(ul - 2.0_dp*u + ur)
            dydt(NB + i) = 3.0_dp*u - u*u*v + c*(vl - 2.0_dp*v + vr)
        end do
    end subroutine brusselator

    function brusselator_y0() result(y)
        real(dp) :: y(2*NB)
        integer :: i
        real(dp), parameter :: PI = 4.0_dp*atan(1.0_dp)
        do i = 1, NB
            y(i) = 1.0_dp + sin(2.0_dp*PI*real(i, dp)/real(NB + 1, dp))
            y(NB + i) = 3.0_dp
        end do
    end function brusselator_y0

    subroutine brusselator_pattern(p, ix)
        integer, allocatable, intent(out) :: p(:), ix(:)
        integer :: j, i, m, pos
        logical :: a(2*NB, 2*NB)
        a = .false.
        do i = 1, NB
            do m = max(1, i - 1), min(NB, i + 1)
                a(i, m) = .true.
                a(NB + i, NB + m) = .true.
            end do
            a(i, NB + i) = .true.
            a(NB + i, i) = .true.
        end do
        allocate (p(2*NB + 1), ix(count(a)))
        pos = 0
        p(1) = 1
        do j = 1, 2*NB
            do i = 1, 2*NB
                if (.not. a(i, j)) cycle
                pos = pos + 1
                ix(pos) = i
            end do
            p(j + 1) = pos + 1
        end do
    end subroutine brusselator_pattern

end program test_radau_sparse
