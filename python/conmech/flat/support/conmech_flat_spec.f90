!> Systems for the flat layer from a name (built-in) or a `spec` (compiled functions).
!!
!! A spec is an integer(c_int64_t) array that describes a compiled system (see
!! conmech/compiled.py, which writes it):
!!
!!     spec(1) kind: 0 none (use the built-in `name`), 1 first-order ode, 2 generalized
!!             coordinates, 3 constrained (excessive coordinates)
!!     spec(2) n (ode: state dimension; generalized: ndof; constrained: coordinates)
!!     spec(3) n_hol    spec(4) n_nh    spec(5) rheonomic (0/1)
!!     spec(6:15) function addresses (0 = absent):
!!         ode:          6 rhs, 7 jac
!!         generalized:  6 mass, 7 forces, 8 forces_jac, 9 energy
!!         constrained:  6 mass, 7 forces, 8 forces_jac, 9 energy, 10 phi, 11 phi_jac,
!!                       12 phi_t, 13 phi_gamma, 14 nh_matrix, 15 nh_gamma
!!     spec(16) (optional, generalized) mass_forces: M and Q in one call
!!     spec(17) (optional, generalized) accel: a = M^-1 Q in one call
!!     spec(18) (optional, ode) jac_prod: J x for an n x k block x (set_c_jac_prod)
!!     spec(19:22) (optional, ode) Taylor coefficients (set_c_taylor): taylor, its work
!!         columns, taylor_var (the variational system), its work columns
!!     spec(23:26) (optional, ode) the same written out for one order (set_c_taylor_fixed):
!!         taylor, its order, taylor_var, its order
!!     spec(27) (optional, constrained) constraint_hessian: d(C^T lam)/dq, d(C v + c0)/dq
!!     spec(28) (optional, generalized) accel_jac: a and d a/d[q, v] in one call
!!
!! Every flat routine that takes a built-in `name` also takes `nspec, spec`: the same
!! routine then runs built-in and compiled systems alike.
module conmech_flat_spec
    use, intrinsic :: iso_c_binding, only: c_int64_t, c_funptr, c_null_funptr, c_intptr_t
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_systems, only: make_system, system_dimension
    use conmech_systems_mech, only: make_constrained, make_generalized
    use conmech_generalized, only: generalized_system, generalized_ode
    use conmech_constrained_system, only: constrained_system
    use conmech_c_system, only: c_ode_system, make_c_ode, set_c_jac_prod, set_c_taylor, &
                                set_c_taylor_fixed
    use conmech_c_mechanics, only: c_generalized_system, c_constrained_system, &
                                   c_mech_pointers, make_c_generalized, make_c_constrained
    implicit none
    private
    public :: KIND_BUILTIN, KIND_ODE, KIND_GENERALIZED, KIND_CONSTRAINED, SPEC_SIZE
    public :: spec_kind, spec_system, spec_generalized, spec_constrained, spec_dimension

    integer, parameter :: KIND_BUILTIN = 0, KIND_ODE = 1, KIND_GENERALIZED = 2, &
                          KIND_CONSTRAINED = 3
    integer, parameter :: SPEC_SIZE = 15

