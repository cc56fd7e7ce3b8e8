!> Test systems with families of equilibria and Jordan blocks on the imaginary axis.
module structure_test_systems
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_system
    implicit none
    private
    public :: cubic_oscillator, drag_line, square_flow, damped_cart

    !> x'' = -x^3: a Jordan block at 0 and a stable (nonlinear) equilibrium.
    type, extends(ode_system) :: cubic_oscillator
    contains
        procedure :: rhs => cubic_rhs
    end type cubic_oscillator

    !> x' = v, v' = -c v: a line of equilibria (any x, v = 0) attracting at rate c.
    type, extends(ode_system) :: drag_line
        real(dp) :: c = 0.5_dp
    contains
        procedure :: rhs => drag_rhs
    end type drag_line

    !> y' = y^2: an isolated equilibrium with a zero eigenvalue (no family).
    type, extends(ode_system) :: square_flow
    contains
        procedure :: rhs => square_rhs
    end type square_flow

    !> The lecture notes' cart pendulum (M = m = l = 1, theta from upright) with viscous
    !! friction c on both coordinates: 2 x'' + cos th th'' - sin th th'^2 = -c x',
    !! cos th x'' + th'' - g sin th = -c th'.
    type, extends(ode_system) :: damped_cart
        real(dp) :: c = 0.3_dp, g = 9.81_dp
    contains
        procedure :: rhs => damped_cart_rhs
    end type damped_cart

contains

    subroutine cubic_rhs(self, t, y, dydt)
        class(cubic_oscillator), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        dydt = [y(2), -y(1)**3]
    end subroutine cubic_rhs

    subroutine drag_rhs(self, t, y, dydt)
        class(drag_line), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        dydt = [y(2), -self%c*y(2)]
    end subroutine drag_rhs

    subroutine square_rhs(self, t, y, dydt)
        class(square_flow), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        dydt = y**2
    end subroutine square_rhs

    subroutine damped_cart_rhs(self, t, y, dydt)
        class(damped_cart), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: c, s, f1, f2, det
        c = cos(y(2))
        s = sin(y(2))
        f1 = s*y(4)**2 - self%c*y(3)
        f2 = self%g*s - self%c*y(4)
        det = 2.0_dp - c*c
        dydt(1:2) = y(3:4)
        dydt(3) = (f1 - c*f2)/det
        dydt(4) = (2.0_dp*f2 - c*f1)/det
    end subroutine damped_cart_rhs

end module structure_test_systems

program test_equilibria_structure
    use conmech_kinds, only: dp, pi
    use conmech_status
    use conmech_generalized, only: generalized_ode
    use conmech_systems_generalized, only: cart_pendulum
    use conmech_equilibria
    use conmech_relative_equilibria, only: relative_linearization
    use conmech_rank, only: numerical_rank, min_norm_solve
    use structure_test_systems
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    real(dp), parameter :: g = 9.81_dp
    ts%name = "test_equilibria_structure"

    call test_cart_jordan()
    call test_cart_relative()
    call test_cart_newton_on_family()
    call test_jordan_without_family()
    call test_attracting_line()
    call test_damped_cart()
    call test_zero_not_family()
    call test_matrices()
    call test_rank_helpers()
    call ts%finish()

