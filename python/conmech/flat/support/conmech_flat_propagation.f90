!> A propagation kept between calls of the flat layer (conmech.Propagator, and solve_ivp's
!! calls of a small system with the same method and tolerances): a built-in or compiled
!! system, its stepper and options, made once and held in Fortran memory that the caller
!! owns through a handle (flat_propagation_new / _until / _grid / _solve / _free). Each
!! propagation is a run of its own from the state the caller passes, by the one driver
!! loop over the kept stepper (init, start and steps, as flat_solve_packed runs it): the
!! same steps and the same bits as that call, without the per-call cost of making the
!! system and the stepper, of the run's result and of the packed arguments' conversion.
!!
!! The system reads its parameters at every call, as the packed route does: a call with
!! parameter values other than the kept ones makes the system again from them.
module conmech_flat_propagation
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t, c_ptr, c_f_pointer, &
        c_intptr_t
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: ode_options, ode_stats
    use conmech_ode_stepper, only: ode_stepper
    use conmech_ode_methods, only: new_stepper
    use conmech_ode_driver, only: ode_drive
    use conmech_ode_result, only: ode_result, start_outputs
    use conmech_ode_solver, only: METHOD_DOPRI5, ode_solve
    use conmech_flat_spec, only: spec_system_of_size
    use conmech_flat_ode_support, only: set_flat_options, set_jacobian_structure, &
        scipy_first_step, METHOD_RK45_SCIPY
    use conmech_flat_packed_support, only: put_message
    implicit none
    private
    public :: kept_propagation, propagation_make, propagation_at, propagation_run, &
        propagation_grid, propagation_solve

    !> What a propagation keeps from call to call.
    type :: kept_propagation
        integer :: n = 0
        character(len=:), allocatable :: name
        integer :: nspec = 0
        integer(c_int64_t), allocatable :: spec(:)
        real(dp), allocatable :: params(:)      !! the values the system was made with
        class(ode_system), allocatable :: sys
        class(ode_stepper), allocatable :: stp
        type(ode_options) :: opt
        logical :: scipy_rk45 = .false.         !! SciPy's initial step at every run ...
        real(dp) :: first_step = 0.0_dp         !! ... unless a first step is given
        !> a run that starts where the last one ended continues its stepper
        !! (ode_stepper%resume: Taylor's steps keep nothing but the expansion at their
        !! end), unless the system was made again since
        logical :: resumable = .true.
    end type kept_propagation

