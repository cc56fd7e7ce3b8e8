!> The command-line layer shared by every program in app/ (fpm compiles the non-program
!! sources of app/ into each executable).
!!
!! One `cli_parser` per program: `start` answers `--help` (exit 0) and `--version` (exit 0)
!! and remembers `--input FILE.nml`; `next` walks the options (`--key value` or
!! `--key=value`); the `get_*` procedures parse the value strictly (the whole field must be
!! a number: `/`, `1,2`, `abc`, `1,,1` are errors naming the option); `fail` prints
!! "PROG: error: ..." on stderr and exits with status 2 (no ERROR STOP, no backtrace);
!! `fail_io` does the same with status 3 for a file-system error during a run.
!! The programs exit 0 on success, 1 when a computation failed, 2 on bad input, 3 when a
!! results file could not be written (disk full, I/O error, permission).
module app_cli
    use, intrinsic :: iso_fortran_env, only: error_unit, output_unit, int64
    use conmech_kinds, only: dp
    implicit none
    private
    public :: cli_parser, cli_cleanup, conmech_version, parse_real, parse_int, parse_list
    public :: unset, nml_list, fmt_real, fmt_list, word_in

    !> Version printed by `--version`.
    character(len=*), parameter :: conmech_version = "0.1.0"
    !> Marker of an unset namelist list entry.
    real(dp), parameter :: unset = -huge(1.0_dp)

    abstract interface
        !> Called before an exit (MPI programs finalize here).
        subroutine cli_cleanup(code)
            integer, intent(in) :: code   !! the exit status about to be returned
        end subroutine cli_cleanup
    end interface

    !> State of one command line.
    type :: cli_parser
        character(len=:), allocatable :: prog     !! program name in messages
        character(len=:), allocatable :: help     !! full help text
        character(len=:), allocatable :: input    !! --input FILE ("" if none)
        character(len=:), allocatable :: key      !! current option
        character(len=:), allocatable :: pending  !! value given as --key=value
        logical :: has_pending = .false.
        logical :: talk = .true.                  !! print messages (MPI: rank 0 only)
        integer :: k = 0, nargs = 0
        procedure(cli_cleanup), pointer, nopass :: cleanup => null()
    contains
        procedure :: start => cli_start
        procedure :: next => cli_next
        procedure :: value => cli_value
        procedure :: get_string => cli_get_string
        procedure :: get_real => cli_get_real
        procedure :: get_int => cli_get_int
        procedure :: get_list => cli_get_list
        procedure :: flag => cli_flag
        procedure :: unknown => cli_unknown
        procedure :: fail => cli_fail
        procedure :: fail_io => cli_fail_io
        procedure :: bad_name => cli_bad_name
        procedure :: done => cli_done
        procedure :: clear => cli_clear
    end type cli_parser

