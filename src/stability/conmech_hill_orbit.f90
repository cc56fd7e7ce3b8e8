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
!! Speed: the state and its STM (20 components) are integrated with a fixed-step DOP853
!! (8th order, the Dormand-Prince coefficients of `conmech_rk_tableaus`) with the Hill
!! right-hand side written out; the default 20 steps per quarter period give
!! |c error| ~ 1e-14 at Hill's m.
!!
!! Monodromy by symmetry: with the time-reversing reflections G0 = diag(1, -1, -1, 1)
!! (x axis) and G1 = diag(-1, 1, 1, -1) (y axis), the half-period STM is
!! B = G1 A^-1 G1 A, and since G1 G0 = -I the monodromy is M = B^2. The option
!! `full_period` integrates the whole period instead (a check, 4x the work).
!!
!! Perigee constant: the non-trivial multipliers are exp(+-2 pi i c). From the trace,
!! S = (trace M - 2)/2 = cos(2 pi c); the branch is c = 1 + acos(S)/(2 pi), the
!! continuation of c = 1 at m = 0 (c > 1 along the direct family, valid while
!! 1 <= c <= 3/2; c is NaN when |S| > 1, an unstable orbit). Conditioning: an error e in S
!! gives e/(2 pi sin(2 pi (c - 1))) in c, about e/2.7 at Hill's m, but it grows as m -> 0
!! (c -> 1, S -> 1: at m = 1e-6, |c error| ~ 3e-9; at m = 0 c = 1 only to ~2e-7).
!!
!! Transverse linearisation (seed 000): with tangent tau = v/|v|, normal n = (-tau_y, tau_x),
!! V = |v|, H the Hessian of F and omega = n.grad F / V - 2 m (the turning rate of the
!! tangent), the normal deviation of an isoenergetic (delta I = 0) perturbation obeys
!! N'' + Phi(t) N = 0 with Phi = 3 (omega + m)^2 + m^2 - n^T H n. Its 2 x 2 monodromy over
!! 2 pi has the non-trivial multipliers of the 4 x 4 monodromy.
!!
!! Thread safety: no saved state; `hill_family` runs chunks of the family in parallel with
!! OpenMP when compiled with -fopenmp.
module conmech_hill_orbit
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_finite
    use conmech_kinds, only: dp, pi
    use conmech_status
    use conmech_lapack, only: dgesv, la_eig, la_finite
    use conmech_rk_tableaus, only: rk_tableau, dop853_tableau
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_stats, ode_integrate, ode_solve, ode_result
    use conmech_hill, only: hill_problem, hill_jacobi, hill_grad_f, hill_hess_f
    !$ use omp_lib, only: omp_get_max_threads
    implicit none
    private

    public :: hill_orbit, hill_orbit_options, hill_variation_orbit, hill_family
    public :: hill_orbit_guess, hill_perigee_c, hill_phi, hill_transverse, hill_transverse_result
    public :: hill_orbit_sample

    !> Options of the variation-orbit solver.
    type :: hill_orbit_options
        integer :: nsteps = 20           !! DOP853 steps per quarter period
        integer :: max_iter = 30         !! Newton iterations
        real(dp) :: tol = 1.0e-13_dp     !! accept when |du| <= tol max(1, |u|)
        logical :: full_period = .false. !! monodromy by direct integration over 2 pi
        logical :: eigenvalues = .true.  !! compute the multipliers with dgeev
    end type hill_orbit_options

    !> A variation orbit with its monodromy.
    type :: hill_orbit
        integer :: info = CM_BAD_INPUT
        character(len=:), allocatable :: message
        real(dp) :: m = 0.0_dp, kappa = 1.0_dp
        real(dp) :: y0(4) = 0.0_dp            !! [x0, 0, 0, v0]
        real(dp) :: period = 2.0_dp*pi
        real(dp) :: jacobi = 0.0_dp           !! Jacobi integral x'^2 + y'^2 - 2F
        real(dp) :: quarter_stm(4, 4) = 0.0_dp  !! A = Phi(pi/2)
        real(dp) :: monodromy(4, 4) = 0.0_dp  !! M = Phi(2 pi)
        real(dp) :: mr(4) = 0.0_dp, mi(4) = 0.0_dp  !! multipliers (dgeev)
        real(dp) :: stability_index = 0.0_dp  !! S = (trace M - 2)/2, stable iff |S| < 1
        real(dp) :: c = 0.0_dp                !! perigee constant
        real(dp) :: residual = 0.0_dp         !! |(x, y')(pi/2)| at the solution
        integer :: iterations = 0             !! Newton iterations
        integer :: nfev = 0                   !! right-hand side evaluations (20-dim)
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
            c = ieee_value(1.0_dp, ieee_quiet_nan)
        end if
    end function hill_perigee_c

    !> z' for z = [x, y, x', y', vec(Phi)] (Phi 4 x 4 by columns).
    pure subroutine var_rhs(m, kappa, z, dz)
        real(dp), intent(in) :: m, kappa, z(20)
        real(dp), intent(out) :: dz(20)
        real(dp) :: x, y, r2, ir, ir3, ir5, fxx, fxy, fyy, tm, k3
        integer :: j, o
        x = z(1)
        y = z(2)
        r2 = x*x + y*y
        ir = 1.0_dp/sqrt(r2)
        ir3 = ir*ir*ir
        ir5 = ir3*ir*ir
        tm = 2.0_dp*m
        dz(1) = z(3)
        dz(2) = z(4)
        dz(3) = tm*z(4) - kappa*x*ir3 + 3.0_dp*m*m*x
        dz(4) = -tm*z(3) - kappa*y*ir3
        k3 = 3.0_dp*kappa*ir5
        fxx = k3*x*x - kappa*ir3 + 3.0_dp*m*m
        fxy = k3*x*y
        fyy = k3*y*y - kappa*ir3
        do j = 1, 4
            o = 4*j
            dz(o + 1) = z(o + 3)
            dz(o + 2) = z(o + 4)
            dz(o + 3) = fxx*z(o + 1) + fxy*z(o + 2) + tm*z(o + 4)
            dz(o + 4) = fxy*z(o + 1) + fyy*z(o + 2) - tm*z(o + 3)
        end do
    end subroutine var_rhs

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
            call var_rhs(m, kappa, z, k(:, 1))
            do i = 2, 12
                zt = z
                do j = 1, i - 1
                    if (tab%a(i, j) /= 0.0_dp) zt = zt + (h*tab%a(i, j))*k(:, j)
                end do
                call var_rhs(m, kappa, zt, k(:, i))
            end do
            do j = 1, 12
                if (tab%b(j) /= 0.0_dp) z = z + (h*tab%b(j))*k(:, j)
            end do
        end do
        nfev = nfev + 12*nsteps
    end subroutine integrate_var

    pure subroutine start_state(u, z)
        real(dp), intent(in) :: u(2)
        real(dp), intent(out) :: z(20)
        z = 0.0_dp
        z(1) = u(1)
        z(4) = u(2)
        z(5) = 1.0_dp
        z(10) = 1.0_dp
        z(15) = 1.0_dp
        z(20) = 1.0_dp
    end subroutine start_state

    !> The variation orbit for (m, kappa) with its monodromy, multipliers and c.
    !! `guess` = (x0, v0) to start Newton from (default: `hill_orbit_guess`).
    !! info: CM_SUCCESS; CM_BAD_INPUT (m < 0, kappa <= 0, bad options); CM_SINGULAR
    !! (singular Newton matrix); CM_NO_CONVERGENCE (Newton failed or diverged).
    subroutine hill_variation_orbit(m, kappa, orb, options, guess)
        real(dp), intent(in) :: m, kappa
        type(hill_orbit), intent(out) :: orb
        type(hill_orbit_options), intent(in), optional :: options
        real(dp), intent(in), optional :: guess(2)
        type(hill_orbit_options) :: opt
        type(rk_tableau) :: tab
        real(dp) :: u(2), du(2), g(2), z(20), a(4, 4), det, scale
        integer :: it
        logical :: final
        if (present(options)) opt = options
        orb%m = m
        orb%kappa = kappa
        if (.not. (m >= 0.0_dp .and. kappa > 0.0_dp .and. ieee_is_finite(m) .and. &
                   ieee_is_finite(kappa)) .or. opt%nsteps < 1 .or. opt%max_iter < 1) then
            orb%info = CM_BAD_INPUT
            orb%message = "hill_variation_orbit: need m >= 0, kappa > 0, nsteps >= 1"
            return
        end if
        if (present(guess)) then
            u = guess
        else
            call hill_orbit_guess(m, kappa, u)
        end if
        if (.not. (all(ieee_is_finite(u)) .and. u(1) > 0.0_dp)) then
            orb%info = CM_BAD_INPUT
            orb%message = "hill_variation_orbit: the guess needs x0 > 0"
            return
        end if
        tab = dop853_tableau()
        final = .false.
        orb%info = CM_NO_CONVERGENCE
        orb%message = "hill_variation_orbit: Newton did not converge"
        do it = 1, opt%max_iter
            orb%iterations = it
            call start_state(u, z)
            call integrate_var(tab, m, kappa, 0.5_dp*pi, opt%nsteps, z, orb%nfev)
            if (.not. all(ieee_is_finite(z))) then
                orb%info = CM_NO_CONVERGENCE
                orb%message = "hill_variation_orbit: non-finite state (the guess is too far)"
                return
            end if
            a = reshape(z(5:20), [4, 4])
            g = [z(1), z(4)]
            det = a(1, 1)*a(4, 4) - a(1, 4)*a(4, 1)
            scale = max(abs(a(1, 1)*a(4, 4)), abs(a(1, 4)*a(4, 1)), tiny(1.0_dp))
            if (abs(det) <= 1.0e-13_dp*scale) then
                orb%info = CM_SINGULAR
                orb%message = "hill_variation_orbit: singular Newton matrix"
                return
            end if
            du(1) = -(a(4, 4)*g(1) - a(1, 4)*g(2))/det
            du(2) = -(-a(4, 1)*g(1) + a(1, 1)*g(2))/det
            orb%residual = sqrt(g(1)**2 + g(2)**2)
            scale = max(1.0_dp, maxval(abs(u)))
            if (maxval(abs(du)) <= opt%tol*scale .or. &
                (final .and. maxval(abs(du)) <= 1.0e-10_dp*scale)) then
                u = u + du
                orb%info = CM_SUCCESS
                orb%message = "success"
                exit
            end if
            u = u + du
            final = maxval(abs(du)) <= 1.0e-7_dp*scale
            if (.not. (u(1) > 0.0_dp) .or. maxval(abs(du)) > 10.0_dp*scale) then
                orb%info = CM_NO_CONVERGENCE
                orb%message = "hill_variation_orbit: Newton diverged"
                return
            end if
        end do
        if (orb%info /= CM_SUCCESS) return
        if (.not. (u(2) > 0.0_dp .and. z(2) > 0.0_dp)) then
            ! Newton found another symmetric periodic solution (e.g. a retrograde one)
            orb%info = CM_NO_CONVERGENCE
            orb%message = "hill_variation_orbit: converged to another periodic orbit, "// &
                          "not the direct variation orbit (a better guess is needed)"
            return
        end if
        orb%y0 = [u(1), 0.0_dp, 0.0_dp, u(2)]
        orb%jacobi = hill_jacobi(m, kappa, orb%y0)
        orb%quarter_stm = a
        if (opt%full_period) then
            call start_state(u, z)
            call integrate_var(tab, m, kappa, 2.0_dp*pi, 4*opt%nsteps, z, orb%nfev)
            orb%monodromy = reshape(z(5:20), [4, 4])
        else
            call monodromy_from_quarter(a, orb%monodromy, orb%info)
            if (orb%info /= CM_SUCCESS) then
                orb%message = "hill_variation_orbit: singular quarter-period STM"
                return
            end if
        end if
        orb%stability_index = 0.5_dp*(orb%monodromy(1, 1) + orb%monodromy(2, 2) + &
                                      orb%monodromy(3, 3) + orb%monodromy(4, 4) - 2.0_dp)
        orb%c = hill_perigee_c(orb%stability_index)
        if (opt%eigenvalues) then
            call la_eig(orb%monodromy, orb%mr, orb%mi, orb%info)
            if (orb%info /= CM_SUCCESS) then
                orb%message = "hill_variation_orbit: dgeev failed"
                return
            end if
        end if
    end subroutine hill_variation_orbit

    !> M = B^2, B = G1 A^-1 G1 A (see the module notes).
    subroutine monodromy_from_quarter(a, mono, info)
        real(dp), intent(in) :: a(4, 4)
        real(dp), intent(out) :: mono(4, 4)
        integer, intent(out) :: info
        real(dp) :: lu(4, 4), x(4, 4), b(4, 4), g1(4)
        integer :: ipiv(4), i, j
        g1 = [-1.0_dp, 1.0_dp, 1.0_dp, -1.0_dp]
        if (.not. la_finite(a)) then
            mono = 0.0_dp
            info = CM_NONFINITE
            return
        end if
        lu = a
        ! x = A^-1 (G1 A): solve A x = G1 A
        do j = 1, 4
            x(:, j) = g1*a(:, j)
        end do
        call dgesv(4, 4, lu, 4, ipiv, x, 4, info)
        if (info /= 0) then
            info = CM_SINGULAR
            return
        end if
        do j = 1, 4
            do i = 1, 4
                b(i, j) = g1(i)*x(i, j)
            end do
        end do
        mono = matmul(b, b)
        info = CM_SUCCESS
    end subroutine monodromy_from_quarter

    !> The family over ms (any order; continuation works best for sorted, close values).
    !! Each orbit starts Newton from the quadratic extrapolation of the previous three of its
    !! chunk (cold start at the chunk's first). With OpenMP the index range is cut into one
    !! contiguous chunk per thread (`nchunks` overrides the number of chunks).
    subroutine hill_family(ms, kappa, orbs, options, nchunks)
        real(dp), intent(in) :: ms(:)
        real(dp), intent(in) :: kappa
        type(hill_orbit), intent(out) :: orbs(:)
        type(hill_orbit_options), intent(in), optional :: options
        integer, intent(in), optional :: nchunks
        type(hill_orbit_options) :: opt
        integer :: nc, ic, i, i0, i1, n, nprev, j
        real(dp) :: u(2), mm(3), uu(2, 3), w
        if (present(options)) opt = options
        n = size(ms)
        nc = 1
        !$ nc = omp_get_max_threads()
        if (present(nchunks)) nc = nchunks
        nc = max(1, min(nc, n))
        !$omp parallel do schedule(static, 1) default(shared) &
        !$omp private(ic, i, i0, i1, nprev, u, mm, uu, j, w)
        do ic = 1, nc
            i0 = (ic - 1)*n/nc + 1
            i1 = ic*n/nc
            nprev = 0
            do i = i0, i1
                if (nprev == 0) then
                    call hill_variation_orbit(ms(i), kappa, orbs(i), opt)
                else
                    ! Lagrange extrapolation through the last min(nprev, 3) orbits
                    u = 0.0_dp
                    do j = 1, min(nprev, 3)
                        w = lagrange_weight(ms(i), mm, min(nprev, 3), j)
                        u = u + w*uu(:, j)
                    end do
                    call hill_variation_orbit(ms(i), kappa, orbs(i), opt, guess=u)
                end if
                if (orbs(i)%info == CM_SUCCESS) then
                    mm(2:3) = mm(1:2)
                    uu(:, 2:3) = uu(:, 1:2)
                    mm(1) = ms(i)
                    uu(:, 1) = [orbs(i)%y0(1), orbs(i)%y0(4)]
                    nprev = nprev + 1
                else
                    nprev = 0
                end if
            end do
        end do
        !$omp end parallel do
    end subroutine hill_family

    pure real(dp) function lagrange_weight(x, xs, np, j) result(w)
        real(dp), intent(in) :: x, xs(3)
        integer, intent(in) :: np, j
        integer :: k
        w = 1.0_dp
        do k = 1, np
            if (k /= j) w = w*(x - xs(k))/(xs(j) - xs(k))
        end do
    end function lagrange_weight

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
        opt%rtol = 1.0e-13_dp
        if (present(rtol)) opt%rtol = rtol
        opt%atol = opt%rtol
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

    !> The orbit and Phi at the times t (e.g. for CSV output): states(4, nt), phi(nt).
    subroutine hill_orbit_sample(orb, t, states, phi, info)
        type(hill_orbit), intent(in) :: orb
        real(dp), intent(in) :: t(:)
        real(dp), intent(out) :: states(:, :)
        real(dp), intent(out) :: phi(:)
        integer, intent(out) :: info
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
        opt%rtol = 1.0e-12_dp
        opt%atol = 1.0e-12_dp
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
