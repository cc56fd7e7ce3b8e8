!> RATTLE as a stepper of the integrator contract (conmech_ode_stepper): mechanical systems
!! with holonomic constraints in excessive coordinates, M q'' = Q(t, q, q') + G^T lambda,
!! phi(t, q) = 0, on the fixed grid t_k = t0 + k h (h = (tf - t0)/N, N = ceil(|tf -
!! t0|/first_step); the last step ends on tf). The state is y = [q; v]; second order,
!! symmetric, symplectic for a constant mass matrix and forces from a potential. One step
!! and its constraint solves: conmech_rattle_step.
!!
!! The continuous extension is the RATTLE side step itself: y at t in [t_{k-1}, t_k] is one
!! RATTLE step of length t - t_{k-1} from the grid point before (its states are on the
!! constraint manifold to round-off; its local error is O(h^3), so event times have the
!! method's second order). The driver finds t_eval points and events on it; the trajectory
!! itself is not altered. There is no polynomial (nf = 0: no dense solution).
!!
!! The caller sets the system `mech` (and proj_tol, proj_max_iter of the position solve)
!! before `init`; the `ode_system` argument of the contract's procedures is not used (the
!! first-order form of the constrained layer is passed there).
module conmech_rattle_stepper
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_text, only: rtoa
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: ode_options, METHOD_RATTLE
    use conmech_ode_stepper, only: ode_stepper, check_first_step
    use conmech_state_packer, only: state_packer
    use conmech_fixed_grid, only: grid_steps, check_grid_steps, grid_time
    use conmech_constrained_system, only: constrained_system
    use conmech_rattle_step, only: rattle_state, rattle_work, rattle_work_init, &
        rattle_prepare, rattle_step, rattle_state_transfer
    implicit none
    private

    public :: rattle_stepper

    !> A RATTLE integration on its grid.
    type, extends(ode_stepper) :: rattle_stepper
        class(constrained_system), allocatable :: mech   !! the system (set before init)
        real(dp) :: proj_tol = 1.0e-14_dp   !! max|phi| of the position solve
        integer :: proj_max_iter = 10       !! its simplified Newton iterations
        integer :: ncoord = 0               !! coordinates (y = [q; v] has 2 ncoord)
        integer :: kdone = 0                !! grid steps done
        integer :: nsteps = 0               !! grid steps of the run
        integer :: cur = 1                  !! which of grid(1:2) holds the state at t
        real(dp) :: t_start = 0.0_dp        !! t0 of the grid
        real(dp) :: hg = 0.0_dp             !! the grid step
        type(rattle_work) :: wk             !! sizes, mass kind, work arrays, counters
        type(rattle_state) :: grid(2)       !! the states at t_old and t
        type(rattle_state) :: side          !! scratch of the side steps
    contains
        procedure :: setup => rattle_setup
        procedure :: start => rattle_start
        procedure :: step => rattle_stepper_step
        procedure :: eval => rattle_eval
        procedure :: eval_unit => rattle_eval_unit
        procedure :: refresh_f => rattle_refresh_f
        procedure :: transfer_state => rattle_transfer
    end type rattle_stepper

contains

    !> The method's part of init: the system, the step option and the grid (y = [q0; v0]);
    !! CM_TOO_MANY_STEPS when the grid has more steps than max_steps. No evaluation.
    subroutine rattle_setup(self, opt, info, msg)
        class(rattle_stepper), intent(inout) :: self
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        info = CM_BAD_INPUT
        if (.not. allocated(self%mech)) then
            msg = "bad input: the RATTLE stepper has no system (set mech before init)"
            return
        else if (self%mech%n_nh /= 0) then
            msg = "bad input: RATTLE handles holonomic constraints only (n_nh = 0)"
            return
        else if (self%n /= 2*self%mech%n) then
            msg = "bad input: y0 must be [q0; v0] of the system's 2 n elements"
            return
        end if
        call check_first_step(self, opt, info, msg, fixed="RATTLE")
        if (info /= CM_SUCCESS) return
        self%ncoord = self%mech%n
        self%t_start = self%t
        self%nsteps = grid_steps(self%t, self%tf, opt%first_step)
        call check_grid_steps(self%nsteps, opt%max_steps, info, msg)
        if (info /= CM_SUCCESS) return
        self%method = METHOD_RATTLE
        self%lands_on_target = .false.
        self%hg = 0.0_dp
        if (self%nsteps > 0) self%hg = (self%tf - self%t)/real(self%nsteps, dp)
        self%h = self%hg
        self%kdone = 0
        self%cur = 1
    end subroutine rattle_setup

    !> The work of the run (M^{-1} once for a constant mass) and the state at t0 (forces,
    !! mass factor, G and M^{-1} G^T).
    subroutine rattle_start(self, sys, info, msg)
        class(rattle_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: n
        n = self%ncoord
        call rattle_work_init(self%wk, self%mech, self%t, self%y(1:n), self%proj_tol, &
                              self%proj_max_iter, info, msg)
        if (info /= CM_SUCCESS) return
        call rattle_prepare(self%mech, self%wk, self%grid(1), self%t, self%y(1:n), &
                            self%y(n + 1:2*n), info, msg)
        self%st%nfev = self%wk%nfev
        if (info == CM_SUCCESS) msg = "success"
    end subroutine rattle_start

    !> The next grid step (`target` is not used: the grid ends on tf).
    subroutine rattle_stepper_step(self, sys, target, info, msg)
        class(rattle_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: target
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: k, cur, nxt, n
        real(dp) :: tk
        n = self%ncoord
        cur = self%cur
        nxt = 3 - cur
        k = self%kdone + 1
        call rattle_step(self%mech, self%wk, self%grid(cur), self%hg, self%grid(nxt), info, &
                         msg)
        self%st%nfev = self%wk%nfev
        if (info /= CM_SUCCESS) then
            call where_failed(self%grid(cur)%t, msg)
            return
        end if
        tk = grid_time(self%t_start, self%tf, self%hg, k, self%nsteps)
        self%grid(nxt)%t = tk
        self%cur = nxt
        self%kdone = k
        self%last = k == self%nsteps
        self%t_old = self%t
        self%h_done = self%hg
        self%t = tk
        self%y_old = self%y
        self%y(1:n) = self%grid(nxt)%q
        self%y(n + 1:2*n) = self%grid(nxt)%v
        self%dense_ready = .true.
        self%st%naccept = self%st%naccept + 1
    end subroutine rattle_stepper_step

    !> The side step of length tt - t_old from the grid point before.
    subroutine rattle_eval(self, tt, yout, info, msg)
        class(rattle_stepper), intent(inout) :: self
        real(dp), intent(in) :: tt
        real(dp), intent(out) :: yout(:)
        integer, intent(out), optional :: info
        character(len=:), allocatable, intent(inout), optional :: msg
        call side_step(self, tt - self%grid(3 - self%cur)%t, yout, info, msg)
    end subroutine rattle_eval

    !> The side step of length x h_done from the grid point before.
    subroutine rattle_eval_unit(self, x, yout, info, msg)
        class(rattle_stepper), intent(inout) :: self
        real(dp), intent(in) :: x
        real(dp), intent(out) :: yout(:)
        integer, intent(out), optional :: info
        character(len=:), allocatable, intent(inout), optional :: msg
        call side_step(self, x*self%h_done, yout, info, msg)
    end subroutine rattle_eval_unit

    subroutine side_step(self, hs, yout, info, msg)
        type(rattle_stepper), intent(inout) :: self
        real(dp), intent(in) :: hs
        real(dp), intent(out) :: yout(:)
        integer, intent(out), optional :: info
        character(len=:), allocatable, intent(inout), optional :: msg
        integer :: inf, n
        character(len=:), allocatable :: mg
        n = self%ncoord
        associate (s0 => self%grid(3 - self%cur))
            call rattle_step(self%mech, self%wk, s0, hs, self%side, inf, mg)
            self%st%nfev = self%wk%nfev
            if (inf == CM_SUCCESS) then
                yout(1:n) = self%side%q
                yout(n + 1:2*n) = self%side%v
            else
                yout = huge(1.0_dp)
                call where_failed(s0%t, mg)
            end if
        end associate
        if (present(info)) info = inf
        if (present(msg) .and. inf /= CM_SUCCESS) msg = mg
    end subroutine side_step

    !> The time of the grid point a failed step started from, in the message.
    subroutine where_failed(t, msg)
        real(dp), intent(in) :: t
        character(len=:), allocatable, intent(inout) :: msg
        msg = msg//" (RATTLE step from t ="//rtoa(t)//")"
    end subroutine where_failed

    !> After a hook changed y: the state at t prepared again (forces, mass, G).
    subroutine rattle_refresh_f(self, sys)
        class(rattle_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        integer :: inf, n
        character(len=:), allocatable :: mg
        n = self%ncoord
        call rattle_prepare(self%mech, self%wk, self%grid(self%cur), self%t, self%y(1:n), &
                            self%y(n + 1:2*n), inf, mg)
        self%st%nfev = self%wk%nfev
        self%f_stale = .false.
    end subroutine rattle_refresh_f

    !> The whole state (conmech_state_packer): the grid, both grid states and the
    !! counters of the run; the work (and M^{-1} of a constant mass) is rebuilt from the
    !! system on unpacking, which needs `mech` set first.
    subroutine rattle_transfer(self, p)
        class(rattle_stepper), intent(inout) :: self
        type(state_packer), intent(inout) :: p
        integer :: k, inf
        character(len=:), allocatable :: mg
        call self%transfer_base(p)
        call p%item(self%ncoord)
        call p%item(self%kdone)
        call p%item(self%nsteps)
        call p%item(self%cur)
        call p%item(self%t_start)
        call p%item(self%hg)
        call p%item(self%proj_tol)
        call p%item(self%proj_max_iter)
        if (p%reading()) then
            if (.not. allocated(self%mech)) then
                p%info = CM_BAD_INPUT
                return
            end if
            call rattle_work_init(self%wk, self%mech, self%t_start, self%y(1:self%ncoord), &
                                  self%proj_tol, self%proj_max_iter, inf, mg)
            if (inf /= CM_SUCCESS) p%info = inf
        end if
        call p%item(self%wk%nfev)
        call p%item(self%wk%nproj)
        call p%item(self%wk%proj_iter)
        call p%item(self%wk%proj_iter_max)
        call p%item(self%wk%nfallback)
        do k = 1, 2
            call rattle_state_transfer(self%wk, self%grid(k), p)
        end do
    end subroutine rattle_transfer

end module conmech_rattle_stepper
