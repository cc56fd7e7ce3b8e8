!> Periodic orbits by Newton shooting, their monodromy matrices and natural-parameter
!! continuation of families.
!!
!! General shooting (`find_periodic_orbit`) solves for the initial state y0 (and the period
!! T) of y(T; y0) = y0 with the phase condition f(y_g) . (y0 - y_g) = 0 (the orbit starts on
!! the hyperplane through the guess y_g normal to the flow), in one of three modes:
!! - PO_FREE_PERIOD: unknowns (y0, T), n + 1 equations (isolated orbits: limit cycles,
!!   forced oscillations with T given is PO_FIXED_PERIOD);
!! - PO_FIXED_PERIOD: unknowns y0, n + 1 equations;
!! - PO_FIXED_ENERGY: unknowns (y0, T), n + 2 equations (the extra one E(y0) = E given):
!!   the choice for conservative systems, whose orbits come in one-parameter families.
!! Symmetric shooting (`find_symmetric_orbit`) is for an orbit that crosses a symmetry line
!! at right angles: the user fixes the components of y0 that the symmetry line fixes,
!! names the free ones, and the components of y(tau) that must vanish at tau (half or
!! quarter period, `period_factor` 2 or 4), tau optionally free.
!!
!! Both iterate Gauss-Newton steps solved in the least-squares sense by LAPACK dgelsd; the
!! Jacobian comes from the state transition matrix of the variational equations
!! (`integrate_stm`, analytic Jacobians where the system has them). A rank-deficient
!! Newton matrix (rcond 1e-10) is reported as CM_SINGULAR (e.g. a fixed period in an
!! isochronous system, or a free period in a conservative one), a failed iteration as
!! CM_NO_CONVERGENCE. On success the monodromy over the full period is integrated (in
!! `mono_segments` pieces) and its Floquet multipliers computed from the pieces by the
!! periodic eigenvalue method (conmech_periodic_multipliers), the flow direction deflated.
!!
!! With shooting_options%discretisation = ORBIT_MULTIPLE or ORBIT_COLLOCATION both
!! routines solve the same equations by multiple shooting or orthogonal collocation
!! instead (conmech_orbit_newton).
module conmech_shooting
    use conmech_kinds, only: dp
    use conmech_central_step, only: central_step
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, METHOD_DOP853
    use conmech_variational, only: integrate_stm
    use conmech_floquet, only: floquet_result, floquet_from_multipliers
    use conmech_block_chain, only: lstsq_solve
    use conmech_orbit_types
    use conmech_orbit_newton, only: find_orbit_bvp
    use conmech_shooting_newton, only: ode_opts, shooting_flow, shooting_step, shooting_check
    use conmech_periodic_multipliers, only: product_multipliers
    implicit none
    private

    public :: PO_FREE_PERIOD, PO_FIXED_PERIOD, PO_FIXED_ENERGY
    public :: ORBIT_SINGLE, ORBIT_MULTIPLE, ORBIT_COLLOCATION
    public :: shooting_options, periodic_orbit, energy_fun, set_parameter_proc
    public :: find_periodic_orbit, find_symmetric_orbit, orbit_monodromy
    public :: continue_symmetric_family, continue_periodic_family, lstsq_solve
    public :: symmetric_count_message, orbit_method_name, no_parameter

