!> The structure-aware Jacobian products of the built-ins (Arenstorf, Hill) against the
!! dense J x at random states (to round-off), their f against `rhs` (bit for bit), the
!! default product of a system without one, and integrate_stm through the product against
!! the generic path (J formed and multiplied): same steps, same STM to round-off.
module jacobian_product_test_systems
    use conmech_kinds, only: dp
    use conmech_systems_basic, only: arenstorf
    implicit none
    private
    public :: arenstorf_dense

    !> Arenstorf without its product: integrate_stm forms J and multiplies.
    type, extends(arenstorf) :: arenstorf_dense
    contains
        procedure :: has_jacobian_product => dense_no
    end type arenstorf_dense

contains

    logical function dense_no(self)
        class(arenstorf_dense), intent(in) :: self
        dense_no = .false.
    end function dense_no

end module jacobian_product_test_systems

program test_jacobian_product
    use conmech
    use conmech_testing, only: test_suite
    use jacobian_product_test_systems, only: arenstorf_dense
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

end program test_jacobian_product
