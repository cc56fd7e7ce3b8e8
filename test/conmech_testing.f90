!> Minimal test assertions for conmech's Fortran tests (no external dependencies).
!! Each test program creates a `test_suite`, calls `check*` and ends with `suite%finish()`,
!! which prints "N passed, N failed" and exits non-zero if anything failed.
module conmech_testing
    use conmech_kinds, only: dp
    implicit none
    private
    public :: test_suite

    type :: test_suite
        character(len=:), allocatable :: name
        integer :: npass = 0
        integer :: nfail = 0
    contains
        procedure :: check => suite_check
        procedure :: check_close => suite_check_close
        procedure :: check_less => suite_check_less
        procedure :: finish => suite_finish
    end type test_suite

contains

    subroutine suite_check(self, ok, what)
        class(test_suite), intent(inout) :: self
        logical, intent(in) :: ok
        character(len=*), intent(in) :: what
        if (ok) then
            self%npass = self%npass + 1
            write (*, '(a)') "  ok    "//what
        else
            self%nfail = self%nfail + 1
            write (*, '(a)') "  FAIL  "//what
        end if
    end subroutine suite_check

    !> |actual - expected| <= tol (absolute).
    subroutine suite_check_close(self, actual, expected, tol, what)
        class(test_suite), intent(inout) :: self
        real(dp), intent(in) :: actual, expected, tol
        character(len=*), intent(in) :: what
        character(len=160) :: buf
        write (buf, '(a,es23.15,a,es23.15,a,es9.2,a)') " (got", actual, ", want", expected, &
            ", tol", tol, ")"
        call self%check(abs(actual - expected) <= tol, what//trim(buf))
    end subroutine suite_check_close

    !> value < bound.
    subroutine suite_check_less(self, value, bound, what)
        class(test_suite), intent(inout) :: self
        real(dp), intent(in) :: value, bound
        character(len=*), intent(in) :: what
        character(len=80) :: buf
        write (buf, '(a,es11.4,a,es11.4,a)') " (", value, " < ", bound, ")"
        call self%check(value < bound, what//trim(buf))
    end subroutine suite_check_less

    subroutine suite_finish(self)
        class(test_suite), intent(in) :: self
        write (*, '(a,": ",i0," passed, ",i0," failed")') self%name, self%npass, self%nfail
        if (self%nfail > 0) error stop 1
    end subroutine suite_finish

end module conmech_testing
