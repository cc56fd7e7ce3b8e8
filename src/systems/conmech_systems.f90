!> Registry of the built-in systems by name, for the apps and the Python layer.
!!
!! `make_system(name, params, sys, info, msg)` allocates the built-in first-order system
!! called `name` with the parameters `params` (in the documented order; missing trailing
!! parameters keep their defaults). Each layer adds its systems here, one `case` each.
module conmech_systems
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_systems_basic
    use conmech_systems_mech, only: make_generalized_ode, mech_initial_state
    use conmech_hill, only: hill_problem
    use conmech_hill_spatial, only: hill_spatial
    use conmech_cr3bp, only: cr3bp
    implicit none
    private
    public :: make_system, system_dimension

contains

    !> Allocate a built-in system by name. Parameters (in order):
    !! harmonic: omega | pendulum: g, l | kepler: mu | arenstorf: mu | vanderpol: mu
    !! | hill: m, kappa | hill_spatial: m, kappa | cr3bp: mu
    subroutine make_system(name, params, sys, info, msg)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        class(ode_system), allocatable, intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        info = CM_SUCCESS
        msg = "success"
        select case (trim(name))
        case ("harmonic")
            block
                type(harmonic_oscillator) :: s
                if (size(params) >= 1) s%omega = params(1)
                allocate (sys, source=s)
            end block
        case ("pendulum")
            block
                type(pendulum_theta) :: s
                if (size(params) >= 1) s%g = params(1)
                if (size(params) >= 2) s%l = params(2)
                allocate (sys, source=s)
            end block
        case ("kepler")
            block
                type(kepler_2d) :: s
                if (size(params) >= 1) s%mu = params(1)
                allocate (sys, source=s)
            end block
        case ("arenstorf")
            block
                type(arenstorf) :: s
                if (size(params) >= 1) s%mu = params(1)
                allocate (sys, source=s)
            end block
        case ("vanderpol")
            block
                type(van_der_pol) :: s
                if (size(params) >= 1) s%mu = params(1)
                allocate (sys, source=s)
            end block
        case ("hill")
            block
                type(hill_problem) :: s
                if (size(params) >= 1) s%m = params(1)
                if (size(params) >= 2) s%kappa = params(2)
                allocate (sys, source=s)
            end block
        case ("hill_spatial")
            block
                type(hill_spatial) :: s
                if (size(params) >= 1) s%m = params(1)
                if (size(params) >= 2) s%kappa = params(2)
                allocate (sys, source=s)
            end block
        case ("cr3bp")
            block
                type(cr3bp) :: s
                if (size(params) >= 1) s%mu = params(1)
                allocate (sys, source=s)
            end block
        case default
            ! the generalized-coordinate seed systems (conmech_systems_mech), y = [q, q']
            call make_generalized_ode(name, params, sys, info, msg)
            if (info /= CM_SUCCESS) msg = "bad input: unknown built-in system '" &
                                          //trim(name)//"'"
        end select
    end subroutine make_system

    !> State dimension of a built-in system (0 if unknown).
    integer function system_dimension(name) result(n)
        character(len=*), intent(in) :: name
        select case (trim(name))
        case ("harmonic", "pendulum", "vanderpol")
            n = 2
        case ("kepler", "arenstorf", "hill")
            n = 4
        case ("cr3bp", "hill_spatial")
            n = 6
        case default
            n = 0
            block
                ! the generalized-coordinate seed systems: 2 ndof
                real(dp), allocatable :: q0(:), v0(:)
                integer :: info
                class(ode_system), allocatable :: sys
                character(len=:), allocatable :: msg
                call make_generalized_ode(name, [real(dp) ::], sys, info, msg)
                if (info == CM_SUCCESS) then
                    call mech_initial_state(name, [real(dp) ::], q0, v0, info)
                    if (info == CM_SUCCESS) n = 2*size(q0)
                end if
            end block
        end select
    end function system_dimension

end module conmech_systems
