!> The family of Hill's variation orbits over m, written incrementally to CSV (resumable).
!!
!!   fpm run hill_family -- --m0 0.01 --m1 0.15 --n 10000 --out family.csv [--kappa 1]
!!                          [--batch 1000]
!!   (add --flag -fopenmp to run the orbits of a batch on all threads)
!!
!! Columns: i,m,x0,v0,jacobi,stability_index,c,status,iterations. Rows are appended batch
!! by batch and flushed; rerunning the same command after an interruption keeps the rows
!! already written and computes only the rest. Exit status 0 when every orbit converged,
!! 1 if some failed (their rows have status < 0), 2 on bad arguments.
program hill_family_app
    use conmech
    implicit none
    real(dp) :: m0, m1, kappa
    integer :: n, batch, i, i0, i1, ios, u, ndone, narg, nfail, k
    character(len=256) :: arg, val, line
    character(len=:), allocatable :: out
    real(dp), allocatable :: ms(:)
    type(hill_orbit), allocatable :: orbs(:)
    logical :: exists

    m0 = 0.01_dp
    m1 = 0.15_dp
    n = 10000
    kappa = 1.0_dp
    batch = 1000
    out = "family.csv"
    narg = command_argument_count()
    i = 1
    do while (i <= narg)
        call get_command_argument(i, arg)
        if (i == narg) call usage_error("missing value after "//trim(arg))
        call get_command_argument(i + 1, val)
        ios = 0
        select case (trim(arg))
        case ("--m0")
            read (val, *, iostat=ios) m0
        case ("--m1")
            read (val, *, iostat=ios) m1
        case ("--n")
            read (val, *, iostat=ios) n
            if (n < 1) ios = 1
        case ("--kappa")
            read (val, *, iostat=ios) kappa
        case ("--batch")
            read (val, *, iostat=ios) batch
            if (batch < 1) ios = 1
        case ("--out")
            out = trim(val)
        case default
            call usage_error("unknown option "//trim(arg))
        end select
        if (ios /= 0) call usage_error("bad value for "//trim(arg)//": "//trim(val))
        i = i + 2
    end do
    if (.not. (m0 >= 0.0_dp .and. m1 >= 0.0_dp .and. kappa > 0.0_dp)) &
        call usage_error("need m0, m1 >= 0 and kappa > 0")

    allocate (ms(n))
    do i = 1, n
        ms(i) = m0
        if (n > 1) ms(i) = m0 + (m1 - m0)*real(i - 1, dp)/real(n - 1, dp)
    end do

    ! resume: count the complete rows already written
    ndone = 0
    inquire (file=out, exist=exists)
    if (exists) then
        open (newunit=u, file=out, status="old", action="read", iostat=ios)
        if (ios /= 0) call fail("cannot read "//out)
        read (u, '(a)', iostat=ios) line
        do
            read (u, '(a)', iostat=ios) line
            if (ios /= 0) exit
            if (index(line, ",") > 0 .and. len_trim(line) > 20) ndone = ndone + 1
        end do
        close (u)
        ndone = min(ndone, n)
        ! rewrite exactly the complete rows (drops a partial last line)
        call truncate_rows(out, ndone)
        write (*, '(a, i0, a)') "resuming: ", ndone, " orbits already in "//out
    else
        open (newunit=u, file=out, status="replace", action="write", iostat=ios)
        if (ios /= 0) call fail("cannot create "//out)
        write (u, '(a)') "i,m,x0,v0,jacobi,stability_index,c,status,iterations"
        close (u)
    end if

    nfail = 0
    open (newunit=u, file=out, status="old", position="append", action="write", iostat=ios)
    if (ios /= 0) call fail("cannot append to "//out)
    do i0 = ndone + 1, n, batch
        i1 = min(n, i0 + batch - 1)
        allocate (orbs(i1 - i0 + 1))
        call hill_family(ms(i0:i1), kappa, orbs)
        do k = 1, size(orbs)
            write (u, '(i0, 6(",", es24.16), ",", i0, ",", i0)') i0 + k - 1, ms(i0 + k - 1), &
                orbs(k)%y0(1), orbs(k)%y0(4), orbs(k)%jacobi, orbs(k)%stability_index, &
                orbs(k)%c, orbs(k)%info, orbs(k)%iterations
            if (orbs(k)%info /= CM_SUCCESS) nfail = nfail + 1
        end do
        flush (u)
        deallocate (orbs)
        write (*, '(a, i0, a, i0)') "done ", i1, " / ", n
    end do
    close (u)
    write (*, '(a, i0, a)') "wrote "//out//" (", nfail, " failures in this run)"
    if (nfail > 0) error stop 1

contains

    subroutine truncate_rows(name, nrows)
        character(len=*), intent(in) :: name
        integer, intent(in) :: nrows
        character(len=512), allocatable :: rows(:)
        character(len=512) :: hdr
        integer :: uu, j, ios2
        allocate (rows(max(nrows, 1)))
        open (newunit=uu, file=name, status="old", action="read")
        read (uu, '(a)') hdr
        do j = 1, nrows
            read (uu, '(a)', iostat=ios2) rows(j)
        end do
        close (uu)
        open (newunit=uu, file=name, status="replace", action="write")
        write (uu, '(a)') trim(hdr)
        do j = 1, nrows
            write (uu, '(a)') trim(rows(j))
        end do
        close (uu)
    end subroutine truncate_rows

    subroutine usage_error(msg)
        character(len=*), intent(in) :: msg
        write (*, '(a)') "error: "//msg
        write (*, '(a)') "usage: hill_family [--m0 M0] [--m1 M1] [--n N] [--kappa K] "// &
            "[--out FILE] [--batch B]"
        error stop 2
    end subroutine usage_error

    subroutine fail(msg)
        character(len=*), intent(in) :: msg
        write (*, '(a)') "error: "//msg
        error stop 1
    end subroutine fail

end program hill_family_app
