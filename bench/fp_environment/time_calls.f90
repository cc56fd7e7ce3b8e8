!> ns per call of an external procedure that sees an IEEE module's names against one that
!! does not (the same work: x = x + 1; both called through a dummy procedure).
program time_calls
    implicit none
    interface
        subroutine step(x)
            real(8), intent(inout) :: x
        end subroutine step
    end interface
    procedure(step) :: sees_ieee, plain
    print '(a, f8.1, a)', "sees an IEEE module:", per_call(sees_ieee), " ns per call"
    print '(a, f8.1, a)', "does not:           ", per_call(plain), " ns per call"
contains
    real(8) function per_call(proc)
        procedure(step) :: proc
        integer, parameter :: n = 10000000
        real(8) :: x
        integer :: i
        integer(8) :: c0, c1, rate
        x = 0
        call system_clock(c0, rate)
        do i = 1, n
            call proc(x)
        end do
        call system_clock(c1)
        per_call = real(c1 - c0, 8)/rate/n*1e9
        if (x /= real(n, 8)) print *, "wrong sum"
    end function per_call
end program time_calls
