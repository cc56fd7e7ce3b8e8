!> A module whose scope uses an intrinsic IEEE module (for one inlined test), and two
!! external procedures: `sees_ieee` uses that module (for nothing IEEE), `plain` does not.
!! gfortran wraps every call of `sees_ieee` in _gfortran_ieee_procedure_entry/_exit, which
!! save and restore the whole floating-point environment.
module uses_ieee
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    implicit none
contains
    logical function finite(x)
        real(8), intent(in) :: x
        finite = ieee_is_finite(x)
    end function finite
end module uses_ieee

subroutine sees_ieee(x)
    use uses_ieee, only: finite
    implicit none
    real(8), intent(inout) :: x
    x = x + 1
end subroutine sees_ieee

subroutine plain(x)
    implicit none
    real(8), intent(inout) :: x
    x = x + 1
end subroutine plain
