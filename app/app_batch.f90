!> Batch results on disk, shared by sweep and hill_family: the arguments file that ties a
!! results CSV to the command that made it, validation of an existing CSV before a resume
!! (torn last line repaired, junk rejected naming the line), durable replace (write to a
!! temporary name, fsync, rename) and a progress line on stderr.
!!
!! A results file OUT is a plain CSV (one header line of column names, one row per job) so
!! that every CSV reader parses it; OUT.args next to it records the arguments that define
!! the jobs. A rerun with the same arguments resumes; different arguments are refused
!! (--force starts over).
module app_batch
    use, intrinsic :: iso_fortran_env, only: error_unit, int64
    use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char, c_long
    use conmech_kinds, only: dp
    use app_cli, only: cli_parser, parse_real, parse_int
    use app_output, only: results_file
    implicit none
    private
    public :: row_t, load_rows, check_args_file, write_args_file, file_exists, file_size
    public :: delete_file, durable_rename, progress_t, max_jobs

    !> Largest number of jobs / orbits / points a program accepts.
    integer, parameter :: max_jobs = 10000000

    !> One CSV row kept as text.
    type :: row_t
        character(len=:), allocatable :: s
    end type row_t

    !> Progress line on stderr: done/total, rate, ETA (every few seconds).
    type :: progress_t
        character(len=:), allocatable :: prog
        integer :: total = 0, start_done = 0
        logical :: on = .true.
        integer(int64) :: t0 = 0, last = 0, rate = 1
        real(dp) :: every = 5.0_dp   !! seconds between lines (CONMECH_PROGRESS_SECONDS)
    contains
        procedure :: begin => progress_begin
        procedure :: tick => progress_tick
        procedure :: clear => progress_clear
    end type progress_t

    interface
        integer(c_int) function c_open(path, flags) bind(C, name="open")
            import :: c_int, c_char
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int), value :: flags
        end function c_open
        integer(c_int) function c_fsync(fd) bind(C, name="fsync")
            import :: c_int
            integer(c_int), value :: fd
        end function c_fsync
        integer(c_int) function c_close(fd) bind(C, name="close")
            import :: c_int
            integer(c_int), value :: fd
        end function c_close
        integer(c_int) function c_rename(old, new) bind(C, name="rename")
            import :: c_int, c_char
            character(kind=c_char), intent(in) :: old(*), new(*)
        end function c_rename
        integer(c_int) function c_truncate(path, length) bind(C, name="truncate")
            import :: c_int, c_char, c_long
            character(kind=c_char), intent(in) :: path(*)
            integer(c_long), value :: length
        end function c_truncate
    end interface

