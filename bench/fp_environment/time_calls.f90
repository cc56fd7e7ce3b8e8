!> ns per call of an external procedure that sees an IEEE module's names against one that
!! does not (the same work: x = x + 1).
program time_calls
    implicit none
    real(8) :: x
    integer :: i
    integer, parameter :: n = 10000000
    integer(8) :: c0, c1, rate
    x = 0
    call system_clock(c0, rate)
    do i = 1, n
        call sees_ieee(x)
    end do
    call system_clock(c1)
    print '(a, f8.1, a)', "sees an IEEE module:", real(c1 - c0, 8)/rate/n*1e9, " ns per call"
    call system_clock(c0, rate)
    do i = 1, n
        call plain(x)
    end do
    call system_clock(c1)
    print '(a, f8.1, a)', "does not:           ", real(c1 - c0, 8)/rate/n*1e9, " ns per call"
    if (x /= 2.0d0*n) print *, "wrong sum"
end program time_calls
