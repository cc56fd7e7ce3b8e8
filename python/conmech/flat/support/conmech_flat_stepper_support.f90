!> Support of the flat stepper routines (python/conmech/flat/flat_stepper.f90): one action
!! of any method's stepper (the method table's) on its state packed into plain arrays owned
!! by the caller (the Python object), so that a step is taken from Python without any state
!! kept in Fortran between calls (thread-safe). The packing is the stepper's own
!! `transfer_state` (conmech_ode_stepper, conmech_state_packer); the common part is at the
!! fixed positions PACK_* for every method.
module conmech_flat_stepper_support
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT, CM_NONFINITE
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: ode_options, METHOD_DOPRI5
    use conmech_ode_stepper, only: ode_stepper, stepper_pack_into, stepper_unpack
    use conmech_ode_methods, only: new_stepper
    use conmech_flat_ode_support, only: METHOD_RK45_SCIPY, scipy_first_step, copy_message, &
        set_jacobian_structure, set_flat_options
    use conmech_flat_spec, only: spec_system, spec_system_of_size
    implicit none
    private
    public :: stepper_action, step_action, stepper_system

    integer, parameter, public :: ACTION_START = 0, ACTION_STEP = 1, ACTION_DENSE = 2, &
        ACTION_SIZES = 3

contains

    !> The built-in (or compiled) system `name` with parameters params of a flat stepper
    !! routine; n > 0: it must have n state variables (checked when the state is made; a
    !! step of an existing state passes n = 0 and skips the check). info /= CM_SUCCESS:
    !! the failure's text in the flat layer's 256-character message.
    subroutine stepper_system(name, params, nspec, spec, n, sys, info, message)
        use, intrinsic :: iso_c_binding, only: c_int64_t
        character(len=*), intent(in) :: name
        real(c_double), intent(in) :: params(:)
        integer(c_int), intent(in) :: nspec, n
        integer(c_int64_t), intent(in) :: spec(:)
        class(ode_system), allocatable, intent(out) :: sys
        integer(c_int), intent(out) :: info
        character(len=256), intent(out) :: message
        character(len=:), allocatable :: msg
        if (n > 0) then
            call spec_system_of_size(name, real(params, dp), nspec, spec, n, &
                                     "bad input: y0 has the wrong size for the system '" &
                                     //trim(name)//"'", sys, info, msg)
        else
            call spec_system(name, real(params, dp), nspec, spec, sys, info, msg)
        end if
        message = ""
        if (info /= CM_SUCCESS) call copy_message(msg, message)
    end subroutine stepper_system

    !> One action on a packed stepper of `method`: ACTION_START (init at (t0, y0) towards
    !! t_bound, then start: f at t0 and the first step), ACTION_STEP (one accepted step),
    !! ACTION_DENSE (the continuous extension of the last step into the fc columns),
    !! ACTION_SIZES (init only: sizes = [nr, ni, nw] of the packed state, nothing
    !! evaluated). info: CM_SUCCESS or the failure; the state (r(nr), iv(ni), w(n, nw)) is
    !! written back after every action but ACTION_SIZES.
    !! method METHOD_RK45_SCIPY (12): DOPRI5 with SciPy's step control (no Lund
    !! stabilisation) and, without first_step, SciPy's initial step (its two evaluations
    !! counted in nfev), as solve_ivp(method="RK45") runs it.
    !! jac_const /= 0: the Jacobian is constant (read once; methods that use one);
    !! nnz >= 0: the sparsity pattern of df/dy by columns (sp_ptr(n + 1), sp_idx(nnz), 1-based)
    !! for grouped differences; both are kept in the packed state.
    !! The state is read from and written back into (r, iv, w) in place.
    subroutine stepper_action(sys, action, n, nr, ni, nw, t0, t_bound, y0, method, rtol, &
                              atol, first_step, max_step, max_steps, jac_const, nnz, sp_ptr, &
                              sp_idx, r, iv, w, sizes, info, message)
        class(ode_system), intent(in) :: sys
        integer(c_int), intent(in) :: action, n, nr, ni, nw, method, max_steps
        real(c_double), intent(in) :: t0, t_bound, y0(n), rtol(n), atol(n)
        real(c_double), intent(in) :: first_step, max_step
        integer(c_int), intent(in) :: jac_const, nnz, sp_ptr(:), sp_idx(:)
        real(c_double), intent(inout), target :: r(max(nr, 1)), w(n, max(nw, 1))
        integer(c_int), intent(inout), target :: iv(max(ni, 1))
        integer(c_int), intent(out) :: sizes(3)
        integer(c_int), intent(out) :: info
        character(len=*), intent(out) :: message
        class(ode_stepper), allocatable :: s
        type(ode_options) :: opt
        character(len=:), allocatable :: msg
        integer :: inf, code
        integer(c_int) :: nfev0
        character(len=32) :: buf

        sizes = 0
        code = method
        if (method == METHOD_RK45_SCIPY) code = METHOD_DOPRI5
        call new_stepper(code, s, inf, msg)
        if (inf == CM_SUCCESS .and. n < 1) then
            inf = CM_BAD_INPUT
            msg = "bad input: y0 is empty"
        end if
        if (inf /= CM_SUCCESS) then
            info = inf
            call copy_message(msg, message)
            return
        end if
        msg = "success"
        select case (action)
        case (ACTION_START, ACTION_SIZES)
            call set_flat_options(opt, code, rtol, atol, first_step, max_step, max_steps, 0)
            nfev0 = 0
            if (method == METHOD_RK45_SCIPY) then
                opt%beta = 0.0_dp
                opt%stretch = 0.0_dp
                if (action == ACTION_START .and. .not. first_step > 0.0_c_double .and. &
                    t_bound /= t0 .and. all(y0 == y0) .and. all(abs(y0) <= huge(1.0_dp))) then
                    call scipy_first_step(sys, [t0, t_bound], y0, &
                                          max(rtol, 100.0_dp*epsilon(1.0_dp)), atol, &
                                          max_step, 4, opt%first_step, nfev0)
                end if
            end if
            call set_jacobian_structure(s, n, jac_const, nnz, sp_ptr, sp_idx, inf, msg)
            if (inf == CM_SUCCESS) call s%init(t0, t_bound, y0, opt, inf, msg, allow_inf=.true.)
            if (action == ACTION_SIZES) then
                if (inf == CM_SUCCESS) call write_back(count_only=.true.)
            else
                if (inf == CM_SUCCESS .and. t_bound /= t0) call s%start(sys, inf, msg)
                if (allocated(s%y)) then
                    s%st%nfev = s%st%nfev + nfev0
                    call write_back()
                end if
            end if
        case (ACTION_STEP, ACTION_DENSE)
            call stepper_unpack(s, code, r(1:nr), iv(1:ni), w(:, 1:nw), inf, msg)
            if (inf == CM_SUCCESS) then
                if (action == ACTION_STEP) then
                    call s%step(sys, s%tf, inf, msg)
                    if (inf == CM_SUCCESS .and. s%f_stale) call s%refresh_f(sys)
                    ! a step that ends where f is not finite fails, as in the driver
                    if (inf == CM_SUCCESS .and. .not. s%f_finite()) then
                        inf = CM_NONFINITE
                        write (buf, '(es14.6)') s%t
                        msg = "non-finite right-hand side at t ="//trim(buf)
                    end if
                else
                    call s%dense(sys)
                end if
                call write_back()
            end if
        case default
            inf = CM_BAD_INPUT
            msg = "bad input: unknown stepper action"
        end select
        info = inf
        if (.not. allocated(msg)) msg = "success"
        call copy_message(msg, message)

    contains

        !> The packed state into (r, iv, w) in place (CM_BAD_INPUT if they are too small);
        !! count_only: only the sizes (into zero-capacity arrays).
        subroutine write_back(count_only)
            logical, intent(in), optional :: count_only
            integer :: pinfo
            if (present(count_only)) then
                call stepper_pack_into(s, r(1:0), iv(1:0), w(:, 1:0), sizes, pinfo)
                return
            end if
            call stepper_pack_into(s, r(1:nr), iv(1:ni), w(:, 1:nw), sizes, pinfo)
            if (pinfo /= CM_SUCCESS) then
                inf = CM_BAD_INPUT
                msg = "bad input: the state arrays are smaller than the stepper's state " &
                      //"(ACTION_SIZES gives the sizes)"
            end if
        end subroutine write_back

    end subroutine stepper_action

    !> ACTION_STEP or ACTION_DENSE on the packed state (r(nr), iv(ni), w(n, nw)) with only
    !! what they read (stepper_action with placeholders for the rest); other actions are
    !! refused with CM_BAD_INPUT.
    subroutine step_action(sys, action, method, n, nr, ni, nw, r, iv, w, info, message)
        class(ode_system), intent(in) :: sys
        integer(c_int), intent(in) :: action, method, n, nr, ni, nw
        real(c_double), intent(inout) :: r(nr), w(n, nw)
        integer(c_int), intent(inout) :: iv(ni)
        integer(c_int), intent(out) :: info
        character(len=*), intent(out) :: message
        integer(c_int) :: none(1), sizes(3)
        real(c_double) :: unused(n)
        if (action /= ACTION_STEP .and. action /= ACTION_DENSE) then
            info = CM_BAD_INPUT
            call copy_message("bad input: action must be 1 (step) or 2 (dense output)", &
                              message)
            return
        end if
        none = 0
        unused = 0.0_c_double
        ! t0, t_bound, y0, tolerances and the pattern are not read by a step: placeholders
        call stepper_action(sys, action, n, nr, ni, nw, 0.0_c_double, 0.0_c_double, unused, &
                            method, unused, unused, 0.0_c_double, 0.0_c_double, 1, 0, -1, &
                            none, none, r, iv, w, sizes, info, message)
    end subroutine step_action

end module conmech_flat_stepper_support
