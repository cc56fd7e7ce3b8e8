!> Flat f2py layer of conmech's control area (src/control): plants with inputs, virtual
!! holonomic constraints and their reduced dynamics, closed-loop simulation, the periodic
!! Riccati equation and the transverse LQR design. Plain subroutines, explicit shapes,
!! info + message; nothing saved between calls.
!!
!! Common arguments. The plant: (name, np, params, nspec, spec) of a generalized system,
!! nd coordinates, m inputs, bmat (nd, m) the input matrix, baddr (0 or the address of a
!! compiled B(t, q)) with its nbp parameters bpar. A law: nil, ilaw (int64), nrl, rlaw
!! (see conmech_support_control) and the Python callback pylaw(t, x, u, n, m) (called
!! only by a law of kind 1).

!> F(t, x, u) and dF/du of the plant.
subroutine flat_control_plant_eval(name, np, params, nspec, spec, nd, m, bmat, baddr, nbp, &
                                   bpar, t, x, u, dxdt, bx, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS
    use conmech_mech_plant, only: mech_plant
    use conmech_support_control, only: build_plant
    implicit none
    include "flat_plant_args.inc"
    real(c_double), intent(in) :: t, x(2*nd), u(m)
    real(c_double), intent(out) :: dxdt(2*nd), bx(2*nd, m)
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
    type(mech_plant) :: plant
    dxdt = 0.0_c_double
    bx = 0.0_c_double
    call build_plant(name, real(params(1:np), dp), nspec, spec, nd, m, bmat, baddr, &
                     bpar(1:nbp), plant, info, message)
    if (info /= CM_SUCCESS) return
    call plant%rhs_u(t, x, u, dxdt)
    call plant%input_matrix(t, x, u, bx)
end subroutine flat_control_plant_eval

!> alpha, beta, gamma of the reduced dynamics and Phibar, Phibar', Phibar'' at thetas, for
!! the virtual constraint described by a kind-3 law (ilaw, rlaw).
subroutine flat_control_vhc(name, np, params, nspec, spec, nd, m, bmat, baddr, nbp, bpar, &
                            nil, ilaw, nrl, rlaw, nth, thetas, alpha, beta, gamma, phis, &
                            dphis, ddphis, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_mech_plant, only: mech_plant
    use conmech_vhc, only: vhc, vhc_eval, vhc_coefficients
    use conmech_support_control, only: build_plant, build_vhc
    implicit none
    include "flat_plant_args.inc"
    include "flat_law_args.inc"
    integer(c_int), intent(in) :: nth
    real(c_double), intent(in) :: thetas(nth)
    real(c_double), intent(out) :: alpha(nth), beta(nth), gamma(nth)
    real(c_double), intent(out) :: phis(nd, nth), dphis(nd, nth), ddphis(nd, nth)
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
    type(mech_plant) :: plant
    type(vhc) :: con
    integer :: i, used, i2
    alpha = 0.0_c_double
    beta = 0.0_c_double
    gamma = 0.0_c_double
    phis = 0.0_c_double
    dphis = 0.0_c_double
    ddphis = 0.0_c_double
    call build_plant(name, real(params(1:np), dp), nspec, spec, nd, m, bmat, baddr, &
                     bpar(1:nbp), plant, info, message)
    if (info /= CM_SUCCESS) return
    call build_vhc(ilaw, rlaw(1:nrl), nd, con, used)
    do i = 1, nth
        call vhc_eval(con, thetas(i), phis(:, i), dphis(:, i), ddphis(:, i))
        call vhc_coefficients(plant, con, thetas(i), alpha(i), beta(i), gamma(i), i2)
        if (i2 /= CM_SUCCESS) then
            info = CM_BAD_INPUT
            message = "vhc: the generalized forces are not quadratic in the velocities "// &
                      "(damping or gyroscopic terms): the reduced dynamics alpha theta'' + "// &
                      "beta theta'^2 + gamma = 0 does not apply"
            return
        end if
    end do
    info = CM_SUCCESS
end subroutine flat_control_vhc

!> The reduced dynamics from y0 = [theta, theta'] over [t0, t1]: the states at t_eval and
!! (with_events /= 0) the crossings of theta' = 0 (up to maxev).
subroutine flat_control_reduced(name, np, params, nspec, spec, nd, m, bmat, baddr, nbp, &
                                bpar, nil, ilaw, nrl, rlaw, y0, t0, t1, neval, t_eval, &
                                with_events, maxev, rtol, atol, ys, nev, ev_t, ev_y, info, &
                                message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS
    use conmech_ode_system, only: ode_events
    use conmech_ode_solver, only: ode_options, ode_result, ode_solve, METHOD_DOP853
    use conmech_vhc, only: vhc_reduced
    use conmech_support_control, only: build_plant, build_vhc
    use conmech_flat_adapters, only: velocity_zero
    implicit none
    include "flat_plant_args.inc"
    include "flat_law_args.inc"
    integer(c_int), intent(in) :: neval, with_events, maxev
    real(c_double), intent(in) :: y0(2), t0, t1, t_eval(max(neval, 1))
    real(c_double), intent(in) :: rtol, atol
    real(c_double), intent(out) :: ys(2, max(neval, 1)), ev_t(max(maxev, 1))
    real(c_double), intent(out) :: ev_y(2, max(maxev, 1))
    integer(c_int), intent(out) :: nev, info
    character(len=256), intent(out) :: message
    type(vhc_reduced) :: red
    type(ode_options) :: oo
    type(ode_result) :: res
    type(velocity_zero) :: ev
    integer :: used
    ys = 0.0_c_double
    ev_t = 0.0_c_double
    ev_y = 0.0_c_double
    nev = 0
    call build_plant(name, real(params(1:np), dp), nspec, spec, nd, m, bmat, baddr, &
                     bpar(1:nbp), red%plant, info, message)
    if (info /= CM_SUCCESS) return
    call build_vhc(ilaw, rlaw(1:nrl), nd, red%con, used)
    oo%method = METHOD_DOP853
    oo%rtol = rtol
    oo%atol = atol
    oo%max_steps = 1000000
    ev%direction = [0]
    ev%terminal = [.false.]
    if (with_events /= 0) then
        if (neval > 0) then
            call ode_solve(red, [t0, t1], y0, oo, res, t_eval=t_eval(1:neval), events=ev)
        else
            call ode_solve(red, [t0, t1], y0, oo, res, events=ev)
        end if
    else
        if (neval > 0) then
            call ode_solve(red, [t0, t1], y0, oo, res, t_eval=t_eval(1:neval))
        else
            call ode_solve(red, [t0, t1], y0, oo, res)
        end if
    end if
    info = res%status
    message = "success"
    if (allocated(res%message)) message = res%message
    if (info < 0) return
    if (neval > 0) ys(:, 1:min(neval, res%nt)) = res%y(:, 1:min(neval, res%nt))
    nev = min(res%nev, maxev)
    if (nev > 0) then
        ev_t(1:nev) = res%ev_t(1:nev)
        ev_y(:, 1:nev) = res%ev_y(:, 1:nev)
    end if
end subroutine flat_control_reduced

!> E(theta) = theta'^2 along the reduced dynamics from E(theta0) = e0: dE/dtheta =
!! -2 (beta E + gamma)/alpha, at the monotone thetas; with stop_at_zero /= 0 the first zero
!! of E (a turning point) is located (found = 1, theta_zero) and E beyond it is NaN.
subroutine flat_control_energy(name, np, params, nspec, spec, nd, m, bmat, baddr, nbp, bpar, &
                               nil, ilaw, nrl, rlaw, theta0, e0, nth, thetas, stop_at_zero, &
                               rtol, atol, es, theta_zero, found, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp, nan_dp
    use conmech_status, only: CM_SUCCESS, CM_EVENT_STOP, CM_BAD_INPUT
    use conmech_ode_solver, only: ode_options, ode_result, ode_solve, METHOD_DOP853
    use conmech_vhc, only: vhc_energy
    use conmech_support_control, only: build_plant, build_vhc
    use conmech_flat_adapters, only: energy_zero
    implicit none
    include "flat_plant_args.inc"
    include "flat_law_args.inc"
    integer(c_int), intent(in) :: nth, stop_at_zero
    real(c_double), intent(in) :: theta0, e0, thetas(nth), rtol, atol
    real(c_double), intent(out) :: es(nth), theta_zero
    integer(c_int), intent(out) :: found, info
    character(len=256), intent(out) :: message
    type(vhc_energy) :: en
    type(ode_options) :: oo
    type(ode_result) :: res
    type(energy_zero) :: ev
    real(c_double) :: tend
    integer :: used, i
    es = nan_dp
    theta_zero = 0.0_c_double
    found = 0
    call build_plant(name, real(params(1:np), dp), nspec, spec, nd, m, bmat, baddr, &
                     bpar(1:nbp), en%plant, info, message)
    if (info /= CM_SUCCESS) return
    call build_vhc(ilaw, rlaw(1:nrl), nd, en%con, used)
    tend = thetas(nth)
    if (tend == theta0) then
        info = CM_BAD_INPUT
        message = "vhc energy: the last theta must differ from theta0"
        return
    end if
    oo%method = METHOD_DOP853
    oo%rtol = rtol
    oo%atol = atol
    oo%max_steps = 1000000
    ev%direction = [-1]
    ev%terminal = [.true.]
    if (stop_at_zero /= 0) then
        call ode_solve(en, [theta0, tend], [e0], oo, res, t_eval=thetas, events=ev)
    else
        call ode_solve(en, [theta0, tend], [e0], oo, res, t_eval=thetas)
    end if
    info = res%status
    message = "success"
    if (allocated(res%message)) message = res%message
    if (info < 0) return
    do i = 1, min(nth, res%nt)
        es(i) = res%y(1, i)
    end do
    if (info == CM_EVENT_STOP .and. res%nev > 0) then
        found = 1
        theta_zero = res%ev_t(1)
    end if
    info = CM_SUCCESS
end subroutine flat_control_energy

!> u = law(t, x) at nx states xs (n, nx).
subroutine flat_control_law_eval(name, np, params, nspec, spec, nd, m, bmat, baddr, nbp, &
                                 bpar, nil, ilaw, nrl, rlaw, pylaw, n, nx, ts, xs, us, info, &
                                 message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS
    use conmech_mech_plant, only: mech_plant
    use conmech_control_system, only: feedback_law
    use conmech_support_control, only: build_plant_law
    implicit none
    include "flat_plant_args.inc"
    include "flat_law_args.inc"
    integer(c_int), intent(in) :: n, nx
    real(c_double), intent(in) :: ts(nx), xs(n, nx)
    real(c_double), intent(out) :: us(m, nx)
    integer(c_int), intent(out) :: info
    character(len=256), intent(out) :: message
    include "flat_control_law.inc"
    type(mech_plant) :: plant
    class(feedback_law), allocatable :: law
    integer :: i
    us = 0.0_c_double
    call build_plant_law(name, real(params(1:np), dp), nspec, spec, nd, m, bmat, baddr, &
                         bpar(1:nbp), ilaw, rlaw(1:nrl), nrl, pylaw, n, plant, law, info, message)
    if (info /= CM_SUCCESS) return
    do i = 1, nx
        call law%eval(ts(i), xs(:, i), us(:, i))
    end do
end subroutine flat_control_law_eval

!> Integrate the closed loop x' = F(t, x, law(t, x)) (see conmech_flat_ode_support's
!! run_solve for the integration arguments, events and store).
subroutine flat_control_solve(name, np, params, nspec, spec, nd, m, bmat, baddr, nbp, bpar, &
                              nil, ilaw, nrl, rlaw, pylaw, events, store, n, t_span, y0, &
                              method, rtol, atol, first_step, max_step, max_steps, dense, &
                              neval, t_eval, ne, ev_dir, ev_term, nfev, naccept, nreject, &
                              dense_form, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS
    use conmech_control_system, only: closed_loop
    use conmech_mech_plant, only: mech_plant
    use conmech_flat_ode_support, only: run_solve
    use conmech_support_control, only: build_plant_law
    implicit none
    include "flat_plant_args.inc"
    include "flat_law_args.inc"
    integer(c_int), intent(in) :: n
    real(c_double), intent(in) :: t_span(2), y0(n), rtol(n), atol(n), first_step, max_step
    integer(c_int), intent(in) :: method, max_steps, dense, neval, ne
    real(c_double), intent(in) :: t_eval(max(neval, 1))
    integer(c_int), intent(in) :: ev_dir(max(ne, 1)), ev_term(max(ne, 1))
    integer(c_int), intent(out) :: nfev, naccept, nreject, dense_form, info
    character(len=256), intent(out) :: message
    include "flat_control_law.inc"
    include "flat_solve_callbacks.inc"
    type(closed_loop) :: cl
    type(mech_plant) :: plant
    integer(c_int) :: counts(5)
    ! no event resolution (SciPy's rule), no Jacobian structure (nnz = -1)
    real(c_double) :: ev_res(max(ne, 1))
    integer(c_int) :: sp_ptr(n + 1), sp_idx(1)
    nfev = 0
    naccept = 0
    nreject = 0
    dense_form = 0
    ev_res = 0.0_c_double
    sp_ptr = 1
    sp_idx = 0
    call build_plant_law(name, real(params(1:np), dp), nspec, spec, nd, m, bmat, baddr, &
                         bpar(1:nbp), ilaw, rlaw(1:nrl), nrl, pylaw, n, plant, cl%law, info, message)
    if (info /= CM_SUCCESS) return
    allocate (cl%plant, source=plant)
    cl%n_inputs = m
    call run_solve(cl, n, t_span, y0, method, rtol, atol, first_step, max_step, max_steps, &
                   dense, neval, t_eval, ne, ev_dir, ev_term, ev_res, 0, -1, sp_ptr, sp_idx, &
                   events, store, counts, dense_form, info, message)
    nfev = counts(1)        ! counts: nfev, njev, nlu, naccept, nreject
    naccept = counts(4)
    nreject = counts(5)
end subroutine flat_control_solve

!> The phase tau, the transverse coordinates xi (k, nx) and the orbital distance of nx
!! states under a transverse LQR law (kind 4).
subroutine flat_control_project(name, np, params, nspec, spec, nd, m, bmat, baddr, nbp, &
                                bpar, nil, ilaw, nrl, rlaw, pylaw, n, k, nx, xs, taus, xis, &
                                dists, nfail, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS
    use conmech_mech_plant, only: mech_plant
    use conmech_control_system, only: feedback_law
    use conmech_support_control, only: build_plant_law, project_states
    implicit none
    include "flat_plant_args.inc"
    include "flat_law_args.inc"
    integer(c_int), intent(in) :: n, k, nx
    real(c_double), intent(in) :: xs(n, nx)
    real(c_double), intent(out) :: taus(nx), xis(k, nx), dists(nx)
    integer(c_int), intent(out) :: nfail, info
    character(len=256), intent(out) :: message
    include "flat_control_law.inc"
    type(mech_plant) :: plant
    class(feedback_law), allocatable :: law
    taus = 0.0_c_double
    xis = 0.0_c_double
    dists = 0.0_c_double
    nfail = 0
    call build_plant_law(name, real(params(1:np), dp), nspec, spec, nd, m, bmat, baddr, &
                         bpar(1:nbp), ilaw, rlaw(1:nrl), nrl, pylaw, n, plant, law, info, message)
    if (info /= CM_SUCCESS) return
    call project_states(law, xs, taus, xis, dists, nfail, info, message)
end subroutine flat_control_project

!> Transverse LQR design around the periodic orbit (y0, period) of the closed loop under a
!! nominal law (see conmech_orbital_stabilisation). Outputs at the nt times t: A_perp,
!! B_perp, P and the gain K (u = u_nom + K xi); the open-loop transverse multipliers
!! (omr, omi), the Gramian's eigenvalues, the Hamiltonian's and the closed loop's
!! multipliers, P's periodicity and smallest eigenvalue, the law's table rtab (the rlaw
!! head of a kind-4 law), and the multipliers of the nonlinear closed loop's N x N
!! monodromy (fmr, fmi; one of them is the trivial 1).
subroutine flat_control_design(name, np, params, nspec, spec, nd, m, bmat, baddr, nbp, bpar, &
                               nil, ilaw, nrl, rlaw, pylaw, n, y0, period, k, qw, rw, ng, &
                               rtol, atol, nt, t, ntab, as, bs, ps, ks, omr, omi, gev, hmr, &
                               hmi, cmr, cmi, periodicity, min_eig, passes, rtab, fmr, fmi, &
                               closure, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_lapack, only: la_eig
    use conmech_mech_plant, only: mech_plant
    use conmech_control_system, only: feedback_law, closed_loop
    use conmech_transverse_general, only: transverse_options, transverse_eval
    use conmech_periodic_riccati, only: riccati_options
    use conmech_orbital_stabilisation, only: orbital_design_result, orbital_design
    use conmech_ode_solver, only: ode_options
    use conmech_variational, only: integrate_stm
    use conmech_rank, only: identity
    use conmech_support_control, only: build_plant_law, pack_riccati
    implicit none
    include "flat_plant_args.inc"
    include "flat_law_args.inc"
    integer(c_int), intent(in) :: n, k, ng, nt, ntab
    real(c_double), intent(in) :: y0(n), period, qw(k, k), rw(m, m)
    real(c_double), intent(in) :: rtol, atol, t(nt)
    real(c_double), intent(out) :: as(k, k, nt), bs(k, m, nt), ps(k, k, nt), ks(m, k, nt)
    real(c_double), intent(out) :: omr(k), omi(k), gev(k), hmr(2*k), hmi(2*k), cmr(k), cmi(k)
    real(c_double), intent(out) :: periodicity, min_eig, rtab(ntab), fmr(n), fmi(n), closure
    integer(c_int), intent(out) :: passes, info
    character(len=256), intent(out) :: message
    include "flat_control_law.inc"
    type(mech_plant) :: plant
    class(feedback_law), allocatable :: nominal
    type(transverse_options) :: topt
    type(riccati_options) :: ropt
    type(orbital_design_result) :: des
    type(closed_loop) :: cl
    type(ode_options) :: oo
    character(len=:), allocatable :: msg
    real(dp) :: x(n), qp(n, k), y(n), mono(n, n)
    integer :: i, o, i2
    as = 0.0_c_double
    bs = 0.0_c_double
    ps = 0.0_c_double
    ks = 0.0_c_double
    omr = 0.0_c_double
    omi = 0.0_c_double
    gev = 0.0_c_double
    hmr = 0.0_c_double
    hmi = 0.0_c_double
    cmr = 0.0_c_double
    cmi = 0.0_c_double
    fmr = 0.0_c_double
    fmi = 0.0_c_double
    rtab = 0.0_c_double
    periodicity = 0.0_c_double
    min_eig = 0.0_c_double
    closure = 0.0_c_double
    passes = 0
    call build_plant_law(name, real(params(1:np), dp), nspec, spec, nd, m, bmat, baddr, &
                         bpar(1:nbp), ilaw, rlaw(1:nrl), nrl, pylaw, n, plant, nominal, info, message)
    if (info /= CM_SUCCESS) return
    if (n /= 2*nd .or. k /= n - 1 .or. ntab /= 1 + 3*n*(ng + 1) + 2*n*k*(ng + 1) + &
        2*m*k*(ng + 1)) then
        info = CM_BAD_INPUT
        message = "design: inconsistent sizes"
        return
    end if
    topt%rtol = rtol
    topt%atol = atol
    ropt%rtol = rtol
    ropt%atol = atol
    call orbital_design(plant, nominal, .true., y0, period, qw, rw, ng, topt, ropt, des)
    info = des%info
    message = des%message
    if (allocated(des%gramian_eig)) gev = des%gramian_eig
    if (des%lq%fr%info == CM_SUCCESS) then
        omr = des%lq%fr%mr
        omi = des%lq%fr%mi
        closure = des%lq%fr%closure
    end if
    call pack_riccati(des%ric, des%lq, t, ps, ks, hmr, hmi, cmr, cmi, periodicity, min_eig, &
                      passes)
    if (info /= CM_SUCCESS) return
    do i = 1, nt
        call transverse_eval(des%lq%fr, t(i), x, qp, as(:, :, i), bs(:, :, i), i2)
    end do
    o = 1
    rtab(1) = period
    rtab(o + 1:o + n*(ng + 1)) = reshape(des%law%xs, [n*(ng + 1)])
    o = o + n*(ng + 1)
    rtab(o + 1:o + n*(ng + 1)) = reshape(des%law%fs, [n*(ng + 1)])
    o = o + n*(ng + 1)
    rtab(o + 1:o + n*(ng + 1)) = reshape(des%law%as, [n*(ng + 1)])
    o = o + n*(ng + 1)
    rtab(o + 1:o + n*k*(ng + 1)) = reshape(des%law%qs, [n*k*(ng + 1)])
    o = o + n*k*(ng + 1)
    rtab(o + 1:o + n*k*(ng + 1)) = reshape(des%law%qd, [n*k*(ng + 1)])
    o = o + n*k*(ng + 1)
    rtab(o + 1:o + m*k*(ng + 1)) = reshape(des%law%ks, [m*k*(ng + 1)])
    o = o + m*k*(ng + 1)
    rtab(o + 1:o + m*k*(ng + 1)) = reshape(des%law%km, [m*k*(ng + 1)])
    ! the nonlinear closed loop under the designed law: its monodromy
    allocate (cl%plant, source=plant)
    allocate (cl%law, source=des%law)
    cl%n_inputs = m
    oo%rtol = rtol
    oo%atol = atol
    oo%max_steps = 1000000
    y = y0
    mono = identity(n)
    call integrate_stm(cl, 0.0_dp, period, y, mono, oo, i2, msg)
    if (i2 < 0) then
        info = i2
        message = "design: the nonlinear closed loop's monodromy failed: "//msg
        return
    end if
    call la_eig(mono, fmr, fmi, i2)
end subroutine flat_control_design

!> The stabilising periodic solution of the Riccati equation of x' = A(t) x + B(t) u given
!! by Python callables afun(t) -> (k, k), bfun(t) -> (k, m) of period `period`: P and K at
!! the nt times t, the multipliers of the Hamiltonian and of the closed loop.
subroutine flat_control_riccati(afun, bfun, k, m, period, qw, rw, rtol, atol, nt, t, ps, ks, &
                                hmr, hmi, cmr, cmi, cl_mono, periodicity, min_eig, passes, &
                                info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_status, only: CM_SUCCESS
    use conmech_periodic_riccati, only: riccati_options, riccati_result, periodic_riccati
    use conmech_flat_adapters, only: callback_lq
    use conmech_support_control, only: pack_riccati
    implicit none
    integer(c_int), intent(in) :: k, m, nt
    real(c_double), intent(in) :: period, qw(k, k), rw(m, m), rtol, atol, t(nt)
    real(c_double), intent(out) :: ps(k, k, nt), ks(m, k, nt), hmr(2*k), hmi(2*k)
    real(c_double), intent(out) :: cmr(k), cmi(k), cl_mono(k, k), periodicity, min_eig
    integer(c_int), intent(out) :: passes, info
    character(len=256), intent(out) :: message
!f2py external afun, bfun
    interface
        subroutine afun(t, a, k)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: k
            real(c_double), intent(in) :: t
            real(c_double), intent(out) :: a(k, k)
        end subroutine afun
        subroutine bfun(t, b, k, m)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: k, m
            real(c_double), intent(in) :: t
            real(c_double), intent(out) :: b(k, m)
        end subroutine bfun
    end interface
    type(callback_lq) :: lq
    type(riccati_options) :: ropt
    type(riccati_result) :: res
    ps = 0.0_c_double
    ks = 0.0_c_double
    hmr = 0.0_c_double
    hmi = 0.0_c_double
    cmr = 0.0_c_double
    cmi = 0.0_c_double
    cl_mono = 0.0_c_double
    periodicity = 0.0_c_double
    min_eig = 0.0_c_double
    passes = 0
    lq%fa => afun
    lq%fb => bfun
    lq%k = k
    lq%m = m
    lq%period = period
    ropt%rtol = rtol
    ropt%atol = atol
    call periodic_riccati(lq, qw, rw, ropt, res)
    info = res%info
    message = res%message
    call pack_riccati(res, lq, t, ps, ks, hmr, hmi, cmr, cmi, periodicity, min_eig, passes)
    if (info == CM_SUCCESS) cl_mono = res%cl_monodromy
end subroutine flat_control_riccati
