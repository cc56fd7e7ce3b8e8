!> Hill's variation orbit, its monodromy matrix, the perigee constant c, the family over m
!! and the transverse linearisation (Hill's equation N'' + Phi(t) N = 0) along it.
!!
!! The variation orbit of Hill's problem (module `conmech_hill`) is the direct periodic orbit
!! of period 2 pi (one synodic month) symmetric about both axes. It starts on the x axis at
!! right angles, y0 = [x0, 0, 0, v0], and crosses the y axis at right angles a quarter period
!! later: x(pi/2) = 0 and y'(pi/2) = 0. These two conditions in the two unknowns (x0, v0)
!! are solved by Newton's method with the exact Jacobian from the state transition matrix
!! A = Phi(pi/2) of the variational equations (symmetric shooting over a quarter period).
!!
!! Speed: the state and three STM columns (x0, x0', v0: 16 components) are integrated by
!! a fixed-step DOP853 with the right-hand side and coefficients written out
!! (`conmech_hill_kernel`); the y0 column follows from the flow, A f(y0) = f(y(pi/2)). The
!! default 20 steps per quarter period give |c error| ~ 1e-14 (m = 1e-6 .. 0.15).
!!
!! Monodromy by symmetry: with the time-reversing reflections G0 = diag(1, -1, -1, 1)
!! (x axis) and G1 = diag(-1, 1, 1, -1) (y axis), the half-period STM is
!! B = G1 A^-1 G1 A (A^-1 from the symplectic form), and since G1 G0 = -I the monodromy
!! is M = B^2. The option `full_period` integrates the whole period instead (a check, 4x
!! the work; S and c then from the trace of that M).
!!
!! Perigee constant: the non-trivial multipliers are exp(+-2 pi i c),
!! S = (trace M - 2)/2 = cos(2 pi c); the branch is c = 1 + acos(S)/(2 pi), the
!! continuation of c = 1 at m = 0 (c > 1 along the direct family, valid while
!! 1 <= c <= 3/2; c is NaN when |S| > 1, an unstable orbit). S and c are not read from the
!! trace (it sums O(1) entries to 1 - S ~ (2 pi m)^2, losing digits as m -> 0: 3e-12 in c
!! at m = 0.01, 2e-10 at m = 1e-6) but from products of the quarter map between the two
!! symmetry sections, s = sin^2(pi (c - 1)/2) and t = cos^2(pi (c - 1)/2)
!! (`section_products`): S = 1 - 8 s t, c = 1 + (2/pi) atan(sqrt(min(s,t)/max(s,t))), to
!! ~1e-14 for every m.
!!
!! Transverse linearisation (as in the lecture notes): with tangent tau = v/|v|,
!! normal n = (-tau_y, tau_x), V = |v|, H the Hessian of F and omega = n.grad F / V - 2 m
!! (the turning rate of the tangent), the normal deviation of an isoenergetic (delta I = 0)
!! perturbation obeys N'' + Phi(t) N = 0 with Phi = 3 (omega + m)^2 + m^2 - n^T H n. Its
!! 2 x 2 monodromy over 2 pi has the non-trivial multipliers of the 4 x 4 monodromy.
!!
!! Thread safety: no saved state (the family over m, in parallel: conmech_hill_family).
module conmech_hill_orbit
    use conmech_kinds, only: dp, pi, nan_dp
    use conmech_outcome, only: outcome
    use conmech_status
    use conmech_lapack, only: la_eig
    use conmech_rk_tableaus, only: rk_tableau, dop853_tableau
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: tolerance_options
    use conmech_ode_solver, only: ode_options, ode_stats, ode_integrate, ode_solve, ode_result
    use conmech_hill, only: hill_problem, hill_jacobi, hill_grad_f, hill_hess_f
    use conmech_hill_kernel, only: hill_kernel_var, hill_kernel_state, hill_var_rhs
    implicit none
    private

    public :: hill_orbit, hill_orbit_options, hill_variation_orbit
    public :: hill_orbit_guess, hill_perigee_c, hill_phi, hill_transverse, hill_transverse_result
    public :: hill_orbit_sample

    !> Options of the variation-orbit solver.
    type :: hill_orbit_options
        integer :: nsteps = 20           !! initial DOP853 steps per quarter period
        integer :: max_nsteps = 2560     !! upper bound of the error-controlled step count
        integer :: max_iter = 30         !! Newton iterations (per step count)
        real(dp) :: tol = 1.0e-14_dp     !! accept when |du| <= tol max(1, |u|)
        real(dp) :: closure_tol = 1.0e-12_dp  !! bound on the true closure error |(x, y')(T/4)|
        logical :: full_period = .false. !! monodromy by direct integration over 2 pi
        logical :: eigenvalues = .true.  !! compute the multipliers with dgeev
    end type hill_orbit_options

    !> A variation orbit with its monodromy.
    type, extends(outcome) :: hill_orbit
        real(dp) :: m = 0.0_dp, kappa = 1.0_dp
        real(dp) :: y0(4) = 0.0_dp            !! [x0, 0, 0, v0]
        real(dp) :: period = 2.0_dp*pi
        real(dp) :: jacobi = 0.0_dp           !! Jacobi integral x'^2 + y'^2 - 2F
        real(dp) :: quarter_stm(4, 4) = 0.0_dp  !! A = Phi(pi/2)
        real(dp) :: monodromy(4, 4) = 0.0_dp  !! M = Phi(2 pi)
        real(dp) :: mr(4) = 0.0_dp, mi(4) = 0.0_dp  !! multipliers (dgeev)
        real(dp) :: stability_index = 0.0_dp  !! S = (trace M - 2)/2, stable iff |S| < 1
        real(dp) :: c = 0.0_dp                !! perigee constant
        real(dp) :: residual = 0.0_dp         !! true closure |(x, y')(pi/2)| (estimated)
        real(dp) :: newton_residual = 0.0_dp  !! closure of the discretised problem
        real(dp) :: quarter_state(4) = 0.0_dp !! state at T/4: [0, y, x'(T/4), 0]
        integer :: nsteps = 0                 !! steps per quarter period used
        integer :: iterations = 0             !! Newton iterations (all step counts)
        integer :: nfev = 0                   !! right-hand side evaluations (20- and 4-dim)
    end type hill_orbit

    !> Transverse linearisation along a variation orbit.
    type :: hill_transverse_result
        integer :: info = CM_BAD_INPUT
        character(len=:), allocatable :: message
        real(dp) :: monodromy(2, 2) = 0.0_dp  !! of N'' + Phi N = 0 over 2 pi
        real(dp) :: half_trace = 0.0_dp       !! cos(2 pi c)
        real(dp) :: c = 0.0_dp                !! 1 + acos(half_trace)/(2 pi)
        real(dp) :: det = 0.0_dp
    end type hill_transverse_result

    !> The orbit with the normal-deviation equation (two solutions) appended.
    type, extends(ode_system) :: transverse_system
        real(dp) :: m = 0.0_dp, kappa = 1.0_dp
    contains
        procedure :: rhs => transverse_rhs
    end type transverse_system

contains

    !> Cold-start guess: the circular Kepler orbit of inertial mean motion 1 + m,
    !! x0 = kappa^(1/3) (1 + m)^(-2/3), v0 = x0 (rotating-frame angular velocity 1).
    pure subroutine hill_orbit_guess(m, kappa, u)
        real(dp), intent(in) :: m, kappa
        real(dp), intent(out) :: u(2)
        u(1) = kappa**(1.0_dp/3.0_dp)*(1.0_dp + m)**(-2.0_dp/3.0_dp)
        u(2) = u(1)
    end subroutine hill_orbit_guess

    !> c = 1 + acos(S)/(2 pi) from the stability index S (NaN if |S| > 1).
    elemental real(dp) function hill_perigee_c(s) result(c)
        real(dp), intent(in) :: s
        if (abs(s) <= 1.0_dp) then
            c = 1.0_dp + acos(s)/(2.0_dp*pi)
        else
            c = nan_dp
        end if
    end function hill_perigee_c

    !> Fixed-step DOP853 (8th-order solution) for the state and its STM over [0, t1].
    pure subroutine integrate_var(tab, m, kappa, t1, nsteps, z, nfev)
        type(rk_tableau), intent(in) :: tab
        real(dp), intent(in) :: m, kappa, t1
        integer, intent(in) :: nsteps
        real(dp), intent(inout) :: z(20)
        integer, intent(inout) :: nfev
        real(dp) :: k(20, 12), zt(20), h
        integer :: istep, i, j
        h = t1/nsteps
        do istep = 1, nsteps
            call hill_var_rhs(m, kappa, 20, z, k(:, 1))
            do i = 2, 12
                zt = z
                do j = 1, i - 1
                    if (tab%a(i, j) /= 0.0_dp) zt = zt + (h*tab%a(i, j))*k(:, j)
                end do
                call hill_var_rhs(m, kappa, 20, zt, k(:, i))
            end do
            do j = 1, 12
                if (tab%b(j) /= 0.0_dp) z = z + (h*tab%b(j))*k(:, j)
            end do
        end do
        nfev = nfev + 12*nsteps
    end subroutine integrate_var

    !> z = [x0, 0, 0, v0, e(cols(1)), ..., e(cols(j))] for u = (x0, v0): the symmetric
    !! start with the columns of the identity STM that are integrated along.
    pure subroutine start_state(u, cols, z)
        real(dp), intent(in) :: u(2)
        integer, intent(in) :: cols(:)
        real(dp), intent(out) :: z(:)
        integer :: j
        z = 0.0_dp
        z(1) = u(1)
        z(4) = u(2)
        do j = 1, size(cols)
            z(4*j + cols(j)) = 1.0_dp
        end do
    end subroutine start_state

    !> The variation orbit for (m, kappa) with its monodromy, multipliers and c.
    !! `guess` = (x0, v0) to start Newton from (default: `hill_orbit_guess`).
    !!
    !! Error control: Newton runs on the fixed-step problem with n = `nsteps` steps per
    !! quarter period; the true closure error of its solution is then estimated by step
    !! doubling: the state alone is integrated from the converged start with nc = n/2
    !! steps, whose closure is (R - 1) times the n-step solution's true closure error,
    !! R = (n/nc)^8 (8th order); dividing by R - 1 with R = (n/nc)^7 instead overestimates
    !! the error twofold (a margin for the coarse solution's pre-asymptotic error; checked
    !! against adaptive Verner 9(8) in the tests). While the estimate exceeds
    !! `closure_tol`, n grows (by the 8th-order error model, at least doubled, at most
    !! `max_nsteps`) and Newton restarts from the last solution. `residual` is this true
    !! closure estimate; `newton_residual` the closure of the discretised problem.
    !! Newton accepts when its step |du| <= tol max(1, |u|) (1e-14); the quarter-period STM
    !! is that of the last iterate, within |du| of the solution.
    !! S and c come from products of quarter-map entries (`section_products`), not from the
    !! trace of M: the trace sums O(1) entries to 1 - S ~ (2 pi m)^2 and carried a
    !! round-off floor of ~1e-12 in c; the products keep c to ~1e-14 (family members agree
    !! with single orbits to < 1e-13 whatever the Newton start).
    !! info: CM_SUCCESS; CM_BAD_INPUT (m < 0, kappa <= 0, bad options); CM_SINGULAR
    !! (singular Newton matrix); CM_NO_CONVERGENCE (Newton failed or diverged, another
    !! orbit was found, or the closure tolerance cannot be met with `max_nsteps`).
    subroutine hill_variation_orbit(m, kappa, orb, options, guess)
        real(dp), intent(in) :: m, kappa
        type(hill_orbit), intent(out) :: orb
        type(hill_orbit_options), intent(in), optional :: options
        real(dp), intent(in), optional :: guess(2)
        type(hill_orbit_options) :: opt
        type(rk_tableau) :: tab
        real(dp) :: u(2), u0(2), ua(2), a(4, 4), zq(4), s(4), err, r8, ss, tt
        integer :: n, nretry, nc
        character(len=40) :: buf
        if (present(options)) opt = options
        orb%m = m
        orb%kappa = kappa
        if (.not. (m >= 0.0_dp .and. kappa > 0.0_dp .and. (abs(m) <= huge(1.0_dp)) .and. &
                   (abs(kappa) <= huge(1.0_dp))) .or. opt%nsteps < 1 .or. opt%max_iter < 1 .or. &
            opt%max_nsteps < opt%nsteps .or. .not. (opt%closure_tol > 0.0_dp) .or. &
            .not. (opt%tol > 0.0_dp)) then
            call orb%fail(CM_BAD_INPUT, "hill_variation_orbit: need m >= 0, kappa > 0, 1 <= "// &
                                        "nsteps <= max_nsteps, tol > 0, closure_tol > 0")
            return
        end if
        if (present(guess)) then
            u = guess
        else
            call hill_orbit_guess(m, kappa, u)
        end if
        if (.not. (all(abs(u) <= huge(1.0_dp)) .and. u(1) > 0.0_dp)) then
            call orb%fail(CM_BAD_INPUT, "hill_variation_orbit: the guess needs x0 > 0")
            return
        end if
        u0 = u
        n = opt%nsteps
        nretry = 0
        do
            call hill_newton(m, kappa, n, opt, u, ua, a, zq, orb)
            if (orb%info /= CM_SUCCESS) then
                ! a coarse discretisation can defeat Newton: retry from the guess with
                ! more steps (twice at most)
                if (nretry >= 2 .or. 4*n > opt%max_nsteps .or. &
                    orb%info == CM_BAD_INPUT) return
                nretry = nretry + 1
                n = 4*n
                u = u0
                cycle
            end if
            ! the closure of the same start with nc = n/2 steps (step doubling) is (R - 1)
            ! times the true closure error of the n-step solution, R = (n/nc)^p; p = 7
            ! instead of the order 8 overestimates it (by 2 in the asymptotic regime)
            nc = n/2
            if (n < 2) nc = 2
            s = [u(1), 0.0_dp, 0.0_dp, u(2)]
            call hill_kernel_state(m, kappa, 0.5_dp*pi, nc, s, orb%nfev)
            r8 = (real(n, dp)/real(nc, dp))**7
            err = sqrt(s(1)**2 + s(4)**2)/abs(r8 - 1.0_dp)
            if (.not. (abs(err) <= huge(1.0_dp))) err = huge(1.0_dp)
            orb%residual = err
            orb%nsteps = n
            if (err <= opt%closure_tol) exit
            if (n >= opt%max_nsteps) then
                write (buf, '(es9.2, a, i0)') err, " with nsteps = ", n
                call orb%fail(CM_NO_CONVERGENCE, "hill_variation_orbit: the true closure "// &
                                                 "error "//trim(buf)//" exceeds closure_tol "// &
                                                 "(raise max_nsteps)")
                return
            end if
            n = min(opt%max_nsteps, max(2*n, &
                    ceiling(1.2_dp*n*(err/opt%closure_tol)**0.125_dp)))
        end do
        if (.not. (u(2) > 0.0_dp .and. zq(2) > 0.0_dp)) then
            ! Newton found another symmetric periodic solution (e.g. a retrograde one)
            call orb%fail(CM_NO_CONVERGENCE, "hill_variation_orbit: converged to another "// &
                                             "periodic orbit, not the direct variation orbit "// &
                                             "(a better guess is needed)")
            return
        end if
        orb%y0 = [u(1), 0.0_dp, 0.0_dp, u(2)]
        orb%quarter_state = zq
        orb%jacobi = hill_jacobi(m, kappa, orb%y0)
        ! the STM column of y0 (e2) from the flow, A f(y(0)) = f(y(pi/2)), at the iterate ua
        ! of the STM
        call flow_column(m, kappa, ua, zq, a)
        orb%quarter_stm = a
        if (opt%full_period) then
            ! a check: the monodromy integrated over 2 pi, S and c from its trace
            block
                real(dp) :: z(20)
                tab = dop853_tableau()
                call start_state(u, [1, 2, 3, 4], z)
                call integrate_var(tab, m, kappa, 2.0_dp*pi, 4*n, z, orb%nfev)
                orb%monodromy = reshape(z(5:20), [4, 4])
            end block
            orb%stability_index = 0.5_dp*(orb%monodromy(1, 1) + orb%monodromy(2, 2) + &
                                          orb%monodromy(3, 3) + orb%monodromy(4, 4) - 2.0_dp)
            orb%c = hill_perigee_c(orb%stability_index)
        else
            call monodromy_from_quarter(m, a, orb%monodromy, orb%info)
            if (orb%info /= CM_SUCCESS) then
                orb%message = "hill_variation_orbit: non-finite quarter-period STM"
                return
            end if
            call section_products(m, kappa, ua, zq, a, ss, tt)
            orb%stability_index = 1.0_dp - 8.0_dp*ss*tt
            orb%c = perigee_c_from_products(ss, tt)
        end if
        if (.not. (abs(orb%stability_index) <= huge(1.0_dp))) then
            call orb%fail(CM_NONFINITE, "hill_variation_orbit: non-finite monodromy")
            return
        end if
        if (opt%eigenvalues) then
            call la_eig(orb%monodromy, orb%mr, orb%mi, orb%info)
            if (orb%info /= CM_SUCCESS) then
                orb%message = "hill_variation_orbit: dgeev failed"
                return
            end if
        end if
    end subroutine hill_variation_orbit

    !> Newton's method on the fixed-step problem with n steps per quarter period, on the
    !! state and the STM columns of x0, x0', v0 (hill_kernel_var). On success u is the
    !! solution, ua the last iterate (u - ua = its Newton step, |u - ua| <= tol), a the STM
    !! at ua (columns 1, 3, 4; column 2 is filled by flow_column) and zq its state at pi/2.
    subroutine hill_newton(m, kappa, n, opt, u, ua, a, zq, orb)
        real(dp), intent(in) :: m, kappa
        integer, intent(in) :: n
        type(hill_orbit_options), intent(in) :: opt
        real(dp), intent(inout) :: u(2)
        real(dp), intent(out) :: ua(2), a(4, 4), zq(4)
        type(hill_orbit), intent(inout) :: orb
        real(dp) :: du(2), g(2), z(16), det, scale
        integer :: it
        call orb%fail(CM_NO_CONVERGENCE, "hill_variation_orbit: Newton did not converge")
        a = 0.0_dp
        zq = 0.0_dp
        ua = u
        do it = 1, opt%max_iter
            orb%iterations = orb%iterations + 1
            call start_state(u, [1, 3, 4], z)
            call hill_kernel_var(m, kappa, 0.5_dp*pi, n, z, orb%nfev)
            if (.not. all(abs(z) <= huge(1.0_dp))) then
                call orb%fail(CM_NO_CONVERGENCE, "hill_variation_orbit: non-finite state (the "// &
                                                 "guess is too far)")
                return
            end if
            a(:, 1) = z(5:8)
            a(:, 3) = z(9:12)
            a(:, 4) = z(13:16)
            zq = z(1:4)
            ua = u
            g = [z(1), z(4)]
            det = a(1, 1)*a(4, 4) - a(1, 4)*a(4, 1)
            scale = max(abs(a(1, 1)*a(4, 4)), abs(a(1, 4)*a(4, 1)), tiny(1.0_dp))
            if (abs(det) <= 1.0e-13_dp*scale) then
                call orb%fail(CM_SINGULAR, "hill_variation_orbit: singular Newton matrix")
                return
            end if
            du(1) = -(a(4, 4)*g(1) - a(1, 4)*g(2))/det
            du(2) = -(-a(4, 1)*g(1) + a(1, 1)*g(2))/det
            orb%newton_residual = sqrt(g(1)**2 + g(2)**2)
            scale = max(1.0_dp, maxval(abs(u)))
            u = u + du
            if (maxval(abs(du)) <= opt%tol*scale) then
                ! the STM is that of the last iterate, within |du| <= tol of the solution
                orb%info = CM_SUCCESS
                orb%message = "success"
                return
            end if
            if (.not. (u(1) > 0.0_dp) .or. maxval(abs(du)) > 10.0_dp*scale) then
                call orb%fail(CM_NO_CONVERGENCE, "hill_variation_orbit: Newton diverged")
                return
            end if
        end do
    end subroutine hill_newton

    !> Column 2 of the quarter-period STM (variation of y0) from columns 3 and the flow:
    !! f(y(0)) = [0, v0, x0'', 0] and A f(y(0)) = f(y(pi/2)) give
    !! A e2 = (f(y(pi/2)) - x0'' A e3)/v0 (exact for the exact flow).
    pure subroutine flow_column(m, kappa, u, zq, a)
        real(dp), intent(in) :: m, kappa, u(2), zq(4)
        real(dp), intent(inout) :: a(4, 4)
        real(dp) :: fx, fy, fq(4), xdd0
        call hill_grad_f(m, kappa, u(1), 0.0_dp, fx, fy)
        xdd0 = 2.0_dp*m*u(2) + fx
        call hill_grad_f(m, kappa, zq(1), zq(2), fx, fy)
        fq = [zq(3), zq(4), 2.0_dp*m*zq(4) + fx, -2.0_dp*m*zq(3) + fy]
        a(:, 2) = (fq - xdd0*a(:, 3))/u(2)
    end subroutine flow_column

    !> The products s = alpha delta/D and t = -beta gamma/D (s + t = 1) of the quarter map
    !! DQ = [alpha, beta; gamma, delta] between two Poincare sections on the energy surface:
    !! at the start, coordinates along the G0-even variation u_E = e1 + (F_x/v0) e4 (dx0,
    !! dv0 at fixed energy) and the odd e3 (dx0'); at pi/2, the section through y(pi/2)
    !! transversal to the flow with coordinates along the G1-even energy direction
    !! (dy, dx') = (x', F_y) and the G1-odd direction across the flow, (dx, dy') x f. With
    !! the reversing symmetries the half-period map is H = R0 DQ^-1 R1 DQ (R0, R1 =
    !! diag(1, -1)), half trace (alpha delta + beta gamma)/D = cos(pi c), so
    !! s = sin^2(theta/2), t = cos^2(theta/2), theta = pi (c - 1), and
    !! S = cos(2 pi c) = 1 - 8 s t. alpha and delta vanish as m -> 0 (c -> 1): computed as
    !! products, s, S and c keep their relative accuracy where 1 - S = 8 s t is small (the
    !! trace of M loses it there: its entries are O(1) and 1 - S ~ (2 pi m)^2). No
    !! division by x'(pi/2), which vanishes at the cusp orbit.
    pure subroutine section_products(m, kappa, u, zq, a, s, t)
        real(dp), intent(in) :: m, kappa, u(2), zq(4), a(4, 4)
        real(dp), intent(out) :: s, t
        real(dp) :: fx, fy, w(4), ydd1, al, be, ga, de, d
        call hill_grad_f(m, kappa, u(1), 0.0_dp, fx, fy)
        w = a(:, 1) + (fx/u(2))*a(:, 4)
        call hill_grad_f(m, kappa, zq(1), zq(2), fx, fy)
        ydd1 = -2.0_dp*m*zq(3) + fy
        al = w(2)*zq(3) + w(3)*fy
        be = a(2, 3)*zq(3) + a(3, 3)*fy
        ga = w(1)*ydd1 - w(4)*zq(3)
        de = a(1, 3)*ydd1 - a(4, 3)*zq(3)
        d = al*de - be*ga
        s = al*de/d
        t = -be*ga/d
    end subroutine section_products

    !> c on the branch c = 1 + acos(S)/(2 pi) (1 <= c <= 3/2) from s, t of
    !! section_products: c = 1 + (2/pi) atan(sqrt(min(s, t)/max(s, t))); NaN when s or t
    !! is negative (|S| > 1, unstable).
    elemental real(dp) function perigee_c_from_products(s, t) result(c)
        real(dp), intent(in) :: s, t
        if (s >= 0.0_dp .and. t >= 0.0_dp .and. s + t > 0.0_dp) then
            c = 1.0_dp + (2.0_dp/pi)*atan2(sqrt(min(s, t)), sqrt(max(s, t)))
        else
            c = nan_dp
        end if
    end function perigee_c_from_products

    !> M = B^2, B = G1 A^-1 G1 A (see the module notes), with A^-1 = W^-1 A^T W from the
    !! symplectic form of Hill's equations in (x, y, x', y'),
    !! w = dx^dx' + dy^dy' - 2 m dx^dy (A^T W A = W), instead of a factorisation.
    pure subroutine monodromy_from_quarter(m, a, mono, info)
        real(dp), intent(in) :: m, a(4, 4)
        real(dp), intent(out) :: mono(4, 4)
        integer, intent(out) :: info
        real(dp) :: w(4, 4), wi(4, 4), ainv(4, 4), b(4, 4), g1(4)
        integer :: i, j
        g1 = [-1.0_dp, 1.0_dp, 1.0_dp, -1.0_dp]
        if (.not. all(abs(a) <= huge(1.0_dp))) then
            mono = 0.0_dp
            info = CM_NONFINITE
            return
        end if
        w = reshape([0.0_dp, 2.0_dp*m, -1.0_dp, 0.0_dp, -2.0_dp*m, 0.0_dp, 0.0_dp, -1.0_dp, &
                     1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp, 0.0_dp], [4, 4])
        wi = reshape([0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp, &
                      -1.0_dp, 0.0_dp, 0.0_dp, 2.0_dp*m, 0.0_dp, -1.0_dp, -2.0_dp*m, 0.0_dp], &
                     [4, 4])
        ainv = matmul(wi, matmul(transpose(a), w))
        ! G1 A^-1 G1
        do j = 1, 4
            do i = 1, 4
                ainv(i, j) = g1(i)*g1(j)*ainv(i, j)
            end do
        end do
        b = matmul(ainv, a)
        mono = matmul(b, b)
        info = CM_SUCCESS
    end subroutine monodromy_from_quarter

    ! ------------------------------------------------------------ transverse linearisation

    !> Phi(t) of the normal-deviation equation at the orbit point s = [x, y, x', y'].
    pure real(dp) function hill_phi(m, kappa, s) result(p)
        real(dp), intent(in) :: m, kappa, s(4)
        real(dp) :: v, nx, ny, fx, fy, fxx, fxy, fyy, om, hnn
        v = sqrt(s(3)**2 + s(4)**2)
        nx = -s(4)/v
        ny = s(3)/v
        call hill_grad_f(m, kappa, s(1), s(2), fx, fy)
        call hill_hess_f(m, kappa, s(1), s(2), fxx, fxy, fyy)
        om = (nx*fx + ny*fy)/v - 2.0_dp*m
        hnn = fxx*nx*nx + 2.0_dp*fxy*nx*ny + fyy*ny*ny
        p = 3.0_dp*(om + m)**2 + m*m - hnn
    end function hill_phi

    subroutine transverse_rhs(self, t, y, dydt)
        class(transverse_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: fx, fy, p
        call hill_grad_f(self%m, self%kappa, y(1), y(2), fx, fy)
        dydt(1) = y(3)
        dydt(2) = y(4)
        dydt(3) = 2.0_dp*self%m*y(4) + fx
        dydt(4) = -2.0_dp*self%m*y(3) + fy
        p = hill_phi(self%m, self%kappa, y(1:4))
        dydt(5) = y(6)
        dydt(6) = -p*y(5)
        dydt(7) = y(8)
        dydt(8) = -p*y(7)
    end subroutine transverse_rhs

    !> Integrate the orbit with N'' + Phi(t) N = 0 over its period (DOP853, rtol = atol =
    !! `rtol`, default 1e-13) and return the 2 x 2 monodromy, its half trace and c.
    subroutine hill_transverse(orb, res, rtol)
        type(hill_orbit), intent(in) :: orb
        type(hill_transverse_result), intent(out) :: res
        real(dp), intent(in), optional :: rtol
        type(transverse_system) :: ts
        type(ode_options) :: opt
        real(dp) :: z(8)
        character(len=:), allocatable :: msg
        if (orb%info /= CM_SUCCESS) then
            res%info = CM_BAD_INPUT
            res%message = "hill_transverse: the orbit was not computed"
            return
        end if
        ts%m = orb%m
        ts%kappa = orb%kappa
        opt = tolerance_options(1.0e-13_dp, rtol)
        if (.not. (opt%rtol > 0.0_dp .and. opt%rtol < 1.0_dp)) then
            res%info = CM_BAD_INPUT
            res%message = "hill_transverse: rtol must be in (0, 1)"
            return
        end if
        z = [orb%y0, 1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp]
        call ode_integrate(ts, 0.0_dp, orb%period, z, opt, res%info, message=msg)
        res%message = msg
        if (res%info < 0) return
        res%monodromy = reshape(z(5:8), [2, 2])
        res%half_trace = 0.5_dp*(z(5) + z(8))
        res%det = z(5)*z(8) - z(6)*z(7)
        res%c = hill_perigee_c(res%half_trace)
        res%info = CM_SUCCESS
    end subroutine hill_transverse

    !> The orbit and Phi at the times t (e.g. for CSV output): states(4, nt), phi(nt),
    !! integrated by DOP853 at rtol = atol = `rtol` (default 1e-12).
    subroutine hill_orbit_sample(orb, t, states, phi, info, rtol)
        type(hill_orbit), intent(in) :: orb
        real(dp), intent(in) :: t(:)
        real(dp), intent(out) :: states(:, :)
        real(dp), intent(out) :: phi(:)
        integer, intent(out) :: info
        real(dp), intent(in), optional :: rtol
        type(hill_problem) :: hp
        type(ode_options) :: opt
        type(ode_result) :: r
        integer :: i
        if (orb%info /= CM_SUCCESS .or. size(t) < 1) then
            info = CM_BAD_INPUT
            return
        end if
        hp%m = orb%m
        hp%kappa = orb%kappa
        opt = tolerance_options(1.0e-12_dp, rtol)
        call ode_solve(hp, [0.0_dp, max(orb%period, maxval(t))], orb%y0, opt, r, t_eval=t)
        info = r%status
        if (info < 0) return
        do i = 1, size(t)
            states(:, i) = r%y(:, i)
            phi(i) = hill_phi(orb%m, orb%kappa, r%y(:, i))
        end do
        info = CM_SUCCESS
    end subroutine hill_orbit_sample

end module conmech_hill_orbit
