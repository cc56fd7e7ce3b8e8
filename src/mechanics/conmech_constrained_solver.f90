!> Integrators for constrained mechanical systems: the index-1 form (accelerations from the
!! KKT system) advanced by RK4 / DOPRI5 / DOP853 / Verner 9(8), with
!! - no stabilisation (PROJ_NONE: the constraints drift, |phi| ~ h^p (A t + B t^2)),
!! - velocity projection after each accepted step (PROJ_VELOCITY),
!! - mass-weighted position projection (simplified Newton) then velocity projection
!!   (PROJ_POSITION_VELOCITY, Hairer-Lubich-Wanner; the default),
!! - Baumgarte stabilisation (PROJ_BAUMGARTE): C a = gamma - 2 alpha (C v + c0) - beta^2 phi.
!!
!! `constrained_solve` runs the core integrator (`ode_solve`, with its step control) and
!! does the projection in a step hook (`projection_hook`) after each accepted step (or
!! every k steps); the right-hand side is evaluated once per step, at the projected state.
!! Outputs are the accepted steps, or the points of `t_eval`, which the steps hit exactly
!! (`hit_t_eval`: every output point is a projected point). The initial state is made
!! consistent first (position then velocity projection; the distances moved are reported).
!! Events (functions of (t, [q; v])) are located by `ode_solve` on the dense output of the
!! steps (Brent's method); the located states are then projected like the steps
!! (position+velocity or velocity; not with "none" or Baumgarte), so event states are on
!! the constraints to `proj_tol` and the event functions vanish there to the integration
!! tolerance. A terminal event ends the run at the (projected) event state.
module conmech_constrained_solver
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_quiet_nan
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system, ode_step_hook, ode_events
    use conmech_ode_solver, only: ode_options, ode_result, ode_solve
    use conmech_constrained_system
    implicit none
    private

    integer, parameter, public :: PROJ_NONE = 0               !! plain index-1 form
    integer, parameter, public :: PROJ_VELOCITY = 1           !! velocity projection only
    integer, parameter, public :: PROJ_POSITION_VELOCITY = 2  !! position, then velocity
    integer, parameter, public :: PROJ_BAUMGARTE = 3          !! Baumgarte stabilisation

    public :: constrained_ode, constrained_options, constrained_result, projection_hook
    public :: constrained_solve, consistent_initial, projection_from_name, take_events

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
        ! events (event functions of [q; v])
        integer :: nev = 0                         !! number of events found
        real(dp), allocatable :: ev_t(:)           !! (nev) event times
        real(dp), allocatable :: ev_q(:, :), ev_v(:, :)  !! (n, nev) states at the events
        integer, allocatable :: ev_id(:)           !! (nev) which event function
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
        changed = .false.
        info = CM_SUCCESS
        self%since = self%since + 1
        if (self%since < self%every) return
        if (self%projection /= PROJ_VELOCITY .and. &
            self%projection /= PROJ_POSITION_VELOCITY) return
        self%since = 0
        call project_state(self, t, y, info)
        changed = info == CM_SUCCESS
    end subroutine hook_project

    !> Project y = [q, v] at t by the hook's projection (position+velocity or velocity),
    !! counting the projection and its iterations; y unchanged on failure (message set).
    subroutine project_state(self, t, y, info)
        class(projection_hook), intent(inout) :: self
        real(dp), intent(in) :: t
        real(dp), intent(inout) :: y(:)
        integer, intent(out) :: info
        real(dp) :: q(self%mech%n), v(self%mech%n)
        integer :: n, it
        character(len=:), allocatable :: msg
        character(len=32) :: buf
        info = CM_SUCCESS
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
    end subroutine project_state

    !> Copy the events of a core result (states y = [q, v, ...]) into `res`.
    subroutine take_events(ores, n, res)
        type(ode_result), intent(in) :: ores
        integer, intent(in) :: n
        type(constrained_result), intent(inout) :: res
        integer :: k
        k = ores%nev
        res%nev = k
        if (k == 0) return
        res%ev_t = ores%ev_t(1:k)
        res%ev_q = ores%ev_y(1:n, 1:k)
        res%ev_v = ores%ev_y(n + 1:2*n, 1:k)
        res%ev_id = ores%ev_id(1:k)
    end subroutine take_events

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
    !!
    !! The index-1 (or Baumgarte) first-order form is advanced by the core `ode_solve` with a
    !! `projection_hook` and `hit_t_eval`: the steps land on the t_eval points, so every
    !! output is a projected step end, and the diagnostics (multipliers, reactions,
    !! residuals, energy, reaction power) are evaluated there.
    subroutine constrained_solve(sys, t_span, q0, v0, options, res, t_eval, events)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: q0(:), v0(:)
        type(constrained_options), intent(in) :: options
        type(constrained_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)
        !> event functions of (t, [q; v]) (see the module documentation)
        class(ode_events), intent(in), optional :: events

        type(constrained_ode) :: f
        type(projection_hook) :: hk
        type(ode_options) :: opt
        type(ode_result) :: ores
        real(dp), allocatable :: q(:), v(:), acc(:), lam(:)
        integer :: n, m, info, iters, j
        character(len=:), allocatable :: msg
        character(len=32) :: buf

        n = sys%n
        m = sys%n_hol + sys%n_nh
        res%message = "bad input"
        ! ------------------------------------------------------------ validation
        ! (the integrator options and t_eval are checked by ode_solve)
        if (n < 1 .or. sys%n_hol < 0 .or. sys%n_nh < 0) then
            res%message = "bad input: the system needs n >= 1 coordinates, n_hol, n_nh >= 0"
        else if (size(q0) /= n .or. size(v0) /= n) then
            write (buf, '(i0)') n
            res%message = "bad input: q0 and v0 must have n = "//trim(buf)//" elements"
        else if (.not. (all(ieee_is_finite(q0)) .and. all(ieee_is_finite(v0)))) then
            res%message = "bad input: q0 or v0 contains NaN or Inf"
        else if (options%projection < PROJ_NONE .or. options%projection > PROJ_BAUMGARTE) then
            res%message = "bad input: unknown projection"
        else if (options%every < 1 .or. options%proj_max_iter < 1 .or. &
                 .not. options%proj_tol > 0.0_dp) then
            res%message = "bad input: every, proj_max_iter and proj_tol must be positive"
        else
            res%status = CM_SUCCESS
        end if
        if (res%status /= CM_SUCCESS) then
            call allocate_outputs(0)
            return
        end if

        allocate (q(n), v(n), acc(n), lam(m))
        q = q0
        v = v0
        ! ------------------------------------------------------------ consistent start
        if (options%project_initial) then
            call consistent_initial(sys, t_span(1), q, v, options%proj_tol, &
                                    options%proj_max_iter, res%dq0, res%dv0, iters, info, msg)
            res%proj_iter = iters
            res%proj_iter_max = iters
            if (info /= CM_SUCCESS) then
                call fail(info, msg)
                return
            end if
        end if
        call constrained_accel(sys, t_span(1), q, v, acc, lam, info, msg, rank=res%rank)
        if (info /= CM_SUCCESS) then
            call fail(info, msg)
            return
        end if
        if (m > 0 .and. res%rank == 0) then
            call fail(CM_BAD_INPUT, "bad input: the constraint Jacobian is zero at the "// &
                      "initial state (rank 0): the constraints cannot be enforced")
            return
        end if

        ! ------------------------------------------------------------ integration
        allocate (f%mech, source=sys)
        call prepare_mass(f%mech, t_span(1), q)     ! a constant M: factorised once
        f%baumgarte = options%projection == PROJ_BAUMGARTE
        f%alpha = options%alpha
        f%beta = options%beta
        allocate (hk%mech, source=sys)
        call prepare_mass(hk%mech, t_span(1), q)
        hk%projection = options%projection
        hk%every = options%every
        hk%proj_tol = options%proj_tol
        hk%proj_max_iter = options%proj_max_iter
        opt = options%ode
        opt%hit_t_eval = .true.
        opt%dense_output = .false.
        opt%save_steps = options%save_steps
        call ode_solve(f, t_span, [q, v], opt, ores, t_eval=t_eval, events=events, hook=hk)
        res%status = ores%status
        res%message = ores%message
        if (ores%nev > 0) call project_events()
        call take_events(ores, n, res)
        if (ores%status == CM_NONFINITE) res%message = ores%message// &
            " (a singular mass matrix or KKT system gives NaN accelerations)"
        res%nfev = ores%stats%nfev
        res%naccept = ores%stats%naccept
        res%nreject = ores%stats%nreject
        res%nproj = hk%nproj
        res%proj_iter = res%proj_iter + hk%proj_iter
        res%proj_iter_max = max(res%proj_iter_max, hk%proj_iter_max)

        ! ------------------------------------------------------------ diagnostics
        call allocate_outputs(ores%nt)
        do j = 1, ores%nt
            call store(j)
        end do
        res%success = res%status >= 0

    contains

        !> Project the located event states (and the final state of a terminal stop, the
        !! dense-output state at the last event) like the steps.
        subroutine project_events()
            integer :: k, inf2
            if (options%projection /= PROJ_VELOCITY .and. &
                options%projection /= PROJ_POSITION_VELOCITY) return
            do k = 1, ores%nev
                call project_state(hk, ores%ev_t(k), ores%ev_y(:, k), inf2)
                if (inf2 /= CM_SUCCESS .and. res%status >= 0) then
                    res%status = inf2
                    res%message = "event state: "//hk%message
                end if
            end do
            if (ores%status == CM_EVENT_STOP .and. ores%nt > 0) then
                if (ores%t(ores%nt) == ores%ev_t(ores%nev)) &
                    ores%y(:, ores%nt) = ores%ev_y(:, ores%nev)
            end if
        end subroutine project_events

        subroutine fail(code, text)
            integer, intent(in) :: code
            character(len=*), intent(in) :: text
            res%status = code
            res%message = text
            res%success = .false.
            call allocate_outputs(0)
        end subroutine fail

        subroutine allocate_outputs(nt)
            integer, intent(in) :: nt
            res%nt = nt
            allocate (res%t(nt), res%q(n, nt), res%v(n, nt), res%lam(m, nt), &
                      res%reaction(n, nt), res%res_pos(nt), res%res_vel(nt), &
                      res%energy(nt), res%power(nt))
        end subroutine allocate_outputs

        !> The state of output j and its diagnostics.
        subroutine store(j)
            integer, intent(in) :: j
            integer :: inf2
            real(dp) :: t
            character(len=:), allocatable :: m2
            t = ores%t(j)
            q = ores%y(1:n, j)
            v = ores%y(n + 1:2*n, j)
            res%t(j) = t
            res%q(:, j) = q
            res%v(:, j) = v
            if (f%baumgarte) then
                call constrained_accel(f%mech, t, q, v, acc, lam, inf2, m2, &
                                       alpha=options%alpha, beta=options%beta)
            else
                call constrained_accel(f%mech, t, q, v, acc, lam, inf2, m2)
            end if
            if (inf2 /= CM_SUCCESS .and. res%status >= 0) then
                res%status = inf2
                res%message = m2
            end if
            res%lam(:, j) = lam
            call constraint_reaction(f%mech, t, q, lam, res%reaction(:, j))
            call constraint_residuals(sys, t, q, v, res%res_pos(j), res%res_vel(j))
            res%energy(j) = 0.0_dp
            if (sys%has_energy()) res%energy(j) = sys%energy(t, q, v)
            res%power(j) = dot_product(res%reaction(:, j), v)
        end subroutine store

    end subroutine constrained_solve

end module conmech_constrained_solver
