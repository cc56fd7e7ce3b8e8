!> Numbers as text, for the messages that library routines return with their status.
module conmech_text
    use, intrinsic :: iso_fortran_env, only: int64
    use conmech_kinds, only: dp
    implicit none
    private

    public :: itoa, rtoa

    !> An integer (default kind or int64) as text, without blanks: itoa(-12) is "-12".
    interface itoa
        module procedure itoa_default, itoa_int64
    end interface itoa

contains

    pure function itoa_default(k) result(text)
        integer, intent(in) :: k
        character(len=:), allocatable :: text
        text = itoa_int64(int(k, int64))
    end function itoa_default

    pure function itoa_int64(k) result(text)
        integer(int64), intent(in) :: k
        character(len=:), allocatable :: text
        character(len=24) :: buf
        write (buf, '(i0)') k
        text = trim(buf)
    end function itoa_int64

    !> A real as text in the es14.6 format, right-justified in its 14 characters (a time in
    !! a message: "  1.250000E+00").
    pure function rtoa(x) result(text)
        real(dp), intent(in) :: x
        character(len=14) :: text
        write (text, '(es14.6)') x
    end function rtoa

end module conmech_text
