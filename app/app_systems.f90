!> What the programs need to know about the built-in systems to check a command line:
!! their names and how many parameters each takes (in the order of `make_system`,
!! `make_generalized`, `make_constrained`; missing trailing parameters keep defaults; the
!! counts and names are the library's, conmech_systems_params).
module app_systems
    use conmech_systems, only: ode_names, constrained_names, generalized_names
    use conmech_systems_params, only: builtin_param_count, builtin_param_names
    implicit none
    private
    public :: ode_names, constrained_names, generalized_names, param_count, param_help

contains

    !> Number of parameters of a built-in system (-1 if unknown).
    integer function param_count(name) result(np)
        character(len=*), intent(in) :: name
        np = builtin_param_count(name)
    end function param_count

    !> The parameters of a system, named in order (for error messages).
    function param_help(name) result(s)
        character(len=*), intent(in) :: name
        character(len=:), allocatable :: s
        s = builtin_param_names(name)
    end function param_help

end module app_systems
