!> The integrator contract: an abstract stepper that every method extends (explicit
!! Runge-Kutta, Radau IIA, Gauss-Legendre, RATTLE, ...), and ONE driver loop
!! (conmech_ode_driver) that runs any of them with outputs, t_eval, events, a step hook and
!! the result. The anchors are SciPy's OdeSolver (a method is a class with `_step_impl`
!! and `_dense_output_impl`) and FLINT's ERK class.
!!
!! Life of a stepper, as the driver (or a user stepping by hand) calls it:
!!
!!     call stp%init(t0, tf, y0, opt, info, msg)  ! check the options (setup: the method's
!!                                                 ! part); no evaluation of f
!!     call stp%start(sys, info, msg)             ! f at t0, the initial step
!!     do
!!         call stp%step(sys, target, info, msg)  ! one ACCEPTED step (its own control)
!!         call stp%dense(sys)                     ! the step's continuous extension ...
!!         call stp%eval(t, y, info, msg)          ! ... evaluated in [t_old, t]
!!         if (stp%last) exit
!!     end do
!!
!! After `step`, (t_old, y_old) is the start of the accepted step, (t, y) its end, h_done
!! its signed length, h the step to try next, `last` whether it reached tf. The
!! continuous extension of the step is a polynomial in x = (s - t_old)/h_done with the
!! coefficients fc(:, 0:nf) in the form `form` (conmech_ode_dense: FORM_HAIRER or
!! FORM_POWER), which `dense_solution` stores segment by segment; a method without a
!! polynomial (nf = 0: RATTLE's side step) overrides `eval` and `eval_unit` instead.
!!
!! `transfer_state` names every piece of the state once (conmech_state_packer), which packs
!! the whole stepper into plain arrays and back: the Python step-by-step objects keep those
!! arrays, so nothing is kept in Fortran between calls. Its common part (`transfer_base`)
!! comes first, at fixed positions for every method (PACK_* below).
!!
!! A new method is one type extending `ode_stepper` (setup (or init), start, step,
!! transfer_state; dense, eval, refresh_f, f_finite when the defaults do not fit) and one
!! entry in the method table (conmech_ode_methods); docs/guide/adding_an_integrator.rst
!! walks through it.
!! Everything is in the object: distinct steppers may run in distinct threads.
module conmech_ode_stepper
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: ode_options, ode_stats
    use conmech_ode_dense, only: FORM_HAIRER, FORM_POWER, interp
    use conmech_state_packer, only: state_packer, packer_write, packer_ready, &
        packer_attach_read, packer_attach_write
    implicit none
    private

    public :: ode_stepper, check_interval, check_first_step, tolerance_vectors, check_t_eval
    public :: stepper_pack, stepper_pack_into, stepper_unpack, stepper_init, min_step_at
    public :: MSG_STEP_TOO_SMALL, MSG_TOO_MANY_STEPS
    public :: FORM_HAIRER, FORM_POWER

    !> Fixed positions of the common part of a packed state (1-based): reals r(PACK_R_*),
    !! integers iv(PACK_I_*), columns w(:, PACK_W_*); the dense coefficients fc(:, 0:nf)
    !! are the columns PACK_W_FC .. PACK_W_FC + nf.
    integer, parameter, public :: PACK_R_T = 1, PACK_R_TOLD = 2, PACK_R_TF = 3, &
        PACK_R_H = 5, PACK_R_HDONE = 6
    integer, parameter, public :: PACK_I_METHOD = 1, PACK_I_N = 2, PACK_I_NF = 3, &
        PACK_I_FORM = 4, PACK_I_NFEV = 5, PACK_I_NJEV = 6, PACK_I_NLU = 7, &
        PACK_I_NACCEPT = 8, PACK_I_NREJECT = 9, PACK_I_LAST = 10
    integer, parameter, public :: PACK_W_Y = 1, PACK_W_YOLD = 2, PACK_W_FC = 3

    character(len=*), parameter :: MSG_NOT_STARTED = "bad input: the packed state was "// &
        "not started for this method (action 0 first) or has the wrong size"

    !> The failure of an adaptive step below `min_step_at` (followed by the time).
    character(len=*), parameter :: MSG_STEP_TOO_SMALL = "step size too small (the "// &
        "required step size is less than 10 spacings between numbers) at t ="
    !> The end of an adaptive run on max_steps (followed by the time).
    character(len=*), parameter :: MSG_TOO_MANY_STEPS = "too many steps: max_steps " &
        //"reached at t ="

    !> The state every stepper has, and the contract of its procedures.
    type, abstract :: ode_stepper
        integer :: method = 0                !! METHOD_* code (conmech_ode_options)
        integer :: n = 0                     !! dimension of y
        real(dp) :: t = 0.0_dp               !! current time (end of the last step)
        real(dp) :: t_old = 0.0_dp           !! start of the last step
        real(dp) :: tf = 0.0_dp              !! end of the interval (may be +-inf by hand)
        real(dp) :: posneg = 1.0_dp          !! direction of integration
        real(dp) :: h = 0.0_dp               !! step to try next (signed)
        real(dp) :: h_done = 0.0_dp          !! length of the last accepted step (signed)
        logical :: last = .false.            !! the last step reached tf
        logical :: hit = .false.             !! the last step was shortened onto `target`
        !> the method can shorten a step to land on a target (false on a fixed grid:
        !! Gauss, RATTLE; the driver then evaluates outputs on the continuous extension)
        logical :: lands_on_target = .true.
        !> set by the driver: a hook follows every step and calls `refresh_f` when
        !! `f_stale`, so the method may skip evaluating f at the step's end
        logical :: defer_f = .false.
        logical :: f_stale = .false.         !! f(t, y) is not evaluated yet (deferred)
        logical :: dense_ready = .false.     !! fc holds the last step's extension
        integer :: nf = 0                    !! degree of the extension (0: none)
        integer :: form = FORM_POWER         !! FORM_HAIRER or FORM_POWER
        type(ode_stats) :: st                !! counters (nfev, naccept, nreject, njev, nlu)
        real(dp), allocatable :: y(:)        !! state at t
        real(dp), allocatable :: y_old(:)    !! state at t_old
        real(dp), allocatable :: fc(:, :)    !! (n, 0:nf) extension of the last step
    contains
        !> Check the options and set the stepper up at (t0, y0) for [t0, tf]: no
        !! evaluation of f. Problem data a caller set on the object before (Radau's mass
        !! matrix) is kept. allow_inf: tf may be infinite (stepping by hand). The default
        !! makes the checks every method makes (`check_interval`), sets the common state
        !! and calls `setup` for the method's part; a method overrides `setup` (or `init`).
        procedure :: init => stepper_init
        !> The method's part of `init`, called with the common state set (t, tf, posneg,
        !! n, y; nf = 0): its own checks (`check_first_step`, tolerances), constants, nf and
        !! form of its extension, arrays. info /= CM_SUCCESS with msg on bad input.
        procedure :: setup => stepper_setup
        !> f at the initial point and the initial step (counted in st%nfev).
        procedure(stepper_start), deferred :: start
        !> Attempt steps with the method's own control until one is accepted, then advance
        !! (see the module documentation). A step that would pass `target` (tf, or an
        !! output point the driver wants to land on) is shortened onto it (Hairer's rule:
        !! stretched by up to 1 %) where `lands_on_target`; `last` when it reached tf.
        !! info: CM_SUCCESS, or the failure (too many steps, step too small, non-finite
        !! values, no convergence) with the time in msg.
        procedure(stepper_step), deferred :: step
        !> Name every piece of the state, in order, to the packer (pack or unpack by the
        !! same list; begin with `call self%transfer_base(p)`).
        procedure(stepper_transfer), deferred :: transfer_state
        !> Build fc for the last step (default: nothing; the step built it). Explicit
        !! Runge-Kutta pairs evaluate their extra stages here, only when asked.
        procedure :: dense => stepper_dense
        !> The continuous extension of the last step at time tt in [t_old, t] (after
        !! `dense`; default: fc at x = (tt - t_old)/h_done). Optional info /= CM_SUCCESS
        !! and msg when a method's evaluation can fail (RATTLE's side step).
        procedure :: eval => stepper_eval
        !> The same at x = (s - t_old)/h_done in [0, 1] (Brent's abscissa of event
        !! location; default: fc at x).
        procedure :: eval_unit => stepper_eval_unit
        !> Re-evaluate what the method keeps of f(t, y) after a hook changed y (or when
        !! `f_stale`); default: nothing kept.
        procedure :: refresh_f => stepper_refresh_f
        !> Whether f at the current point is finite (default: true, nothing kept).
        procedure :: f_finite => stepper_f_finite
        !> Continue, towards a new end tf ahead in the same direction, a stepper that
        !! stands where its last run reached its end, instead of `init` and `start` there
        !! (the options are the last run's): resumed = .true. when the method then steps
        !! as a new run from (t, y) would (it keeps nothing of earlier steps but what it
        !! computed at t: Taylor's expansion), else .false. (the default) and the caller
        !! starts a new run.
        procedure :: resume => stepper_resume
        !> The common part of the state (first in every `transfer_state`).
        procedure, non_overridable :: transfer_base => stepper_transfer_base
        !> Set the common state up at (t0, y0) (for `init`): method, n, interval,
        !! direction, y, y_old, fc(:, 0:nf) in `form`, cleared counters and flags.
        procedure, non_overridable :: setup_base => stepper_setup_base
    end type ode_stepper

    abstract interface
        subroutine stepper_start(self, sys, info, msg)
            import :: ode_stepper, ode_system
            class(ode_stepper), intent(inout) :: self
            class(ode_system), intent(in) :: sys
            integer, intent(out) :: info
            character(len=:), allocatable, intent(out) :: msg
        end subroutine stepper_start
        subroutine stepper_step(self, sys, target, info, msg)
            import :: ode_stepper, ode_system, dp
            class(ode_stepper), intent(inout) :: self
            class(ode_system), intent(in) :: sys
            real(dp), intent(in) :: target
            integer, intent(out) :: info
            character(len=:), allocatable, intent(out) :: msg
        end subroutine stepper_step
        subroutine stepper_transfer(self, p)
            import :: ode_stepper, state_packer
            class(ode_stepper), intent(inout) :: self
            type(state_packer), intent(inout) :: p
        end subroutine stepper_transfer
    end interface

contains

    subroutine stepper_init(self, t0, tf, y0, opt, info, msg, allow_inf)
        class(ode_stepper), intent(inout) :: self
        real(dp), intent(in) :: t0, tf
        real(dp), intent(in) :: y0(:)
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        logical, intent(in), optional :: allow_inf
        call check_common(t0, tf, y0, opt, info, msg, allow_inf)
        if (info /= CM_SUCCESS) return
        call self%setup_base(opt%method, t0, tf, y0, 0, FORM_POWER)
        call self%setup(opt, info, msg)
        if (info /= CM_SUCCESS) return
        if (ubound(self%fc, 2) /= self%nf) then
            deallocate (self%fc)
            allocate (self%fc(self%n, 0:self%nf))
            self%fc = 0.0_dp
        end if
    end subroutine stepper_init

    subroutine stepper_setup(self, opt, info, msg)
        class(ode_stepper), intent(inout) :: self
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        info = CM_BAD_INPUT
        msg = "bad input: the stepper overrides neither init nor setup"
    end subroutine stepper_setup

    !> The step option of a method (for `setup`, with t and tf set): `step_option` on
    !! [t, tf].
    subroutine check_first_step(self, opt, info, msg, fixed)
        class(ode_stepper), intent(in) :: self
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        character(len=*), intent(in), optional :: fixed
        call step_option(self%t, self%tf, opt, info, msg, fixed)
    end subroutine check_first_step

    subroutine stepper_dense(self, sys)
        class(ode_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        self%dense_ready = .true.
    end subroutine stepper_dense

    subroutine stepper_eval(self, tt, yout, info, msg)
        class(ode_stepper), intent(inout) :: self
        real(dp), intent(in) :: tt
        real(dp), intent(out) :: yout(:)
        integer, intent(out), optional :: info
        character(len=:), allocatable, intent(inout), optional :: msg
        call interp(self%fc, self%form, (tt - self%t_old)/self%h_done, yout)
        if (present(info)) info = CM_SUCCESS
    end subroutine stepper_eval

    subroutine stepper_eval_unit(self, x, yout, info, msg)
        class(ode_stepper), intent(inout) :: self
        real(dp), intent(in) :: x
        real(dp), intent(out) :: yout(:)
        integer, intent(out), optional :: info
        character(len=:), allocatable, intent(inout), optional :: msg
        call interp(self%fc, self%form, x, yout)
        if (present(info)) info = CM_SUCCESS
    end subroutine stepper_eval_unit

    subroutine stepper_refresh_f(self, sys)
        class(ode_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        self%f_stale = .false.
    end subroutine stepper_refresh_f

    subroutine stepper_resume(self, tf, opt, resumed)
        class(ode_stepper), intent(inout) :: self
        real(dp), intent(in) :: tf
        type(ode_options), intent(in) :: opt
        logical, intent(out) :: resumed
        resumed = .false.
    end subroutine stepper_resume

    logical function stepper_f_finite(self)
        class(ode_stepper), intent(in) :: self
        stepper_f_finite = .true.
    end function stepper_f_finite

    subroutine stepper_setup_base(self, method, t0, tf, y0, nf, form)
        class(ode_stepper), intent(inout) :: self
        integer, intent(in) :: method
        real(dp), intent(in) :: t0, tf, y0(:)
        integer, intent(in) :: nf, form
        self%method = method
        self%n = size(y0)
        self%t = t0
        self%t_old = t0
        self%tf = tf
        self%posneg = sign(1.0_dp, tf - t0)
        self%h = 0.0_dp
        self%h_done = 0.0_dp
        self%last = .false.
        self%hit = .false.
        self%f_stale = .false.
        self%dense_ready = .false.
        self%nf = nf
        self%form = form
        self%st = ode_stats()
        self%y = y0
        self%y_old = y0
        ! (kept from an earlier run of the same shape)
        if (allocated(self%fc)) then
            if (size(self%fc, 1) /= self%n .or. lbound(self%fc, 2) /= 0 .or. &
                ubound(self%fc, 2) /= nf) deallocate (self%fc)
        end if
        if (.not. allocated(self%fc)) allocate (self%fc(self%n, 0:nf))
        self%fc = 0.0_dp
    end subroutine stepper_setup_base

    subroutine stepper_transfer_base(self, p)
        class(ode_stepper), intent(inout) :: self
        type(state_packer), intent(inout) :: p
        ! iv: PACK_I_METHOD .. PACK_I_LAST, then the other flags
        call p%item(self%method)
        call p%item(self%n)
        call p%item(self%nf)
        call p%item(self%form)
        call p%item(self%st%nfev)
        call p%item(self%st%njev)
        call p%item(self%st%nlu)
        call p%item(self%st%naccept)
        call p%item(self%st%nreject)
        call p%item(self%last)
        call p%item(self%hit)
        call p%item(self%lands_on_target)
        call p%item(self%defer_f)
        call p%item(self%f_stale)
        call p%item(self%dense_ready)
        ! r: PACK_R_T .. PACK_R_HDONE, h_next
        call p%item(self%t)
        call p%item(self%t_old)
        call p%item(self%tf)
        call p%item(self%posneg)
        call p%item(self%h)
        call p%item(self%h_done)
        call p%item(self%st%h_next)
        ! w: PACK_W_Y, PACK_W_YOLD, PACK_W_FC ..
        call p%column(self%y)
        call p%column(self%y_old)
        call p%columns(self%fc, 0, self%nf)
    end subroutine stepper_transfer_base

    !> Pack the whole state of stp into the packer's arrays (p%r(1:p%nr), p%iv(1:p%ni),
    !! p%w(:, 1:p%nw)).
    subroutine stepper_pack(stp, p)
        class(ode_stepper), intent(inout) :: stp
        type(state_packer), intent(out) :: p
        call packer_write(p, stp%n)
        call stp%transfer_state(p)          ! count the sizes
        call packer_ready(p)
        call stp%transfer_state(p)          ! write
    end subroutine stepper_pack

    !> Pack the whole state of stp into the caller's arrays in place (no count pass, no
    !! allocation): sizes = [nr, ni, nw] of the state; info = CM_BAD_INPUT when it does not
    !! fit (sizes are then what it needs, the arrays partly written).
    subroutine stepper_pack_into(stp, r, iv, w, sizes, info)
        class(ode_stepper), intent(inout) :: stp
        real(dp), intent(inout), target, contiguous :: r(:)
        integer, intent(inout), target, contiguous :: iv(:)
        real(dp), intent(inout), target, contiguous :: w(:, :)
        integer, intent(out) :: sizes(3)
        integer, intent(out) :: info
        type(state_packer) :: p
        call packer_attach_write(p, r, iv, w)
        call stp%transfer_state(p)
        sizes = [p%nr, p%ni, p%nw]
        info = p%info
    end subroutine stepper_pack_into

    !> Rebuild stp from a state packed by `stepper_pack` (or `stepper_pack_into`) for
    !! `method`, read in place; CM_BAD_INPUT when (r, iv, w) does not hold a started state
    !! of this method and dimension.
    subroutine stepper_unpack(stp, method, r, iv, w, info, msg)
        class(ode_stepper), intent(inout) :: stp
        integer, intent(in) :: method
        real(dp), intent(in), target, contiguous :: r(:)
        integer, intent(in), target, contiguous :: iv(:)
        real(dp), intent(in), target, contiguous :: w(:, :)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(state_packer) :: p
        info = CM_BAD_INPUT
        if (size(iv) < PACK_I_LAST .or. size(w, 2) < PACK_W_FC) then
            msg = MSG_NOT_STARTED
            return
        end if
        if (iv(PACK_I_METHOD) /= method .or. iv(PACK_I_N) /= size(w, 1)) then
            msg = MSG_NOT_STARTED
            return
        end if
        call packer_attach_read(p, r, iv, w)
        call stp%transfer_state(p)
        if (p%info /= CM_SUCCESS) then
            msg = MSG_NOT_STARTED
            return
        end if
        info = CM_SUCCESS
        msg = "success"
    end subroutine stepper_unpack

    !> The checks of `init` with the step option (for a method that overrides `init`):
    !! `check_common`, then `check_first_step`'s rule on first_step as if t = t0 and
    !! tf = tf (with `fixed`, the name of a fixed-step method: first_step is the step).
    subroutine check_interval(t0, tf, y0, opt, info, msg, fixed, allow_inf)
        real(dp), intent(in) :: t0, tf, y0(:)
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        character(len=*), intent(in), optional :: fixed
        logical, intent(in), optional :: allow_inf
        call check_common(t0, tf, y0, opt, info, msg, allow_inf)
        if (info /= CM_SUCCESS) return
        call step_option(t0, tf, opt, info, msg, fixed)
    end subroutine check_interval

    !> The checks every method makes in `init`: y0 non-empty and finite, t0 and tf finite
    !! (tf may be infinite if allow_inf), max_step > 0, first_step >= 0, max_steps >= 1.
    !! info = CM_BAD_INPUT with a message naming the argument.
    subroutine check_common(t0, tf, y0, opt, info, msg, allow_inf)
        real(dp), intent(in) :: t0, tf, y0(:)
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        logical, intent(in), optional :: allow_inf
        logical :: inf_ok
        inf_ok = .false.
        if (present(allow_inf)) inf_ok = allow_inf
        info = CM_BAD_INPUT
        if (size(y0) < 1) then
            msg = "bad input: y0 is empty"
        else if (.not. all(abs(y0) <= huge(1.0_dp))) then
            msg = "bad input: y0 contains NaN or Inf"
        else if (.not. ((abs(t0) <= huge(1.0_dp)) .and. ((abs(tf) <= huge(1.0_dp)) .or. &
                                                  (inf_ok .and. tf == tf)))) then
            msg = "bad input: t_span must be finite"
        else if (.not. opt%max_step > 0.0_dp) then
            msg = "bad input: max_step must be positive"
        else if (.not. opt%first_step >= 0.0_dp) then
            msg = "bad input: first_step must be positive"
        else if (opt%max_steps < 1) then
            msg = "bad input: max_steps must be positive"
        else
            info = CM_SUCCESS
            msg = "success"
        end if
    end subroutine check_common

    !> The step option on [t0, tf]: with `fixed` (the method's name) first_step is the
    !! step, required, and the interval finite; else first_step (0: the method's
    !! heuristic) is not longer than the interval.
    subroutine step_option(t0, tf, opt, info, msg, fixed)
        real(dp), intent(in) :: t0, tf
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        ! inout: every branch sets it, and a message of the same length (the success of
        ! the checks before) is overwritten in place rather than freed and allocated again
        character(len=:), allocatable, intent(inout) :: msg
        character(len=*), intent(in), optional :: fixed
        info = CM_BAD_INPUT
        if (present(fixed)) then
            if (.not. (opt%first_step > 0.0_dp .and. opt%first_step < huge(1.0_dp))) then
                msg = "bad input: "//fixed//" is a fixed-step method and needs a step "// &
                      "(first_step > 0)"
                return
            else if (.not. (abs(tf) <= huge(1.0_dp))) then
                msg = "bad input: t_span must be finite"
                return
            end if
        else if (opt%first_step > abs(tf - t0) .and. tf /= t0) then
            msg = "bad input: first_step exceeds the length of t_span"
            return
        end if
        info = CM_SUCCESS
        msg = "success"
    end subroutine step_option

    !> Per-component tolerances from the options (rtol raised to rtol_min, default 100 eps
    !! as SciPy; Taylor's method goes down to eps).
    subroutine tolerance_vectors(opt, n, rtolv, atolv, info, msg, rtol_min)
        type(ode_options), intent(in) :: opt
        integer, intent(in) :: n
        real(dp), allocatable, intent(out) :: rtolv(:), atolv(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(inout) :: msg     ! set on every path
        real(dp), intent(in), optional :: rtol_min
        logical :: ok
        allocate (rtolv(n), atolv(n))
        info = CM_BAD_INPUT
        call per_component(opt%rtol, opt%rtol_vec, "rtol", rtolv, ok)
        if (.not. ok) return
        call per_component(opt%atol, opt%atol_vec, "atol", atolv, ok)
        if (.not. ok) return
        if (.not. all(rtolv >= 0.0_dp)) then
            msg = "bad input: rtol must be non-negative"
            return
        end if
        if (.not. all(atolv >= 0.0_dp)) then
            msg = "bad input: atol must be non-negative"
            return
        end if
        if (present(rtol_min)) then
            rtolv = max(rtolv, rtol_min)
        else
            rtolv = max(rtolv, 100.0_dp*epsilon(1.0_dp))
        end if
        info = CM_SUCCESS
        msg = "success"
    contains
        !> v = the options' vector `name`_vec where given (it must have the size of y0),
        !! else the scalar tolerance in every component; not ok (and the message) otherwise.
        subroutine per_component(scalar, vec, name, v, ok)
            real(dp), intent(in) :: scalar
            real(dp), allocatable, intent(in) :: vec(:)
            character(len=*), intent(in) :: name
            real(dp), intent(inout) :: v(:)
            logical, intent(out) :: ok
            ok = .true.
            if (.not. allocated(vec)) then
                v = scalar
            else if (size(vec) /= n) then
                ok = .false.
                msg = "bad input: "//name//" must be a scalar or have the size of y0"
            else
                v = vec
            end if
        end subroutine per_component
    end subroutine tolerance_vectors

    !> The smallest step of the adaptive methods at t in the direction posneg: 10 times the
    !! distance from t to the next double that way (SciPy's OdeSolver min_step). A step
    !! proposed below it by the step control is raised to it once (SciPy's rule); an
    !! attempt below it (after rejections, or a max_step below it) ends the run.
    elemental real(dp) function min_step_at(t, posneg) result(hmin)
        real(dp), intent(in) :: t, posneg
        hmin = 10.0_dp*abs(nearest(t, posneg) - t)
    end function min_step_at

    !> Check t_eval: finite, inside t_span, sorted in the direction of integration.
    subroutine check_t_eval(t0, tf, t_eval, info, msg)
        real(dp), intent(in) :: t0, tf, t_eval(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: i
        info = CM_BAD_INPUT
        if (.not. all(abs(t_eval) <= huge(1.0_dp))) then
            msg = "bad input: t_eval contains non-finite values"
            return
        end if
        do i = 1, size(t_eval)
            if ((t_eval(i) - t0)*(tf - t_eval(i)) < 0.0_dp) then
                msg = "bad input: t_eval values must lie in t_span"
                return
            end if
            ! max(i - 1, 1): at i = 1 the difference is 0 (nothing to compare)
            if ((t_eval(i) - t_eval(max(i - 1, 1)))*(tf - t0) < 0.0_dp) then
                msg = "bad input: t_eval must be sorted in the direction of integration"
                return
            end if
        end do
        info = CM_SUCCESS
        msg = "success"
    end subroutine check_t_eval

end module conmech_ode_stepper