contains

    function cart() result(sys)
        type(generalized_ode) :: sys
        type(cart_pendulum) :: cp
        cp%g = g
        cp%ndof = 2
        allocate (sys%mech, source=cp)

    end function cart

    !> The notes' cart (M = m = l = 1; finite-difference Jacobian, ~1e-9): lines of
    !! equilibria in x; hanging: a Jordan block
    !! at 0 (x drifts) beside the pair +-i sqrt(2 g); upright: a saddle with the same drift.
    subroutine test_cart_jordan()
        type(generalized_ode) :: sys
        type(equilibrium_result) :: e
        sys = cart()
        call analyze_equilibrium(sys, [0.3_dp, pi, 0.0_dp, 0.0_dp], e)
        call ts%check(e%info == CM_SUCCESS, "cart hanging: analysed")
        call ts%check(e%kind == EQ_SECULAR, "cart hanging: unstable by secular drift")
        call ts%check(e%zero_multiplicity == 2 .and. e%largest_block == 2, &
                      "cart hanging: double zero eigenvalue, one 2x2 Jordan block")
        call ts%check(e%family_dim == 1, "cart hanging: a line of equilibria")
        call ts%check(size(e%drift, 2) == 1, "cart hanging: one drift direction")
        if (size(e%drift, 2) == 1) call ts%check_close(e%drift(1, 1), 1.0_dp, 1.0e-10_dp, &
                                                       "cart hanging: the drift is along x")
        if (e%family_dim == 1) call ts%check_close(abs(e%family(1, 1)), 1.0_dp, 1.0e-6_dp, &
                                                   "cart hanging: the family is along x")
        call ts%check_close(maxval(e%wi), sqrt(2.0_dp*g), 1.0e-8_dp, &
                            "cart hanging: the pendulum's +-i sqrt(2 g) (notes)")
        call analyze_equilibrium(sys, [-1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp], e)
        call ts%check(e%kind == EQ_UNSTABLE .and. e%saddle, "cart upright: saddle")
        call ts%check(e%largest_block == 2 .and. size(e%drift, 2) == 1, &
                      "cart upright: the drift is reported beside the saddle")
        call ts%check_close(maxval(e%wr), sqrt(2.0_dp*g), 1.0e-8_dp, &
                            "cart upright: +-sqrt(2 g) (notes)")
    end subroutine test_cart_jordan

    !> Relative to the momentum P = 2 x' + cos th th' and the family (x), the hanging
    !! equilibrium is a centre with z'' + 2 g z = 0, the upright one a saddle z'' - 2 g z = 0.
    subroutine test_cart_relative()
        type(generalized_ode) :: sys
        type(equilibrium_result) :: e, r
        real(dp) :: grads(2, 4), ar(4, 4), w(4, 4)
        integer :: m, info
        character(len=:), allocatable :: msg
        sys = cart()
        call analyze_equilibrium(sys, [0.0_dp, pi, 0.0_dp, 0.0_dp], e)
        grads(1, :) = [0.0_dp, 0.0_dp, 2.0_dp, cos(pi)]   ! dP at v = 0
        grads(2, :) = 0.0_dp                              ! dE vanishes at an equilibrium
        call relative_linearization(e%jacobian, grads, e%family, ar, w, m, info, msg)
        call ts%check(info == CM_SUCCESS .and. m == 2, "relative: 2-D reduced linearisation")
        call classify_matrix(ar(1:m, 1:m), r)
        call ts%check(r%kind == EQ_CENTRE, "relative: hanging is a centre (notes)")
        call ts%check_close(maxval(r%wi), sqrt(2.0_dp*g), 1.0e-8_dp, &
                            "relative: +-i sqrt(2 g) (notes)")
        call ts%check(maxval(abs(r%wr)) <= 1.0e-12_dp, "relative: purely imaginary")
        call analyze_equilibrium(sys, [0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp], e)
        grads(1, :) = [0.0_dp, 0.0_dp, 2.0_dp, 1.0_dp]
        call relative_linearization(e%jacobian, grads, e%family, ar, w, m, info, msg)
        call classify_matrix(ar(1:m, 1:m), r)
        call ts%check(r%kind == EQ_UNSTABLE .and. r%saddle, "relative: upright is a saddle")
        call ts%check_close(maxval(r%wr), sqrt(2.0_dp*g), 1.0e-8_dp, &
                            "relative: +-sqrt(2 g) (notes)")
        ! a gradient that the linearisation does not conserve is refused
        grads(1, :) = [0.0_dp, 1.0_dp, 0.0_dp, 0.0_dp]
        call relative_linearization(e%jacobian, grads, e%family, ar, w, m, info, msg)
        call ts%check(info == CM_BAD_INPUT .and. index(msg, "conserve") > 0, &
                      "relative: a non-integral is refused: "//msg)
    end subroutine test_cart_relative

    !> Newton with minimum-norm steps converges onto the cart's line of equilibria (the
    !! Jacobian is singular everywhere on it).
    subroutine test_cart_newton_on_family()
        type(generalized_ode) :: sys
        real(dp) :: y(4)
        integer :: info, rank
        character(len=:), allocatable :: msg
        sys = cart()
        y = [0.7_dp, pi - 0.3_dp, 0.05_dp, -0.02_dp]
        call find_equilibrium(sys, y, info, msg, rank=rank)
        call ts%check(info == CM_SUCCESS, "Newton on the family: converged ("//msg//")")
        call ts%check_close(y(2), pi, 1.0e-12_dp, "Newton on the family: theta = pi")
        call ts%check(maxval(abs(y(3:4))) <= 1.0e-12_dp, "Newton on the family: at rest")
        call ts%check(rank == 3, "Newton on the family: rank 3 = 4 - family dimension")
    end subroutine test_cart_newton_on_family

    !> x'' = -x^3: Jordan block at 0, no family: linearly unstable (secular), no drift
    !! family; the classification says so and reports the drift along x.
    subroutine test_jordan_without_family()
        type(cubic_oscillator) :: sys
        type(equilibrium_result) :: e

        call analyze_equilibrium(sys, [0.0_dp, 0.0_dp], e)
        call ts%check(e%kind == EQ_SECULAR .and. e%family_dim == 0, &
                      "x'' = -x^3: a Jordan block, no family")
        call ts%check(size(e%drift, 2) == 1, "x'' = -x^3: drift along x reported")
    end subroutine test_jordan_without_family

    !> x' = v, v' = -c v: the line v = 0 attracts: stable (family), not asymptotically.
    subroutine test_attracting_line()
        type(drag_line) :: sys
        type(equilibrium_result) :: e
        real(dp) :: y(2)
        integer :: info
        character(len=:), allocatable :: msg

        call analyze_equilibrium(sys, [2.0_dp, 0.0_dp], e)
        call ts%check(e%kind == EQ_STABLE_FAMILY .and. e%family_dim == 1, &
                      "drag line: stable on an attracting family of dimension 1")
        y = [1.0_dp, 0.4_dp]
        call find_equilibrium(sys, y, info, msg)
        call ts%check(info == CM_SUCCESS .and. abs(y(2)) < 1.0e-14_dp, &
                      "drag line: Newton reaches the line")
    end subroutine test_attracting_line

    !> The cart with friction on both coordinates: the hanging equilibria form a line that
    !! attracts: stable, not asymptotically (a simple zero eigenvalue along x).
    subroutine test_damped_cart()
        type(damped_cart) :: sys
        type(equilibrium_result) :: e

        call analyze_equilibrium(sys, [0.0_dp, pi, 0.0_dp, 0.0_dp], e)
        call ts%check(e%kind == EQ_STABLE_FAMILY .and. e%family_dim == 1 .and. &
                      e%zero_multiplicity == 1, "damped cart hanging: attracting line")
        call analyze_equilibrium(sys, [0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp], e)
        call ts%check(e%kind == EQ_UNSTABLE, "damped cart upright: unstable")
    end subroutine test_damped_cart

    !> y' = y^2 (two copies): a semisimple double zero that no family explains: degenerate;
    !! Newton converges (slowly) but the root is not a family.
    subroutine test_zero_not_family()
        type(square_flow) :: sys
        type(equilibrium_result) :: e

        call analyze_equilibrium(sys, [0.0_dp, 0.0_dp], e)
        call ts%check(e%kind == EQ_DEGENERATE .and. e%family_dim == 0, &
                      "y' = y^2: degenerate, no family")
    end subroutine test_zero_not_family

    !> Matrices alone: a 3x3 Jordan block at 0, a Jordan block at +-i (resonance),
    !! a semisimple repeated pair (two equal oscillators: a centre), close distinct pairs.
    subroutine test_matrices()
        type(equilibrium_result) :: r
        real(dp) :: a(4, 4), b(3, 3)
        b = 0.0_dp
        b(1, 2) = 1.0_dp
        b(2, 3) = 1.0_dp
        call classify_matrix(b, r)
        call ts%check(r%kind == EQ_SECULAR .and. r%largest_block == 3 .and. &
                      size(r%drift, 2) == 1, "3x3 nilpotent: block of size 3, one drift")
        ! [[J, I], [0, J]] with J = [[0, 1], [-1, 0]]: a Jordan block at +-i
        a = 0.0_dp
        a(1, 2) = 1.0_dp; a(2, 1) = -1.0_dp
        a(3, 4) = 1.0_dp; a(4, 3) = -1.0_dp
        a(1, 3) = 1.0_dp; a(2, 4) = 1.0_dp
        call classify_matrix(a, r)
        call ts%check(r%kind == EQ_SECULAR .and. r%largest_block == 2, &
                      "resonant block at +-i: secular")
        call ts%check_close(r%secular_frequency, 1.0_dp, 1.0e-7_dp, "resonance at w = 1")
        a(1, 3) = 0.0_dp; a(2, 4) = 0.0_dp
        call classify_matrix(a, r)
        call ts%check(r%kind == EQ_CENTRE .and. r%largest_block == 1, &
                      "two equal oscillators: semisimple, a centre")
        ! an oscillator and a damped mode: degenerate (centre manifold)
        a = 0.0_dp
        a(1, 2) = 1.0_dp; a(2, 1) = -1.0_dp; a(3, 3) = -1.0_dp; a(4, 4) = -2.0_dp
        call classify_matrix(a, r)
        call ts%check(r%kind == EQ_DEGENERATE, "axis pair with Re < 0: degenerate")
        ! a plain zero eigenvalue of a matrix (no system to test a family): degenerate
        a = 0.0_dp
        a(2, 2) = -1.0_dp; a(3, 4) = 1.0_dp; a(4, 3) = -1.0_dp
        call classify_matrix(a, r)
        call ts%check(r%kind == EQ_DEGENERATE .and. r%zero_multiplicity == 1, &
                      "simple zero without a system: degenerate")
    end subroutine test_matrices

    subroutine test_rank_helpers()
        real(dp) :: a(3, 3), x(3)
        integer :: rank, info
        a = reshape([1.0_dp, 2.0_dp, 3.0_dp, 2.0_dp, 4.0_dp, 6.0_dp, 0.0_dp, 1.0_dp, 1.0_dp], &
                    [3, 3])
        call numerical_rank(a, 1.0e-10_dp, rank, info)
        call ts%check(info == CM_SUCCESS .and. rank == 2, "rank of a rank-2 matrix")
        call min_norm_solve(a, matmul(a, [1.0_dp, 0.0_dp, 0.0_dp]), x, 1.0e-10_dp, rank, info)
        call ts%check(rank == 2 .and. maxval(abs(matmul(a, x) - [1.0_dp, 2.0_dp, 3.0_dp])) &
                      < 1.0e-12_dp, "minimum-norm solution solves a consistent system")
        call ts%check_close(dot_product(x, [2.0_dp, -1.0_dp, 0.0_dp]), 0.0_dp, 1.0e-12_dp, &
                            "minimum-norm solution is orthogonal to the kernel")
    end subroutine test_rank_helpers

end program test_equilibria_structure
