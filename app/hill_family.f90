!> The family of Hill's variation orbits over m, written incrementally to CSV (resumable).
!!
!!   fpm run hill_family -- --m0 0.01 --m1 0.15 --n 10000 --out family.csv
!!   (add --flag -fopenmp to run blocks of orbits on all threads)
!!
!! Columns: i,m,x0,v0,jacobi,stability_index,c,status,iterations. The orbits are computed in
!! fixed blocks of 32 consecutive grid points (block k holds i = 32(k-1)+1 .. 32k): each
!! block starts Newton cold at its first orbit and continues along the block. The blocks
!! do not depend on the thread count, the --batch size or where a run was interrupted, so
!! the file is bit-identical however it was produced. Rows are appended in order, batch by
!! batch, and flushed; a rerun with the same arguments resumes (a torn last row is dropped
!! and recomputed), other arguments are refused (OUT.args), --force starts over.
program hill_family_app
    use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
    use conmech
    use app_cli
    use app_namelist, only: check_namelist
    use app_batch
    use app_output, only: results_file
    implicit none
    !> Orbits per continuation block (part of the result's definition: do not change).
    integer, parameter :: block = 32
    character(len=*), parameter :: help = &
        "usage: hill_family [--m0 M0] [--m1 M1] [--n N] [--kappa K] [--out FILE] "// &
        "[--batch B] [--force] [--quiet]"//new_line("a")// &
        "The family of Hill's variation orbits on the grid m = m0 .. m1 (N points), one CSV"// &
        new_line("a")//"row per orbit: i,m,x0,v0,jacobi,stability_index,c,status,iterations."// &
        new_line("a")//"Options:"//new_line("a")// &
        "  --m0 M0 --m1 M1   the range of m (default 0.01 .. 0.15), >= 0"//new_line("a")// &
        "  --n N             grid points (default 10000, 1..10000000)"//new_line("a")// &
        "  --kappa K         mass parameter (default 1), > 0"//new_line("a")// &
        "  --out FILE        results CSV (default family.csv in the current directory);"// &
        new_line("a")//"                    an existing FILE made by the same arguments is"// &
        " resumed"//new_line("a")// &
        "  --batch B         orbits computed between two writes (default 1024; does not"// &
        new_line("a")//"                    change the results)"//new_line("a")// &
        "  --force           overwrite FILE made by other arguments"//new_line("a")// &
        "  --quiet           no progress line on stderr"//new_line("a")// &
        "  --input FILE.nml  read the options from a namelist &hill_family ... /"// &
        " (see jobs/hill_family.nml)"//new_line("a")//"  --help, --version"//new_line("a")// &
        "Threads: fpm run hill_family --flag -fopenmp (results identical to serial)."// &
        new_line("a")//"Exit status: 0 every orbit converged, 1 some failed (status < 0 in"// &
        " their rows), 2 bad input,"//new_line("a")//"3 the results could not be written "// &
        "(disk full, I/O error: rerun to resume)."//new_line("a")//"Example:"//new_line("a")// &
        "  hill_family --m0 0.01 --m1 0.15 --n 10000 --out family.csv"
    character(len=*), parameter :: header = &
        "i,m,x0,v0,jacobi,stability_index,c,status,iterations"
    type(cli_parser) :: cli
    type(progress_t) :: progress
    real(dp) :: m0_, m1_, kappa_
    integer :: n_, batch_, i, b0, b1, ndone, nfail, nrows, ib, nb, first_block
    character(len=1024) :: out_file
    character(len=:), allocatable :: key, canon
    logical :: force_, quiet_, fresh
    real(dp), allocatable :: ms(:)
    type(hill_orbit), allocatable :: orbs(:)
    type(hill_orbit_options) :: hopt
    logical, allocatable :: have(:)
    type(results_file) :: outf
    logical :: ok
    character(len=:), allocatable :: why, row

    call cli%start("hill_family", help)
    m0_ = 0.01_dp
    m1_ = 0.15_dp
    n_ = 10000
    kappa_ = 1.0_dp
    batch_ = 1024
    out_file = "family.csv"
    force_ = .false.
    quiet_ = .false.
    if (len(cli%input) > 0) call read_input()
    do while (cli%next(key))
        select case (key)
        case ("--m0"); call cli%get_real(m0_)
        case ("--m1"); call cli%get_real(m1_)
        case ("--n"); call cli%get_int(n_)
        case ("--kappa"); call cli%get_real(kappa_)
        case ("--batch"); call cli%get_int(batch_)
        case ("--out"); call cli%get_string(out_file)
        case ("--force"); call cli%flag(); force_ = .true.
        case ("--quiet"); call cli%flag(); quiet_ = .true.
        case default; call cli%unknown()
        end select
    end do
    if (.not. (m0_ >= 0.0_dp .and. m0_ <= huge(m0_))) call cli%fail("--m0 must be >= 0 "// &
                                                                     "and finite")
    if (.not. (m1_ >= 0.0_dp .and. m1_ <= huge(m1_))) call cli%fail("--m1 must be >= 0 "// &
                                                                     "and finite")
    if (.not. (kappa_ > 0.0_dp .and. kappa_ <= huge(kappa_))) &
        call cli%fail("--kappa must be positive and finite")
    if (n_ < 1 .or. n_ > max_jobs) call cli%fail("--n must be in 1..10000000")
    if (batch_ < 1 .or. batch_ > max_jobs) call cli%fail("--batch must be in 1..10000000")
    if (len_trim(out_file) == 0) call cli%fail("--out must not be empty")
    batch_ = block*((batch_ + block - 1)/block)
    canon = "m0="//fmt_real(m0_)//" m1="//fmt_real(m1_)//" n="//itoa(n_)//" kappa="// &
        fmt_real(kappa_)//" block="//itoa(block)

    allocate (ms(n_))
    do i = 1, n_
        ms(i) = m0_
        if (n_ > 1) ms(i) = m0_ + (m1_ - m0_)*real(i - 1, dp)/real(n_ - 1, dp)
    end do

    ! ---- resume: check OUT before the first orbit (arguments, header, rows 1..k in order)
    call check_args_file(cli, trim(out_file), canon, force_, fresh)
    call write_args_file(cli, trim(out_file), canon)
    allocate (have(n_))
    have = .false.
    ndone = 0
    if (.not. fresh .and. file_size(trim(out_file)) > 0) then
        call load_rows(cli, trim(out_file), header, 9, 1, n_, .true., .true., have, ndone)
        if (file_size(trim(out_file)) > 0) write (*, '(a, i0, a)') "resuming: ", ndone, &
            " orbits already in "//trim(out_file)
    end if
    if (file_size(trim(out_file)) <= 0) then
        ! a new file (or one whose header was torn): start it with the header
        call outf%open(trim(out_file), "w", ok, why)
        if (.not. ok) call cli%fail("cannot write "//trim(out_file)//": "//why)
        call outf%put(header, ok, why)
        if (ok) call outf%close(ok, why)
        if (.not. ok) call cli%fail_io("cannot write "//trim(out_file)//": "//why)
    end if
    deallocate (have)
    call outf%open(trim(out_file), "a", ok, why)
    if (.not. ok) call cli%fail("cannot append to "//trim(out_file)//": "//why)
    call progress%begin("hill_family", n_, ndone, on=.not. quiet_)

    ! the multipliers (dgeev) are not written: S and c come from the quarter map
    hopt%eigenvalues = .false.
    ! batches of whole blocks, from the block holding the first missing orbit
    first_block = ndone/block + 1
    do b0 = (first_block - 1)*block + 1, n_, batch_
        b1 = min(n_, b0 + batch_ - 1)
        allocate (orbs(b0:b1))
        nb = (b1 - b0)/block + 1
        !$omp parallel do schedule(dynamic) default(shared) private(ib, i)
        do ib = 1, nb
            i = b0 + (ib - 1)*block
            call hill_family(ms(i:min(b1, i + block - 1)), kappa_, &
                             orbs(i:min(b1, i + block - 1)), hopt, nchunks=1)
        end do
        !$omp end parallel do
        do i = max(b0, ndone + 1), b1
            row = itoa(i)//","//fmt_real(ms(i))//","//fmt_real(orbs(i)%y0(1))// &
                ","//fmt_real(orbs(i)%y0(4))//","//fmt_real(orbs(i)%jacobi)//","// &
                fmt_real(orbs(i)%stability_index)//","//fmt_real(orbs(i)%c)//","// &
                itoa(orbs(i)%info)//","//itoa(orbs(i)%iterations)
            call outf%put(row, ok, why)
            if (.not. ok) exit
        end do
        if (ok) call outf%flush(ok, why)
        ! a full disk or an I/O error is not a failed orbit: say what it is
        if (.not. ok) call cli%fail_io("cannot write "//trim(out_file)//": "//why)
        deallocate (orbs)
        call progress%tick(b1)
    end do
    call outf%close(ok, why)
    if (.not. ok) call cli%fail_io("cannot write "//trim(out_file)//": "//why)

    ! the whole file: count rows and failures
    allocate (have(n_))
    have = .false.
    call load_rows(cli, trim(out_file), header, 9, 1, n_, .true., .false., have, nrows, &
                   status_col=8, nfail=nfail)
    write (*, '(a, i0, a)') "wrote "//trim(out_file)//" (", nrows, " orbits)"
    flush (output_unit)
    deallocate (key, canon, ms, have)
    if (allocated(why)) deallocate (why)
    if (allocated(row)) deallocate (row)
    if (allocated(outf%name)) deallocate (outf%name)
    call cli%clear()
    call progress%clear()
    if (nrows /= n_) then
        write (error_unit, '(a)') "hill_family: error: the file is incomplete"
        stop 1, quiet=.true.
    end if
    if (nfail > 0) then
        write (error_unit, '(a, i0, a, i0, a)') "hill_family: ", nfail, " of ", n_, &
            " orbits failed (status /= 0 in their rows)"
        stop 1, quiet=.true.
    end if

contains

    function itoa(k) result(s)
        integer, intent(in) :: k
        character(len=:), allocatable :: s
        character(len=16) :: b
        write (b, '(i0)') k
        s = trim(b)
    end function itoa

    !> The options from a namelist &hill_family ... / (the command line overrides them).
    subroutine read_input()
        real(dp) :: m0, m1, kappa
        integer :: n, batch, ios2
        character(len=:), allocatable :: lines(:)
        character(len=1024) :: out
        logical :: force, quiet
        character(len=512) :: msg
        namelist /hill_family/ m0, m1, n, kappa, batch, out, force, quiet
        m0 = m0_; m1 = m1_; n = n_; kappa = kappa_; batch = batch_; out = out_file
        force = force_; quiet = quiet_
        call check_namelist(cli, cli%input, "hill_family", &
            "m0:r m1:r n:i kappa:r batch:i out:s1024 force:l quiet:l", lines)
        read (lines, nml=hill_family, iostat=ios2, iomsg=msg)
        if (ios2 /= 0) call cli%fail("--input "//cli%input//": namelist &hill_family: "// &
                                     trim(msg))
        m0_ = m0; m1_ = m1; n_ = n; kappa_ = kappa; batch_ = batch; out_file = out
        force_ = force; quiet_ = quiet
    end subroutine read_input

end program hill_family_app