contains

    !> General Newton shooting for a periodic orbit from the guess (y0, period).
    !! `energy` and `energy_value` are required for PO_FIXED_ENERGY (its gradient is
    !! taken by central differences).
    subroutine find_periodic_orbit(sys, y0, period, orbit, mode, options, energy, &
                                   energy_value)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: y0(:)
        real(dp), intent(in) :: period
        type(periodic_orbit), intent(out) :: orbit
        integer, intent(in), optional :: mode
        type(shooting_options), intent(in), optional :: options
        procedure(energy_fun), optional :: energy
        real(dp), intent(in), optional :: energy_value
        type(shooting_options) :: opt
        integer :: md, n, neq, nun, it, j
        real(dp), allocatable :: y(:), yt(:), phi(:, :), f0(:), ft(:), jac(:, :), r(:), dx(:)
        real(dp), allocatable :: yg(:), yp(:)
        real(dp) :: t, h
        logical :: ok, done
        character(len=:), allocatable :: msg
        if (present(options)) opt = options
        md = PO_FREE_PERIOD
        if (present(mode)) md = mode
        n = size(y0)
        orbit%iterations = 0
        if (n < 1 .or. .not. (period > 0.0_dp) .or. md < 1 .or. md > 3 .or. &
            .not. all(abs(y0) <= huge(1.0_dp))) then
            call orbit%fail(CM_BAD_INPUT, "find_periodic_orbit: bad input (empty y0, period "// &
                                          "<= 0 or mode)")
            return
        end if
        if (md == PO_FIXED_ENERGY .and. .not. (present(energy) .and. present(energy_value))) &
            then
            call orbit%fail(CM_BAD_INPUT, "find_periodic_orbit: PO_FIXED_ENERGY needs energy "// &
                                          "and energy_value")
            return
        end if
        if (md /= PO_FIXED_PERIOD) then
            msg = equilibrium_message(sys, y0, period)
            if (len(msg) > 0) then
                call orbit%fail(CM_BAD_INPUT, "find_periodic_orbit: "//msg)
                return
            end if
        end if
        if (opt%discretisation /= ORBIT_SINGLE) then
            call find_orbit_bvp(sys, y0, period, orbit, opt, md, energy, energy_value)
            return
        end if
        neq = n + 1
        nun = n + 1
        if (md == PO_FIXED_PERIOD) nun = n
        if (md == PO_FIXED_ENERGY) neq = n + 2
        allocate (y(n), yt(n), phi(n, n), f0(n), ft(n), jac(neq, nun), r(neq), dx(nun))
        allocate (yg(n), yp(n))
        yg = y0
        call sys%rhs(0.0_dp, yg, f0)
        y = y0
        t = period
        call orbit%fail(CM_NO_CONVERGENCE, "find_periodic_orbit: Newton did not converge")
        do it = 1, opt%max_iter
            orbit%iterations = it
            call shooting_flow(sys, y, t, opt, yt, phi, orbit, "find_periodic_orbit", ok)
            if (.not. ok) return
            call sys%rhs(t, yt, ft)
            r(1:n) = yt - y
            r(n + 1) = dot_product(f0, y - yg)
            jac = 0.0_dp
            jac(1:n, 1:n) = phi
            do j = 1, n
                jac(j, j) = jac(j, j) - 1.0_dp
            end do
            jac(n + 1, 1:n) = f0
            if (md /= PO_FIXED_PERIOD) jac(1:n, n + 1) = ft
            if (md == PO_FIXED_ENERGY) then
                r(n + 2) = energy(y) - energy_value
                do j = 1, n
                    h = central_step(y(j))
                    yp = y
                    yp(j) = y(j) + h
                    jac(n + 2, j) = energy(yp)
                    yp(j) = y(j) - h
                    jac(n + 2, j) = (jac(n + 2, j) - energy(yp))/(2.0_dp*h)
                end do
            end if
            call shooting_step(jac, r, opt, nun, dx, orbit, "find_periodic_orbit", &
                               "singular Newton matrix (the orbit is not isolated: fix the "// &
                               "energy or the period?)", ok)
            if (.not. ok) return
            y = y + dx(1:n)
            if (md /= PO_FIXED_PERIOD) t = t + dx(n + 1)
            call shooting_check(dx, y, t, opt, orbit, "find_periodic_orbit", "the period", done)
            if (done) exit
        end do
        if (orbit%info /= CM_SUCCESS) return
        orbit%y0 = y
        orbit%period = t
        if (opt%monodromy) call orbit_monodromy(sys, orbit, ode_opts(opt), opt%mono_segments)
    end subroutine find_periodic_orbit

    !> Symmetric shooting. y0 holds the fixed components (on the symmetry line); the
    !! components `free` of y0 are unknowns, and so is tau if `free_time`; the components
    !! `targets` of y(tau) must vanish. The period is `period_factor` * tau (default 2:
    !! half-period shooting; 4 for an orbit with two perpendicular symmetry lines).
    subroutine find_symmetric_orbit(sys, y0, free, tau, targets, orbit, options, free_time, &
                                    period_factor)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: y0(:)
        integer, intent(in) :: free(:)
        real(dp), intent(in) :: tau
        integer, intent(in) :: targets(:)
        type(periodic_orbit), intent(out) :: orbit
        type(shooting_options), intent(in), optional :: options
        logical, intent(in), optional :: free_time
        real(dp), intent(in), optional :: period_factor
        type(shooting_options) :: opt
        logical :: ft_free
        real(dp) :: pf, t
        integer :: n, nf, ntg, nun, it, j
        logical :: ok, done
        real(dp), allocatable :: y(:), yt(:), phi(:, :), f(:), jac(:, :), r(:), dx(:)
        character(len=:), allocatable :: msg
        if (present(options)) opt = options
        ft_free = .false.
        if (present(free_time)) ft_free = free_time
        pf = 2.0_dp
        if (present(period_factor)) pf = period_factor
        n = size(y0)
        nf = size(free)
        ntg = size(targets)
        nun = nf
        if (ft_free) nun = nf + 1
        if (n < 1 .or. nun < 1 .or. ntg < 1 .or. .not. (tau > 0.0_dp) .or. &
            any(free < 1) .or. any(free > n) .or. any(targets < 1) .or. any(targets > n) &
            .or. .not. all(abs(y0) <= huge(1.0_dp))) then
            call orbit%fail(CM_BAD_INPUT, "find_symmetric_orbit: bad input (indices, tau > 0, "// &
                                          "finite y0)")
            return
        end if
        msg = symmetric_count_message(nf, ft_free, ntg, opt%discretisation /= ORBIT_SINGLE)
        if (len(msg) > 0) then
            call orbit%fail(CM_BAD_INPUT, "find_symmetric_orbit: "//msg)
            return
        end if
        if (ft_free) then
            msg = equilibrium_message(sys, y0, pf*tau)
            if (len(msg) > 0) then
                call orbit%fail(CM_BAD_INPUT, "find_symmetric_orbit: "//msg)
                return
            end if
        end if
        if (opt%discretisation /= ORBIT_SINGLE) then
            call find_orbit_bvp(sys, y0, pf*tau, orbit, opt, free=free, targets=targets, &
                                free_time=ft_free, period_factor=pf)
            return
        end if
        allocate (y(n), yt(n), phi(n, n), f(n), jac(ntg, nun), r(ntg), dx(nun))
        y = y0
        t = tau
        call orbit%fail(CM_NO_CONVERGENCE, "find_symmetric_orbit: Newton did not converge")
        do it = 1, opt%max_iter
            orbit%iterations = it
            call shooting_flow(sys, y, t, opt, yt, phi, orbit, "find_symmetric_orbit", ok)
            if (.not. ok) return
            r = yt(targets)
            do j = 1, nf
                jac(:, j) = phi(targets, free(j))
            end do
            if (ft_free) then
                call sys%rhs(t, yt, f)
                jac(:, nun) = f(targets)
            end if
            call shooting_step(jac, r, opt, min(nun, ntg), dx, orbit, "find_symmetric_orbit", &
                               "singular Newton matrix", ok)
            if (.not. ok) return
            y(free) = y(free) + dx(1:nf)
            if (ft_free) t = t + dx(nun)
            call shooting_check(dx, y, t, opt, orbit, "find_symmetric_orbit", "the time", done)
            if (done) exit
        end do
        if (orbit%info /= CM_SUCCESS) return
        orbit%y0 = y
        orbit%period = pf*t
        if (opt%monodromy) call orbit_monodromy(sys, orbit, ode_opts(opt), opt%mono_segments)
    end subroutine find_symmetric_orbit

    !> Integrate the monodromy of orbit (y0, period) in `pieces` equal pieces (default 1)
    !! and its Floquet multipliers from them (periodic eigenvalues, the flow direction
    !! deflated; conmech_periodic_multipliers).
    subroutine orbit_monodromy(sys, orbit, ode, pieces)
        class(ode_system), intent(in) :: sys
        type(periodic_orbit), intent(inout) :: orbit
        type(ode_options), intent(in) :: ode
        integer, intent(in), optional :: pieces
        real(dp), allocatable :: y(:), phi(:, :, :), fs(:, :), fe(:, :)
        character(len=:), allocatable :: msg
        real(dp) :: t0, t1
        integer :: n, info, np, l, j
        n = size(orbit%y0)
        np = 1
        if (present(pieces)) np = max(1, pieces)
        allocate (y(n), phi(n, n, np), fs(n, np), fe(n, np))
        y = orbit%y0
        do l = 1, np
            t0 = orbit%period*(l - 1)/np
            t1 = orbit%period*l/np
            phi(:, :, l) = 0.0_dp
            do j = 1, n
                phi(j, j, l) = 1.0_dp
            end do
            call sys%rhs(t0, y, fs(:, l))
            call integrate_stm(sys, t0, t1, y, phi(:, :, l), ode, info, msg)
            if (info < 0) then
                call orbit%fail(info, "monodromy: integration failed: "//msg)
                return
            end if
            call sys%rhs(t1, y, fe(:, l))
        end do
        orbit%monodromy = phi(:, :, 1)
        do l = 2, np
            orbit%monodromy = matmul(phi(:, :, l), orbit%monodromy)
        end do
        call product_multipliers(phi, orbit%multipliers, fs, fe, max(ode%rtol, ode%atol))
        call floquet_from_multipliers(orbit%multipliers, orbit%monodromy, orbit%period, &
                                      orbit%floquet)
        if (orbit%floquet%info /= CM_SUCCESS) then
            call orbit%fail(orbit%floquet%info, "monodromy: the periodic eigenvalue iteration "// &
                                                "failed")
        end if
    end subroutine orbit_monodromy

    !> "" if nfree free components (and the time, if free_time) can meet ntg targets, else
    !! a message naming both counts: fewer unknowns than targets is an overdetermined
    !! system Newton cannot solve in general; more unknowns than targets (a family, e.g.
    !! an isochronous oscillator: single shooting's minimum-norm Gauss-Newton step picks a
    !! member) is refused only with `exact` (multiple shooting and collocation).
    pure function symmetric_count_message(nfree, free_time, ntg, exact) result(msg)
        integer, intent(in) :: nfree, ntg
        logical, intent(in) :: free_time, exact
        character(len=:), allocatable :: msg
        character(len=64) :: a, b
        integer :: nun
        nun = nfree + merge(1, 0, free_time)
        msg = ""
        if (nun == ntg .or. (nun > ntg .and. .not. exact)) return
        write (a, '(i0,a,i0,a)') nun, " unknowns (", nfree, " free components"
        if (free_time) a = trim(a)//" + the time"
        write (b, '(i0,a)') ntg, " targets"
        msg = trim(a)//") for "//trim(b)//": symmetric shooting needs as many "// &
              "unknowns (free components, and the time if free) as targets"
    end function symmetric_count_message

    !> "" unless y0 is an equilibrium of an autonomous flow to the resolution of a
    !! periodic orbit (|f(0, y0)| period <= 1e-10 max(1, |y0|)); then a message saying so.
    function equilibrium_message(sys, y0, period) result(msg)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: y0(:), period
        character(len=:), allocatable :: msg
        real(dp) :: f(size(y0))
        character(len=32) :: buf
        call sys%rhs(0.0_dp, y0, f)
        msg = ""
        if (.not. all(abs(f) <= huge(1.0_dp))) return
        if (norm2(f)*period <= 1.0e-10_dp*max(1.0_dp, maxval(abs(y0)))) then
            write (buf, '(es9.2)') norm2(f)
            msg = "y0 is an equilibrium (|f(y0)| = "//trim(adjustl(buf))// &
                  "): a periodic orbit needs a start on the orbit, e.g. a small "// &
                  "oscillation about the equilibrium"
        end if
    end function equilibrium_message

    !> Natural-parameter continuation of a symmetric family over the parameters ps: the
    !! parameter is set by `set_param`, each orbit starts from the (linear, then quadratic)
    !! extrapolation of the previous ones. (y0, tau) is the guess for ps(1). A failure
    !! restarts the extrapolation from the last success.
    subroutine continue_symmetric_family(sys, set_param, ps, y0, free, tau, targets, orbits, &
                                         options, free_time, period_factor)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        real(dp), intent(in) :: ps(:)
        real(dp), intent(in) :: y0(:)
        integer, intent(in) :: free(:)
        real(dp), intent(in) :: tau
        integer, intent(in) :: targets(:)
        type(periodic_orbit), intent(out) :: orbits(:)
        type(shooting_options), intent(in), optional :: options
        logical, intent(in), optional :: free_time
        real(dp), intent(in), optional :: period_factor
        real(dp) :: hist(size(y0) + 1, 3), pp(3), g(size(y0) + 1), pf
        integer :: i, nh, n
        n = size(y0)
        pf = 2.0_dp
        if (present(period_factor)) pf = period_factor
        nh = 0
        do i = 1, size(ps)
            call set_param(sys, ps(i))
            call next_guess(ps(i), y0, tau, pp, hist, nh, g)
            call find_symmetric_orbit(sys, g(1:n), free, g(n + 1), targets, orbits(i), &
                                      options, free_time, pf)
            if (orbits(i)%info == CM_SUCCESS) then
                call push(ps(i), [orbits(i)%y0, orbits(i)%period/pf], pp, hist, nh)
            end if
        end do
    end subroutine continue_symmetric_family

    !> Natural-parameter continuation with general shooting (see find_periodic_orbit).
    subroutine continue_periodic_family(sys, set_param, ps, y0, period, orbits, mode, options)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        real(dp), intent(in) :: ps(:)
        real(dp), intent(in) :: y0(:)
        real(dp), intent(in) :: period
        type(periodic_orbit), intent(out) :: orbits(:)
        integer, intent(in), optional :: mode
        type(shooting_options), intent(in), optional :: options
        real(dp) :: hist(size(y0) + 1, 3), pp(3), g(size(y0) + 1)
        integer :: i, nh, n
        n = size(y0)
        nh = 0
        do i = 1, size(ps)
            call set_param(sys, ps(i))
            call next_guess(ps(i), y0, period, pp, hist, nh, g)
            call find_periodic_orbit(sys, g(1:n), g(n + 1), orbits(i), mode, options)
            if (orbits(i)%info == CM_SUCCESS) then
                call push(ps(i), [orbits(i)%y0, orbits(i)%period], pp, hist, nh)
            end if
        end do
    end subroutine continue_periodic_family

    !> The guess g = [y, T] at p: the start (y0, t0) until a solution is known, then the
    !! extrapolation of the last (up to three) solutions.
    pure subroutine next_guess(p, y0, t0, pp, hist, nh, g)
        real(dp), intent(in) :: p, y0(:), t0, pp(3), hist(:, :)
        integer, intent(in) :: nh
        real(dp), intent(out) :: g(:)
        if (nh == 0) then
            g(1:size(y0)) = y0
            g(size(y0) + 1) = t0
        else
            call extrapolate(p, pp, hist, nh, g)
        end if
    end subroutine next_guess

    pure subroutine push(p, v, pp, hist, nh)
        real(dp), intent(in) :: p, v(:)
        real(dp), intent(inout) :: pp(3), hist(:, :)
        integer, intent(inout) :: nh
        pp(2:3) = pp(1:2)
        hist(:, 2:3) = hist(:, 1:2)
        pp(1) = p
        hist(:, 1) = v
        nh = min(nh + 1, 3)
    end subroutine push

    pure subroutine extrapolate(p, pp, hist, nh, g)
        real(dp), intent(in) :: p, pp(3), hist(:, :)
        integer, intent(in) :: nh
        real(dp), intent(out) :: g(:)
        integer :: j, k
        real(dp) :: w
        g = 0.0_dp
        do j = 1, nh
            w = 1.0_dp
            do k = 1, nh
                if (k /= j) w = w*(p - pp(k))/(pp(j) - pp(k))
            end do
            g = g + w*hist(:, j)
        end do
    end subroutine extrapolate

end module conmech_shooting
