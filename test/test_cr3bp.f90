!> The spatial CR3BP and Hill's problem in space as built-in systems: libration points
!! (equilibria, Jacobi constants, L4/L5 closed forms), the exact Jacobian against
!! differences, the Jacobian product against the dense product, the Jacobi integral along
!! a solution, and the energy of the built-in systems (conmech_system_energy).
program test_cr3bp
    use conmech
    use conmech_testing
    implicit none
    type(test_suite) :: ts
    ts%name = "test_cr3bp"
    call test_libration(ts)
    call test_jacobians(ts)
    call test_jacobi_conserved(ts)
    call test_energy(ts)
    call ts%finish()

contains

    subroutine test_libration(ts)
        type(test_suite), intent(inout) :: ts
        real(dp) :: pos(3, 5), cj(5), f(6), mus(3)
        type(cr3bp) :: s
        integer :: info, k, j
        mus = [0.012150585609624_dp, 0.5_dp, 1.0e-6_dp]
        do j = 1, 3
            s%mu = mus(j)
            call cr3bp_libration_points(s%mu, pos, cj, info)
            call ts%check(info == CM_SUCCESS, "libration points computed")
            do k = 1, 5
                call s%rhs(0.0_dp, [pos(:, k), 0.0_dp, 0.0_dp, 0.0_dp], f)
                call ts%check_less(maxval(abs(f)), 1.0e-13_dp, "L_k is an equilibrium")
            end do
            call ts%check(pos(1, 3) < -s%mu .and. -s%mu < pos(1, 1) .and. &
                          pos(1, 1) < 1.0_dp - s%mu .and. 1.0_dp - s%mu < pos(1, 2), &
                          "L3 < primary 1 < L1 < primary 2 < L2")
            ! L4, L5: C = 3 - mu (1 - mu)
            call ts%check_close(cj(4), 3.0_dp - s%mu*(1.0_dp - s%mu), 1.0e-14_dp, &
                                "C(L4) = 3 - mu (1 - mu)")
        end do
        call cr3bp_libration_points(0.7_dp, pos, cj, info)
        call ts%check(info == CM_BAD_INPUT, "mu > 1/2 is bad input")
    end subroutine test_libration

    subroutine test_jacobians(ts)
        type(test_suite), intent(inout) :: ts
        type(cr3bp) :: s
        type(hill_spatial) :: h
        real(dp) :: y(6), jac(6, 6), fd(6, 6), fp(6), fm(6), x(6, 3), jx(6, 3), dydt(6)
        real(dp) :: jx2(6, 3)
        integer :: j
        y = [0.8_dp, 0.05_dp, 0.03_dp, 0.01_dp, 0.2_dp, -0.05_dp]
        call s%jacobian(0.0_dp, y, jac)
        do j = 1, 6
            call s%rhs(0.0_dp, y + 1.0e-6_dp*unit(j), fp)
            call s%rhs(0.0_dp, y - 1.0e-6_dp*unit(j), fm)
            fd(:, j) = (fp - fm)/2.0e-6_dp
        end do
        call ts%check_less(maxval(abs(jac - fd)), 1.0e-8_dp, "cr3bp: Jacobian = differences")
        call random_number(x)
        call s%jacobian_product(0.0_dp, 6, 3, y, x, jx)
        call ts%check_less(maxval(abs(jx - matmul(jac, x))), 1.0e-14_dp, &
                           "cr3bp: J x = dense product")
        call s%rhs_jacobian_product(0.0_dp, 6, 3, y, dydt, x, jx2)
        call ts%check_less(maxval(abs(jx2 - jx)), 0.0_dp + tiny(1.0_dp), &
                           "cr3bp: rhs_jacobian_product = jacobian_product")
        call ts%check(s%has_jacobian() .and. s%has_jacobian_product(), "cr3bp: analytic")
        h%m = 0.1_dp
        y = [0.7_dp, -0.2_dp, 0.05_dp, 0.1_dp, 0.5_dp, 0.02_dp]
        call h%jacobian(0.0_dp, y, jac)
        do j = 1, 6
            call h%rhs(0.0_dp, y + 1.0e-6_dp*unit(j), fp)
            call h%rhs(0.0_dp, y - 1.0e-6_dp*unit(j), fm)
            fd(:, j) = (fp - fm)/2.0e-6_dp
        end do
        call ts%check_less(maxval(abs(jac - fd)), 1.0e-7_dp, &
                           "hill_spatial: Jacobian = differences")
        call h%jacobian_product(0.0_dp, 6, 3, y, x, jx)
        call ts%check_less(maxval(abs(jx - matmul(jac, x))), 1.0e-14_dp, &
                           "hill_spatial: J x = dense product")
    end subroutine test_jacobians

    function unit(j) result(e)
        integer, intent(in) :: j
        real(dp) :: e(6)
        e = 0.0_dp
        e(j) = 1.0_dp
    end function unit

    subroutine test_jacobi_conserved(ts)
        type(test_suite), intent(inout) :: ts
        type(cr3bp) :: s
        type(ode_options) :: o
        real(dp) :: y(6), c0
        integer :: info
        character(len=:), allocatable :: msg
        y = [0.8_dp, 0.05_dp, 0.03_dp, 0.01_dp, 0.2_dp, -0.05_dp]
        c0 = cr3bp_jacobi(s%mu, y)
        o%rtol = 1.0e-12_dp
        o%atol = 1.0e-12_dp
        call ode_integrate(s, 0.0_dp, 5.0_dp, y, o, info, message=msg)
        call ts%check(info == CM_SUCCESS, "cr3bp: integrated")
        call ts%check_less(abs(cr3bp_jacobi(s%mu, y) - c0), 1.0e-10_dp, &
                           "cr3bp: Jacobi constant conserved")
    end subroutine test_jacobi_conserved

    subroutine test_energy(ts)
        type(test_suite), intent(inout) :: ts
        class(ode_system), allocatable :: sys
        real(dp) :: e
        integer :: info
        character(len=:), allocatable :: msg
        call make_system("harmonic", [2.0_dp], sys, info, msg)
        call system_energy(sys, 0.0_dp, [0.3_dp, -0.7_dp], e, info, msg)
        call ts%check_close(e, 0.5_dp*(0.49_dp + 4.0_dp*0.09_dp), 1.0e-15_dp, &
                            "energy of the harmonic oscillator")
        call ts%check(system_has_energy(sys), "the harmonic oscillator has an energy")
        call make_system("double_pendulum", [real(dp) ::], sys, info, msg)
        call system_energy(sys, 0.0_dp, [0.1_dp, 0.2_dp, 0.0_dp, 0.0_dp], e, info, msg)
        call ts%check_close(e, -9.81_dp*(2.0_dp*cos(0.1_dp) + cos(0.2_dp)), 1.0e-13_dp, &
                            "energy of the double pendulum at rest = U")
        call ts%check(system_has_energy(sys), "the double pendulum has an energy")
        call system_energy(sys, 0.0_dp, [0.1_dp, 0.2_dp, 0.0_dp], e, info, msg)
        call ts%check(info == CM_BAD_INPUT .and. index(msg, "even") > 0, &
                      "double pendulum: an odd state size is bad input with a message")
        call system_energy(sys, 0.0_dp, [real(dp) ::], e, info, msg)
        call ts%check(info == CM_BAD_INPUT, "double pendulum: an empty state is bad input")
        call make_system("vanderpol", [1.0_dp], sys, info, msg)
        call ts%check(.not. system_has_energy(sys), "Van der Pol has no energy")
        call system_energy(sys, 0.0_dp, [0.1_dp, 0.2_dp], e, info, msg)
        call ts%check(info == CM_BAD_INPUT .and. index(msg, "no energy") > 0, &
                      "Van der Pol: energy is bad input with a message")
        call make_system("cr3bp", [0.1_dp], sys, info, msg)
        call system_energy(sys, 0.0_dp, [0.5_dp, 0.0_dp, 0.0_dp], e, info, msg)
        call ts%check(info == CM_BAD_INPUT, "wrong state size is bad input")
    end subroutine test_energy

end program test_cr3bp
