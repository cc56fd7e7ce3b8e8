!> The parameter count and names of a built-in system (conmech_systems_params), so that
!! the Python layer checks parameter lists exactly as the registries and the programs do.

!> count = the number of parameters of the built-in `name` (-1 if unknown); names = their
!! names in order, comma-separated.
subroutine flat_builtin_params(name, count, names)
    use, intrinsic :: iso_c_binding, only: c_int
    use conmech_systems_params, only: builtin_param_count, builtin_param_names
    implicit none
    character(len=*), intent(in) :: name
    integer(c_int), intent(out) :: count
    character(len=256), intent(out) :: names
    count = int(builtin_param_count(name), c_int)
    names = builtin_param_names(name)
end subroutine flat_builtin_params
