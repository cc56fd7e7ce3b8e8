!> conmech's control area: the periodic Riccati solver against closed forms (the double
!! integrator's algebraic Riccati solution P = [sqrt 3, 1; 1, sqrt 3]), a system without a
!! stabilising solution, the virtual-constraint feedback and reduced dynamics of the cart
!! pendulum (alpha, beta, gamma in closed form; the closed loop stays on the constraint),
!! and the transverse LQR design (closed-loop multipliers inside the unit circle, the
!! nonlinear closed loop's monodromy agreeing).
module control_test_lq
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS
    use conmech_ode_system, only: ode_events
    use conmech_periodic_riccati, only: periodic_lq
    implicit none
    private
    public :: constant_lq, speed_event

    !> g = y(2) (theta' of the reduced dynamics).
    type, extends(ode_events) :: speed_event
    contains
        procedure :: eval => speed_eval
    end type speed_event

    !> x' = A x + B u with constant coefficients (any period).
    type, extends(periodic_lq) :: constant_lq
        real(dp), allocatable :: a(:, :), b(:, :)
    contains
        procedure :: coefficients => const_coef
    end type constant_lq

contains

    subroutine speed_eval(self, t, y, g)
        class(speed_event), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: g(:)
        g(1) = y(2)
    end subroutine speed_eval

    subroutine const_coef(self, t, a, b, info)
        class(constant_lq), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(out) :: a(:, :), b(:, :)
        integer, intent(out) :: info
        a = self%a
        b = self%b
        info = CM_SUCCESS
    end subroutine const_coef

end module control_test_lq

program test_control
    use conmech
    use conmech_testing
    use control_test_lq
    use conmech_control_system, only: closed_loop
    use conmech_mech_plant, only: mech_plant
    use conmech_vhc
    use conmech_periodic_riccati
    use conmech_transverse_general, only: transverse_options
    use conmech_orbital_stabilisation
    implicit none
    type(test_suite) :: ts
    type(mech_plant) :: plant

    ts%name = "test_control"
    call test_riccati()
    call make_plant()
    call test_vhc()
    call test_design()
    call ts%finish()

contains

    subroutine test_riccati()
        type(constant_lq) :: lq
        type(riccati_options) :: opt
        type(riccati_result) :: res
        real(dp) :: p(2, 2), kg(1, 2), want(2, 2)
        integer :: info
        lq%k = 2
        lq%m = 1
        lq%period = 0.7_dp
        lq%a = reshape([0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp], [2, 2])
        lq%b = reshape([0.0_dp, 1.0_dp], [2, 1])
        call periodic_riccati(lq, reshape([1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2]), &
                              reshape([1.0_dp], [1, 1]), opt, res)
        call ts%check(res%info == CM_SUCCESS, "double integrator: "//res%message)
        want = reshape([sqrt(3.0_dp), 1.0_dp, 1.0_dp, sqrt(3.0_dp)], [2, 2])
        call riccati_gain(res, lq, 0.31_dp, kg, p, info)
        call ts%check_less(maxval(abs(p - want)), 1.0e-10_dp, "P = [sqrt 3, 1; 1, sqrt 3]")
        call ts%check_less(maxval(abs(kg - reshape([1.0_dp, sqrt(3.0_dp)], [1, 2]))), &
                           1.0e-10_dp, "K = R^-1 B^T P = [1, sqrt 3]")
        call ts%check(res%periodicity <= 1.0e-10_dp .and. res%min_eig > 0.0_dp, &
                      "periodic and positive definite")
        ! closed loop x'' + sqrt 3 x' + x = 0: multipliers exp(T (-sqrt 3 +- i)/2)
        call ts%check_close(maxval(sqrt(res%cmr**2 + res%cmi**2)), &
                            exp(-0.5_dp*sqrt(3.0_dp)*0.7_dp), 1.0e-10_dp, &
                            "closed-loop multipliers")
        ! x' = x with no input: not stabilisable
        lq%k = 1
        lq%a = reshape([1.0_dp], [1, 1])
        lq%b = reshape([0.0_dp], [1, 1])
        call periodic_riccati(lq, reshape([1.0_dp], [1, 1]), reshape([1.0_dp], [1, 1]), opt, &
                              res)
        call ts%check(res%info /= CM_SUCCESS .and. &
                      index(res%message, "no stabilising periodic solution") > 0, &
                      "not stabilisable: "//res%message)
    end subroutine test_riccati

    !> The cart pendulum (M = m = l = 1, theta from the upright), force on the cart.
    subroutine make_plant()
        integer :: info
        character(len=:), allocatable :: msg
        call make_generalized("cart_pendulum", [1.0_dp, 1.0_dp, 1.0_dp, 9.81_dp], plant%mech, &
                              info, msg)
        plant%n_inputs = 1
        plant%b = reshape([1.0_dp, 0.0_dp], [2, 1])
    end subroutine make_plant

    function cart_law() result(law)
        type(vhc_law) :: law
        law%n_inputs = 1
        law%plant = plant
        law%con%n = 2
        law%con%ip = 2
        law%con%kind = VHC_POLY
        law%con%ncoef = 2
        law%con%c = reshape([0.0_dp, -1.6_dp], [1, 2])
        law%con%sgn = -1.0_dp    ! the cofactor of B = e_x is -e_theta: B_perp = e_theta
        law%kp = [25.0_dp]
        law%kd = [10.0_dp]
    end function cart_law

    subroutine test_vhc()
        type(vhc_law) :: law
        type(closed_loop) :: cl
        type(ode_options) :: oo
        real(dp) :: al, be, ga, y(4), th
        integer :: info, i
        law = cart_law()
        do i = 0, 4
            th = -0.4_dp + 0.2_dp*i
            call vhc_coefficients(plant, law%con, th, al, be, ga, info)
            call ts%check_less(abs(al - (1.0_dp - 1.6_dp*cos(th))) + abs(be) + &
                               abs(ga + 9.81_dp*sin(th)), 1.0e-13_dp, &
                               "alpha, beta, gamma in closed form")
        end do
        allocate (cl%plant, source=plant)
        allocate (cl%law, source=law)
        cl%n_inputs = 1
        oo%rtol = 1.0e-11_dp
        oo%atol = 1.0e-11_dp
        y = [-1.6_dp*0.3_dp, 0.3_dp, 0.0_dp, 0.0_dp]
        call ode_integrate(cl, 0.0_dp, 3.0_dp, y, oo, info)
        call ts%check_less(abs(y(1) + 1.6_dp*y(2)) + abs(y(3) + 1.6_dp*y(4)), 1.0e-9_dp, &
                           "the feedback keeps x = -1.6 theta")
    end subroutine test_vhc

    subroutine test_design()
        type(vhc_law) :: law
        type(transverse_options) :: topt
        type(riccati_options) :: ropt
        type(orbital_design_result) :: des
        type(closed_loop) :: cl
        type(vhc_reduced) :: red
        type(ode_options) :: oo
        type(ode_result) :: r
        real(dp) :: y0(4), period, qw(3, 3), rw(1, 1), mono(4, 4), y(4), wr(4), wi(4), far
        integer :: info, j
        law = cart_law()
        ! the period of the reduced orbit from theta = 0.3 at rest: theta' returns to 0
        red%plant = plant
        red%con = law%con
        oo%rtol = 1.0e-13_dp
        oo%atol = 1.0e-13_dp
        call ode_solve(red, [0.0_dp, 1.0_dp], [0.3_dp, 0.0_dp], oo, r, events=zero_speed())
        period = 2.0_dp*r%ev_t(1)
        y0 = [-1.6_dp*0.3_dp, 0.3_dp, 0.0_dp, 0.0_dp]
        qw = 0.0_dp
        do j = 1, 3
            qw(j, j) = 1.0_dp
        end do
        rw = 0.1_dp
        call orbital_design(plant, law, .true., y0, period, qw, rw, 200, topt, ropt, des)
        call ts%check(des%info == CM_SUCCESS, "cart pendulum design: "//des%message)
        if (des%info /= CM_SUCCESS) return
        far = maxval(sqrt(des%ric%cmr**2 + des%ric%cmi**2))
        call ts%check_less(far, 0.5_dp, "closed-loop transverse multipliers inside")
        allocate (cl%plant, source=plant)
        allocate (cl%law, source=des%law)
        cl%n_inputs = 1
        y = y0
        mono = 0.0_dp
        do j = 1, 4
            mono(j, j) = 1.0_dp
        end do
        oo%rtol = 1.0e-11_dp
        oo%atol = 1.0e-11_dp
        call integrate_stm(cl, 0.0_dp, period, y, mono, oo, info)
        call la_eig(mono, wr, wi, info)
        call ts%check_close(maxval(sqrt(wr**2 + wi**2), sqrt(wr**2 + wi**2) < 0.99_dp), far, &
                            1.0e-6_dp, "nonlinear closed loop: the same largest multiplier")
        call ts%check_less(maxval(abs(y - y0)), 1.0e-8_dp, "the orbit is a closed-loop orbit")
    end subroutine test_design

    function zero_speed() result(ev)
        type(speed_event) :: ev
        ev%direction = [0]
        ev%terminal = [.true.]
    end function zero_speed

end program test_control