contains

    !> The kind of system a spec describes (KIND_BUILTIN for built-ins or a short spec).
    integer function spec_kind(nspec, spec)
        integer, intent(in) :: nspec
        integer(c_int64_t), intent(in) :: spec(:)
        spec_kind = KIND_BUILTIN
        if (nspec >= SPEC_SIZE) spec_kind = int(spec(1))
    end function spec_kind

    type(c_funptr) function fptr(addr)
        integer(c_int64_t), intent(in) :: addr
        if (addr == 0) then
            fptr = c_null_funptr
        else
            fptr = transfer(int(addr, c_intptr_t), c_null_funptr)
        end if
    end function fptr

    function mech_pointers(spec) result(fp)
        integer(c_int64_t), intent(in) :: spec(:)
        type(c_mech_pointers) :: fp
        fp%mass = fptr(spec(6))
        fp%forces = fptr(spec(7))
        fp%forces_jac = fptr(spec(8))
        fp%energy = fptr(spec(9))
        fp%phi = fptr(spec(10))
        fp%phi_jac = fptr(spec(11))
        fp%phi_t = fptr(spec(12))
        fp%phi_gamma = fptr(spec(13))
        fp%nh_matrix = fptr(spec(14))
        fp%nh_gamma = fptr(spec(15))
        if (size(spec) >= 16) fp%mass_forces = fptr(spec(16))
        if (size(spec) >= 17) fp%accel = fptr(spec(17))
        if (size(spec) >= 27) fp%constraint_hessian = fptr(spec(27))
        if (size(spec) >= 28) fp%accel_jac = fptr(spec(28))
    end function mech_pointers

    !> State dimension of the first-order system (built-in by name, or from the spec).
    integer function spec_dimension(name, nspec, spec)
        character(len=*), intent(in) :: name
        integer, intent(in) :: nspec
        integer(c_int64_t), intent(in) :: spec(:)
        select case (spec_kind(nspec, spec))
        case (KIND_ODE)
            spec_dimension = int(spec(2))
        case (KIND_GENERALIZED)
            spec_dimension = 2*int(spec(2))
        case (KIND_BUILTIN)
            spec_dimension = system_dimension(name)
        case default
            spec_dimension = 0
        end select
    end function spec_dimension

    !> The first-order system: built-in `name` (spec kind 0), or compiled (kinds 1, 2).
    subroutine spec_system(name, params, nspec, spec, sys, info, msg)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        integer, intent(in) :: nspec
        integer(c_int64_t), intent(in) :: spec(:)
        class(ode_system), allocatable, intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        select case (spec_kind(nspec, spec))
        case (KIND_BUILTIN)
            call make_system(name, params, sys, info, msg)
        case (KIND_ODE)
            block
                type(c_ode_system) :: s
                call make_c_ode(int(spec(2)), fptr(spec(6)), fptr(spec(7)), params, s, &
                                info, msg)
                if (size(spec) >= 18) call set_c_jac_prod(s, fptr(spec(18)))
                if (size(spec) >= 22) call set_c_taylor(s, fptr(spec(19)), int(spec(20)), &
                                                        fptr(spec(21)), int(spec(22)))
                if (size(spec) >= 26) call set_c_taylor_fixed(s, fptr(spec(23)), &
                                                              int(spec(24)), &
                                                              fptr(spec(25)), int(spec(26)))
                if (info == CM_SUCCESS) allocate (sys, source=s)
            end block
        case (KIND_GENERALIZED)
            block
                type(generalized_ode) :: w
                class(generalized_system), allocatable :: g
                call spec_generalized(name, params, nspec, spec, g, info, msg)
                if (info == CM_SUCCESS) then
                    call move_alloc(g, w%mech)
                    allocate (sys, source=w)
                end if
            end block
        case (KIND_CONSTRAINED)
            info = CM_BAD_INPUT
            msg = "bad input: a constrained system runs with conmech.constrained.solve"
        case default
            info = CM_BAD_INPUT
            msg = "bad input: unknown kind of compiled system"
        end select
    end subroutine spec_system

    !> A generalized-coordinate system: built-in `name` or compiled (spec kind 2).
    subroutine spec_generalized(name, params, nspec, spec, mech, info, msg)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        integer, intent(in) :: nspec
        integer(c_int64_t), intent(in) :: spec(:)
        class(generalized_system), allocatable, intent(out) :: mech
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        select case (spec_kind(nspec, spec))
        case (KIND_BUILTIN)
            call make_generalized(name, params, mech, info, msg)
        case (KIND_GENERALIZED)
            block
                type(c_generalized_system) :: s
                call make_c_generalized(int(spec(2)), mech_pointers(spec), params, s, info, &
                                        msg)
                if (info == CM_SUCCESS) allocate (mech, source=s)
            end block
        case default
            info = CM_BAD_INPUT
            msg = "bad input: not a system in generalized coordinates"
        end select
    end subroutine spec_generalized

    !> A constrained system: built-in `name` or compiled (spec kind 3).
    subroutine spec_constrained(name, params, nspec, spec, cs, info, msg)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        integer, intent(in) :: nspec
        integer(c_int64_t), intent(in) :: spec(:)
        class(constrained_system), allocatable, intent(out) :: cs
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        select case (spec_kind(nspec, spec))
        case (KIND_BUILTIN)
            call make_constrained(name, params, cs, info, msg)
        case (KIND_CONSTRAINED)
            block
                type(c_constrained_system) :: s
                call make_c_constrained(int(spec(2)), int(spec(3)), int(spec(4)), &
                                        spec(5) /= 0, mech_pointers(spec), params, s, info, &
                                        msg)
                if (info == CM_SUCCESS) allocate (cs, source=s)
            end block
        case default
            info = CM_BAD_INPUT
            msg = "bad input: not a constrained system"
        end select
    end subroutine spec_constrained

end module conmech_flat_spec
