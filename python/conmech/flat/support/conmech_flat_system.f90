!> The one system argument set of the flat layer: every flat routine that runs on a
!! first-order system takes
!!
!!     name, np, params, nspec, spec, fun, jfun, source
!!
!! and hands them to `flat_system`, which builds the `ode_system` once:
!!
!!     source = SOURCE_SPEC     a built-in system by `name` or a compiled one from `spec`
!!                              (conmech_flat_spec); `fun` and `jfun` are never called
!!     source = SOURCE_FUN      a Python right-hand side fun(t, y, dydt, n), Jacobian by
!!                              finite differences; `jfun` is never called
!!     source = SOURCE_FUN_JAC  fun and its exact Jacobian jfun(t, y, dfdy, n)
!!
!! The routines that continue in a parameter take the parametric set
!!
!!     name, np, params, nspec, spec, ip, fun, jfun, source, p0
!!
!! (`flat_param_system`): the built-in or compiled system continued in params(ip), or
!! fun(t, y, p, dydt, n) with jfun(t, y, p, dfdy, n) at the parameter value p0.
!!
!! f2py has no optional call-back argument (an omitted one is looked up as a module
!! attribute and fails), so the Python side always passes two callables and says with
!! `source` which of them are real; the placeholders cost one argument conversion per call,
!! never a call.
module conmech_flat_system
    use, intrinsic :: iso_c_binding, only: c_int, c_int64_t
    use conmech_kinds, only: dp
    use conmech_status, only: CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_flat_spec, only: spec_system
    use conmech_flat_adapters, only: callback_system, callback_jac_system
    use conmech_flat_spec, only: spec_kind, KIND_BUILTIN
    use conmech_param_system, only: builtin_param_system, make_param_system, &
                                    make_compiled_param_system
    implicit none
    private
    public :: flat_system, flat_param_system, SOURCE_SPEC, SOURCE_FUN, SOURCE_FUN_JAC

    integer(c_int), parameter :: SOURCE_SPEC = 0, SOURCE_FUN = 1, SOURCE_FUN_JAC = 2

contains

    !> The first-order system of dimension n described by one flat argument set (above);
    !! info /= 0 and `message` (the flat routine's own output) when it cannot be built.
    subroutine flat_system(name, params, nspec, spec, fun, jfun, source, n, sys, info, message)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        integer, intent(in) :: nspec
        integer(c_int64_t), intent(in) :: spec(:)
        procedure() :: fun, jfun
        integer(c_int), intent(in) :: source, n
        class(ode_system), allocatable, intent(out) :: sys
        integer, intent(out) :: info
        character(len=*), intent(out) :: message
        character(len=:), allocatable :: msg
        info = 0
        msg = "success"
        select case (source)
        case (SOURCE_SPEC)
            call spec_system(name, params, nspec, spec, sys, info, msg)
        case (SOURCE_FUN, SOURCE_FUN_JAC)
            call python_system(fun, jfun, source, n, .false., 0.0_dp, sys)
        case default
            info = CM_BAD_INPUT
            msg = "bad input: unknown system source"
        end select
        message = msg
    end subroutine flat_system

    !> The system of the parametric flat argument set (above) and the parameter value it
    !! starts from (params(ip), or p0 for Python functions). ip < 0 with a built-in or
    !! compiled system: the system itself, with no parameter (p_start = p0). info /= 0 and
    !! `message` (the flat routine's own output) when it cannot be built.
    subroutine flat_param_system(name, params, nspec, spec, ip, fun, jfun, source, n, p0, &
                                 sys, p_start, info, message)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        integer, intent(in) :: nspec
        integer(c_int64_t), intent(in) :: spec(:)
        integer(c_int), intent(in) :: ip, source, n
        procedure() :: fun, jfun
        real(dp), intent(in) :: p0
        class(ode_system), allocatable, intent(out) :: sys
        real(dp), intent(out) :: p_start
        integer, intent(out) :: info
        character(len=*), intent(out) :: message
        character(len=:), allocatable :: msg
        type(builtin_param_system) :: b
        class(ode_system), allocatable :: inner
        info = 0
        msg = "success"
        p_start = p0
        select case (source)
        case (SOURCE_SPEC)
            if (ip < 0) then
                call spec_system(name, params, nspec, spec, sys, info, msg)
            else if (spec_kind(nspec, spec) == KIND_BUILTIN) then
                call make_param_system(name, params, ip, b, info, msg)
            else
                call spec_system(name, params, nspec, spec, inner, info, msg)
                if (info == 0) call make_compiled_param_system(inner, params, ip, b, info, msg)
            end if
            if (ip >= 0 .and. info == 0) then
                if (size(params) > 0) p_start = params(max(ip, 1))
                allocate (sys, source=b)
            end if
        case (SOURCE_FUN, SOURCE_FUN_JAC)
            call python_system(fun, jfun, source, n, .true., p0, sys)
        case default
            info = CM_BAD_INPUT
            msg = "bad input: unknown system source"
        end select
        message = msg
    end subroutine flat_param_system

    !> The adapter of a Python right-hand side fun (and, for SOURCE_FUN_JAC, its Jacobian
    !! jfun), with the parameter value p when `parametric`.
    subroutine python_system(fun, jfun, source, n, parametric, p, sys)
        procedure() :: fun, jfun
        integer(c_int), intent(in) :: source, n
        logical, intent(in) :: parametric
        real(dp), intent(in) :: p
        class(ode_system), allocatable, intent(out) :: sys
        if (source == SOURCE_FUN_JAC) then
            allocate (callback_jac_system :: sys)
        else
            allocate (callback_system :: sys)
        end if
        select type (sys)
        class is (callback_system)
            sys%f => fun
            sys%n = n
            sys%parametric = parametric
            sys%p = p
        end select
        select type (sys)
        type is (callback_jac_system)
            sys%jac => jfun
        end select
    end subroutine python_system

end module conmech_flat_system
