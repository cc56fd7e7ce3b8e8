!> Flat f2py layer of the stability layer: Hill's variation orbit and family, transverse
!! linearisation, equilibria, state transition matrices (for any system given by the one
!! flat argument set of conmech_flat_system), Hill's equation. Periodic orbits:
!! flat_orbits.f90; continuation: flat_branch.f90.
!! Plain subroutines, c_double/c_int explicit-shape arrays, an `info` code and a message.
!! Nothing is saved between calls; nothing stops or prints.
!!
!! Callback conventions (as in flat_ode.f90): fun(t, y, dydt, n), jfun(t, y, dfdy, n);
!! phi(t, p) for Hill's equation.

!> Hill's variation orbit with its monodromy (see conmech_hill_orbit).
!! use_guess /= 0: Newton starts from guess = (x0, v0). full_period /= 0: monodromy by
!! direct integration over 2 pi instead of the symmetry.
subroutine flat_hill_orbit(m, kappa, nsteps, full_period, use_guess, guess, closure_tol, &
                           max_nsteps, y0, period, jacobi, mono, mr, mi, s, c, residual, &
                           quarter, nsteps_used, iterations, nfev, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_hill_orbit, only: hill_orbit, hill_orbit_options, hill_variation_orbit
    implicit none
    include "flat_hill_orbit_args.inc"
    type(hill_orbit) :: orb
    type(hill_orbit_options) :: opt
    real(c_double), allocatable :: g(:)
    if (nsteps > 0) opt%nsteps = nsteps
    if (closure_tol > 0.0_c_double) opt%closure_tol = closure_tol
    if (max_nsteps > 0) opt%max_nsteps = max_nsteps
    opt%full_period = full_period /= 0
    if (use_guess /= 0) g = guess
    call hill_variation_orbit(m, kappa, orb, opt, g)   ! unallocated g: no guess
    y0 = orb%y0
    period = orb%period
    jacobi = orb%jacobi
    mono = orb%monodromy
    mr = orb%mr
    mi = orb%mi
    s = orb%stability_index
    c = orb%c
    residual = orb%residual
    quarter = orb%quarter_state
    nsteps_used = orb%nsteps
    iterations = orb%iterations
    nfev = orb%nfev
    info = orb%info
    message = orb%message
end subroutine flat_hill_orbit

!> Locate the m where the stability index S of the variation family crosses `target`
!! (+1 or -1) between the orbits at ma (start ua = (x0, v0)) and mb (ub); see
!! hill_locate_index. Returns the located m, its orbit's (x0, v0), S, c, true closure.
subroutine flat_hill_locate(ma, ua, mb, ub, kappa, target, mtol, m_star, u_star, s, c, &
                            residual, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_status, only: CM_SUCCESS
    use conmech_hill_orbit, only: hill_orbit, hill_variation_orbit
    use conmech_hill_family, only: hill_locate_index
    implicit none
    real(c_double), intent(in) :: ma, ua(2), mb, ub(2), kappa, target, mtol
    real(c_double), intent(out) :: m_star, u_star(2), s, c, residual
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
    type(hill_orbit) :: oa, ob, orb
    m_star = 0.0_c_double
    u_star = 0.0_c_double
    s = 0.0_c_double
    c = 0.0_c_double
    residual = 0.0_c_double
    call hill_variation_orbit(ma, kappa, oa, guess=ua)
    call hill_variation_orbit(mb, kappa, ob, guess=ub)
    if (oa%info /= CM_SUCCESS .or. ob%info /= CM_SUCCESS) then
        info = merge(oa%info, ob%info, oa%info /= CM_SUCCESS)
        message = "the bracketing orbits did not converge"
        return
    end if
    call hill_locate_index(oa, ob, target, orb, mtol=mtol)
    info = orb%info
    message = orb%message
    if (info /= CM_SUCCESS) return
    m_star = orb%m
    u_star = [orb%y0(1), orb%y0(4)]
    s = orb%stability_index
    c = orb%c
    residual = orb%residual
end subroutine flat_hill_locate

!> The family of variation orbits over ms(nm) by continuation (see hill_family).
subroutine flat_hill_family(nm, ms, kappa, nsteps, chunk_size, y0s, jacobis, monos, ss, cs, &
                            residuals, quarters, nsteps_used, infos, iters)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_hill_orbit, only: hill_orbit, hill_orbit_options
    use conmech_hill_family, only: hill_family
    implicit none
    integer(c_int), intent(in) :: nm
    real(c_double), intent(in) :: ms(nm), kappa
    integer(c_int), intent(in) :: nsteps, chunk_size
    real(c_double), intent(out) :: y0s(4, nm), jacobis(nm), monos(4, 4, nm), ss(nm), cs(nm)
    real(c_double), intent(out) :: residuals(nm), quarters(4, nm)
    integer(c_int), intent(out) :: nsteps_used(nm), infos(nm), iters(nm)
    type(hill_orbit), allocatable :: orbs(:)
    type(hill_orbit_options) :: opt
    integer, allocatable :: chunk
    integer :: i
    if (nsteps > 0) opt%nsteps = nsteps
    opt%eigenvalues = .false.
    allocate (orbs(nm))
    if (chunk_size > 0) chunk = chunk_size
    call hill_family(ms, kappa, orbs, opt, chunk_size=chunk)   ! unallocated: the default
    do i = 1, nm
        residuals(i) = orbs(i)%residual
        quarters(:, i) = orbs(i)%quarter_state
        nsteps_used(i) = orbs(i)%nsteps
        y0s(:, i) = orbs(i)%y0
        jacobis(i) = orbs(i)%jacobi
        monos(:, :, i) = orbs(i)%monodromy
        ss(i) = orbs(i)%stability_index
        cs(i) = orbs(i)%c
        infos(i) = orbs(i)%info
        iters(i) = orbs(i)%iterations
    end do
end subroutine flat_hill_family

!> Transverse linearisation along the variation orbit starting at y0: 2x2 monodromy of
!! N'' + Phi N = 0 over 2 pi, its half trace and c; Phi and the orbit at the times t(nt).
subroutine flat_hill_transverse(m, kappa, y0, rtol, nt, t, states, phi, mono2, half_trace, &
                                c, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: pi
    use conmech_status, only: CM_SUCCESS
    use conmech_hill_orbit, only: hill_orbit, hill_transverse, hill_transverse_result, &
                                  hill_orbit_sample
    implicit none
    real(c_double), intent(in) :: m, kappa, y0(4), rtol
    integer(c_int), intent(in) :: nt
    real(c_double), intent(in) :: t(nt)
    real(c_double), intent(out) :: states(4, nt), phi(nt), mono2(2, 2), half_trace, c
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
    type(hill_orbit) :: orb
    type(hill_transverse_result) :: tr
    integer :: inf
    orb%m = m
    orb%kappa = kappa
    orb%y0 = y0
    orb%period = 2.0_c_double*pi
    orb%info = CM_SUCCESS
    call hill_transverse(orb, tr, rtol)
    info = tr%info
    message = tr%message
    mono2 = tr%monodromy
    half_trace = tr%half_trace
    c = tr%c
    states = 0.0_c_double
    phi = 0.0_c_double
    if (info /= CM_SUCCESS .or. nt < 1) return
    call hill_orbit_sample(orb, t, states, phi, inf, rtol)
    if (inf /= CM_SUCCESS) then
        info = inf
        message = "sampling the orbit failed"
    end if
end subroutine flat_hill_transverse

!> Lagrange-Dirichlet test on a symmetric Hessian (dsyev).
subroutine flat_lagrange_dirichlet(n, hess, tol, stable, w, info)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_equilibria, only: lagrange_dirichlet
    implicit none
    integer(c_int), intent(in) :: n
    real(c_double), intent(in) :: hess(n, n), tol
    integer(c_int), intent(out) :: stable, info
    real(c_double), intent(out) :: w(n)
    logical :: st
    call lagrange_dirichlet(hess, st, w, info, tol)
    stable = merge(1, 0, st)
end subroutine flat_lagrange_dirichlet

!> State and state transition matrix from t0 to t1 (DOP853) of the system given by the one
!! flat argument set (conmech_flat_system).
subroutine flat_stm(name, np, params, nspec, spec, fun, jfun, source, n, y0, t0, t1, rtol, &
                    atol, y1, phi, nfev, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_stats
    use conmech_flat_system, only: flat_system
    use conmech_variational, only: integrate_stm
    use conmech_rank, only: identity
    implicit none
    integer(c_int), intent(in) :: n
    real(c_double), intent(in) :: y0(n), t0, t1, rtol, atol
    real(c_double), intent(out) :: y1(n), phi(n, n)
    integer(c_int), intent(out) :: nfev, info
    character(len=256), intent(out) :: message
    include "flat_system_args.inc"
    class(ode_system), allocatable :: sys
    character(len=:), allocatable :: msg
    type(ode_options) :: opt
    type(ode_stats) :: st
    nfev = 0
    y1 = y0
    phi = identity(n)
    call flat_system(name, params(1:np), nspec, spec, fun, jfun, source, n, sys, info, message)
    if (info /= 0) return
    opt%rtol = rtol
    opt%atol = atol
    call integrate_stm(sys, t0, t1, y1, phi, opt, info, msg, st)
    nfev = st%nfev
    message = msg
end subroutine flat_stm

!> Hill's equation N'' + Phi(t) N = 0 with Phi given by ns samples over one period.
subroutine flat_hill_equation_samples(ns, p, period, rtol, mono, half_trace, det, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_floquet, only: hill_result, hill_solve_samples
    implicit none
    integer(c_int), intent(in) :: ns
    real(c_double), intent(in) :: p(ns), period, rtol
    real(c_double), intent(out) :: mono(2, 2), half_trace, det
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
    type(hill_result) :: r
    call hill_solve_samples(p, period, r, rtol)
    mono = r%monodromy
    half_trace = r%half_trace
    det = r%det
    info = r%info
    message = r%message
end subroutine flat_hill_equation_samples

!> Hill's equation with Phi(t) a Python callback phi(t, p).
subroutine flat_hill_equation_callback(phi, period, rtol, mono, half_trace, det, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_support_stab, only: callback_hill_solve
    implicit none
    real(c_double), intent(in) :: period, rtol
    real(c_double), intent(out) :: mono(2, 2), half_trace, det
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
!f2py external phi
    interface
        subroutine phi(t, p)
            use, intrinsic :: iso_c_binding, only: c_double
            real(c_double), intent(in) :: t
            real(c_double), intent(out) :: p
        end subroutine phi
    end interface
    call callback_hill_solve(phi, period, rtol, mono, half_trace, det, info, message)
end subroutine flat_hill_equation_callback

!> Transverse linearisation of a periodic orbit (y0, period) of the planar natural system
!! q'' = -grad V + 2 omega J q' with V from the callback pot(q, v, g, h): the 2 x 2 monodromy
!! of N'' + Phi N = 0, its half trace and determinant, the closure of the orbit integrated,
!! the 4 x 4 monodromy (same integrator) and Phi at the times t(nt) along the orbit.
subroutine flat_transverse_callback(pot, omega, y0, period, rtol, nt, t, phi_t, mono2, &
                                    half_trace, det, closure, mono4, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_status, only: CM_SUCCESS
    use conmech_ode_solver, only: ode_options, ode_integrate
    use conmech_variational, only: integrate_stm
    use conmech_transverse, only: transverse_result, transverse_monodromy, transverse_phi
    use conmech_flat_adapters, only: callback_natural
    implicit none
    real(c_double), intent(in) :: omega, y0(4), period, rtol
    integer(c_int), intent(in) :: nt
    real(c_double), intent(in) :: t(nt)
    real(c_double), intent(out) :: phi_t(nt), mono2(2, 2), half_trace, det, closure
    real(c_double), intent(out) :: mono4(4, 4)
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
!f2py external pot
    interface
        subroutine pot(q, v, g, h)
            use, intrinsic :: iso_c_binding, only: c_double
            real(c_double), intent(in) :: q(2)
            real(c_double), intent(out) :: v, g(2), h(2, 2)
        end subroutine pot
    end interface
    type(callback_natural) :: sys
    type(transverse_result) :: tr
    type(ode_options) :: oo
    real(c_double) :: y(4), tprev
    integer :: i, j
    character(len=:), allocatable :: msg
    sys%pot => pot
    sys%omega = omega
    phi_t = 0.0_c_double
    mono4 = 0.0_c_double
    call transverse_monodromy(sys, y0, period, tr, rtol)
    info = tr%info
    message = tr%message
    mono2 = tr%monodromy
    half_trace = tr%half_trace
    det = tr%det
    closure = tr%closure
    if (info /= CM_SUCCESS) return
    oo%rtol = rtol
    oo%atol = rtol
    y = y0
    do j = 1, 4
        mono4(j, j) = 1.0_c_double
    end do
    call integrate_stm(sys, 0.0_c_double, period, y, mono4, oo, info, msg)
    if (info < 0) then
        message = msg
        return
    end if
    y = y0
    tprev = 0.0_c_double
    do i = 1, nt
        if (t(i) > tprev) call ode_integrate(sys, tprev, t(i), y, oo, info, message=msg)
        if (info < 0) then
            message = msg
            return
        end if
        tprev = max(tprev, t(i))
        phi_t(i) = transverse_phi(sys, y)
    end do
    info = CM_SUCCESS
end subroutine flat_transverse_callback

!> Newton's method for an equilibrium f(t, y) = 0 from the guess y, for the system given by
!! the one flat argument set (conmech_flat_system).
subroutine flat_find_equilibrium(name, np, params, nspec, spec, fun, jfun, source, n, y, t, &
                                 tol, max_iter, yout, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_ode_system, only: ode_system
    use conmech_flat_system, only: flat_system
    use conmech_equilibria, only: find_equilibrium
    implicit none
    integer(c_int), intent(in) :: n, max_iter
    real(c_double), intent(in) :: y(n), t, tol
    real(c_double), intent(out) :: yout(n)
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
    include "flat_system_args.inc"
    class(ode_system), allocatable :: sys
    character(len=:), allocatable :: msg
    yout = y
    call flat_system(name, params(1:np), nspec, spec, fun, jfun, source, n, sys, info, message)
    if (info /= 0) return
    call find_equilibrium(sys, yout, info, msg, t, tol, max_iter)
    message = msg
end subroutine flat_find_equilibrium
