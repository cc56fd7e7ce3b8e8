!> The first-order form of a constrained system for the Runge-Kutta methods, and the
!! projection that keeps it on the constraint manifold:
!! - `constrained_ode`: y = [q, v], y' = [v, a] with the accelerations from the
!!   acceleration-level KKT system (index 1), or Baumgarte's stabilised constraint
!!   C a = gamma - 2 alpha (C v + c0) - beta^2 phi;
!! - `projection_hook`: a step hook of the driver that projects y after every accepted
!!   step (or every k steps): mass-weighted position projection by simplified Newton, then
!!   velocity projection (Hairer-Lubich-Wanner), or velocity projection only; it projects
!!   the located event states the same way (`at_event`);
!! - `consistent_initial`: the initial state made consistent (position then velocity).
module conmech_constrained_ode
    use conmech_kinds, only: dp, nan_dp
    use conmech_status
    use conmech_text, only: rtoa
    use conmech_ode_system, only: ode_system, ode_step_hook
    use conmech_constrained_system
    use conmech_constrained_result, only: PROJ_VELOCITY, PROJ_POSITION_VELOCITY
    implicit none
    private

    public :: constrained_ode, projection_hook, consistent_initial

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
    !! t_eval/dense points are interpolated between projected steps, so they are on the
    !! manifold only to the local error; event states too, unless `project_events`
    !! (constrained_solve sets it: the located states are projected like the steps).
    !! Counters: nproj, proj_iter, proj_iter_max.
    type, extends(ode_step_hook) :: projection_hook
        class(constrained_system), allocatable :: mech
        integer :: projection = PROJ_POSITION_VELOCITY   !! or PROJ_VELOCITY
        integer :: every = 1
        real(dp) :: proj_tol = 1.0e-14_dp
        integer :: proj_max_iter = 10
        integer :: nproj = 0, proj_iter = 0, proj_iter_max = 0
        integer :: since = 0
        logical :: project_events = .false.   !! project the located event states too
    contains
        procedure :: after_step => hook_project
        procedure :: at_event => hook_project_event
    end type projection_hook

contains

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
        if (info /= CM_SUCCESS) dydt(n + 1:2*n) = nan_dp
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

    !> With project_events: project a located event state like the steps
    !! (position+velocity or velocity; not with "none" or Baumgarte), so that event states
    !! are on the constraints to proj_tol.
    subroutine hook_project_event(self, t, y, info)
        class(projection_hook), intent(inout) :: self
        real(dp), intent(in) :: t
        real(dp), intent(inout) :: y(:)
        integer, intent(out) :: info
        info = CM_SUCCESS
        if (.not. self%project_events) return
        if (self%projection /= PROJ_VELOCITY .and. &
            self%projection /= PROJ_POSITION_VELOCITY) return
        call project_state(self, t, y, info)
    end subroutine hook_project_event

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
            self%message = msg//" at t ="//rtoa(t)
            return
        end if
        self%nproj = self%nproj + 1
        y(1:n) = q
        y(n + 1:2*n) = v
    end subroutine project_state

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

end module conmech_constrained_ode
