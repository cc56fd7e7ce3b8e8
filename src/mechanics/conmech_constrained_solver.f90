!> Integrators for constrained mechanical systems: the index-1 form (accelerations from the
!! KKT system) advanced by RK4 / DOPRI5 / DOP853 / Verner 9(8), with
!! - no stabilisation (PROJ_NONE: the constraints drift, |phi| ~ h^p (A t + B t^2)),
!! - velocity projection after each accepted step (PROJ_VELOCITY),
!! - mass-weighted position projection (simplified Newton) then velocity projection
!!   (PROJ_POSITION_VELOCITY, Hairer-Lubich-Wanner; the default),
!! - Baumgarte stabilisation (PROJ_BAUMGARTE): C a = gamma - 2 alpha (C v + c0) - beta^2 phi.
!!
!! The solver drives its own steps with the tableaus of `conmech_rk_tableaus` and Hairer's
!! step-size control (error norm, safety 0.9, step-ratio bounds, no growth after a
!! rejection, as in `conmech_ode_solver`), because the projection must act between
!! accepted steps. After a projection the first stage is re-evaluated (FSAL is lost):
!! one extra right-hand side per projected step. Outputs are the accepted steps, or the
!! points of `t_eval`, which the steps hit exactly (no interpolation: every output point is
!! a projected point). The initial state is made consistent first (position then velocity
!! projection; the distances moved are reported).
module conmech_constrained_solver
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_quiet_nan
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system, ode_step_hook
    use conmech_ode_solver, only: ode_options, METHOD_RK4, METHOD_DOPRI5, METHOD_DOP853, &
                                  METHOD_VERNER98
    use conmech_rk_tableaus, only: rk_tableau, dopri5_tableau, dop853_tableau, verner98_tableau
    use conmech_constrained_system
    implicit none
    private

    integer, parameter, public :: PROJ_NONE = 0               !! plain index-1 form
    integer, parameter, public :: PROJ_VELOCITY = 1           !! velocity projection only
    integer, parameter, public :: PROJ_POSITION_VELOCITY = 2  !! position, then velocity
    integer, parameter, public :: PROJ_BAUMGARTE = 3          !! Baumgarte stabilisation

    public :: constrained_ode, constrained_options, constrained_result, projection_hook
    public :: constrained_solve, consistent_initial, projection_from_name

    !> First-order form y = [q, v] of a constrained system (index-1 / Baumgarte).
    !! NaN accelerations when the KKT solve fails (singular mass matrix).
    type, extends(ode_system) :: constrained_ode
        class(constrained_system), allocatable :: mech
        logical :: baumgarte = .false.
        real(dp) :: alpha = 0.0_dp
        real(dp) :: beta = 0.0_dp
    contains
        procedure :: rhs => cons_rhs
    end type constrained_ode

    !> The projection as a step hook of the core integrators: `ode_solve(f, ..., hook=h)`
    !! with f a `constrained_ode` and h a `projection_hook` holding the same system gives
    !! projected integration with everything `ode_solve` offers (events, dense output,
    !! t_eval by interpolation). Differences to `constrained_solve`: one more right-hand
    !! side per projected step (the core evaluates the FSAL stage before the hook), and
    !! t_eval/dense/event points are interpolated between projected steps, so they are on
    !! the manifold only to the local error. Counters: nproj, proj_iter, proj_iter_max.
    type, extends(ode_step_hook) :: projection_hook
        class(constrained_system), allocatable :: mech
        integer :: projection = PROJ_POSITION_VELOCITY   !! or PROJ_VELOCITY
        integer :: every = 1
        real(dp) :: proj_tol = 1.0e-14_dp
        integer :: proj_max_iter = 10
        integer :: nproj = 0, proj_iter = 0, proj_iter_max = 0
        integer :: since = 0
    contains
        procedure :: after_step => hook_project
    end type projection_hook

    !> Options of `constrained_solve`.
    type :: constrained_options
        type(ode_options) :: ode                   !! method, rtol, atol, first_step, ...
        integer :: projection = PROJ_POSITION_VELOCITY
        integer :: every = 1                       !! project every k accepted steps
        real(dp) :: alpha = 5.0_dp                 !! Baumgarte damping
        real(dp) :: beta = 5.0_dp                  !! Baumgarte stiffness
        real(dp) :: proj_tol = 1.0e-14_dp          !! target max|phi| of the projection
        integer :: proj_max_iter = 10              !! simplified Newton iterations
        logical :: project_initial = .true.        !! make (q0, v0) consistent first
        logical :: save_steps = .true.             !! without t_eval: keep every step
    end type constrained_options

    !> Result of `constrained_solve`: columns are output times.
    type :: constrained_result
        integer :: status = CM_BAD_INPUT
        character(len=:), allocatable :: message
        logical :: success = .false.
        integer :: nt = 0
        real(dp), allocatable :: t(:)              !! (nt)
        real(dp), allocatable :: q(:, :), v(:, :)  !! (n, nt)
        real(dp), allocatable :: lam(:, :)         !! (n_hol + n_nh, nt) multipliers
        real(dp), allocatable :: reaction(:, :)    !! (n, nt) reaction forces C^T lambda
        real(dp), allocatable :: res_pos(:)        !! (nt) max |phi|
        real(dp), allocatable :: res_vel(:)        !! (nt) max |C v + c0|
        real(dp), allocatable :: energy(:)         !! (nt) if the system defines it, else 0
        real(dp), allocatable :: power(:)          !! (nt) reaction . v
        integer :: rank = 0                        !! rank of the constraints (at t0)
        integer :: nfev = 0, naccept = 0, nreject = 0
        integer :: nproj = 0                       !! projections performed
        integer :: proj_iter = 0                   !! total position-projection iterations
        integer :: proj_iter_max = 0               !! largest iteration count of one
        real(dp) :: dq0 = 0.0_dp                   !! |q0 moved| by the initial projection
        real(dp) :: dv0 = 0.0_dp                   !! |v0 moved| by the initial projection
    end type constrained_result

