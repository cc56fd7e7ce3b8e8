!> Support of the flat f2py layer for ensembles (compiled into the extension, not wrapped).
!!
!! `builtin_members` gives member i the built-in system `name` (or the compiled system of
!! `spec`, conmech_flat_spec) with the parameters of column i of a table;
!! `callback_progress` relays the ensemble's progress reports to an external procedure
!! progress(done, total, cancel)
!! (an f2py callback into Python, called by the calling thread between chunks only).
module conmech_flat_ensemble_support
    use, intrinsic :: iso_c_binding, only: c_int, c_int64_t
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_system
    use conmech_flat_spec, only: spec_system
    use conmech_ensemble, only: ensemble_members, ensemble_progress
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

    !> Progress reports relayed to progress(done, total, cancel), all integer(c_int).
    type, extends(ensemble_progress) :: callback_progress
        procedure(), pointer, nopass :: f => null()
    contains
        procedure :: report => callback_report
    end type callback_progress

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

    subroutine callback_report(self, done, total, cancel)
        class(callback_progress), intent(inout) :: self
        integer, intent(in) :: done, total
        logical, intent(out) :: cancel
        integer(c_int) :: d, t, c
        d = done
        t = total
        c = 0
        call self%f(d, t, c)
        cancel = c /= 0
    end subroutine callback_report

end module conmech_flat_ensemble_support
