!> The structure-aware Jacobian products of the built-ins (Arenstorf, Hill) against the
!! dense J x at random states (to round-off), their f against `rhs` (bit for bit), the
!! default product of a system without one, and integrate_stm through the product against
!! the generic path (J formed and multiplied): same steps, same STM to round-off.
module jacobian_product_test_systems
    use conmech_kinds, only: dp
    use conmech_systems_basic, only: arenstorf
    use conmech_param_system, only: builtin_param_system
    implicit none
    private
    public :: arenstorf_dense, param_dense

    !> Arenstorf without its product: integrate_stm forms J and multiplies.
    type, extends(arenstorf) :: arenstorf_dense
    contains
        procedure :: has_jacobian_product => dense_no
    end type arenstorf_dense

    !> A parameter-continuation wrapper that hides the wrapped product (the dense path).
    type, extends(builtin_param_system) :: param_dense
    contains
        procedure :: has_jacobian_product => param_dense_no
    end type param_dense

contains

    logical function dense_no(self)
        class(arenstorf_dense), intent(in) :: self
        dense_no = .false.
    end function dense_no

    logical function param_dense_no(self)
        class(param_dense), intent(in) :: self
        param_dense_no = .false.
    end function param_dense_no

end module jacobian_product_test_systems

program test_jacobian_product
    use conmech
    use conmech_testing, only: test_suite
    use jacobian_product_test_systems, only: arenstorf_dense, param_dense
    implicit none
    type(test_suite) :: ts
    type(arenstorf) :: are
    type(hill_problem) :: hill
    type(kepler_2d) :: kep

    ts%name = "test_jacobian_product"
    call ts%check(are%has_jacobian_product() .and. hill%has_jacobian_product() .and. &
                  .not. kep%has_jacobian_product(), "has_jacobian_product: built-ins")
    call check_products(are, "arenstorf")
    call check_products(hill, "hill")
    call check_products(kep, "kepler (default product)")
    call check_fd(are, "arenstorf")
    call check_stm()
    call check_param_system()
    call ts%finish()

