!> A compiled (bind(C)) system with a C Jacobian product `jac_prod`: the product agrees
!! with the built-in Arenstorf's J x, and integrate_stm through it gives the built-in's
!! state and STM (same steps); without it (set_c_jac_prod(null)) the finite-difference path.
module test_c_jac_prod_funcs
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    implicit none
contains
    !> Arenstorf's orbit, p = [mu] (the built-in's arithmetic).
    subroutine are_c_rhs(t, y, f, p) bind(c)
        real(c_double), value :: t
        real(c_double), intent(in) :: y(*), p(*)
        real(c_double), intent(out) :: f(*)
        real(c_double) :: mu, mp, d1, d2
        mu = p(1)
        mp = 1.0_c_double - mu
        d1 = (y(1) + mu)**2 + y(2)**2
        d1 = d1*sqrt(d1)
        d2 = (y(1) - mp)**2 + y(2)**2
        d2 = d2*sqrt(d2)
        f(1) = y(3)
        f(2) = y(4)
        f(3) = y(1) + 2.0_c_double*y(4) - mp*(y(1) + mu)/d1 - mu*(y(1) - mp)/d2
        f(4) = y(2) - 2.0_c_double*y(3) - mp*y(2)/d1 - mu*y(2)/d2
    end subroutine are_c_rhs
    !> jx = J x, written out (two rows copied, the Coriolis entries folded).
    subroutine are_c_jac_prod(t, y, k, x, jx, p) bind(c)
        real(c_double), value :: t
        real(c_double), intent(in) :: y(*), p(*)
        integer(c_int), value :: k
        real(c_double), intent(in) :: x(4, *)
        real(c_double), intent(out) :: jx(4, *)
        real(c_double) :: mu, mp, x1, x2, s1, s2, a1, a2, b1, b2, uxx, uxy, uyy
        integer :: j
        mu = p(1)
        mp = 1.0_c_double - mu
        x1 = y(1) + mu
        x2 = y(1) - mp
        s1 = x1**2 + y(2)**2
        s2 = x2**2 + y(2)**2
        a1 = mp/(s1*sqrt(s1))
        a2 = mu/(s2*sqrt(s2))
        b1 = 3.0_c_double*a1/s1
        b2 = 3.0_c_double*a2/s2
        uxx = 1.0_c_double - a1 - a2 + b1*x1**2 + b2*x2**2
        uxy = (b1*x1 + b2*x2)*y(2)
        uyy = 1.0_c_double - a1 - a2 + (b1 + b2)*y(2)**2
        do j = 1, k
            jx(1, j) = x(3, j)
            jx(2, j) = x(4, j)
            jx(3, j) = uxx*x(1, j) + uxy*x(2, j) + 2.0_c_double*x(4, j)
            jx(4, j) = uxy*x(1, j) + uyy*x(2, j) - 2.0_c_double*x(3, j)
        end do
    end subroutine are_c_jac_prod
end module test_c_jac_prod_funcs

program test_c_jac_prod
    use, intrinsic :: iso_c_binding, only: c_funloc, c_null_funptr
    use conmech
    use conmech_testing, only: test_suite
    use test_c_jac_prod_funcs
    implicit none
    real(dp), parameter :: period = 17.0652165601579625588917206249_dp
    real(dp), parameter :: y0(4) = [0.994_dp, 0.0_dp, 0.0_dp, &
                                    -2.00158510637908252240537862224_dp]
    type(test_suite) :: ts

    ts%name = "test_c_jac_prod"
    call run()    ! locals of a procedure are freed on return (LeakSanitizer)
    call ts%finish()

contains

    subroutine run()
        type(c_ode_system) :: cs
        type(arenstorf) :: are
        type(ode_options) :: opt
        type(ode_stats) :: st1, st2
        real(dp) :: y(4), x(4, 3), jx(4, 3), ref(4, 3), y1(4), y2(4), p1(4, 4), p2(4, 4)
        integer :: info, info1, info2, i
        character(len=:), allocatable :: msg
        call make_c_ode(4, c_funloc(are_c_rhs), c_null_funptr, [are%mu], cs, info, msg)
        call ts%check(info == CM_SUCCESS .and. .not. cs%has_jacobian_product(), &
                      "make_c_ode: no product without jac_prod")
        call set_c_jac_prod(cs, c_funloc(are_c_jac_prod))
        call ts%check(cs%has_jacobian_product(), "set_c_jac_prod: has_jacobian_product")
        y = [0.5_dp, 0.3_dp, 0.1_dp, -0.2_dp]
        x = reshape([(sin(1.3_dp*i), i=1, 12)], [4, 3])
        call cs%jacobian_product(0.0_dp, 4, 3, y, x, jx)
        call are%jacobian_product(0.0_dp, 4, 3, y, x, ref)
        call ts%check_less(maxval(abs(jx - ref))/maxval(abs(ref)), 1.0e-14_dp, &
                           "C jac_prod = built-in J x")

        opt%method = METHOD_DOP853
        opt%rtol = 1.0e-10_dp
        opt%atol = 1.0e-10_dp
        y1 = y0; y2 = y0
        p1 = 0.0_dp
        do i = 1, 4
            p1(i, i) = 1.0_dp
        end do
        p2 = p1
        call integrate_stm(cs, 0.0_dp, period, y1, p1, opt, info1, stats=st1)
        call integrate_stm(are, 0.0_dp, period, y2, p2, opt, info2, stats=st2)
        call ts%check(info1 == CM_SUCCESS .and. info2 == CM_SUCCESS .and. &
                      st1%nfev == st2%nfev, "integrate_stm through jac_prod: success, same nfev")
        ! the STM's rounding differs (other formulas), and it is under error control: the steps
        ! differ at round-off, the results by about the tolerance times the orbit's sensitivity
        call ts%check_less(maxval(abs(y1 - y2)), 1.0e-8_dp, &
                           "integrate_stm through jac_prod: the built-in's state")
        call ts%check_less(maxval(abs(p1 - p2))/maxval(abs(p2)), 1.0e-8_dp, &
                           "integrate_stm through jac_prod: the built-in's STM")

        ! without the product: the finite-difference Jacobian path, STM to ~1e-6
        call set_c_jac_prod(cs, c_null_funptr)
        y1 = y0
        p1 = 0.0_dp
        do i = 1, 4
            p1(i, i) = 1.0_dp
        end do
        call integrate_stm(cs, 0.0_dp, period, y1, p1, opt, info1)
        call ts%check(info1 == CM_SUCCESS .and. .not. cs%has_jacobian_product(), &
                      "set_c_jac_prod(null): the default path")
        call ts%check_less(maxval(abs(p1 - p2))/maxval(abs(p2)), 1.0e-4_dp, &
                           "finite-difference STM near the exact one")
    end subroutine run

end program test_c_jac_prod
