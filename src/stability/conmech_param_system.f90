!> A built-in system (by name, `conmech_systems`) with one of its parameters made settable,
!! for the continuation of its periodic orbits in that parameter: `set_builtin_param`
!! (a `set_parameter_proc`) rebuilds the system with params(ip) = p.
module conmech_param_system
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_systems, only: make_system
    use conmech_generalized, only: generalized_ode
    use conmech_c_system, only: c_ode_system
    use conmech_c_mechanics, only: c_generalized_system
    implicit none
    private
    public :: builtin_param_system, set_builtin_param, make_param_system
    public :: make_compiled_param_system

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
        procedure :: rhs_jacobian => bp_rhs_jac
        procedure :: has_jacobian_product => bp_has_jac_prod
        procedure :: jacobian_product => bp_jac_prod
        procedure :: rhs_jacobian_product => bp_rhs_jac_prod
        procedure :: taylor_size => bp_taylor_size
        procedure :: taylor_jet => bp_taylor_jet
    end type builtin_param_system

contains

    !> Build it; info CM_BAD_INPUT for an unknown name or ip out of range. ip = 0: no
    !! parameter is continued (a continuation in the period of a system that may have no
    !! parameter at all); `set_builtin_param` then leaves the system unchanged.
    subroutine make_param_system(name, params, ip, sys, info, msg)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        integer, intent(in) :: ip
        type(builtin_param_system), intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        if (ip < 0 .or. ip > size(params)) then
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

    !> The same for a compiled system (conmech_c_system / conmech_c_mechanics: its parameter
    !! array p is set in place, no rebuild); info CM_BAD_INPUT for ip out of range or a
    !! system that is not compiled. ip = 0: no parameter (as for make_param_system).
    subroutine make_compiled_param_system(inner, params, ip, sys, info, msg)
        class(ode_system), intent(in) :: inner
        real(dp), intent(in) :: params(:)
        integer, intent(in) :: ip
        type(builtin_param_system), intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        info = CM_BAD_INPUT
        if (ip < 0 .or. ip > size(params)) then
            msg = "the continuation parameter index is out of range"
            return
        end if
        sys%name = ""
        sys%params = params
        sys%ip = ip
        allocate (sys%inner, source=inner)
        if (ip == 0) then
            info = CM_SUCCESS
            msg = "success"
            return
        end if
        if (.not. set_compiled(sys%inner, ip, params(ip))) then
            msg = "continuation in a parameter needs a built-in or a compiled system"
            return
        end if
        info = CM_SUCCESS
        msg = "success"
    end subroutine make_compiled_param_system

    !> Set parameter ip of a compiled system in place; false if it is not one.
    logical function set_compiled(inner, ip, p) result(ok)
        class(ode_system), intent(inout) :: inner
        integer, intent(in) :: ip
        real(dp), intent(in) :: p
        ok = .false.
        select type (inner)
        type is (c_ode_system)
            if (ip <= size(inner%p)) then
                inner%p(ip) = p
                ok = .true.
            end if
        type is (generalized_ode)
            select type (mech => inner%mech)
            type is (c_generalized_system)
                if (ip <= size(mech%core%p)) then
                    mech%core%p(ip) = p
                    ok = .true.
                end if
            end select
        end select
    end function set_compiled

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

    !> f and J of the wrapped system (its own shared-work version, if any).
    subroutine bp_rhs_jac(self, t, y, dydt, dfdy)
        class(builtin_param_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp), intent(out) :: dfdy(:, :)
        call self%inner%rhs_jacobian(t, y, dydt, dfdy)
    end subroutine bp_rhs_jac

    !> Whether the wrapped system has a structure-aware J x (then `integrate_stm` uses it).
    logical function bp_has_jac_prod(self)
        class(builtin_param_system), intent(in) :: self
        bp_has_jac_prod = self%inner%has_jacobian_product()
    end function bp_has_jac_prod

    !> jx = J x of the wrapped system (the state is not extended: the parameter enters
    !! only through the wrapped system's own parameters).
    subroutine bp_jac_prod(self, t, n, k, y, x, jx)
        class(builtin_param_system), intent(in) :: self
        real(dp), intent(in) :: t
        integer, intent(in) :: n, k
        real(dp), intent(in) :: y(n), x(n, k)
        real(dp), intent(out) :: jx(n, k)
        call self%inner%jacobian_product(t, n, k, y, x, jx)
    end subroutine bp_jac_prod

    !> f and J x of the wrapped system at once.
    subroutine bp_rhs_jac_prod(self, t, n, k, y, dydt, x, jx)
        class(builtin_param_system), intent(in) :: self
        real(dp), intent(in) :: t
        integer, intent(in) :: n, k
        real(dp), intent(in) :: y(n), x(n, k)
        real(dp), intent(out) :: dydt(n), jx(n, k)
        call self%inner%rhs_jacobian_product(t, n, k, y, dydt, x, jx)
    end subroutine bp_rhs_jac_prod

    !> The wrapped system's Taylor work size (0: it has no Taylor code of that kind).
    integer function bp_taylor_size(self, kind)
        class(builtin_param_system), intent(in) :: self
        integer, intent(in) :: kind
        bp_taylor_size = self%inner%taylor_size(kind)
    end function bp_taylor_size

    !> The wrapped system's Taylor coefficients (its parameters as last set).
    subroutine bp_taylor_jet(self, kind, t, order, nw, w)
        class(builtin_param_system), intent(in) :: self
        integer, intent(in) :: kind, order, nw
        real(dp), intent(in) :: t
        real(dp), intent(inout) :: w(0:order, nw)
        call self%inner%taylor_jet(kind, t, order, nw, w)
    end subroutine bp_taylor_jet

    !> set_param of a builtin_param_system or an extension of it (other systems are left
    !! unchanged).
    subroutine set_builtin_param(sys, p)
        class(ode_system), intent(inout) :: sys
        real(dp), intent(in) :: p
        integer :: info
        character(len=:), allocatable :: msg
        select type (sys)
        class is (builtin_param_system)
            if (sys%ip == 0) return
            sys%params(sys%ip) = p
            if (len(sys%name) == 0) then
                if (.not. set_compiled(sys%inner, sys%ip, p)) return
            else
                call make_system(sys%name, sys%params, sys%inner, info, msg)
            end if
        end select
    end subroutine set_builtin_param

end module conmech_param_system