contains

    logical function file_exists(name)
        character(len=*), intent(in) :: name
        inquire (file=name, exist=file_exists)
    end function file_exists

    !> Size in bytes (-1 if missing).
    integer(int64) function file_size(name)
        character(len=*), intent(in) :: name
        logical :: ex
        inquire (file=name, exist=ex, size=file_size)
        if (.not. ex) file_size = -1
    end function file_size

    subroutine delete_file(name)
        character(len=*), intent(in) :: name
        integer :: u, ios
        if (.not. file_exists(name)) return
        open (newunit=u, file=name, status="old", iostat=ios)
        if (ios == 0) close (u, status="delete")
    end subroutine delete_file

    !> fsync `tmp` (already closed), rename it to `final` (atomic), fsync again.
    subroutine durable_rename(tmp, final, ok)
        character(len=*), intent(in) :: tmp, final
        logical, intent(out) :: ok
        integer(c_int) :: fd, rc
        fd = c_open(tmp//c_null_char, 0_c_int)
        ok = fd >= 0
        if (.not. ok) return
        rc = c_fsync(fd)
        ok = rc == 0
        rc = c_close(fd)
        if (.not. ok) return
        ok = c_rename(tmp//c_null_char, final//c_null_char) == 0
    end subroutine durable_rename

    !> The arguments file: refuse OUT made by other arguments; with `force` start over.
    !! `fresh` is .true. when there is nothing to resume.
    subroutine check_args_file(cli, out, args, force, fresh)
        type(cli_parser), intent(inout) :: cli
        character(len=*), intent(in) :: out, args
        logical, intent(in) :: force
        logical, intent(out) :: fresh
        character(len=4096) :: line
        integer :: u, ios
        fresh = .true.
        if (force) then
            call delete_file(out)
            call delete_file(out//".args")
            return
        end if
        if (file_exists(out//".args")) then
            open (newunit=u, file=out//".args", status="old", action="read", iostat=ios)
            if (ios == 0) read (u, '(a)', iostat=ios) line
            if (ios == 0) read (u, '(a)', iostat=ios) line
            if (ios /= 0) call cli%fail("cannot read "//out//".args (use --force to start over)")
            close (u)
            if (trim(line) /= args) call cli%fail(out//" was made by different arguments:"// &
                new_line("a")//"  file: "//trim(line)//new_line("a")//"  now:  "//args// &
                new_line("a")//"use another --out, or --force to overwrite it")
            fresh = .false.
        else if (file_size(out) > 0) then
            call cli%fail(out//" exists without "//out//".args (not made by "//cli%prog// &
                          "?); use another --out, or --force to overwrite it")
        end if
    end subroutine check_args_file

    !> Write OUT.args: a comment, the canonical arguments, the command as typed.
    subroutine write_args_file(cli, out, args)
        type(cli_parser), intent(inout) :: cli
        character(len=*), intent(in) :: out, args
        integer :: l
        character(len=:), allocatable :: cmd, msg
        type(results_file) :: f
        logical :: ok
        call get_command(length=l)
        allocate (character(len=l) :: cmd)
        call get_command(cmd)
        call f%open(out//".args", "w", ok, msg)
        if (.not. ok) call cli%fail("cannot write "//out//".args: "//msg)
        call f%put("# conmech "//cli%prog//": the arguments that made "//out// &
                   " (a resume must match them)"//new_line("a")//args//new_line("a")// &
                   "# command: "//cmd, ok, msg)
        if (ok) then
            call f%close(ok, msg)
        else
            call f%close(ok, cmd)
            ok = .false.
        end if
        if (.not. ok) call cli%fail_io("cannot write "//out//".args: "//msg)
    end subroutine write_args_file

    !> Is this a number as the programs write it (incl. NaN, Infinity)?
    logical function csv_number(s)
        character(len=*), intent(in) :: s
        real(dp) :: x
        select case (trim(adjustl(s)))
        case ("NaN", "Infinity", "-Infinity", "+Infinity")
            csv_number = .true.
        case default
            call parse_real(s, x, csv_number)
        end select
    end function csv_number

    !> Read and check an existing results CSV: line 1 must be `header`, every row
    !! `nfields` numbers with an integer key in [lo, hi] first (`ordered`: keys lo, lo+1,..
    !! in this order). A last line without its newline (torn by a kill) is dropped; with
    !! `repair` it is also cut from the file. A key seen twice: a row identical to the first
    !! copy is a duplicate (a resume of a copied or merged file) and is dropped (with
    !! `repair` also from the file, rewritten durably, with a note on stderr); a different
    !! row is an error naming both lines. Any other bad line, a key out of range, or (when
    !! `ordered`) out of order is an error naming the file and line.
    !! have(key) / rows(key)%s receive the rows (the first copy wins; with `rows`, a key
    !! already there from an earlier file is compared with it); nrows counts the distinct
    !! keys of this file; nfail the rows whose field `status_col` is not 0; in_order tells
    !! whether the keys come in increasing order.
    subroutine load_rows(cli, file, header, nfields, lo, hi, ordered, repair, have, nrows, &
                         rows, status_col, nfail, in_order)
        type(cli_parser), intent(inout) :: cli
        character(len=*), intent(in) :: file, header
        integer, intent(in) :: nfields, lo, hi
        logical, intent(in) :: ordered, repair
        logical, intent(inout) :: have(lo:)
        integer, intent(out) :: nrows
        type(row_t), intent(inout), optional :: rows(lo:)
        integer, intent(in), optional :: status_col
        integer, intent(out), optional :: nfail
        logical, intent(out), optional :: in_order
        integer(int64) :: sz, keep, here
        integer(int64), allocatable :: first_at(:)
        integer, allocatable :: first_line(:), dups(:)
        integer :: u, ios, ln, key, nf, a, b, j, sl, ndup, last_key
        character(len=8192) :: line
        character :: last
        logical :: torn, ok, failed, seen_here, sorted
        character(len=:), allocatable :: first, kname
        kname = header(:max(1, index(header, ",") - 1))
        nrows = 0
        ndup = 0
        last_key = lo - 1
        sorted = .true.
        if (present(nfail)) nfail = 0
        if (present(in_order)) in_order = .true.
        sz = file_size(file)
        if (sz <= 0) return
        open (newunit=u, file=file, access="stream", form="unformatted", action="read", &
              status="old", iostat=ios)
        if (ios /= 0) call cli%fail("cannot read "//file)
        read (u, pos=sz) last
        close (u)
        torn = last /= new_line("a")
        allocate (first_at(lo:hi), first_line(lo:hi), dups(16))
        first_line = 0
        open (newunit=u, file=file, status="old", action="read", iostat=ios)
        if (ios /= 0) call cli%fail("cannot read "//file)
        ln = 0
        keep = 0
        do
            read (u, '(a)', iostat=ios, size=sl, advance="no") line
            if (is_iostat_end(ios)) exit
            if (ios /= 0 .and. .not. is_iostat_eor(ios)) then
                sl = len(line) + 1   ! longer than any row: junk
            end if
            ln = ln + 1
            if (ios /= 0 .and. .not. is_iostat_eor(ios)) then
                ! skip the rest of an over-long line
                read (u, '(a)', iostat=ios)
            end if
            if (torn) then
                ! is this the last line? peek by position: the torn tail has no newline
                if (keep + sl >= sz) then
                    if (repair) then
                        close (u)
                        call cut(file, keep)
                        if (ln == 1) call cli%fail(file//" has a torn header line (a kill "// &
                            "during its creation?); use --force")
                        write (error_unit, '(a)') cli%prog//": "//file//" line "// &
                            itoa(ln)//": incomplete last row dropped (a kill mid-write)"
                        u = -1
                    end if
                    exit
                end if
            end if
            here = keep
            keep = keep + sl + 1
            if (ln == 1) then
                if (line(:sl) /= header) call cli%fail(file//" line 1: header '"// &
                    line(:min(sl, 200))//"' is not '"//header//"'")
                cycle
            end if
            ! a row: nfields comma-separated numbers, the first an integer key
            ok = sl <= len(line)
            nf = 0
            failed = .false.
            key = lo - 1
            if (ok) then
                a = 1
                do j = 1, nfields
                    b = index(line(a:sl), ",")
                    if (j < nfields .and. b == 0) then
                        ok = .false.
                        exit
                    end if
                    if (j == nfields) then
                        if (b /= 0) then
                            ok = .false.
                            exit
                        end if
                        b = sl + 1
                    else
                        b = a + b - 1
                    end if
                    if (j == 1) then
                        call parse_int(line(a:b - 1), key, ok)
                    else
                        ok = csv_number(line(a:b - 1))
                        if (present(status_col)) then
                            if (j == status_col) failed = trim(line(a:b - 1)) /= "0"
                        end if
                    end if
                    if (.not. ok) exit
                    a = b + 1
                end do
            end if
            if (.not. ok) call cli%fail(file//" line "//itoa(ln)//": not a valid row: '"// &
                line(:min(sl, 200))//"'; fix or delete the line, or use --force to start over")
            if (key < lo .or. key > hi) call cli%fail(file//" line "//itoa(ln)//": "//kname// &
                " = "//itoa(key)//" is out of range "//itoa(lo)//".."//itoa(hi)//": '"// &
                line(:min(sl, 200))//"'; fix or delete the line, or use --force to start over")
            seen_here = first_line(key) > 0
            if (have(key)) then
                ! the key again: the same row is a harmless duplicate, another is an error
                if (seen_here) then
                    first = read_at(first_at(key))
                else if (present(rows)) then
                    first = rows(key)%s
                else
                    first = line(:sl)
                end if
                if (first /= line(:sl)) then
                    if (seen_here) then
                        call cli%fail(file//" line "//itoa(ln)//": "//kname//" = "// &
                            itoa(key)//" appears again (first at line "//itoa(first_line(key))// &
                            ") with different values; keep one of the two lines, or use "// &
                            "--force to start over")
                    else
                        call cli%fail(file//" line "//itoa(ln)//": "//kname//" = "// &
                            itoa(key)//" was already read from another file with different "// &
                            "values; keep one of the two rows, or use --force to start over")
                    end if
                end if
                ndup = ndup + 1
                if (ndup > size(dups)) dups = [dups, dups]
                dups(ndup) = ln
                cycle
            end if
            if (ordered .and. key /= lo + nrows) call cli%fail(file//" line "//itoa(ln)// &
                ": "//kname//" = "//itoa(key)//" out of order (expected "//itoa(lo + nrows)// &
                "; the rows are written in order); use --force to start over")
            if (key < last_key) sorted = .false.
            last_key = key
            have(key) = .true.
            first_at(key) = here
            first_line(key) = ln
            nrows = nrows + 1
            if (present(rows)) rows(key)%s = line(:sl)
            if (present(nfail) .and. failed) nfail = nfail + 1
        end do
        if (u /= -1) close (u)
        if (ln == 0 .and. repair) call cut(file, 0_int64)
        if (present(in_order)) in_order = sorted
        if (ndup > 0 .and. repair) then
            call drop_lines(dups(:ndup))
            write (error_unit, '(a)') cli%prog//": "//file//": "//itoa(ndup)// &
                " duplicated row(s) removed (identical copies of earlier rows, from line "// &
                itoa(dups(1))//" on)"
        end if
    contains
        subroutine cut(name, length)
            character(len=*), intent(in) :: name
            integer(int64), intent(in) :: length
            if (c_truncate(name//c_null_char, int(length, c_long)) /= 0) &
                call cli%fail("cannot repair "//name)
        end subroutine cut

        !> The line starting at byte offset `off` (0-based) of `file`.
        function read_at(off) result(s)
            integer(int64), intent(in) :: off
            character(len=:), allocatable :: s
            integer :: v, io
            character :: ch
            integer(int64) :: k
            s = ""
            open (newunit=v, file=file, access="stream", form="unformatted", action="read", &
                  status="old", iostat=io)
            if (io /= 0) call cli%fail("cannot read "//file)
            k = off + 1
            do
                read (v, pos=k, iostat=io) ch
                if (io /= 0 .or. ch == new_line("a")) exit
                s = s//ch
                k = k + 1
            end do
            close (v)
        end function read_at

        !> Rewrite `file` without the lines `drop` (increasing), durably.
        subroutine drop_lines(drop)
            integer, intent(in) :: drop(:)
            integer :: r, io, l, k, ll
            character(len=:), allocatable :: tmp, why
            character(len=256) :: msg
            logical :: done, ok
            type(results_file) :: w
            tmp = file//".tmp"
            open (newunit=r, file=file, status="old", action="read", iostat=io, iomsg=msg)
            if (io /= 0) call cli%fail("cannot read "//file//": "//trim(msg))
            call w%open(tmp, "w", ok, why)
            if (.not. ok) call cli%fail_io("cannot write "//tmp//": "//why)
            l = 0
            k = 1
            do
                read (r, '(a)', iostat=io, size=ll, advance="no") line
                if (is_iostat_end(io)) exit
                l = l + 1
                if (k <= size(drop)) then
                    if (drop(k) == l) then
                        k = k + 1
                        cycle
                    end if
                end if
                call w%put(line(:ll), ok, why)
                if (.not. ok) exit
            end do
            close (r)
            if (ok) then
                call w%close(ok, why)
            else
                call w%close(done, tmp)
                tmp = file//".tmp"
            end if
            if (.not. ok) then
                call delete_file(tmp)
                call cli%fail_io("cannot write "//tmp//": "//why)
            end if
            call durable_rename(tmp, file, done)
            if (.not. done) call cli%fail_io("cannot replace "//file//" by "//tmp)
        end subroutine drop_lines
    end subroutine load_rows

    function itoa(k) result(s)
        integer, intent(in) :: k
        character(len=:), allocatable :: s
        character(len=16) :: b
        write (b, '(i0)') k
        s = trim(b)
    end function itoa

    subroutine progress_begin(self, prog, total, start_done, on)
        class(progress_t), intent(inout) :: self
        character(len=*), intent(in) :: prog
        integer, intent(in) :: total, start_done
        logical, intent(in) :: on
        character(len=32) :: env
        integer :: l, st
        real(dp) :: x
        logical :: ok
        self%prog = prog
        self%total = total
        self%start_done = start_done
        self%on = on
        call get_environment_variable("CONMECH_PROGRESS_SECONDS", env, l, st)
        if (st == 0 .and. l > 0) then
            call parse_real(env(:l), x, ok)
            if (ok .and. x >= 0.0_dp) self%every = x
        end if
        call system_clock(self%t0, self%rate)
        self%last = self%t0
    end subroutine progress_begin

    !> Print "PROG: done/total, rate/s, ETA" if `every` seconds passed since the last line.
    subroutine progress_tick(self, ndone)
        class(progress_t), intent(inout) :: self
        integer, intent(in) :: ndone
        integer(int64) :: now
        real(dp) :: el, rate, eta
        if (.not. self%on) return
        call system_clock(now)
        if (real(now - self%last, dp) < self%every*real(self%rate, dp)) return
        self%last = now
        el = real(now - self%t0, dp)/real(self%rate, dp)
        rate = real(ndone - self%start_done, dp)/max(el, 1.0e-9_dp)
        eta = real(self%total - ndone, dp)/max(rate, 1.0e-12_dp)
        write (error_unit, '(a,i0,a,i0,a,f0.1,a,f0.1,a,i0,a)') self%prog//": ", ndone, &
            "/", self%total, " (", 100.0_dp*real(ndone, dp)/real(max(self%total, 1), dp), &
            "%), ", rate, " per s, ETA ", nint(min(eta, 1.0e9_dp)), " s"
        flush (error_unit)
    end subroutine progress_tick

    subroutine progress_clear(self)
        class(progress_t), intent(inout) :: self
        if (allocated(self%prog)) deallocate (self%prog)
    end subroutine progress_clear

end module app_batch
