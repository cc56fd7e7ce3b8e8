!> Compiled (bind(C)) user systems: c_ode_system and c_generalized_system agree with the
!! hand-written built-ins; the exact accelerations' Jacobian agrees with finite differences.
module test_c_funcs
    use, intrinsic :: iso_c_binding, only: c_double
    implicit none
contains
    subroutine kep_rhs(t, y, f, p) bind(c)
        real(c_double), value :: t
        real(c_double), intent(in) :: y(*), p(*)
        real(c_double), intent(out) :: f(*)
        real(c_double) :: r2
        r2 = y(1)**2 + y(2)**2
        f(1:2) = y(3:4)
        f(3:4) = -p(1)*y(1:2)/(r2*sqrt(r2))
    end subroutine kep_rhs
    ! cart pendulum, q = [x, th], p = [M, m, l, g] (theta from the upright)
    subroutine cart_mass(t, q, mm, p) bind(c)
        real(c_double), value :: t
        real(c_double), intent(in) :: q(*), p(*)
        real(c_double), intent(out) :: mm(2, 2)
        mm(1, 1) = p(1) + p(2)
        mm(2, 1) = p(2)*p(3)*cos(q(2))
        mm(1, 2) = mm(2, 1)
        mm(2, 2) = p(2)*p(3)**2
    end subroutine cart_mass
    subroutine cart_forces(t, q, v, f, p) bind(c)
        real(c_double), value :: t
        real(c_double), intent(in) :: q(*), v(*), p(*)
        real(c_double), intent(out) :: f(*)
        f(1) = p(2)*p(3)*sin(q(2))*v(2)**2
        f(2) = p(2)*p(4)*p(3)*sin(q(2))
    end subroutine cart_forces
    subroutine cart_fjac(t, q, v, a, r, p) bind(c)
        real(c_double), value :: t
        real(c_double), intent(in) :: q(*), v(*), a(*), p(*)
        real(c_double), intent(out) :: r(2, 4)
        real(c_double) :: s, c, ml
        s = sin(q(2))
        c = cos(q(2))
        ml = p(2)*p(3)
        r = 0.0_c_double
        r(1, 2) = ml*c*v(2)**2 + ml*s*a(2)
        r(2, 2) = p(2)*p(4)*p(3)*c + ml*s*a(1)
        r(1, 4) = 2.0_c_double*ml*s*v(2)
    end subroutine cart_fjac
end module test_c_funcs

program test_c_system
    use, intrinsic :: iso_c_binding, only: c_funloc, c_null_funptr
    use conmech
    use conmech_testing, only: test_suite
    use test_c_funcs
    implicit none
    type(test_suite) :: ts
    type(c_ode_system) :: ck
    type(kepler_2d) :: bk
    type(c_generalized_system) :: cg
    type(generalized_ode) :: wc, wf
    type(c_mech_pointers) :: fp
    type(ode_options) :: opt
    type(ode_result) :: ra, rb
    real(dp) :: y(4), ja(4, 4), jf(4, 4)
    integer :: info
    character(len=:), allocatable :: msg

    ts%name = "test_c_system"
    call make_c_ode(4, c_funloc(kep_rhs), c_null_funptr, [1.0_dp], ck, info, msg)
    call ts%check(info == CM_SUCCESS .and. .not. ck%has_jacobian(), "make_c_ode")
    opt%method = METHOD_DOP853
    opt%rtol = 1.0e-11_dp
    opt%atol = 1.0e-11_dp
    call ode_solve(ck, [0.0_dp, 10.0_dp], [0.4_dp, 0.0_dp, 0.0_dp, 2.0_dp], opt, ra)
    call ode_solve(bk, [0.0_dp, 10.0_dp], [0.4_dp, 0.0_dp, 0.0_dp, 2.0_dp], opt, rb)
    call ts%check(ra%success .and. rb%success .and. ra%stats%nfev == rb%stats%nfev, &
                  "compiled Kepler takes the built-in's steps")
    call ts%check_less(maxval(abs(ra%y(:, ra%nt) - rb%y(:, rb%nt))), 1.0e-10_dp, &
                       "compiled Kepler ends where the built-in does")
    call make_c_ode(0, c_funloc(kep_rhs), c_null_funptr, [1.0_dp], ck, info, msg)
    call ts%check(info == CM_BAD_INPUT, "n = 0 is bad input")
    call make_c_ode(4, c_null_funptr, c_null_funptr, [1.0_dp], ck, info, msg)
    call ts%check(info == CM_BAD_INPUT, "a null right-hand side is bad input")

    fp%mass = c_funloc(cart_mass)
    fp%forces = c_funloc(cart_forces)
    fp%forces_jac = c_funloc(cart_fjac)
    call make_c_generalized(2, fp, [1.3_dp, 0.7_dp, 0.9_dp, 9.81_dp], cg, info, msg)
    call ts%check(info == CM_SUCCESS .and. cg%has_forces_jacobian(), "make_c_generalized")
    allocate (wc%mech, source=cg)
    cg%core%fjac_f => null()
    allocate (wf%mech, source=cg)
    y = [0.1_dp, 2.5_dp, 0.3_dp, -0.4_dp]
    call wc%jacobian(0.0_dp, y, ja)
    call wf%jacobian(0.0_dp, y, jf)
    call ts%check(wc%has_jacobian() .and. .not. wf%has_jacobian(), "exact Jacobian reported")
    call ts%check_less(maxval(abs(ja - jf)), 1.0e-7_dp, &
                       "exact accelerations' Jacobian = finite differences")
    ! gfortran keeps a deferred-length character of the main program on its stack, not in
    ! static storage: free it, or LeakSanitizer reports its last value as leaked
    if (allocated(msg)) deallocate (msg)
    call ts%finish()
end program test_c_system
