!> Systems for the flat layer from a name (built-in) or a `spec` (compiled functions).
!!
!! A spec is an integer(c_int64_t) array that describes a compiled system (see
!! conmech/compiled.py, which writes it):
!!
!!     <generated: tools/generate_slots.py spec layout>
!!     spec(1) kind: 0 none (the built-in `name`), 1 ode, 2 generalized, 3 constrained
!!     spec(2) n (ode: state dimension; generalized: ndof; constrained: coordinates)
!!     spec(3) n_hol    spec(4) n_nh    spec(5) rheonomic (0/1)
!!     spec(6) rhs (ode); mass (generalized/constrained)
!!     spec(7) jac (ode, optional); forces (generalized/constrained)
!!     spec(8) forces_jac (generalized/constrained, optional)
!!     spec(9) energy (generalized/constrained, optional)
!!     spec(10) phi (constrained, optional)
!!     spec(11) phi_jac (constrained, optional)
!!     spec(12) phi_t (constrained, optional)
!!     spec(13) phi_gamma (constrained, optional)
!!     spec(14) nh_matrix (constrained, optional)
!!     spec(15) nh_gamma (constrained, optional)
!!     spec(16) mass_forces (generalized, optional)
!!     spec(17) accel (generalized, optional)
!!     spec(18) jac_prod (ode, optional)
!!     spec(19) jet (ode, optional)
!!     spec(20) nw (ode, optional)
!!     spec(21) var (ode, optional)
!!     spec(22) nw_var (ode, optional)
!!     spec(23) jet_fixed (ode, optional)
!!     spec(24) order (ode, optional)
!!     spec(25) var_fixed (ode, optional)
!!     spec(26) order_var (ode, optional)
!!     spec(27) constraint_hessian (constrained, optional)
!!     spec(28) accel_jac (generalized, optional)
!!     </generated>
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
    use conmech_c_entries, only: SPEC_KIND_BUILTIN, SPEC_KIND_ODE, SPEC_KIND_GENERALIZED, &
                                 SPEC_KIND_CONSTRAINED, N_MECH_ENTRIES, MECH_ENTRY_SLOTS, &
                                 set_mech_entry, SLOT_KIND, SLOT_N, SLOT_N_HOL, SLOT_N_NH, &
                                 SLOT_RHEONOMIC, SLOT_RHS, SLOT_JAC, SLOT_JAC_PROD, &
                                 SLOT_TAYLOR_JET, SLOT_TAYLOR_NW, SLOT_TAYLOR_VAR, &
                                 SLOT_TAYLOR_NW_VAR, SLOT_TAYLOR_JET_FIXED, SLOT_TAYLOR_ORDER, &
                                 SLOT_TAYLOR_VAR_FIXED, SLOT_TAYLOR_ORDER_VAR, SLOT_NH_GAMMA
    implicit none
    private
    public :: KIND_BUILTIN, KIND_ODE, KIND_GENERALIZED, KIND_CONSTRAINED, SPEC_SIZE
    public :: spec_kind, spec_system, spec_generalized, spec_constrained, spec_dimension
    public :: spec_system_of_size, spec_c_ode, check_spec_size

    integer, parameter :: KIND_BUILTIN = SPEC_KIND_BUILTIN, KIND_ODE = SPEC_KIND_ODE, &
                          KIND_GENERALIZED = SPEC_KIND_GENERALIZED, &
                          KIND_CONSTRAINED = SPEC_KIND_CONSTRAINED
    !> the shortest spec of a compiled system: up to the last function every kind has a
    !! slot for (later slots are read when the spec is long enough)
    integer, parameter :: SPEC_SIZE = SLOT_NH_GAMMA