contains

    !> At 20 random states (away from the singularities) and blocks of k = 1, 4, 7
    !! columns: jacobian_product = J x and rhs_jacobian_product = [rhs, J x].
    subroutine check_products(sys, label)
        class(ode_system), intent(in) :: sys
        character(len=*), intent(in) :: label
        real(dp) :: y(4), jac(4, 4), x(4, 7), jx(4, 7), jx2(4, 7), ref(4, 7), f(4), f2(4)
        real(dp) :: err, err2, errf, scl
        integer :: trial, kk, k
        integer, parameter :: ks(3) = [1, 4, 7]
        err = 0.0_dp; err2 = 0.0_dp; errf = 0.0_dp
        do trial = 1, 20
            call random_number(y)
            y(1:2) = 0.4_dp + 0.6_dp*y(1:2)
            y(3:4) = 2.0_dp*y(3:4) - 1.0_dp
            call random_number(x)
            x = 2.0_dp*x - 1.0_dp
            call sys%jacobian(0.0_dp, y, jac)
            call sys%rhs(0.0_dp, y, f)
            do kk = 1, size(ks)
                k = ks(kk)
                ref(:, 1:k) = matmul(jac, x(:, 1:k))
                scl = maxval(abs(jac))*maxval(abs(x(:, 1:k)))
                call sys%jacobian_product(0.0_dp, 4, k, y, x(:, 1:k), jx(:, 1:k))
                call sys%rhs_jacobian_product(0.0_dp, 4, k, y, f2, x(:, 1:k), jx2(:, 1:k))
                err = max(err, maxval(abs(jx(:, 1:k) - ref(:, 1:k)))/scl)
                err2 = max(err2, maxval(abs(jx2(:, 1:k) - ref(:, 1:k)))/scl)
                errf = max(errf, maxval(abs(f2 - f)))
            end do
        end do
        call ts%check_less(err, 8*epsilon(1.0_dp), label//": jacobian_product = J x")
        call ts%check_less(err2, 8*epsilon(1.0_dp), label//": rhs_jacobian_product J x")
        call ts%check(errf == 0.0_dp, label//": rhs_jacobian_product f = rhs bit for bit")
    end subroutine check_products

    !> The analytic J against the central finite difference (independent: only rhs).
    subroutine check_fd(sys, label)
        class(ode_system), intent(in) :: sys
        character(len=*), intent(in) :: label
        real(dp) :: y(4), jac(4, 4), jfd(4, 4)
        y = [0.5_dp, 0.3_dp, 0.1_dp, -0.2_dp]
        call sys%jacobian(0.0_dp, y, jac)
        call ode_fd_jacobian(sys, 0.0_dp, y, jfd)
        call ts%check_less(maxval(abs(jac - jfd))/maxval(abs(jac)), 1.0e-9_dp, &
                           label//": analytic J = finite-difference J")
    end subroutine check_fd

    !> One Arenstorf period with the STM: product path against the generic path.
    subroutine check_stm()
        real(dp), parameter :: period = 17.0652165601579625588917206249_dp
        real(dp), parameter :: y0(4) = [0.994_dp, 0.0_dp, 0.0_dp, &
                                        -2.00158510637908252240537862224_dp]
        type(arenstorf_dense) :: dense
        type(ode_options) :: opt
        type(ode_stats) :: st1, st2
        real(dp) :: y1(4), y2(4), p1(4, 4), p2(4, 4)
        integer :: i, info1, info2
        opt%method = METHOD_DOP853
        opt%rtol = 1.0e-10_dp
        opt%atol = 1.0e-10_dp
        y1 = y0; y2 = y0
        p1 = 0.0_dp
        do i = 1, 4
            p1(i, i) = 1.0_dp
        end do
        p2 = p1
        call integrate_stm(are, 0.0_dp, period, y1, p1, opt, info1, stats=st1)
        call integrate_stm(dense, 0.0_dp, period, y2, p2, opt, info2, stats=st2)
        call ts%check(info1 == CM_SUCCESS .and. info2 == CM_SUCCESS, &
                      "integrate_stm (arenstorf) succeeds on both paths")
        call ts%check(st1%nfev == st2%nfev .and. st1%nfev == 3908, &
                      "integrate_stm (arenstorf): nfev 3908 on both paths")
        call ts%check_less(maxval(abs(p1 - p2))/maxval(abs(p2)), 1.0e-12_dp, &
                           "integrate_stm (arenstorf): product STM = generic STM")
        call ts%check_less(maxval(abs(y1 - y0)), 1.0e-6_dp, "arenstorf orbit closes")
    end subroutine check_stm

    !> builtin_param_system forwards the wrapped product: it reports it, the products agree
    !! with the wrapped system's bit for bit, and the continuation of Hill's variation
    !! orbits in m (symmetric shooting) gives the same branch through the product path
    !! as through the dense path (J formed), to round-off.
    subroutine check_param_system()
        type(builtin_param_system) :: ps
        type(param_dense) :: pd
        type(cont_options) :: o
        type(branch) :: b1, b2
        real(dp) :: y(4), x(4, 4), jx(4, 4), jx2(4, 4), f(4), f2(4), err
        real(dp), parameter :: y0(4) = [0.8_dp, 0.0_dp, 0.0_dp, 1.0_dp]
        integer :: info, i
        character(len=:), allocatable :: msg
        call make_param_system("hill", [0.15_dp, 1.0_dp], 1, ps, info, msg)
        call make_param_system("hill", [0.15_dp, 1.0_dp], 1, pd%builtin_param_system, &
                               info, msg)
        call ts%check(info == CM_SUCCESS .and. ps%has_jacobian_product() .and. &
                      .not. pd%has_jacobian_product(), "param system forwards the product")
        y = [0.7_dp, 0.2_dp, -0.1_dp, 0.9_dp]
        call random_number(x)
        call ps%rhs_jacobian_product(0.0_dp, 4, 4, y, f, x, jx)
        call ps%inner%rhs_jacobian_product(0.0_dp, 4, 4, y, f2, x, jx2)
        call ts%check(all(jx == jx2) .and. all(f == f2), &
                      "param system: f and J x = the wrapped system's (bit for bit)")
        o%conservative = .true.
        o%p_max = 0.25_dp
        o%max_points = 6
        call continue_orbits(ps, set_builtin_param, 0.15_dp, y0, 8.0_dp*atan(1.0_dp), b1, &
                             o, [1, 4], [1, 4], .false., 4.0_dp)
        call continue_orbits(pd, set_builtin_param, 0.15_dp, y0, 8.0_dp*atan(1.0_dp), b2, &
                             o, [1, 4], [1, 4], .false., 4.0_dp)
        call ts%check(b1%info == CM_SUCCESS .and. b2%info == CM_SUCCESS .and. &
                      b1%npoints == 6 .and. b2%npoints == 6, "hill family on both paths")
        err = 0.0_dp
        do i = 1, min(b1%npoints, b2%npoints)
            err = max(err, abs(b1%points(i)%p - b2%points(i)%p), &
                      abs(b1%points(i)%period - b2%points(i)%period), &
                      maxval(abs(b1%points(i)%y0 - b2%points(i)%y0)), &
                      abs(b1%points(i)%stability_index - b2%points(i)%stability_index))
        end do
        call ts%check_less(err, 1.0e-9_dp, "hill family: product path = dense path")
    end subroutine check_param_system

end program test_jacobian_product
