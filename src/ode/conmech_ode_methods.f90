!> The method table: for each method code (conmech_ode_options), its names, its
!! properties and its stepper type. `ode_solve`, `ode_integrate`, the flat layer and the
!! Python package (method names, which methods need a step or take a Jacobian) all read
!! it, so a new method is a stepper type and one `case` here (see
!! docs/guide/adding_an_integrator.rst).
module conmech_ode_methods
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_options
    use conmech_ode_stepper, only: ode_stepper
    use conmech_rk_stepper, only: rk_stepper
    use conmech_taylor_stepper, only: taylor_stepper
    use conmech_radau_stepper, only: radau_stepper
    use conmech_gauss, only: gauss_stepper
    implicit none
    private

    public :: method_info, method_entry, new_stepper, method_from_name
    !> Codes are looked up in 1 .. MAX_METHOD_CODE.
    integer, parameter, public :: MAX_METHOD_CODE = 32

    !> What the drivers and the Python layer need to know of a method.
    type :: method_info
        integer :: code = 0                     !! METHOD_* (0: no method of this code)
        character(len=16) :: name = ""          !! canonical name ("DOP853")
        character(len=48) :: aliases = ""       !! other accepted names, space separated
        integer :: order = 0                    !! order of the propagated solution
        logical :: fixed_step = .false.         !! first_step is the step, required
        logical :: uses_jacobian = .false.      !! takes the system's df/dy
        logical :: constrained_only = .false.   !! only for constrained systems
    end type method_info

contains

    !> The table: the entry of method `code` (info%code = 0 if there is none) and, if
    !! `stp` is present, a fresh stepper of its type (unallocated when the method has no
    !! stepper of the ODE layer: RATTLE is built by constrained_solve).
    subroutine method_entry(code, info, stp)
        integer, intent(in) :: code
        type(method_info), intent(out) :: info
        class(ode_stepper), allocatable, intent(out), optional :: stp
        select case (code)
        case (METHOD_RK4)
            info = method_info(code, "RK4", "", 4, fixed_step=.true.)
            if (present(stp)) allocate (rk_stepper :: stp)
        case (METHOD_DOPRI5)
            info = method_info(code, "DOPRI5", "RK45", 5)
            if (present(stp)) allocate (rk_stepper :: stp)
        case (METHOD_DOP853)
            info = method_info(code, "DOP853", "", 8)
            if (present(stp)) allocate (rk_stepper :: stp)
        case (METHOD_VERNER98)
            info = method_info(code, "VERNER98", "RKV98 VERN9", 9)
            if (present(stp)) allocate (rk_stepper :: stp)
        case (METHOD_RADAU5)
            info = method_info(code, "RADAU5", "RADAU", 5, uses_jacobian=.true.)
            if (present(stp)) allocate (radau_stepper :: stp)
        case (METHOD_GAUSS4)
            info = method_info(code, "GAUSS4", "", 4, fixed_step=.true.)
            if (present(stp)) allocate (gauss_stepper :: stp)
        case (METHOD_GAUSS6)
            info = method_info(code, "GAUSS6", "", 6, fixed_step=.true.)
            if (present(stp)) allocate (gauss_stepper :: stp)
        case (METHOD_TAYLOR)     ! order from the tolerance (15 at 1e-12)
            info = method_info(code, "TAYLOR", "", 0)
            if (present(stp)) allocate (taylor_stepper :: stp)
        case (METHOD_RATTLE)
            info = method_info(code, "RATTLE", "", 2, fixed_step=.true., &
                               constrained_only=.true.)
        case default
            info = method_info()
        end select
    end subroutine method_entry

    !> A fresh stepper for method `code`; CM_BAD_INPUT with a message if there is none.
    subroutine new_stepper(code, stp, info, msg)
        integer, intent(in) :: code
        class(ode_stepper), allocatable, intent(out) :: stp
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(method_info) :: mi
        call method_entry(code, mi, stp)
        info = CM_SUCCESS
        msg = "success"
        if (allocated(stp)) return
        info = CM_BAD_INPUT
        if (mi%constrained_only) then
            msg = "bad input: "//trim(mi%name)//" is a method for constrained systems " &
                  //"(constrained_solve, conmech.constrained.solve)"
        else
            msg = "bad input: unknown method"
        end if
    end subroutine new_stepper

    !> Method code from a name, case-insensitive: a canonical name of the table ("RK4",
    !! "DOPRI5", "DOP853", "VERNER98", "RADAU5", "GAUSS4", "GAUSS6", "RATTLE", ...) or one
    !! of its aliases ("RK45", "RKV98", "Vern9", "Radau"); 0 if unknown.
    function method_from_name(name) result(m)
        character(len=*), intent(in) :: name
        integer :: m
        type(method_info) :: mi
        character(len=len(name)) :: key
        character(len=64) :: names
        integer :: code, i, j
        key = upper(adjustl(name))
        m = 0
        if (len_trim(key) == 0) return
        do code = 1, MAX_METHOD_CODE
            call method_entry(code, mi)
            if (mi%code == 0) cycle
            names = trim(mi%name)//" "//upper(mi%aliases)
            i = 1
            do while (i <= len_trim(names))
                j = index(names(i:), " ") + i - 2
                if (names(i:j) == trim(key)) then
                    m = code
                    return
                end if
                i = j + 2
            end do
        end do
    end function method_from_name

    pure function upper(s) result(u)
        character(len=*), intent(in) :: s
        character(len=len(s)) :: u
        integer :: i, c
        u = s
        do i = 1, len(s)
            c = iachar(s(i:i))
            if (c >= iachar("a") .and. c <= iachar("z")) u(i:i) = achar(c - 32)
        end do
    end function upper

end module conmech_ode_methods
