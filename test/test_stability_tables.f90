!> The small shared pieces of the stability layer and of the built-in systems: the code ->
!! name tables, Illinois' regula falsi, the status of a result (`fail`), and the dense
!! Jacobians of motion in a rotating frame against their column products.
program test_stability_tables
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_code_names, only: code_name
    use conmech_illinois, only: illinois_bracket
    use conmech_outcome, only: outcome
    use conmech_branch_types, only: special_name, SP_FOLD, SP_BP, SP_PD, SP_NS
    use conmech_eq_branch_types, only: eq_special_name, EQ_FOLD, EQ_HOPF
    use conmech_orbit_types, only: orbit_method_name, ORBIT_SINGLE, ORBIT_MULTIPLE, &
                                   ORBIT_COLLOCATION, periodic_orbit
    use conmech_equilibria, only: classification_name, EQ_ASYMPTOTICALLY_STABLE, EQ_CENTRE
    use conmech_rotating_frame, only: rotating_frame_product, rotating_frame_jacobian, &
                                      spatial_frame_product, spatial_frame_jacobian
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    ts%name = "test_stability_tables"
    call test_names()
    call test_illinois()
    call test_outcome()
    call test_frames()
    call ts%finish()

contains

    subroutine test_names()
        call ts%check(code_name(2, [1, 2, 3], [character(len=3) :: "a", "bb", "ccc"], "?") &
                      == "bb", "code_name: the name of the code, trimmed")
        call ts%check(code_name(7, [1, 2], [character(len=2) :: "a", "b"], "none") == "none", &
                      "code_name: an unknown code gives the fallback")
        call ts%check(special_name(SP_FOLD) == "fold" .and. special_name(SP_BP) == &
                      "branch point" .and. special_name(SP_PD) == "period doubling" .and. &
                      special_name(SP_NS) == "Neimark-Sacker" .and. special_name(-1) == &
                      "unknown", "special_name table")
        call ts%check(eq_special_name(EQ_FOLD) == "fold" .and. eq_special_name(EQ_HOPF) == &
                      "Hopf" .and. eq_special_name(99) == "unknown", "eq_special_name table")
        call ts%check(orbit_method_name(ORBIT_SINGLE) == "single" .and. &
                      orbit_method_name(ORBIT_MULTIPLE) == "multiple" .and. &
                      orbit_method_name(ORBIT_COLLOCATION) == "collocation", &
                      "orbit_method_name table")
        call ts%check(classification_name(EQ_ASYMPTOTICALLY_STABLE) == &
                      "asymptotically stable" .and. classification_name(EQ_CENTRE) == &
                      "centre (linearly stable)" .and. classification_name(-5) == &
                      "degenerate (linearisation inconclusive)", "classification_name table")
    end subroutine test_names

    !> Root of x^3 - 2 on [0, 2]: Illinois reaches 1e-15 in far fewer evaluations than the
    !! 50 of bisection.
    subroutine test_illinois()
        type(illinois_bracket) :: br
        real(dp) :: c, fc, root
        integer :: it
        logical :: moved
        root = 2.0_dp**(1.0_dp/3.0_dp)
        br%a = 0.0_dp
        br%b = 2.0_dp
        br%fa = f(br%a)
        br%fb = f(br%b)
        do it = 1, 100
            c = br%trial()
            call ts%check(c > min(br%a, br%b) .and. c < max(br%a, br%b), &
                          "illinois: the trial lies inside the bracket")
            fc = f(c)
            if (abs(c - root) <= 1.0e-15_dp .or. fc == 0.0_dp) exit
            call br%update(c, fc, moved)
            call ts%check(br%fa*br%fb < 0.0_dp, "illinois: the bracket keeps the sign change")
        end do
        call ts%check_close(c, root, 1.0e-15_dp, "illinois: the cube root of 2")
        call ts%check_less(real(it, dp), 15.0_dp, "illinois: superlinear (under 15 trials)")
        ! equal values at both ends: the secant has no root, the midpoint is taken
        br%a = 1.0_dp
        br%b = 3.0_dp
        br%fa = 1.0_dp
        br%fb = 1.0_dp
        call ts%check_close(br%trial(), 2.0_dp, 0.0_dp, "illinois: midpoint when fa == fb")
    end subroutine test_illinois

    pure real(dp) function f(x)
        real(dp), intent(in) :: x
        f = x**3 - 2.0_dp
    end function f

    subroutine test_outcome()
        type(periodic_orbit) :: orbit
        type(outcome) :: o
        call ts%check(o%info == CM_BAD_INPUT, "outcome: unset means bad input")
        call orbit%fail(CM_SINGULAR, "singular")
        call ts%check(orbit%info == CM_SINGULAR .and. orbit%message == "singular", &
                      "fail sets the status and the message of an orbit")
    end subroutine test_outcome

    !> J x by the column products equals the dense J times x (planar and spatial).
    subroutine test_frames()
        real(dp) :: x4(4, 3), j4(4, 4), p4(4, 3), x6(6, 5), j6(6, 6), p6(6, 5), h(6)
        integer :: i, j
        do j = 1, 3
            do i = 1, 4
                x4(i, j) = sin(real(3*i + 7*j, dp))
            end do
        end do
        call rotating_frame_jacobian(1.5_dp, -0.25_dp, 0.75_dp, 0.3_dp, j4)
        call rotating_frame_product(3, 1.5_dp, -0.25_dp, 0.75_dp, 0.3_dp, x4, p4)
        call ts%check_less(maxval(abs(matmul(j4, x4) - p4)), 1.0e-15_dp, &
                           "planar rotating frame: product = dense J x")
        call ts%check(j4(3, 4) == 0.3_dp .and. j4(4, 3) == -0.3_dp .and. j4(1, 3) == 1.0_dp, &
                      "planar rotating frame: Coriolis and velocity entries")
        h = [2.0_dp, -0.5_dp, 0.25_dp, -1.0_dp, 0.125_dp, 3.0_dp]
        do j = 1, 5
            do i = 1, 6
                x6(i, j) = cos(real(5*i + 2*j, dp))
            end do
        end do
        call spatial_frame_jacobian(h, 2.0_dp, j6)
        call spatial_frame_product(5, h, 2.0_dp, x6, p6)
        call ts%check_less(maxval(abs(matmul(j6, x6) - p6)), 1.0e-14_dp, &
                           "spatial rotating frame: product = dense J x")
        call ts%check(all(j6(4:6, 1:3) == transpose(j6(4:6, 1:3))), &
                      "spatial rotating frame: the Hessian block is symmetric")
        call ts%check(j6(4, 5) == 2.0_dp .and. j6(5, 4) == -2.0_dp .and. j6(6, 4) == 0.0_dp, &
                      "spatial rotating frame: Coriolis entries")
    end subroutine test_frames

end program test_stability_tables