contains

    !> The kind of system a spec describes (KIND_BUILTIN for built-ins or a short spec).
    integer function spec_kind(nspec, spec)
        integer, intent(in) :: nspec
        integer(c_int64_t), intent(in) :: spec(:)
        spec_kind = KIND_BUILTIN
        if (nspec >= SPEC_SIZE) spec_kind = int(spec(SLOT_KIND))
    end function spec_kind

    type(c_funptr) function fptr(addr)
        integer(c_int64_t), intent(in) :: addr
        if (addr == 0) then
            fptr = c_null_funptr
        else
            fptr = transfer(int(addr, c_intptr_t), c_null_funptr)
        end if
    end function fptr

    !> The mechanical entries of a spec (those its length holds; the others null).
    function mech_pointers(spec) result(fp)
        integer(c_int64_t), intent(in) :: spec(:)
        type(c_mech_pointers) :: fp
        integer :: k
        do k = 1, N_MECH_ENTRIES
            if (size(spec) >= MECH_ENTRY_SLOTS(k)) &
                call set_mech_entry(fp, k, fptr(spec(MECH_ENTRY_SLOTS(k))))
        end do
    end function mech_pointers

    !> State dimension of the first-order system (built-in by name, or from the spec).
    integer function spec_dimension(name, nspec, spec)
        character(len=*), intent(in) :: name
        integer, intent(in) :: nspec
        integer(c_int64_t), intent(in) :: spec(:)
        select case (spec_kind(nspec, spec))
        case (KIND_ODE)
            spec_dimension = int(spec(SLOT_N))
        case (KIND_GENERALIZED)
            spec_dimension = 2*int(spec(SLOT_N))
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
                call spec_c_ode(params, spec, s, info, msg)
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

    !> The compiled system of a spec of kind KIND_ODE (as `spec_system` makes it) into a
    !! non-polymorphic object, which a caller may keep in a local variable: no allocation
    !! of a polymorphic copy, and no finalization of it.
    subroutine spec_c_ode(params, spec, s, info, msg)
        real(dp), intent(in) :: params(:)
        integer(c_int64_t), intent(in) :: spec(:)
        type(c_ode_system), intent(out) :: s
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        call make_c_ode(int(spec(SLOT_N)), fptr(spec(SLOT_RHS)), fptr(spec(SLOT_JAC)), &
                        params, s, info, msg)
        if (size(spec) >= SLOT_JAC_PROD) call set_c_jac_prod(s, fptr(spec(SLOT_JAC_PROD)))
        if (size(spec) >= SLOT_TAYLOR_NW_VAR) &
            call set_c_taylor(s, fptr(spec(SLOT_TAYLOR_JET)), int(spec(SLOT_TAYLOR_NW)), &
                              fptr(spec(SLOT_TAYLOR_VAR)), int(spec(SLOT_TAYLOR_NW_VAR)))
        if (size(spec) >= SLOT_TAYLOR_ORDER_VAR) &
            call set_c_taylor_fixed(s, fptr(spec(SLOT_TAYLOR_JET_FIXED)), &
                                    int(spec(SLOT_TAYLOR_ORDER)), &
                                    fptr(spec(SLOT_TAYLOR_VAR_FIXED)), &
                                    int(spec(SLOT_TAYLOR_ORDER_VAR)))
    end subroutine spec_c_ode

    !> The first-order system of `spec_system`, which must have n state variables: else
    !! CM_BAD_INPUT with `size_msg`, or (size_msg = "") a message naming the size it needs.
    subroutine spec_system_of_size(name, params, nspec, spec, n, size_msg, sys, info, msg)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        integer, intent(in) :: nspec, n
        integer(c_int64_t), intent(in) :: spec(:)
        character(len=*), intent(in) :: size_msg
        class(ode_system), allocatable, intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        call spec_system(name, params, nspec, spec, sys, info, msg)
        call check_spec_size(name, nspec, spec, n, size_msg, info, msg)
    end subroutine spec_system_of_size

    !> The size check of `spec_system_of_size` after a system was made with status info:
    !! CM_BAD_INPUT (and the message) when it succeeded with a size other than n.
    subroutine check_spec_size(name, nspec, spec, n, size_msg, info, msg)
        character(len=*), intent(in) :: name
        integer, intent(in) :: nspec, n
        integer(c_int64_t), intent(in) :: spec(:)
        character(len=*), intent(in) :: size_msg
        integer, intent(inout) :: info
        character(len=:), allocatable, intent(inout) :: msg
        character(len=24) :: buf
        if (info /= CM_SUCCESS .or. spec_dimension(name, nspec, spec) == n) return
        info = CM_BAD_INPUT
        if (len(size_msg) > 0) then
            msg = size_msg
        else
            write (buf, '(i0)') spec_dimension(name, nspec, spec)
            msg = "bad input: y0 must have size "//trim(buf)//" for the system '"//trim(name)//"'"
        end if
    end subroutine check_spec_size

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
                call make_c_generalized(int(spec(SLOT_N)), mech_pointers(spec), params, s, &
                                        info, msg)
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
                call make_c_constrained(int(spec(SLOT_N)), int(spec(SLOT_N_HOL)), &
                                        int(spec(SLOT_N_NH)), spec(SLOT_RHEONOMIC) /= 0, &
                                        mech_pointers(spec), params, s, info, msg)
                if (info == CM_SUCCESS) allocate (cs, source=s)
            end block
        case default
            info = CM_BAD_INPUT
            msg = "bad input: not a constrained system"
        end select
    end subroutine spec_constrained

end module conmech_flat_spec
