!> Bad input gives a clear status and message: singular mass matrices, inconsistent
!! constraints, a non-converging projection, wrong dimensions, unknown names and options.
module test_mech_bad_types
    use conmech
    implicit none

    !> A pendulum with a second constraint x = 5 that cannot hold with x^2 + y^2 = l^2.
    type, extends(pendulum_xy) :: pendulum_inconsistent
    contains
        procedure :: phi => inc_phi
        procedure :: phi_jac => inc_jac
    end type pendulum_inconsistent

    !> A pendulum whose constraint Jacobian is (wrongly) zero: the constraint cannot be
    !! enforced or projected back onto.
    type, extends(pendulum_xy) :: pendulum_zero_jac
    contains
        procedure :: phi_jac => zero_jac
    end type pendulum_zero_jac

contains

    subroutine zero_jac(self, t, q, g)
        class(pendulum_zero_jac), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        g = 0.0_dp
    end subroutine zero_jac

    subroutine inc_phi(self, t, q, c)
        class(pendulum_inconsistent), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c(1) = 0.5_dp*(q(1)**2 + q(2)**2 - self%l**2)
        c(2) = q(1) - 5.0_dp
    end subroutine inc_phi
    subroutine inc_jac(self, t, q, g)
        class(pendulum_inconsistent), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        g(1, :) = q(1:2)
        g(2, :) = [1.0_dp, 0.0_dp]
    end subroutine inc_jac

end module test_mech_bad_types