contains

    !> The propagation of the system `name` (parameters params, function table
    !! spec(1:nspec)) of size n with the packed options ipar = [np, nspec, method,
    !! max_steps, ...] and rpar = [first_step, max_step, rtol(1:n), atol(1:n), ...] of
    !! flat_solve_packed. info /= CM_SUCCESS with msg on bad input.
    subroutine propagation_make(name, params, nspec, spec, ipar, rpar, n, p, info, msg)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        integer, intent(in) :: nspec, n
        integer(c_int64_t), intent(in) :: spec(:)
        integer(c_int), intent(in) :: ipar(:)
        real(c_double), intent(in) :: rpar(:)
        type(kept_propagation), intent(inout) :: p
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer(c_int) :: none(1)
        p%n = n
        p%name = name
        p%nspec = nspec
        p%spec = spec(1:max(nspec, 1))
        p%params = params
        call spec_system_of_size(name, params, nspec, spec, n, "", p%sys, info, msg)
        if (info /= CM_SUCCESS) return
        call set_flat_options(p%opt, ipar(3), rpar(3:2 + n), rpar(3 + n:2 + 2*n), rpar(1), &
                              rpar(2), ipar(4), 0)
        ! every caller reads the points up to res%nt: no final copy to cut the arrays
        p%opt%trim_outputs = .false.
        p%scipy_rk45 = ipar(3) == METHOD_RK45_SCIPY
        p%first_step = rpar(1)
        if (p%scipy_rk45) then
            p%opt%method = METHOD_DOPRI5
            p%opt%beta = 0.0_dp
            p%opt%stretch = 0.0_dp
        end if
        call new_stepper(p%opt%method, p%stp, info, msg)
        if (info /= CM_SUCCESS) return
        none = 0
        call set_jacobian_structure(p%stp, int(n, c_int), 0, -1, none, none, info, msg)
    end subroutine propagation_make

    !> The propagation at `handle` (made by flat_propagation_new), or a null pointer with
    !! a refusal in iout (cleared first) when there is none or (n, lp given) the state's
    !! size is not its size or lp is below its number of parameters.
    function propagation_at(handle, n, lp, iout) result(p)
        integer(c_int64_t), intent(in) :: handle
        integer(c_int), intent(in), optional :: n, lp
        integer(c_int64_t), intent(inout), optional :: iout(40)
        type(kept_propagation), pointer :: p
        type(c_ptr) :: cp
        p => null()
        if (present(iout)) iout = 0
        if (handle /= 0) then
            cp = transfer(int(handle, c_intptr_t), cp)
            call c_f_pointer(cp, p)
            if (.not. (present(n) .and. present(lp))) return
            if (n == p%n .and. lp >= size(p%params)) return
        end if
        p => null()
        if (.not. present(iout)) return
        iout(7) = CM_BAD_INPUT
        call put_message("bad input: no propagation at this handle, or the state's size "// &
                         "or the number of parameters is not the propagation's", iout)
    end function propagation_at

    !> One propagation of y from t0 to t1 with the parameters params (as many as the
    !! propagation was made with; y is left as it was unless the run reached t1: info >=
    !! 0); counts = [nfev, njev, nlu, naccept, nreject] of the run.
    subroutine propagation_run(p, params, t0, t1, y, counts, info, msg)
        type(kept_propagation), intent(inout) :: p
        real(dp), intent(in) :: params(:)
        real(dp), intent(in) :: t0, t1
        real(dp), intent(inout) :: y(:)
        integer(c_int), intent(out) :: counts(5)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(ode_stats) :: st
        real(dp) :: yr(size(y))
        integer(c_int) :: nfev
        counts = 0
        call prepare_run(p, params, t0, t1, y, nfev, info, msg)
        if (info /= CM_SUCCESS) return
        yr = y
        call ode_drive(p%stp, p%sys, t0, t1, yr, p%opt, st, info, msg, resume=p%resumable)
        p%resumable = .true.
        counts = [nfev + st%nfev, st%njev, st%nlu, st%naccept, st%nreject]
        if (info >= 0) y = yr
    end subroutine propagation_run

    !> The states at the times `times` (sorted from t0 towards their last) into out(:, j)
    !! by one run from (t0, y) to the last time, as solve_ivp with t_eval gives them (the
    !! steps' continuous extension between their ends); nt the number of times reached,
    !! y the state at the last of them.
    subroutine propagation_grid(p, params, t0, times, y, out, nt, counts, info, msg)
        type(kept_propagation), intent(inout) :: p
        real(dp), intent(in) :: params(:)
        real(dp), intent(in) :: t0, times(:)
        real(dp), intent(inout) :: y(:)
        real(dp), intent(inout) :: out(:, :)
        integer, intent(out) :: nt
        integer(c_int), intent(out) :: counts(5)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(ode_result) :: res
        type(ode_stats) :: st
        real(dp) :: yr(size(y))
        integer(c_int) :: nfev
        integer :: m
        counts = 0
        nt = 0
        m = size(times)
        call prepare_run(p, params, t0, times(m), y, nfev, info, msg)
        if (info /= CM_SUCCESS) return
        yr = y
        call start_outputs(res, p%n)
        call ode_drive(p%stp, p%sys, t0, times(m), yr, p%opt, st, info, msg, res=res, &
                       t_eval=times, resume=p%resumable)
        p%resumable = .true.
        counts = [nfev + st%nfev, st%njev, st%nlu, st%naccept, st%nreject]
        nt = min(res%nt, m)
        if (nt > 0) then
            out(:, 1:nt) = res%y(:, 1:nt)
            y = res%y(:, nt)
        end if
    end subroutine propagation_grid

    !> One run of solve_ivp from (t0, y0) to t1 by the kept propagation, with the first
    !! step h0 (0: the method's), the largest step hmax, the step limit max_steps and the
    !! output times t_eval (none: every step's point) of this call: the points in res, as
    !! solve_into gives them for the same packed arguments (a new run, never resumed: the
    !! same bits and counts), without making the system and the stepper again.
    subroutine propagation_solve(p, params, t0, t1, y0, h0, hmax, max_steps, res, counts, &
                                 info, msg, t_eval)
        type(kept_propagation), intent(inout) :: p
        real(dp), intent(in) :: params(:)
        real(dp), intent(in) :: t0, t1, y0(:), h0, hmax
        integer, intent(in) :: max_steps
        type(ode_result), intent(out) :: res
        integer(c_int), intent(out) :: counts(5)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        real(dp), intent(in), optional :: t_eval(:)
        integer(c_int) :: nfev
        counts = 0
        p%first_step = h0
        p%opt%first_step = h0
        p%opt%max_step = hmax
        p%opt%max_steps = max_steps
        call prepare_run(p, params, t0, t1, y0, nfev, info, msg)
        if (info /= CM_SUCCESS) return
        call ode_solve(p%sys, [t0, t1], y0, p%opt, res, t_eval=t_eval, stepper=p%stp)
        p%resumable = .false.           ! a later propagation starts a run of its own
        counts = [nfev + res%stats%nfev, res%stats%njev, res%stats%nlu, &
                  res%stats%naccept, res%stats%nreject]
        info = res%status
        msg = res%message
    end subroutine propagation_solve

    !> Before a run from (t0, y) to t1: the system made again if its parameters changed
    !! (the stepper then starts anew), SciPy's initial step for its RK45 (nfev its
    !! evaluations).
    subroutine prepare_run(p, params, t0, t1, y, nfev, info, msg)
        type(kept_propagation), intent(inout) :: p
        real(dp), intent(in) :: params(:), t0, t1, y(:)
        integer(c_int), intent(out) :: nfev
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        info = CM_SUCCESS
        nfev = 0
        if (any(params /= p%params)) then
            p%params = params
            p%resumable = .false.
            call spec_system_of_size(p%name, params, p%nspec, p%spec, p%n, "", p%sys, info, &
                                     msg)
            if (info /= CM_SUCCESS) return
        end if
        if (p%scipy_rk45 .and. .not. p%first_step > 0.0_dp) then
            call scipy_first_step(p%sys, [t0, t1], y, max(p%opt%rtol_vec, &
                                  100.0_dp*epsilon(1.0_dp)), p%opt%atol_vec, p%opt%max_step, &
                                  4, p%opt%first_step, nfev)
        end if
    end subroutine prepare_run

end module conmech_flat_propagation
