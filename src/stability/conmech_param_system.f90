!> A built-in system (by name, `conmech_systems`) with one of its parameters made settable,
!! for the continuation of its periodic orbits in that parameter: `set_builtin_param`
!! (a `set_parameter_proc`) rebuilds the system with params(ip) = p.
module conmech_param_system
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_systems, only: make_system
    implicit none
    private
    public :: builtin_param_system, set_builtin_param, make_param_system

    !> The built-in system `name` with parameters `params`; params(ip) is the continued one.
    type, extends(ode_system) :: builtin_param_system
        class(ode_system), allocatable :: inner
        character(len=:), allocatable :: name
        real(dp), allocatable :: params(:)
        integer :: ip = 1
    contains
        procedure :: rhs => bp_rhs
        procedure :: jacobian => bp_jac
        procedure :: has_jacobian => bp_has_jac
    end type builtin_param_system

contains

    !> Build it; info CM_BAD_INPUT for an unknown name or ip out of range.
    subroutine make_param_system(name, params, ip, sys, info, msg)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        integer, intent(in) :: ip
        type(builtin_param_system), intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        if (ip < 1 .or. ip > size(params)) then
            info = CM_BAD_INPUT
            msg = "the continuation parameter index is out of range (1.."// &
                  achar(48 + min(9, size(params)))//")"
            return
        end if
        sys%name = trim(name)
        sys%params = params
        sys%ip = ip
        call make_system(sys%name, sys%params, sys%inner, info, msg)
    end subroutine make_param_system

    subroutine bp_rhs(self, t, y, dydt)
        class(builtin_param_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        call self%inner%rhs(t, y, dydt)
    end subroutine bp_rhs

    subroutine bp_jac(self, t, y, dfdy)
        class(builtin_param_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        call self%inner%jacobian(t, y, dfdy)
    end subroutine bp_jac

    logical function bp_has_jac(self)
        class(builtin_param_system), intent(in) :: self
        bp_has_jac = self%inner%has_jacobian()
    end function bp_has_jac

    !> set_param of a builtin_param_system (other systems are left unchanged).
    subroutine set_builtin_param(sys, p)
        class(ode_system), intent(inout) :: sys
        real(dp), intent(in) :: p
        integer :: info
        character(len=:), allocatable :: msg
        select type (sys)
        type is (builtin_param_system)
            sys%params(sys%ip) = p
            call make_system(sys%name, sys%params, sys%inner, info, msg)
        end select
    end subroutine set_builtin_param

end module conmech_param_system