program test_mechanics_bad_input
    use conmech
    use conmech_testing, only: test_suite
    use test_mech_bad_types
    implicit none
    type(test_suite) :: ts
    class(constrained_system), allocatable :: cs
    class(generalized_system), allocatable :: gs
    type(constrained_options) :: opt
    type(constrained_result) :: r
    type(ode_options) :: gopt
    type(ode_result) :: gr
    real(dp) :: a(2), lam(1), lam2(3)
    integer :: info
    character(len=:), allocatable :: msg

    ts%name = "test_mechanics_bad_input"

    ! ---------------------------------------------------------------- singular mass matrix
    call make_constrained("pendulum_xy", [0.0_dp, 9.81_dp, 1.0_dp], cs, info, msg)
    call constrained_accel(cs, 0.0_dp, [0.0_dp, -1.0_dp], [0.0_dp, 0.0_dp], a, lam, info, msg)
    call ts%check(info == CM_SINGULAR, "constrained_accel: zero mass -> CM_SINGULAR")
    call ts%check(index(msg, "singular mass matrix") > 0, "message: "//msg)
    call constrained_solve(cs, [0.0_dp, 1.0_dp], [0.0_dp, -1.0_dp], [0.0_dp, 0.0_dp], opt, r)
    call ts%check(r%status == CM_SINGULAR .and. .not. r%success, &
                  "constrained_solve: zero mass -> CM_SINGULAR: "//r%message)
    call make_generalized("cart_pendulum", [0.0_dp, 1.0_dp, 1.0_dp, 9.81_dp], gs, info, msg)
    ! cart mass 0 and the bob straight up/down: M = [[1, 1], [1, 1]] is singular
    call generalized_solve(gs, [0.0_dp, 1.0_dp], [0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp], gopt, gr)
    call ts%check(gr%status == CM_SINGULAR .and. .not. gr%success, &
                  "generalized_solve: singular M -> CM_SINGULAR: "//gr%message)
    call make_generalized("pendulum_angle", [-1.0_dp, 9.81_dp, 1.0_dp], gs, info, msg)
    call generalized_solve(gs, [0.0_dp, 1.0_dp], [0.1_dp], [0.0_dp], gopt, gr)
    call ts%check(gr%status == CM_SINGULAR, "generalized_solve: negative mass -> CM_SINGULAR")

    ! ---------------------------------------------------------------- inconsistent constraints
    block
        type(pendulum_inconsistent) :: pinc
        pinc%n = 2
        pinc%n_hol = 2
        call constrained_solve(pinc, [0.0_dp, 1.0_dp], [0.0_dp, -1.0_dp], [0.0_dp, 0.0_dp], &
                               opt, r)
        call ts%check(r%status == CM_NO_CONVERGENCE .and. .not. r%success, &
                      "inconsistent constraints -> CM_NO_CONVERGENCE")
        call ts%check(index(r%message, "inconsistent initial position") > 0, &
                      "message: "//r%message)
    end block

    ! ---------------------------------------------------------------- non-converging projection
    call make_constrained("pendulum_xy", [real(dp) ::], cs, info, msg)
    opt = constrained_options()
    opt%proj_max_iter = 1
    call constrained_solve(cs, [0.0_dp, 1.0_dp], [3.0_dp, -3.0_dp], [0.0_dp, 0.0_dp], opt, r)
    call ts%check(r%status == CM_NO_CONVERGENCE, &
                  "projection from far with 1 iteration -> CM_NO_CONVERGENCE")
    call ts%check(index(r%message, "did not converge") > 0, "message: "//r%message)
    ! during the integration: huge steps, a single simplified Newton iteration
    opt = constrained_options()
    opt%proj_max_iter = 1
    opt%proj_tol = 1.0e-15_dp
    opt%ode%method = METHOD_RK4
    opt%ode%first_step = 0.3_dp
    call constrained_solve(cs, [0.0_dp, 3.0_dp], [sin(1.0_dp), -cos(1.0_dp)], &
                           [0.0_dp, 0.0_dp], opt, r)
    call ts%check(r%status == CM_NO_CONVERGENCE .and. index(r%message, " at t =") > 0, &
                  "projection failing during the run -> CM_NO_CONVERGENCE: "//r%message)

    ! the same through the step hook of the core ode_solve
    block
        type(constrained_ode) :: f
        type(projection_hook) :: hk
        type(ode_options) :: oo
        allocate (f%mech, source=cs)
        allocate (hk%mech, source=cs)
        hk%proj_max_iter = 1
        hk%proj_tol = 1.0e-15_dp
        oo%method = METHOD_RK4
        oo%first_step = 0.3_dp
        call ode_solve(f, [0.0_dp, 3.0_dp], [sin(1.0_dp), -cos(1.0_dp), 0.0_dp, 0.0_dp], oo, &
                       gr, hook=hk)
        call ts%check(gr%status == CM_NO_CONVERGENCE .and. &
                      index(gr%message, "did not converge") > 0, &
                      "hook: non-converging projection stops ode_solve: "//gr%message)
    end block

    ! ---------------------------------------------------------------- wrong dimensions
    opt = constrained_options()
    call constrained_solve(cs, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp], &
                           opt, r)
    call ts%check(r%status == CM_BAD_INPUT .and. index(r%message, "q0 and v0") > 0, &
                  "q0 of the wrong size -> CM_BAD_INPUT: "//r%message)
    call constrained_accel(cs, 0.0_dp, [1.0_dp, 0.0_dp], [0.0_dp, 0.0_dp], a, lam2, info, msg)
    call ts%check(info == CM_BAD_INPUT, "lambda of the wrong size -> CM_BAD_INPUT: "//msg)
    call make_generalized("double_pendulum", [real(dp) ::], gs, info, msg)
    call generalized_solve(gs, [0.0_dp, 1.0_dp], [0.1_dp], [0.0_dp, 0.0_dp], gopt, gr)
    call ts%check(gr%status == CM_BAD_INPUT, "generalized q0 wrong size -> CM_BAD_INPUT")
    block
        type(pendulum_xy) :: unset
        call constrained_solve(unset, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], [0.0_dp, 0.0_dp], &
                               opt, r)
        call ts%check(r%status == CM_BAD_INPUT, "system with n = 0 -> CM_BAD_INPUT: " &
                      //r%message)
    end block

    ! ---------------------------------------------------------------- options and names
    opt%projection = 17
    call constrained_solve(cs, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], [0.0_dp, 0.0_dp], opt, r)
    call ts%check(r%status == CM_BAD_INPUT, "unknown projection -> CM_BAD_INPUT")
    opt = constrained_options()
    opt%ode%method = METHOD_RK4
    call constrained_solve(cs, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], [0.0_dp, 0.0_dp], opt, r)
    call ts%check(r%status == CM_BAD_INPUT, "RK4 without a step -> CM_BAD_INPUT")
    opt = constrained_options()
    call constrained_solve(cs, [0.0_dp, 1.0_dp], [1.0_dp, 0.0_dp], [0.0_dp, 0.0_dp], opt, r, &
                           [0.5_dp, 0.2_dp])
    call ts%check(r%status == CM_BAD_INPUT, "unsorted t_eval -> CM_BAD_INPUT")
    call make_constrained("no_such_system", [real(dp) ::], cs, info, msg)
    call ts%check(info == CM_BAD_INPUT .and. index(msg, "unknown") > 0, "unknown name: "//msg)
    call ts%check(projection_from_name("position+velocity") == PROJ_POSITION_VELOCITY .and. &
                  projection_from_name("none") == PROJ_NONE .and. &
                  projection_from_name("velocity") == PROJ_VELOCITY .and. &
                  projection_from_name("baumgarte") == PROJ_BAUMGARTE .and. &
                  projection_from_name("sideways") == -1, "projection names")

    ! ---------------------------------------------------------------- zero constraint Jacobian
    block
        type(pendulum_zero_jac) :: zj
        type(constrained_options) :: zopt
        real(dp) :: qz(2)
        integer :: iters
        zj%n = 2
        zj%n_hol = 1
        call constrained_solve(zj, [0.0_dp, 1.0_dp], [0.6_dp, -0.8_dp], [0.0_dp, 0.0_dp], &
                               zopt, r)
        call ts%check(r%status == CM_BAD_INPUT .and. .not. r%success .and. &
                      index(r%message, "Jacobian is zero") > 0, &
                      "zero constraint Jacobian at the start -> CM_BAD_INPUT: "//r%message)
        ! a projection that cannot reduce |phi| fails instead of keeping the state
        qz = [0.7_dp, -0.8_dp]
        call project_position(zj, 0.0_dp, qz, 1.0e-14_dp, 10, iters, info, msg)
    end block
    call ts%check(info == CM_NO_CONVERGENCE .and. index(msg, "did not converge") > 0, &
                  "project_position with a zero Jacobian -> CM_NO_CONVERGENCE: "//msg)

    ! gfortran keeps a deferred-length character of the main program on its stack, not in
    ! static storage: free it, or LeakSanitizer reports its last value as leaked
    if (allocated(msg)) deallocate (msg)
    call ts%finish()
end program test_mechanics_bad_input
