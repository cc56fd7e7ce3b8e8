!> Support of the flat f2py layer for ensembles (compiled into the extension, not wrapped).
!!
!! `builtin_members` gives member i the built-in system `name` (or the compiled system of
!! `spec`, conmech_flat_spec) with the parameters of column i of a table;
!! `callback_progress` (conmech_flat_adapters, re-exported) relays the ensemble's progress
!! reports to a Python progress(done, total, cancel).
module conmech_flat_ensemble_support
    use, intrinsic :: iso_c_binding, only: c_int, c_int64_t
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_system
    use conmech_flat_spec, only: spec_system
    use conmech_ensemble, only: ensemble_members
    use conmech_flat_adapters, only: callback_progress
    implicit none
    private
    public :: builtin_members, callback_progress

    !> Member i: the built-in system `name` with parameters params(:, i).
    type, extends(ensemble_members) :: builtin_members
        character(len=:), allocatable :: name
        real(dp), allocatable :: params(:, :)   !! (np, m)
        integer :: nspec = 0                    !! 0: built-in `name`
        integer(c_int64_t), allocatable :: spec(:)
    contains
        procedure :: count => builtin_count
        procedure :: system => builtin_system
    end type builtin_members

contains

    integer function builtin_count(self)
        class(builtin_members), intent(in) :: self
        builtin_count = size(self%params, 2)
    end function builtin_count

    subroutine builtin_system(self, i, sys, info, msg)
        class(builtin_members), intent(in) :: self
        integer, intent(in) :: i
        class(ode_system), allocatable, intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        call spec_system(self%name, self%params(:, i), self%nspec, self%spec, sys, info, msg)
    end subroutine builtin_system

end module conmech_flat_ensemble_support
