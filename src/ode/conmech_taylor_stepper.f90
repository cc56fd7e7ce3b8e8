!> Taylor's method with the coefficients the system supplies (`taylor_size`, `taylor_jet` of
!! conmech_ode_system; generated from the model by `conmech.symbolic`).
!!
!! Each step expands the solution about the current point to order p,
!! y(t + s) = sum_k y^[k] s^k, and evaluates the polynomial at s = h. Order and step follow
!! Jorba and Zou (2005), as heyoka does, with the order raised and the step lengthened to
!! match (conmech_taylor_core's taylor_order and taylor_decay):
!!
!! - p = p0 + max(3, p0/5), p0 = ceil(-ln(eps)/2 + 1) (at least 2) for the tolerance
!!   eps = max(rtol, atol) (the smallest components of vector tolerances): order 18 at
!!   1e-12, 24 at 1e-16;
!! - rho = min over k = p - 1, p of (1/N_k)^(1/k), N_k = max_i |y_i^[k]| eps/E_i with
!!   E_i = max(atol_i, rtol_i ||y||_inf) (the radius of convergence seen by the last two
!!   coefficients; rtol = atol = eps gives Jorba and Zou's mixed absolute/relative norm);
!!   h = rho exp(-lambda0 (p0 + 1)/(p + 1)), lambda0 = 2 + 0.7/(p0 - 1): the first
!!   neglected term is as small as at Jorba and Zou's order and step, h = rho exp(-lambda0).
!!
!! Safety check of the step: the coefficients at the step's end are computed at once (the
!! next step needs them), so f(t + h, y(t + h)) = y^[1] there is known for free; it is
!! compared with the derivative of the step's polynomial at h. The difference times h is
!! about (p + 1) times the local error; a step whose estimate exceeds 10 E_i (plus a rounding
!! floor) is rejected and retried from the same expansion with a shorter step. This guards
!! against accidentally small last coefficients (symmetries, a passage near a
!! singularity), where the Jorba-Zou estimate alone would be too optimistic.
!!
!! The continuous extension of a step is its Taylor polynomial itself (degree p, the
!! accuracy of the step anywhere in it): fc(:, k) = y^[k] h^k in the power form.
!! All state is in the object (thread-safe). nfev counts the expansions (one per step,
!! plus one at the start and one per rejected step).
module conmech_taylor_stepper
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_text, only: rtoa
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: ode_options, ode_stats, METHOD_TAYLOR
    use conmech_ode_stepper, only: ode_stepper, check_interval, tolerance_vectors, FORM_POWER
    use conmech_state_packer, only: state_packer
    use conmech_taylor_events, only: taylor_events, limit_step
    use conmech_taylor_core, only: taylor_order, taylor_decay, taylor_scales, taylor_add_time, &
        taylor_shrink, TAYLOR_CHECK_MAX, taylor_eval_jet, taylor_check_jet, taylor_next_rho, &
        taylor_eval_step
    implicit none
    private

    public :: taylor_stepper, taylor_order, taylor_propagate

    !> State of a Taylor integration beyond the contract's common state: the two
    !! expansions (at the current point, and at the start of the last step: its polynomial).
    !! Set `kind` = 1 before `init` to integrate the variational system (y0 = [y; Phi]).
    type, extends(ode_stepper) :: taylor_stepper
        integer :: kind = 0               !! 0 the system, 1 its variational system
        integer :: nblock = 0             !! first block of y (the state; the rest: Phi)
        integer :: order = 0              !! p
        integer :: nw = 0                 !! columns of the work arrays (from the system)
        real(dp) :: t_lo = 0.0_dp         !! t + t_lo: the time in double length
        real(dp) :: hmax = huge(1.0_dp)
        real(dp) :: first_step = 0.0_dp
        real(dp) :: eps = 0.0_dp          !! tolerance that set the order
        real(dp) :: decay = 0.0_dp        !! h/rho (taylor_decay)
        real(dp) :: err = 0.0_dp          !! safety-check ratio of the last accepted step
        integer :: nsteps = 0, max_steps = 100000
        logical :: finite = .false.       !! f at the current point finite
        real(dp), allocatable :: rtol(:), atol(:), dy(:), ynew(:), e(:)
        !> (0:p, nw, 2): the expansion at (t, y) is jets(:, :, ic), the one at (t_old,
        !! y_old) (the last step's polynomial, and the next step's work array) the other;
        !! an accepted step swaps them by flipping ic (no copy)
        real(dp), allocatable :: jets(:, :, :)
        integer :: ic = 1
        !> compiled events: steps are shortened so that none holds two roots of one event
        class(taylor_events), pointer :: ev => null()
    contains
        procedure :: init => taylor_init
        procedure :: start => taylor_start
        procedure :: step => taylor_step
        procedure :: transfer_state => taylor_transfer
        procedure :: dense => taylor_dense
        procedure :: eval => taylor_eval
        procedure :: eval_unit => taylor_eval_unit
        procedure :: refresh_f => taylor_refresh
        procedure :: f_finite => taylor_f_finite
        procedure :: resume => taylor_resume
    end type taylor_stepper

contains

    !> Check the options and set up at (t0, y0) on [t0, tf] (no evaluation: the system's
    !! Taylor code is looked up in `start`). rtol may go down to the unit round-off.
    subroutine taylor_init(self, t0, tf, y0, opt, info, msg, allow_inf)
        class(taylor_stepper), intent(inout) :: self
        real(dp), intent(in) :: t0, tf
        real(dp), intent(in) :: y0(:)
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        logical, intent(in), optional :: allow_inf
        integer :: n
        n = size(y0)
        call check_interval(t0, tf, y0, opt, info, msg, allow_inf=allow_inf)
        if (info /= CM_SUCCESS) return
        call tolerance_vectors(opt, n, self%rtol, self%atol, info, msg, &
                               rtol_min=epsilon(1.0_dp))
        if (info /= CM_SUCCESS) return
        self%eps = max(minval(self%rtol), minval(self%atol))
        self%order = taylor_order(self%eps)
        self%decay = taylor_decay(self%eps)
        call self%setup_base(METHOD_TAYLOR, t0, tf, y0, self%order, FORM_POWER)
        self%nblock = n
        if (self%kind == 1) self%nblock = nint((sqrt(4.0_dp*n + 1.0_dp) - 1.0_dp)/2.0_dp)
        if (self%kind == 1 .and. self%nblock*(self%nblock + 1) /= n) then
            info = CM_BAD_INPUT
            msg = "bad input: the variational system's state must have n + n**2 components"
            return
        end if
        self%t_lo = 0.0_dp
        call set_hmax(self, abs(opt%max_step), abs(tf - t0))
        self%first_step = opt%first_step
        self%max_steps = opt%max_steps
        self%nsteps = 0
        self%err = 0.0_dp
        self%nw = 0
        self%finite = .false.
        ! the arrays of an earlier run of the same size are kept (a Propagator's runs;
        ! `start` re-sizes the expansions when the order or the system differ)
        if (allocated(self%dy)) then
            if (size(self%dy) /= n) deallocate (self%dy, self%ynew, self%e)
        end if
        if (.not. allocated(self%dy)) allocate (self%dy(n), self%ynew(n), self%e(n))
    end subroutine taylor_init

    !> Continue from the end of the last run towards tf: the expansion at (t, y) is the
    !! one the last accepted step computed there, and a Taylor step keeps nothing else, so
    !! the steps are those of a new run from (t, y) (for a system that depends on t, up
    !! to the rounding of the time that expansion was made at, t_old + h_done), with one
    !! evaluation less. Only after a run that reached its end with f finite there.
    subroutine taylor_resume(self, tf, opt, resumed)
        class(taylor_stepper), intent(inout) :: self
        real(dp), intent(in) :: tf
        type(ode_options), intent(in) :: opt
        logical, intent(out) :: resumed
        resumed = .false.
        if (.not. (self%last .and. self%finite .and. allocated(self%jets))) return
        if (.not. (tf - self%t)*self%posneg > 0.0_dp) return
        if (associated(self%ev)) return
        ! a new run's state from (t, y), as init sets it (copies of t and y: setup_base
        ! writes both)
        call self%setup_base(METHOD_TAYLOR, (self%t), tf, [self%y(1:self%n)], self%order, &
                             FORM_POWER)
        call set_hmax(self, abs(opt%max_step), abs(tf - self%t))
        self%t_lo = 0.0_dp
        self%nsteps = 0
        self%err = 0.0_dp
        call first_proposal(self)
        resumed = .true.
    end subroutine taylor_resume

    !> The expansion at the initial point and the first step. A system without Taylor
    !! coefficients is CM_BAD_INPUT with a message saying so.
    subroutine taylor_start(self, sys, info, msg)
        class(taylor_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        info = CM_SUCCESS
        msg = "success"
        self%nw = sys%taylor_size(self%kind)
        if (self%nw < self%n) then
            info = CM_BAD_INPUT
            if (self%kind == 1) then
                msg = "bad input: the system has no Taylor coefficients of its variational "// &
                      "system (method TAYLOR)"
            else
                msg = "bad input: the system has no Taylor coefficients (method TAYLOR "// &
                      "needs a system from conmech.symbolic with a smooth right-hand "// &
                      "side, or a type that overrides taylor_size and taylor_jet)"
            end if
            return
        end if
        if (allocated(self%jets)) then
            if (any(shape(self%jets) /= [self%order + 1, self%nw, 2])) deallocate (self%jets)
        end if
        ! taylor_jet writes every coefficient it reads (the columns past the state are its
        ! work space), so the expansions are cleared once, when made, not at every start
        if (.not. allocated(self%jets)) then
            allocate (self%jets(0:self%order, self%nw, 2))
            self%jets = 0.0_dp
        end if
        self%ic = 1
        call expand(self, sys, self%jets(:, :, 1), self%t, self%y)
        if (.not. self%f_finite()) then
            info = CM_NONFINITE
            msg = "the right-hand side is not finite at the initial point"
            return
        end if
        call first_proposal(self)
    end subroutine taylor_start

    !> The expansion w at (t, y) (y copied into its zeroth coefficients), and whether f there
    !! is finite.
    subroutine expand(self, sys, w, t, y)
        class(taylor_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        real(dp), intent(inout) :: w(0:self%order, self%nw)
        real(dp), intent(in) :: t, y(self%n)
        integer :: i
        w(0, 1:self%n) = y
        call sys%taylor_jet(self%kind, t, self%order, self%nw, w)
        self%st%nfev = self%st%nfev + 1
        self%finite = .true.
        do i = 1, self%n
            if (.not. abs(w(1, i)) <= huge(1.0_dp)) self%finite = .false.
        end do
    end subroutine expand

    !> The largest step: max_step, at most the run's span (Inf or NaN: no bound).
    subroutine set_hmax(self, max_step, span)
        class(taylor_stepper), intent(inout) :: self
        real(dp), intent(in) :: max_step, span
        self%hmax = min(max_step, span)
        if (.not. self%hmax <= huge(1.0_dp)) self%hmax = huge(1.0_dp)
    end subroutine set_hmax

    !> A run's first step: Jorba and Zou's from the expansion at its start, or first_step.
    subroutine first_proposal(self)
        class(taylor_stepper), intent(inout) :: self
        call propose(self)
        if (self%first_step > 0.0_dp) self%h = min(self%first_step, self%hmax)*self%posneg
    end subroutine first_proposal

    !> Jorba and Zou's step from the current expansion (signed, at most hmax); the scales
    !! E_i at the current point are kept for the step's safety check.
    subroutine propose(self)
        class(taylor_stepper), intent(inout) :: self
        real(dp) :: rho
        call taylor_next_rho(self%n, self%nblock, self%order, self%jets(:, :, self%ic), &
                             self%rtol, self%atol, self%eps, self%decay, self%e, rho)
        self%h = min(rho, self%hmax)*self%posneg
    end subroutine propose

    !> One accepted step towards `target` (landing on it if the step would pass it). The
    !! candidate state is written by Horner straight into the other expansion's zeroth
    !! coefficients, the system expands there in place, and an accepted step makes that
    !! expansion the current one by flipping ic.
    subroutine taylor_step(self, sys, target, info, msg)
        class(taylor_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: target
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        real(dp) :: h, err, d
        integer :: p, n, ic, io
        logical :: fin
        ! msg is set on failure only (as the Runge-Kutta steppers): no allocation per step
        info = CM_SUCCESS
        p = self%order
        n = self%n
        ic = self%ic
        io = 3 - ic
        h = self%h
        self%last = .false.
        do
            if (self%nsteps >= self%max_steps) then
                info = CM_TOO_MANY_STEPS
                msg = "more than max_steps steps, at t ="//rtoa(self%t)
                return
            end if
            if (.not. (0.1_dp*abs(h) > abs(self%t)*epsilon(1.0_dp))) then
                info = CM_STEP_TOO_SMALL
                msg = "step size too small at t ="//rtoa(self%t)
                return
            end if
            self%hit = .false.
            if ((self%t + h - target)*self%posneg >= 0.0_dp) then
                h = (target - self%t) - self%t_lo
                self%hit = .true.
            end if
            if (associated(self%ev)) then
                d = h
                call limit_step(self%ev, self%t, p, self%jets(:, :, ic), h)
                if (h /= d) self%hit = .false.
            end if
            self%nsteps = self%nsteps + 1
            call taylor_eval_jet(n, p, self%jets(:, :, ic), h, self%jets(:, :, io), self%ynew, &
                                 self%dy)
            call sys%taylor_jet(self%kind, self%t + h, p, self%nw, self%jets(:, :, io))
            self%st%nfev = self%st%nfev + 1
            call taylor_check_jet(n, p, h, self%jets(:, :, io), self%dy, self%e, err, fin)
            if (err <= TAYLOR_CHECK_MAX) exit
            ! rejected (or not finite): a shorter step from the same expansion
            self%st%nreject = self%st%nreject + 1
            h = taylor_shrink(h, err, p)
        end do
        ! accept: the new expansion becomes the current one, the old the step's polynomial
        self%err = err
        self%finite = fin
        self%ic = io
        self%st%naccept = self%st%naccept + 1
        self%t_old = self%t
        ! sections, not whole allocatables: no reallocation check per step
        self%y_old(1:n) = self%y(1:n)
        if (self%hit) then
            self%t = target
            self%t_lo = 0.0_dp
        else
            call taylor_add_time(self%t, self%t_lo, h)
        end if
        self%y(1:n) = self%jets(0, 1:n, io)
        self%h_done = h
        self%dense_ready = .false.
        self%last = self%hit .and. target == self%tf
        call propose(self)
        self%st%h_next = self%h
    end subroutine taylor_step

    !> The continuous extension of the last step: fc(:, k) = y^[k] h^k (power form in
    !! x = (s - t_old)/h_done).
    subroutine taylor_dense(self, sys)
        class(taylor_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        real(dp) :: hk
        integer :: k
        hk = 1.0_dp
        do k = 0, self%order
            self%fc(:, k) = self%jets(k, 1:self%n, 3 - self%ic)*hk
            hk = hk*self%h_done
        end do
        self%dense_ready = .true.
    end subroutine taylor_dense

    !> The last step's Taylor polynomial at tt (in [t_old, t]): the step's own Horner
    !! chains, interleaved over the components (the derivative they also give goes to the
    !! scratch dy, unused between steps).
    subroutine taylor_eval(self, tt, yout, info, msg)
        class(taylor_stepper), intent(inout) :: self
        real(dp), intent(in) :: tt
        real(dp), intent(out) :: yout(:)
        integer, intent(out), optional :: info
        character(len=:), allocatable, intent(inout), optional :: msg
        call taylor_eval_step(self%n, self%order, self%jets(:, 1:self%n, 3 - self%ic), &
                              tt - self%t_old, yout, self%dy)
        if (present(info)) info = CM_SUCCESS
    end subroutine taylor_eval

    !> The same at x = (s - t_old)/h_done in [0, 1].
    subroutine taylor_eval_unit(self, x, yout, info, msg)
        class(taylor_stepper), intent(inout) :: self
        real(dp), intent(in) :: x
        real(dp), intent(out) :: yout(:)
        integer, intent(out), optional :: info
        character(len=:), allocatable, intent(inout), optional :: msg
        call taylor_eval(self, self%t_old + x*self%h_done, yout, info, msg)
    end subroutine taylor_eval_unit

    !> After a hook changed y: the expansion at the new point (and a new step).
    subroutine taylor_refresh(self, sys)
        class(taylor_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        call expand(self, sys, self%jets(:, :, self%ic), self%t, self%y)
        call propose(self)
        self%f_stale = .false.
    end subroutine taylor_refresh

    !> f at the current point finite (found by the expansion's own pass over it:
    !! comparisons, no ieee_arithmetic, whose procedures save and restore the
    !! floating-point state on every call).
    logical function taylor_f_finite(self)
        class(taylor_stepper), intent(in) :: self
        taylor_f_finite = allocated(self%jets) .and. self%finite
    end function taylor_f_finite

    !> The whole state, for step-by-step use (the state parts of both expansions; the
    !! operations' columns are scratch, recomputed by the next expansion). A state packed
    !! before the first expansion (init only, or a start that failed) holds zero
    !! coefficients. The scales E_i of the step's safety check are a function of y and the
    !! tolerances: recomputed on reading, as `propose` computed them.
    subroutine taylor_transfer(self, p)
        class(taylor_stepper), intent(inout) :: self
        type(state_packer), intent(inout) :: p
        real(dp), allocatable :: a(:, :), b(:, :)
        call self%transfer_base(p)
        call p%item(self%kind)
        call p%item(self%nblock)
        call p%item(self%order)
        call p%item(self%nw)
        call p%item(self%t_lo)
        call p%item(self%hmax)
        call p%item(self%first_step)
        call p%item(self%eps)
        call p%item(self%decay)
        call p%item(self%err)
        call p%item(self%nsteps)
        call p%item(self%max_steps)
        call p%column(self%rtol)
        call p%column(self%atol)
        if (.not. p%reading()) then
            ! the columns 0..order of the packed layout (explicit bounds: an assignment of
            ! the transpose would give them the bounds 1..order + 1)
            allocate (a(self%n, 0:self%order), b(self%n, 0:self%order))
            a = 0.0_dp
            b = 0.0_dp
            if (allocated(self%jets) .and. self%nw > 0) then      ! started
                a(:, :) = transpose(self%jets(:, 1:self%n, self%ic))
                b(:, :) = transpose(self%jets(:, 1:self%n, 3 - self%ic))
            end if
        end if
        call p%columns(a, 0, self%order)
        call p%columns(b, 0, self%order)
        if (p%reading()) then
            if (allocated(self%jets)) deallocate (self%jets)
            allocate (self%jets(0:self%order, max(self%nw, self%n), 2))
            self%jets = 0.0_dp
            self%ic = 1
            if (allocated(a)) self%jets(:, 1:self%n, 1) = transpose(a)
            if (allocated(b)) self%jets(:, 1:self%n, 2) = transpose(b)
            self%finite = all(abs(self%jets(1, 1:self%n, 1)) <= huge(1.0_dp))
            if (allocated(self%dy)) deallocate (self%dy, self%ynew, self%e)
            allocate (self%dy(self%n), self%ynew(self%n), self%e(self%n))
            self%dy = 0.0_dp
            self%ynew = 0.0_dp
            call taylor_scales(self%n, self%nblock, self%y, self%rtol, self%atol, self%e)
        end if
    end subroutine taylor_transfer

    !> Advance y from t0 to t1 in place by Taylor's method (kind 0: the system, kind 1: its
    !! variational system, y = [y; Phi]), storing nothing: the lean path for shooting and
    !! ensembles.
    subroutine taylor_propagate(sys, t0, t1, y, opt, info, stats, msg, kind)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t0, t1
        real(dp), intent(inout) :: y(:)
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        type(ode_stats), intent(out) :: stats
        character(len=:), allocatable, intent(out) :: msg
        integer, intent(in), optional :: kind
        type(taylor_stepper) :: stp
        character(len=:), allocatable :: smsg
        stats = ode_stats()
        if (present(kind)) stp%kind = kind
        call stp%init(t0, t1, y, opt, info, msg)
        if (info /= CM_SUCCESS .or. t1 == t0) return
        call stp%start(sys, info, msg)
        if (info /= CM_SUCCESS) then
            stats = stp%st
            return
        end if
        do
            call stp%step(sys, t1, info, smsg)        ! smsg: set on failure only
            if (info /= CM_SUCCESS) then
                msg = smsg
                exit
            end if
            if (.not. stp%f_finite()) then
                info = CM_NONFINITE
                msg = "non-finite right-hand side at t ="//rtoa(stp%t)
                exit
            end if
            if (stp%last) exit
        end do
        y = stp%y
        stats = stp%st
    end subroutine taylor_propagate

end module conmech_taylor_stepper
