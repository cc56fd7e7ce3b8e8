!> Results files written through the C library, so that a write error is seen and named.
!!
!! libgfortran (12) drops the error of a write that the operating system refuses: on a
!! full disk a formatted WRITE, FLUSH and CLOSE all return iostat = 0 and the rows are
!! lost silently. The batch programs therefore write their results files with C stdio
!! (fopen, fwrite, fflush, fclose, and ferror after each): every row is checked, and a
!! failure carries the system's message (strerror(errno): "No space left on device",
!! "Input/output error", "Permission denied"), which the programs report as a
!! file-system error (exit 3), not as a failed job. The streams are line buffered, so a
!! kill leaves at most the row being written torn (a resume drops it).
module app_output
    use, intrinsic :: iso_c_binding, only: c_ptr, c_null_ptr, c_associated, c_char, &
                                           c_null_char, c_int, c_size_t, c_f_pointer
    implicit none
    private
    public :: results_file

    !> setvbuf's line-buffered mode (_IOLBF: 1 in glibc, musl and the BSDs).
    integer(c_int), parameter :: IOLBF = 1

    !> One open results file.
    type :: results_file
        type(c_ptr) :: fp = c_null_ptr
        character(len=:), allocatable :: name
    contains
        procedure :: open => out_open
        procedure :: put => out_put
        procedure :: flush => out_flush
        procedure :: close => out_close
        procedure :: is_open => out_is_open
    end type results_file

    interface
        function c_fopen(path, mode) result(fp) bind(C, name="fopen")
            import :: c_ptr, c_char
            character(kind=c_char), intent(in) :: path(*), mode(*)
            type(c_ptr) :: fp
        end function c_fopen
        function c_fwrite(buf, size, n, fp) result(k) bind(C, name="fwrite")
            import :: c_ptr, c_char, c_size_t
            character(kind=c_char), intent(in) :: buf(*)
            integer(c_size_t), value :: size, n
            type(c_ptr), value :: fp
            integer(c_size_t) :: k
        end function c_fwrite
        function c_setvbuf(fp, buf, mode, size) result(r) bind(C, name="setvbuf")
            import :: c_ptr, c_int, c_size_t
            type(c_ptr), value :: fp, buf
            integer(c_int), value :: mode
            integer(c_size_t), value :: size
            integer(c_int) :: r
        end function c_setvbuf
        function c_ferror(fp) result(r) bind(C, name="ferror")
            import :: c_ptr, c_int
            type(c_ptr), value :: fp
            integer(c_int) :: r
        end function c_ferror
        function c_fflush(fp) result(r) bind(C, name="fflush")
            import :: c_ptr, c_int
            type(c_ptr), value :: fp
            integer(c_int) :: r
        end function c_fflush
        function c_fclose(fp) result(r) bind(C, name="fclose")
            import :: c_ptr, c_int
            type(c_ptr), value :: fp
            integer(c_int) :: r
        end function c_fclose
        function c_errno_location() result(p) bind(C, name="__errno_location")
            import :: c_ptr
            type(c_ptr) :: p
        end function c_errno_location
        function c_strerror(code) result(p) bind(C, name="strerror")
            import :: c_ptr, c_int
            integer(c_int), value :: code
            type(c_ptr) :: p
        end function c_strerror
        function c_strlen(s) result(n) bind(C, name="strlen")
            import :: c_ptr, c_size_t
            type(c_ptr), value :: s
            integer(c_size_t) :: n
        end function c_strlen
    end interface

contains

    !> The message of the current errno (strerror).
    function errno_message() result(s)
        character(len=:), allocatable :: s
        integer(c_int), pointer :: e
        type(c_ptr) :: p
        character(kind=c_char), pointer :: chars(:)
        integer :: i, n
        call c_f_pointer(c_errno_location(), e)
        p = c_strerror(e)
        n = 0
        if (c_associated(p)) n = int(c_strlen(p))
        allocate (character(len=n) :: s)
        if (n == 0) return
        call c_f_pointer(p, chars, [n])
        do i = 1, n
            s(i:i) = chars(i)
        end do
    end function errno_message

    !> Open `name` for writing: mode "w" (new or emptied) or "a" (append). ok = .false.
    !! and msg = the system's reason when it cannot be opened.
    subroutine out_open(self, name, mode, ok, msg)
        class(results_file), intent(inout) :: self
        character(len=*), intent(in) :: name, mode
        logical, intent(out) :: ok
        character(len=:), allocatable, intent(out) :: msg
        integer(c_int) :: r
        self%name = name
        self%fp = c_fopen(name//c_null_char, mode//c_null_char)
        ok = c_associated(self%fp)
        msg = ""
        if (.not. ok) then
            msg = errno_message()
            return
        end if
        ! line buffered: every row reaches the file in one write, so a kill never leaves
        ! more than the row being written torn (which a resume drops)
        r = c_setvbuf(self%fp, c_null_ptr, IOLBF, 0_c_size_t)
    end subroutine out_open

    logical function out_is_open(self)
        class(results_file), intent(in) :: self
        out_is_open = c_associated(self%fp)
    end function out_is_open

    !> Write `line` and a newline (one fwrite); ok = .false. with the reason on failure.
    subroutine out_put(self, line, ok, msg)
        class(results_file), intent(inout) :: self
        character(len=*), intent(in) :: line
        logical, intent(out) :: ok
        character(len=:), allocatable, intent(out) :: msg
        character(len=len(line) + 1) :: buf
        buf = line//new_line("a")
        ! the count alone is not enough: a line-buffered stream reports a failed write of
        ! the line through its error indicator
        ok = c_fwrite(buf, 1_c_size_t, int(len(buf), c_size_t), self%fp) == &
            int(len(buf), c_size_t)
        ok = ok .and. c_ferror(self%fp) == 0
        msg = ""
        if (.not. ok) msg = errno_message()
    end subroutine out_put

    !> Hand the buffered rows to the system (fflush); ok = .false. with the reason.
    subroutine out_flush(self, ok, msg)
        class(results_file), intent(inout) :: self
        logical, intent(out) :: ok
        character(len=:), allocatable, intent(out) :: msg
        ok = c_fflush(self%fp) == 0 .and. c_ferror(self%fp) == 0
        msg = ""
        if (.not. ok) msg = errno_message()
    end subroutine out_flush

    !> Close (flushing what is left); ok = .false. with the reason on failure.
    subroutine out_close(self, ok, msg)
        class(results_file), intent(inout) :: self
        logical, intent(out) :: ok
        character(len=:), allocatable, intent(out) :: msg
        ok = .true.
        msg = ""
        if (.not. c_associated(self%fp)) return
        ok = c_ferror(self%fp) == 0
        ok = c_fclose(self%fp) == 0 .and. ok
        self%fp = c_null_ptr
        if (.not. ok) msg = errno_message()
    end subroutine out_close

end module app_output