contains

    !> The k-th command argument, whole.
    function argument(k) result(s)
        integer, intent(in) :: k
        character(len=:), allocatable :: s
        integer :: l
        call get_command_argument(k, length=l)
        allocate (character(len=l) :: s)
        if (l > 0) call get_command_argument(k, s)
    end function argument

    !> Answer --help / --version (exit 0) and find --input; call first.
    subroutine cli_start(self, prog, help, talk, cleanup)
        class(cli_parser), intent(inout) :: self
        character(len=*), intent(in) :: prog, help
        logical, intent(in), optional :: talk
        procedure(cli_cleanup), optional :: cleanup
        integer :: k
        character(len=:), allocatable :: a
        self%prog = prog
        self%help = help
        self%input = ""
        self%key = ""
        self%pending = ""
        if (present(talk)) self%talk = talk
        if (present(cleanup)) self%cleanup => cleanup
        self%nargs = command_argument_count()
        self%k = 0
        do k = 1, self%nargs
            a = argument(k)
            if (a == "--help" .or. a == "-h") then
                if (self%talk) write (output_unit, '(a)') self%help
                call self%done()
            else if (a == "--version" .or. a == "-V") then
                if (self%talk) write (output_unit, '(a)') prog//" (conmech "// &
                    conmech_version//")"
                call self%done()
            end if
        end do
        k = 1
        do while (k <= self%nargs)
            a = argument(k)
            if (a == "--input") then
                if (k == self%nargs) then
                    self%key = a
                    call self%fail("missing value after --input")
                end if
                self%input = argument(k + 1)
                k = k + 1
            else if (len(a) > 8) then
                if (a(1:8) == "--input=") self%input = a(9:)
            end if
            k = k + 1
        end do
    end subroutine cli_start

    !> Move to the next option; .false. at the end. --input (read by start) is skipped.
    logical function cli_next(self, key) result(more)
        class(cli_parser), intent(inout) :: self
        character(len=:), allocatable, intent(out) :: key
        character(len=:), allocatable :: a
        integer :: eq
        do
            self%k = self%k + 1
            more = self%k <= self%nargs
            if (.not. more) then
                key = ""
                return
            end if
            a = argument(self%k)
            self%has_pending = .false.
            self%pending = ""
            if (len(a) < 2) then
                call self%fail("unexpected argument '"//a//"'")
            else if (a(1:1) /= "-") then
                call self%fail("unexpected argument '"//a//"' (options start with --)")
            end if
            eq = index(a, "=")
            if (eq > 0 .and. a(1:2) == "--") then
                self%pending = a(eq + 1:)
                self%has_pending = .true.
                a = a(:eq - 1)
            end if
            self%key = a
            if (a == "--input") then
                if (.not. self%has_pending) self%k = self%k + 1
                cycle
            end if
            key = a
            return
        end do
    end function cli_next

    !> The value of the current option (the next argument, or after '=').
    function cli_value(self) result(s)
        class(cli_parser), intent(inout) :: self
        character(len=:), allocatable :: s
        if (self%has_pending) then
            s = self%pending
            self%has_pending = .false.
            return
        end if
        if (self%k >= self%nargs) call self%fail("missing value after "//self%key)
        self%k = self%k + 1
        s = argument(self%k)
    end function cli_value

    subroutine cli_get_string(self, s)
        class(cli_parser), intent(inout) :: self
        character(len=*), intent(out) :: s
        character(len=:), allocatable :: v
        v = self%value()
        if (len_trim(v) == 0) call self%fail("empty value after "//self%key)
        if (len(v) > len(s)) call self%fail("value of "//self%key//" too long")
        s = v
    end subroutine cli_get_string

    subroutine cli_get_real(self, x)
        class(cli_parser), intent(inout) :: self
        real(dp), intent(out) :: x
        character(len=:), allocatable :: v
        logical :: ok
        v = self%value()
        call parse_real(v, x, ok)
        if (.not. ok) call self%fail("bad value for "//self%key//": '"//v// &
                                     "' is not a finite number")
    end subroutine cli_get_real

    subroutine cli_get_int(self, i)
        class(cli_parser), intent(inout) :: self
        integer, intent(out) :: i
        character(len=:), allocatable :: v
        logical :: ok
        v = self%value()
        call parse_int(v, i, ok)
        if (.not. ok) call self%fail("bad value for "//self%key//": '"//v// &
                                     "' is not an integer")
    end subroutine cli_get_int

    !> A comma-separated list of numbers; every field must be a number.
    subroutine cli_get_list(self, x)
        class(cli_parser), intent(inout) :: self
        real(dp), allocatable, intent(out) :: x(:)
        character(len=:), allocatable :: v, bad
        logical :: ok
        v = self%value()
        call parse_list(v, x, ok, bad)
        if (.not. ok) call self%fail("bad value for "//self%key//": field '"//bad// &
                                     "' of '"//v//"' is not a finite number")
    end subroutine cli_get_list

    !> An option without a value (--force=... is an error).
    subroutine cli_flag(self)
        class(cli_parser), intent(inout) :: self
        if (self%has_pending) call self%fail(self%key//" takes no value")
    end subroutine cli_flag

    subroutine cli_unknown(self)
        class(cli_parser), intent(inout) :: self
        call self%fail("unknown option "//self%key)
    end subroutine cli_unknown

    !> A name not among the valid ones: say which are.
    subroutine cli_bad_name(self, what, got, valid)
        class(cli_parser), intent(inout) :: self
        character(len=*), intent(in) :: what, got, valid
        call self%fail("unknown "//what//" '"//trim(got)//"'; valid: "//trim(valid))
    end subroutine cli_bad_name

    !> Print "PROG: error: MSG" on stderr and exit with status 2.
    subroutine cli_fail(self, msg)
        class(cli_parser), intent(inout) :: self
        character(len=*), intent(in) :: msg
        if (self%talk) then
            write (error_unit, '(a)') self%prog//": error: "//msg
            write (error_unit, '(a)') "(see "//self%prog//" --help)"
        end if
        if (associated(self%cleanup)) call self%cleanup(2)
        stop 2, quiet=.true.
    end subroutine cli_fail

    !> A file-system error during a run (a results file that cannot be written: disk full,
    !! I/O error, permission): print "PROG: error: MSG" on stderr and exit with status 3.
    !! Rerunning the same command resumes once the cause is fixed.
    subroutine cli_fail_io(self, msg)
        class(cli_parser), intent(inout) :: self
        character(len=*), intent(in) :: msg
        if (self%talk) then
            write (error_unit, '(a)') self%prog//": error: "//msg
            write (error_unit, '(a)') "(a file-system error, not a failed computation: "// &
                "fix it and rerun the same command to resume)"
        end if
        if (associated(self%cleanup)) call self%cleanup(3)
        stop 3, quiet=.true.
    end subroutine cli_fail_io

    !> Exit 0 (after --help / --version).
    subroutine cli_done(self)
        class(cli_parser), intent(inout) :: self
        if (associated(self%cleanup)) call self%cleanup(0)
        stop 0, quiet=.true.
    end subroutine cli_done

    !> Release the strings (before a normal end: the programs end valgrind-clean).
    subroutine cli_clear(self)
        class(cli_parser), intent(inout) :: self
        if (allocated(self%prog)) deallocate (self%prog)
        if (allocated(self%help)) deallocate (self%help)
        if (allocated(self%input)) deallocate (self%input)
        if (allocated(self%key)) deallocate (self%key)
        if (allocated(self%pending)) deallocate (self%pending)
    end subroutine cli_clear

    ! ------------------------------------------------------------------ strict parsing

    logical function is_digit(c)
        character, intent(in) :: c
        is_digit = c >= "0" .and. c <= "9"
    end function is_digit

    !> A real number, the whole field: [+-]digits[.digits][e[+-]digits]; finite.
    subroutine parse_real(s, x, ok)
        character(len=*), intent(in) :: s
        real(dp), intent(out) :: x
        logical, intent(out) :: ok
        character(len=:), allocatable :: t
        integer :: i, n, nd, ios
        x = 0.0_dp
        ok = .false.
        t = trim(adjustl(s))
        n = len(t)
        if (n == 0) return
        i = 1
        if (t(1:1) == "+" .or. t(1:1) == "-") i = 2
        nd = 0
        do while (i <= n)
            if (.not. is_digit(t(i:i))) exit
            nd = nd + 1
            i = i + 1
        end do
        if (i <= n) then
            if (t(i:i) == ".") then
                i = i + 1
                do while (i <= n)
                    if (.not. is_digit(t(i:i))) exit
                    nd = nd + 1
                    i = i + 1
                end do
            end if
        end if
        if (nd == 0) return
        if (i <= n) then
            if (index("eEdD", t(i:i)) == 0) return
            i = i + 1
            if (i <= n) then
                if (t(i:i) == "+" .or. t(i:i) == "-") i = i + 1
            end if
            nd = 0
            do while (i <= n)
                if (.not. is_digit(t(i:i))) exit
                nd = nd + 1
                i = i + 1
            end do
            if (nd == 0 .or. nd > 4) return
        end if
        if (i /= n + 1) return
        read (t, *, iostat=ios) x
        ok = ios == 0 .and. abs(x) <= huge(1.0_dp)
    end subroutine parse_real

    !> An integer, the whole field (digits, or a number like 1e6 with an integral value).
    subroutine parse_int(s, i, ok)
        character(len=*), intent(in) :: s
        integer, intent(out) :: i
        logical, intent(out) :: ok
        real(dp) :: x
        i = 0
        call parse_real(s, x, ok)
        if (.not. ok) return
        ok = x == aint(x) .and. abs(x) <= real(huge(i), dp)
        if (ok) i = int(x)
    end subroutine parse_int

    !> Comma-separated numbers; an empty field is an error (`bad` is the field).
    subroutine parse_list(s, x, ok, bad)
        character(len=*), intent(in) :: s
        real(dp), allocatable, intent(out) :: x(:)
        logical, intent(out) :: ok
        character(len=:), allocatable, intent(out) :: bad
        integer :: m, j, a, b
        m = 1
        do j = 1, len(s)
            if (s(j:j) == ",") m = m + 1
        end do
        allocate (x(m))
        bad = ""
        a = 1
        do j = 1, m
            b = index(s(a:), ",")
            if (b == 0) then
                b = len(s) + 1
            else
                b = a + b - 1
            end if
            call parse_real(s(a:b - 1), x(j), ok)
            if (.not. ok) then
                bad = s(a:b - 1)
                return
            end if
            a = b + 1
        end do
    end subroutine parse_list

    !> The set entries of a namelist list (leading, none unset after a set one).
    function nml_list(cli, arr, name) result(x)
        type(cli_parser), intent(inout) :: cli
        real(dp), intent(in) :: arr(:)
        character(len=*), intent(in) :: name
        real(dp), allocatable :: x(:)
        integer :: m
        m = 0
        do while (m < size(arr))
            if (arr(m + 1) == unset) exit
            m = m + 1
        end do
        if (any(arr(m + 1:) /= unset)) call cli%fail("namelist "//cli%input//": '"// &
            name//"' has an empty entry")
        if (.not. all(abs(arr(:m)) <= huge(1.0_dp))) call cli%fail("namelist "//cli%input// &
            ": '"//name//"' has a non-finite entry")
        x = arr(:m)
    end function nml_list

    !> A real for CSV: 18 significant digits, 3-digit exponent (round trip exact).
    function fmt_real(x) result(s)
        real(dp), intent(in) :: x
        character(len=:), allocatable :: s
        character(len=32) :: b
        write (b, '(es25.17e3)') x
        s = trim(adjustl(b))
    end function fmt_real

    !> Reals joined by commas.
    function fmt_list(x) result(s)
        real(dp), intent(in) :: x(:)
        character(len=:), allocatable :: s
        integer :: j
        s = ""
        do j = 1, size(x)
            if (j > 1) s = s//","
            s = s//fmt_real(x(j))
        end do
    end function fmt_list

    !> Is `w` one of the space-separated words of `list`?
    logical function word_in(w, list)
        character(len=*), intent(in) :: w, list
        word_in = len_trim(w) > 0 .and. index(" "//list//" ", " "//trim(w)//" ") > 0
    end function word_in

end module app_cli