contains

    !> Projection code from a name: "none", "velocity", "position+velocity", "baumgarte";
    !! -1 if unknown.
    pure function projection_from_name(name) result(p)
        character(len=*), intent(in) :: name
        integer :: p
        select case (trim(adjustl(name)))
        case ("none", "index1")
            p = PROJ_NONE
        case ("velocity")
            p = PROJ_VELOCITY
        case ("position+velocity", "position", "projection")
            p = PROJ_POSITION_VELOCITY
        case ("baumgarte")
            p = PROJ_BAUMGARTE
        case default
            p = -1
        end select
    end function projection_from_name

    subroutine cons_rhs(self, t, y, dydt)
        class(constrained_ode), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: lam(self%mech%n_hol + self%mech%n_nh)
        integer :: n, info
        n = self%mech%n
        dydt(1:n) = y(n + 1:2*n)
        if (self%baumgarte) then
            call constrained_accel(self%mech, t, y(1:n), y(n + 1:2*n), dydt(n + 1:2*n), lam, &
                                   info, alpha=self%alpha, beta=self%beta)
        else
            call constrained_accel(self%mech, t, y(1:n), y(n + 1:2*n), dydt(n + 1:2*n), lam, &
                                   info)
        end if
        if (info /= CM_SUCCESS) dydt(n + 1:2*n) = ieee_value(1.0_dp, ieee_quiet_nan)
    end subroutine cons_rhs

    !> Project y = [q, v] after an accepted step of the core integrator.
    subroutine hook_project(self, t, y, changed, info)
        class(projection_hook), intent(inout) :: self
        real(dp), intent(in) :: t
        real(dp), intent(inout) :: y(:)
        logical, intent(out) :: changed
        integer, intent(out) :: info
        real(dp) :: q(self%mech%n), v(self%mech%n)
        integer :: n, it
        character(len=:), allocatable :: msg
        character(len=32) :: buf
        changed = .false.
        info = CM_SUCCESS
        self%since = self%since + 1
        if (self%since < self%every) return
        if (self%projection /= PROJ_VELOCITY .and. &
            self%projection /= PROJ_POSITION_VELOCITY) return
        self%since = 0
        n = self%mech%n
        q = y(1:n)
        v = y(n + 1:2*n)
        if (self%projection == PROJ_POSITION_VELOCITY) then
            call project_position(self%mech, t, q, self%proj_tol, self%proj_max_iter, it, &
                                  info, msg)
            self%proj_iter = self%proj_iter + it
            self%proj_iter_max = max(self%proj_iter_max, it)
        end if
        if (info == CM_SUCCESS) call project_velocity(self%mech, t, q, v, info, msg)
        if (info /= CM_SUCCESS) then
            write (buf, '(es14.6)') t
            self%message = msg//" at t ="//trim(buf)
            return
        end if
        self%nproj = self%nproj + 1
        y(1:n) = q
        y(n + 1:2*n) = v
        changed = .true.
    end subroutine hook_project

    !> Make (q, v) consistent at t: position projection (if holonomic constraints) then
    !! velocity projection. dq, dv: Euclidean distances moved.
    subroutine consistent_initial(sys, t, q, v, tol, max_iter, dq, dv, iters, info, msg)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(inout) :: q(:), v(:)
        real(dp), intent(in) :: tol
        integer, intent(in) :: max_iter
        real(dp), intent(out) :: dq, dv
        integer, intent(out) :: iters, info
        character(len=:), allocatable, intent(out) :: msg
        real(dp) :: q_in(size(q)), v_in(size(v))
        q_in = q
        v_in = v
        dq = 0.0_dp
        dv = 0.0_dp
        call project_position(sys, t, q, tol, max_iter, iters, info, msg, &
                              newton=.true.)
        if (info /= CM_SUCCESS) then
            msg = "inconsistent initial position: "//msg
            return
        end if
        call project_velocity(sys, t, q, v, info, msg)
        if (info /= CM_SUCCESS) then
            msg = "inconsistent initial velocity: "//msg
            return
        end if
        dq = norm2(q - q_in)
        dv = norm2(v - v_in)
    end subroutine consistent_initial

    !> Integrate the constrained system from (q0, v0) over t_span (forward or backward).
    subroutine constrained_solve(sys, t_span, q0, v0, options, res, t_eval)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: q0(:), v0(:)
        type(constrained_options), intent(in) :: options
        type(constrained_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)

        type(constrained_ode) :: f
        type(rk_tableau) :: tab
        real(dp), allocatable :: y(:), ynew(:), k(:, :), ytmp(:), sk(:), rtolv(:), atolv(:)
        real(dp), allocatable :: q(:), v(:), acc(:), lam(:)
        real(dp) :: t, tf, h, hnew, hmax, posneg, err, facold, safe, facc1, facc2, expo1
        real(dp) :: fac, target, beta
        integer :: n, m, nsteps, i_eval, n_eval, info, iters, cap, nf_new, since_proj
        logical :: adaptive, reject, hit
        character(len=:), allocatable :: msg
        character(len=32) :: buf

        n = sys%n
        m = sys%n_hol + sys%n_nh
        tf = t_span(2)
        n_eval = 0
        if (present(t_eval)) n_eval = size(t_eval)
        res%message = "bad input"
        ! ------------------------------------------------------------ validation
        if (n < 1 .or. sys%n_hol < 0 .or. sys%n_nh < 0) then
            res%message = "bad input: the system needs n >= 1 coordinates, n_hol, n_nh >= 0"
            return
        end if
        if (size(q0) /= n .or. size(v0) /= n) then
            write (buf, '(i0)') n
            res%message = "bad input: q0 and v0 must have n = "//trim(buf)//" elements"
            return
        end if
        if (.not. (all(ieee_is_finite(q0)) .and. all(ieee_is_finite(v0)))) then
            res%message = "bad input: q0 or v0 contains NaN or Inf"
            return
        end if
        if (.not. all(ieee_is_finite(t_span))) then
            res%message = "bad input: t_span must be finite"
            return
        end if
        if (options%projection < PROJ_NONE .or. options%projection > PROJ_BAUMGARTE) then
            res%message = "bad input: unknown projection"
            return
        end if
        if (options%ode%method < METHOD_RK4 .or. options%ode%method > METHOD_VERNER98) then
            res%message = "bad input: unknown method"
            return
        end if
        if (options%ode%method == METHOD_RK4 .and. .not. options%ode%first_step > 0.0_dp) then
            res%message = "bad input: RK4 needs a fixed step (options%ode%first_step > 0)"
            return
        end if
        if (options%every < 1 .or. options%proj_max_iter < 1 .or. &
            .not. options%proj_tol > 0.0_dp) then
            res%message = "bad input: every, proj_max_iter and proj_tol must be positive"
            return
        end if
        if (.not. (options%ode%rtol >= 0.0_dp .and. options%ode%atol >= 0.0_dp)) then
            res%message = "bad input: rtol and atol must be non-negative"
            return
        end if
        if (n_eval > 0) then
            if (any((t_eval - t_span(1))*(tf - t_eval) < 0.0_dp)) then
                res%message = "bad input: t_eval values must lie in t_span"
                return
            end if
            if (n_eval > 1) then
                if (any((t_eval(2:) - t_eval(:n_eval - 1))*(tf - t_span(1)) < 0.0_dp)) then
                    res%message = "bad input: t_eval must be sorted in the direction of " &
                                  //"integration"
                    return
                end if
            end if
        end if

        allocate (q(n), v(n), acc(n), lam(m), y(2*n), ynew(2*n), ytmp(2*n), sk(2*n))
        allocate (rtolv(2*n), atolv(2*n), k(2*n, 16))
        cap = 64
        if (n_eval > 0) cap = n_eval + 1
        allocate (res%t(cap), res%q(n, cap), res%v(n, cap), res%lam(m, cap), &
                  res%reaction(n, cap), res%res_pos(cap), res%res_vel(cap), res%energy(cap), &
                  res%power(cap))

        t = t_span(1)
        q = q0
        v = v0
        ! ------------------------------------------------------------ consistent start
        if (options%project_initial) then
            call consistent_initial(sys, t, q, v, options%proj_tol, options%proj_max_iter, &
                                    res%dq0, res%dv0, iters, info, msg)
            res%proj_iter = iters
            if (info /= CM_SUCCESS) then
                res%status = info
                res%message = msg
                call shrink()
                return
            end if
        end if
        call constrained_accel(sys, t, q, v, acc, lam, info, msg, rank=res%rank)
        if (info /= CM_SUCCESS) then
            res%status = info
            res%message = msg
            call shrink()
            return
        end if

        allocate (f%mech, source=sys)
        f%baumgarte = options%projection == PROJ_BAUMGARTE
        f%alpha = options%alpha
        f%beta = options%beta
        y(1:n) = q
        y(n + 1:) = v
        rtolv = max(options%ode%rtol, 100.0_dp*epsilon(1.0_dp))
        atolv = options%ode%atol
        if (allocated(options%ode%rtol_vec)) rtolv = max(options%ode%rtol_vec, &
                                                          100.0_dp*epsilon(1.0_dp))
        if (allocated(options%ode%atol_vec)) atolv = options%ode%atol_vec

        beta = 0.0_dp
        select case (options%ode%method)
        case (METHOD_RK4)
            adaptive = .false.
        case (METHOD_DOPRI5)
            adaptive = .true.
            tab = dopri5_tableau()
            safe = 0.9_dp; facc1 = 1.0_dp/0.2_dp; facc2 = 1.0_dp/10.0_dp
            beta = 0.04_dp                       ! Lund stabilisation, as dopri5.f
            if (options%ode%beta >= 0.0_dp) beta = options%ode%beta
            expo1 = 0.2_dp - 0.75_dp*beta
        case (METHOD_VERNER98)
            adaptive = .true.
            tab = verner98_tableau()
            safe = 0.9_dp; facc1 = 1.0_dp/0.333_dp; facc2 = 1.0_dp/6.0_dp
            expo1 = 1.0_dp/9.0_dp
        case default
            adaptive = .true.
            tab = dop853_tableau()
            safe = 0.9_dp; facc1 = 1.0_dp/0.333_dp; facc2 = 1.0_dp/6.0_dp
            expo1 = 1.0_dp/8.0_dp
        end select
        if (options%ode%safety > 0.0_dp) safe = options%ode%safety
        if (options%ode%fac_min > 0.0_dp) facc1 = 1.0_dp/options%ode%fac_min
        if (options%ode%fac_max > 0.0_dp) facc2 = 1.0_dp/options%ode%fac_max
        posneg = sign(1.0_dp, tf - t)
        hmax = min(abs(options%ode%max_step), abs(tf - t))

        i_eval = 1
        res%status = CM_SUCCESS
        res%message = "success"
        call output_point(.true.)
        main: block
        if (res%status /= CM_SUCCESS .or. tf == t) exit main

        call f%rhs(t, y, k(:, 1))
        res%nfev = res%nfev + 1
        if (adaptive) then
            if (options%ode%first_step > 0.0_dp) then
                h = posneg*min(options%ode%first_step, hmax)
            else
                h = hinit()
            end if
        else
            h = posneg*min(options%ode%first_step, abs(tf - t))
        end if
        facold = 1.0e-4_dp
        reject = .false.
        nsteps = 0
        since_proj = 0
        ! ------------------------------------------------------------ main loop
        do
            if (nsteps >= options%ode%max_steps) then
                res%status = CM_TOO_MANY_STEPS
                write (buf, '(es14.6)') t
                res%message = "too many steps: max_steps reached at t ="//trim(buf)
                exit
            end if
            if (0.1_dp*abs(h) <= abs(t)*epsilon(1.0_dp) .or. abs(h) < tiny(1.0_dp)) then
                res%status = CM_STEP_TOO_SMALL
                write (buf, '(es14.6)') t
                res%message = "step size too small at t ="//trim(buf)
                exit
            end if
            ! the next point the steps must hit
            target = tf
            if (n_eval > 0 .and. i_eval <= n_eval) target = t_eval(i_eval)
            hit = .false.
            if ((t + 1.01_dp*h - target)*posneg >= 0.0_dp) then
                h = target - t
                hit = .true.
            end if
            nsteps = nsteps + 1
            select case (options%ode%method)
            case (METHOD_RK4)
                call rk4_step()
            case (METHOD_DOPRI5)
                call dopri5_step()
            case (METHOD_VERNER98)
                call verner_step()
            case default
                call dop853_step()
            end select

            if (.not. (err <= 1.0_dp)) then
                if (.not. adaptive) then
                    res%status = CM_NONFINITE
                    write (buf, '(es14.6)') t
                    res%message = "non-finite state (singular mass matrix?) in a step from t =" &
                                  //trim(buf)
                    exit
                end if
                if (err /= err .or. err > huge(1.0_dp)) then
                    h = 0.1_dp*h
                else
                    h = h/min(facc1, err**expo1/safe)
                end if
                reject = .true.
                if (res%naccept >= 1) res%nreject = res%nreject + 1
                cycle
            end if
            ! ---------------------------------------------------------- accepted
            res%naccept = res%naccept + 1
            if (adaptive) then
                fac = max(facc2, min(facc1, err**expo1/facold**beta/safe))
                hnew = h/fac
                facold = max(err, 1.0e-4_dp)
            else
                hnew = posneg*options%ode%first_step   ! fixed step (a cut step is not kept)
            end if
            t = t + h
            if (hit) t = target
            y = ynew
            since_proj = since_proj + 1
            nf_new = 0
            if (since_proj >= options%every .and. (options%projection == PROJ_VELOCITY .or. &
                options%projection == PROJ_POSITION_VELOCITY)) then
                since_proj = 0
                call project(info)
                if (info /= CM_SUCCESS) exit
                nf_new = 1
            end if
            if (nf_new == 1 .or. options%ode%method /= METHOD_DOPRI5) then
                call f%rhs(t, y, k(:, 1))
                res%nfev = res%nfev + 1
            else
                k(:, 1) = k(:, 7)
            end if
            if (.not. all(ieee_is_finite(k(:, 1)))) then
                res%status = CM_NONFINITE
                write (buf, '(es14.6)') t
                res%message = "non-finite right-hand side (singular mass matrix?) at t =" &
                              //trim(buf)
                exit
            end if
            if (n_eval == 0) then
                if (options%save_steps .or. (hit .and. target == tf)) call output_point(.false.)
            else if (hit .and. i_eval <= n_eval) then
                do while (i_eval <= n_eval)
                    if (t_eval(i_eval) /= t) exit
                    call output_point(.false.)
                    i_eval = i_eval + 1
                end do
            end if
            if (res%status /= CM_SUCCESS) exit
            if (hit .and. target == tf) exit
            if (adaptive) then
                if (abs(hnew) > hmax) hnew = posneg*hmax
                if (reject) hnew = posneg*min(abs(hnew), abs(h))
            end if
            reject = .false.
            h = hnew
        end do
        end block main
        call shrink()
        res%success = res%status >= 0

    contains

        !> Position (if asked) then velocity projection of y at t.
        subroutine project(info)
            integer, intent(out) :: info
            character(len=:), allocatable :: pmsg
            integer :: it
            q = y(1:n)
            v = y(n + 1:)
            it = 0
            if (options%projection == PROJ_POSITION_VELOCITY) then
                call project_position(sys, t, q, options%proj_tol, options%proj_max_iter, it, &
                                      info, pmsg)
                res%proj_iter = res%proj_iter + it
                res%proj_iter_max = max(res%proj_iter_max, it)
                if (info /= CM_SUCCESS) then
                    write (buf, '(es14.6)') t
                    res%status = info
                    res%message = pmsg//" at t ="//trim(buf)
                    return
                end if
            end if
            call project_velocity(sys, t, q, v, info, pmsg)
            if (info /= CM_SUCCESS) then
                write (buf, '(es14.6)') t
                res%status = info
                res%message = pmsg//" at t ="//trim(buf)
                return
            end if
            res%nproj = res%nproj + 1
            y(1:n) = q
            y(n + 1:) = v
        end subroutine project

        !> Outputs at the current (t, y); at the start only where t_eval asks for it.
        subroutine output_point(first)
            logical, intent(in) :: first
            if (first .and. n_eval > 0) then
                do while (i_eval <= n_eval)
                    if (t_eval(i_eval) /= t) exit
                    call store()
                    i_eval = i_eval + 1
                end do
                return
            end if
            call store()
        end subroutine output_point

        !> Store the diagnostics of (t, y).
        subroutine store()
            integer :: j, inf2
            character(len=:), allocatable :: m2
            call grow()
            j = res%nt + 1
            res%nt = j
            q = y(1:n)
            v = y(n + 1:)
            res%t(j) = t
            res%q(:, j) = q
            res%v(:, j) = v
            if (f%baumgarte) then
                call constrained_accel(sys, t, q, v, acc, lam, inf2, m2, &
                                       alpha=options%alpha, beta=options%beta)
            else
                call constrained_accel(sys, t, q, v, acc, lam, inf2, m2)
            end if
            if (inf2 /= CM_SUCCESS) then
                res%status = inf2
                res%message = m2
            end if
            res%lam(:, j) = lam
            res%reaction(:, j) = reaction_of(lam)
            call constraint_residuals(sys, t, q, v, res%res_pos(j), res%res_vel(j))
            res%energy(j) = 0.0_dp
            if (sys%has_energy()) res%energy(j) = sys%energy(t, q, v)
            res%power(j) = dot_product(res%reaction(:, j), v)
        end subroutine store

        function reaction_of(lm) result(r)
            real(dp), intent(in) :: lm(:)
            real(dp) :: r(n), c(m, n), c0(m)
            r = 0.0_dp
            if (m == 0) return
            call constraint_matrix(sys, t, q, c, c0)
            r = matmul(lm, c)
        end function reaction_of

        subroutine grow()
            integer :: newcap
            real(dp), allocatable :: t1(:), t2(:, :)
            if (res%nt < size(res%t)) return
            newcap = 2*size(res%t)
            allocate (t1(newcap)); t1(:res%nt) = res%t(:res%nt); call move_alloc(t1, res%t)
            allocate (t1(newcap)); t1(:res%nt) = res%res_pos(:res%nt)
            call move_alloc(t1, res%res_pos)
            allocate (t1(newcap)); t1(:res%nt) = res%res_vel(:res%nt)
            call move_alloc(t1, res%res_vel)
            allocate (t1(newcap)); t1(:res%nt) = res%energy(:res%nt)
            call move_alloc(t1, res%energy)
            allocate (t1(newcap)); t1(:res%nt) = res%power(:res%nt)
            call move_alloc(t1, res%power)
            allocate (t2(n, newcap)); t2(:, :res%nt) = res%q(:, :res%nt)
            call move_alloc(t2, res%q)
            allocate (t2(n, newcap)); t2(:, :res%nt) = res%v(:, :res%nt)
            call move_alloc(t2, res%v)
            allocate (t2(n, newcap)); t2(:, :res%nt) = res%reaction(:, :res%nt)
            call move_alloc(t2, res%reaction)
            allocate (t2(m, newcap)); t2(:, :res%nt) = res%lam(:, :res%nt)
            call move_alloc(t2, res%lam)
        end subroutine grow

        !> Trim the output arrays to nt columns.
        subroutine shrink()
            integer :: nt
            nt = res%nt
            if (.not. allocated(res%t)) then
                allocate (res%t(0), res%q(n, 0), res%v(n, 0), res%lam(m, 0), &
                          res%reaction(n, 0), res%res_pos(0), res%res_vel(0), &
                          res%energy(0), res%power(0))
                return
            end if
            res%t = res%t(:nt)
            res%q = res%q(:, :nt)
            res%v = res%v(:, :nt)
            res%lam = res%lam(:, :nt)
            res%reaction = res%reaction(:, :nt)
            res%res_pos = res%res_pos(:nt)
            res%res_vel = res%res_vel(:nt)
            res%energy = res%energy(:nt)
            res%power = res%power(:nt)
        end subroutine shrink

        function hinit() result(hh)
            real(dp) :: hh, dnf, dny, der2, der12, h1
            sk = atolv + rtolv*abs(y)
            dnf = sum((k(:, 1)/sk)**2)
            dny = sum((y/sk)**2)
            if (dnf <= 1.0e-10_dp .or. dny <= 1.0e-10_dp) then
                hh = 1.0e-6_dp
            else
                hh = sqrt(dny/dnf)*0.01_dp
            end if
            hh = min(hh, hmax)*posneg
            ytmp = y + hh*k(:, 1)
            call f%rhs(t + hh, ytmp, k(:, 2))
            res%nfev = res%nfev + 1
            der2 = sqrt(sum(((k(:, 2) - k(:, 1))/sk)**2))/abs(hh)
            if (der2 /= der2) der2 = huge(1.0_dp)
            der12 = max(abs(der2), sqrt(dnf))
            if (der12 <= 1.0e-15_dp) then
                h1 = max(1.0e-6_dp, abs(hh)*1.0e-3_dp)
            else
                h1 = (0.01_dp/der12)**(1.0_dp/real(tab%order, dp))
            end if
            hh = min(100.0_dp*abs(hh), h1, hmax)*posneg
        end function hinit

        subroutine stages(s1, s2)
            integer, intent(in) :: s1, s2
            integer :: s, j
            do s = s1, s2
                ytmp = y
                do j = 1, s - 1
                    if (tab%a(s, j) /= 0.0_dp) ytmp = ytmp + (h*tab%a(s, j))*k(:, j)
                end do
                call f%rhs(t + tab%c(s)*h, ytmp, k(:, s))
            end do
            res%nfev = res%nfev + (s2 - s1 + 1)
        end subroutine stages

        subroutine rk4_step()
            real(dp) :: h2
            h2 = 0.5_dp*h
            ytmp = y + h2*k(:, 1)
            call f%rhs(t + h2, ytmp, k(:, 2))
            ytmp = y + h2*k(:, 2)
            call f%rhs(t + h2, ytmp, k(:, 3))
            ytmp = y + h*k(:, 3)
            call f%rhs(t + h, ytmp, k(:, 4))
            res%nfev = res%nfev + 3
            ynew = y + (h/6.0_dp)*(k(:, 1) + 2.0_dp*(k(:, 2) + k(:, 3)) + k(:, 4))
            err = 0.0_dp
            if (.not. all(ieee_is_finite(ynew))) err = ieee_value(1.0_dp, ieee_quiet_nan)
        end subroutine rk4_step

        subroutine dopri5_step()
            integer :: j
            call stages(2, 6)
            ynew = y
            do j = 1, 6
                if (tab%b(j) /= 0.0_dp) ynew = ynew + (h*tab%b(j))*k(:, j)
            end do
            call f%rhs(t + h, ynew, k(:, 7))
            res%nfev = res%nfev + 1
            ytmp = 0.0_dp
            do j = 1, 7
                if (tab%e(j) /= 0.0_dp) ytmp = ytmp + tab%e(j)*k(:, j)
            end do
            sk = atolv + rtolv*max(abs(y), abs(ynew))
            err = abs(h)*sqrt(sum((ytmp/sk)**2)/real(2*n, dp))
            if (.not. all(ieee_is_finite(ynew))) err = ieee_value(1.0_dp, ieee_quiet_nan)
        end subroutine dopri5_step

        subroutine dop853_step()
            integer :: j
            real(dp) :: err5, err3, deno
            call stages(2, 12)
            ytmp = 0.0_dp
            do j = 1, 12
                if (tab%b(j) /= 0.0_dp) ytmp = ytmp + tab%b(j)*k(:, j)
            end do
            ynew = y + h*ytmp
            sk = atolv + rtolv*max(abs(y), abs(ynew))
            err3 = sum(((ytmp - tab%bhh(1)*k(:, 1) - tab%bhh(9)*k(:, 9) &
                         - tab%bhh(12)*k(:, 12))/sk)**2)
            ytmp = 0.0_dp
            do j = 1, 12
                if (tab%e(j) /= 0.0_dp) ytmp = ytmp + tab%e(j)*k(:, j)
            end do
            err5 = sum((ytmp/sk)**2)
            deno = err5 + 0.01_dp*err3
            if (deno <= 0.0_dp) deno = 1.0_dp
            err = abs(h)*err5*sqrt(1.0_dp/(real(2*n, dp)*deno))
            if (.not. all(ieee_is_finite(ynew))) err = ieee_value(1.0_dp, ieee_quiet_nan)
        end subroutine dop853_step

        subroutine verner_step()
            integer :: j
            call stages(2, 16)
            ytmp = 0.0_dp
            do j = 1, 15
                if (tab%b(j) /= 0.0_dp) ytmp = ytmp + tab%b(j)*k(:, j)
            end do
            ynew = y + h*ytmp
            ytmp = 0.0_dp
            do j = 1, 16
                if (tab%e(j) /= 0.0_dp) ytmp = ytmp + tab%e(j)*k(:, j)
            end do
            sk = atolv + rtolv*max(abs(y), abs(ynew))
            err = abs(h)*sqrt(sum((ytmp/sk)**2)/real(2*n, dp))
            if (.not. all(ieee_is_finite(ynew))) err = ieee_value(1.0_dp, ieee_quiet_nan)
        end subroutine verner_step

    end subroutine constrained_solve

end module conmech_constrained_solver
