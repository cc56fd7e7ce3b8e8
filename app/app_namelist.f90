!> A strict check of a namelist input file before the program reads it, so that every
!! mistake is named: the file, the line, the key and the value.
!!
!! A Fortran namelist READ reports most mistakes as "End of file" or "Cannot match
!! namelist object name" without saying where. `check_namelist` reads the file as text
!! first and accepts only what the READ will take with the meaning the user intended:
!!
!! - a text file (no NUL or other control bytes: a binary file is named as such);
!! - before the group only blank lines and comments (! ...); then `&group` (or `$group`)
!!   with the program's group name (a wrong name is named), items, and the terminator `/`
!!   (or `&end`, `$end`) before the end of the file;
!! - items `key = values` with a known key (the valid ones are listed otherwise), an
!!   optional subscript `key(i)` or `key(i:j)` on array keys within their bounds, values
!!   separated by blanks or commas, repeat counts `r*value`, empty (null) values;
!! - values of the key's type: integers as digits (`10`, not `ten`, `2.5` or `1e3`),
!!   finite reals, logicals `.true.`/`.false.`/`T`/`F`, strings in quotes (`'pendulum'`)
!!   no longer than the key's variable; a scalar takes one value, an array at most its
!!   size from the subscript on.
!!
!! A mistake ends the program with exit status 2 and a message
!! "--input FILE line L: KEY = VALUE: what is wrong".
!!
!! The keys are given as a spec string of blank-separated `name:type`, where type is `i`
!! (integer), `r` (real), `l` (logical), `sN` (string of at most N characters) or `rN`
!! (real array of N entries), e.g. "count:i t_end:r params:r64 out:s1024 force:l".
module app_namelist
    use, intrinsic :: iso_fortran_env, only: int64
    use conmech_kinds, only: dp
    use app_cli, only: cli_parser, parse_real
    implicit none
    private
    public :: check_namelist

    !> Largest namelist file read.
    integer(int64), parameter :: max_bytes = 1048576

    !> The scanner's state over the file's text.
    type :: scanner
        character(len=:), allocatable :: text
        integer :: pos = 1, line = 1
    end type scanner

contains

    function itoa(k) result(s)
        integer, intent(in) :: k
        character(len=:), allocatable :: s
        character(len=16) :: b
        write (b, '(i0)') k
        s = trim(b)
    end function itoa

    pure function lower(s) result(t)
        character(len=*), intent(in) :: s
        character(len=len(s)) :: t
        integer :: i
        t = s
        do i = 1, len(s)
            if (s(i:i) >= "A" .and. s(i:i) <= "Z") t(i:i) = achar(iachar(s(i:i)) + 32)
        end do
    end function lower

    pure logical function is_name_char(c)
        character, intent(in) :: c
        is_name_char = (c >= "a" .and. c <= "z") .or. (c >= "A" .and. c <= "Z") .or. &
                       (c >= "0" .and. c <= "9") .or. c == "_"
    end function is_name_char

    pure logical function is_blank(c)
        character, intent(in) :: c
        is_blank = c == " " .or. c == achar(9) .or. c == achar(13) .or. c == new_line("a")
    end function is_blank

    !> The type and size of `key` in the spec ("" if unknown).
    subroutine lookup(spec, key, kind, size)
        character(len=*), intent(in) :: spec, key
        character, intent(out) :: kind
        integer, intent(out) :: size
        integer :: a, b, c, ios
        character(len=:), allocatable :: item
        kind = " "
        size = 0
        a = 1
        do while (a <= len(spec))
            b = index(spec(a:), " ")
            if (b == 0) then
                b = len(spec) + 1
            else
                b = a + b - 1
            end if
            item = spec(a:b - 1)
            a = b + 1
            c = index(item, ":")
            if (c == 0) cycle
            if (lower(item(:c - 1)) /= lower(key)) cycle
            kind = item(c + 1:c + 1)
            if (len(item) > c + 1) then
                read (item(c + 2:), *, iostat=ios) size
                if (ios /= 0) size = 0
            end if
            return
        end do
    end subroutine lookup

    !> The names of the spec, comma-separated.
    function spec_names(spec) result(s)
        character(len=*), intent(in) :: spec
        character(len=:), allocatable :: s
        integer :: a, b, c
        s = ""
        a = 1
        do while (a <= len(spec))
            b = index(spec(a:), " ")
            if (b == 0) then
                b = len(spec) + 1
            else
                b = a + b - 1
            end if
            c = index(spec(a:b - 1), ":")
            if (c > 1) s = s//merge(", ", "  ", len(s) > 0)//spec(a:a + c - 2)
            a = b + 1
        end do
        s = trim(adjustl(s))
    end function spec_names

    !> Skip blanks, newlines and comments (and commas when `commas`).
    subroutine skip(sc, commas)
        type(scanner), intent(inout) :: sc
        logical, intent(in) :: commas
        character :: c
        do while (sc%pos <= len(sc%text))
            c = sc%text(sc%pos:sc%pos)
            if (c == new_line("a")) then
                sc%line = sc%line + 1
            else if (c == "!") then
                do while (sc%pos <= len(sc%text))
                    if (sc%text(sc%pos:sc%pos) == new_line("a")) exit
                    sc%pos = sc%pos + 1
                end do
                cycle
            else if (.not. (is_blank(c) .or. (commas .and. c == ","))) then
                return
            end if
            sc%pos = sc%pos + 1
        end do
    end subroutine skip

    !> Check the namelist input file `file` for the group `group` against `spec` (see the
    !! module documentation); a mistake ends the program through cli%fail (exit 2).
    !! `lines` receives the file's lines, for the program's namelist READ from this
    !! internal file (the text checked is the text read; a last line without its newline
    !! reads like any other).
    subroutine check_namelist(cli, file, group, spec, lines)
        type(cli_parser), intent(inout) :: cli
        character(len=*), intent(in) :: file, group, spec
        character(len=:), allocatable, intent(out) :: lines(:)
        type(scanner) :: sc
        character(len=:), allocatable :: pre, key, name
        character :: kind, c
        integer :: size, start_line, lo, hi, nvals, k, line0
        logical :: ended
        pre = "--input "//file
        call read_text(cli, file, sc%text)
        ! binary input: a control byte other than tab, CR, LF
        do k = 1, len(sc%text)
            c = sc%text(k:k)
            if (iachar(c) < 32 .and. .not. (c == achar(9) .or. c == achar(10) .or. &
                                             c == achar(13))) then
                call cli%fail(pre//" line "//itoa(1 + count_lines(sc%text(:k)))// &
                    ": not a text file (byte "//itoa(iachar(c))//" at offset "// &
                    itoa(k - 1)//"): a namelist &"//group//" ... / is expected")
            end if
        end do
        call skip(sc, .false.)
        if (sc%pos > len(sc%text)) call cli%fail(pre//": no namelist group &"//group// &
            " in the file (empty or only comments)")
        c = sc%text(sc%pos:sc%pos)
        if (c /= "&" .and. c /= "$") call cli%fail(pre//" line "//itoa(sc%line)// &
            ": expected &"//group//" to start the namelist, found '"// &
            snippet(sc)//"'")
        sc%pos = sc%pos + 1
        name = word(sc)
        if (lower(name) /= lower(group)) call cli%fail(pre//" line "//itoa(sc%line)// &
            ": wrong group name '&"//name//"' (this program reads &"//group//")")
        start_line = sc%line
        ended = .false.
        do
            call skip(sc, .true.)
            if (sc%pos > len(sc%text)) exit
            c = sc%text(sc%pos:sc%pos)
            if (c == "/") then
                ended = .true.
                exit
            end if
            if (c == "&" .or. c == "$") then
                sc%pos = sc%pos + 1
                name = word(sc)
                if (lower(name) == "end") then
                    ended = .true.
                    exit
                end if
                call cli%fail(pre//" line "//itoa(sc%line)//": '"//c//name// &
                    "' inside the group &"//group//" (a missing '/' before it?)")
            end if
            line0 = sc%line
            key = word(sc)
            if (len(key) == 0) call cli%fail(pre//" line "//itoa(sc%line)// &
                ": expected a key (name = value), found '"//snippet(sc)//"'")
            call lookup(spec, key, kind, size)
            if (kind == " ") call cli%fail(pre//" line "//itoa(line0)//": unknown key '"// &
                key//"' in &"//group//" (valid: "//spec_names(spec)//")")
            lo = 1
            hi = max(size, 1)
            call skip(sc, .false.)
            if (sc%pos <= len(sc%text)) then
                if (sc%text(sc%pos:sc%pos) == "(") call subscript(sc, key, kind, size, lo, hi)
            end if
            call skip(sc, .false.)
            if (sc%pos > len(sc%text)) exit
            if (sc%text(sc%pos:sc%pos) /= "=") call cli%fail(pre//" line "//itoa(sc%line)// &
                ": expected '=' after the key '"//key//"', found '"//snippet(sc)//"'")
            sc%pos = sc%pos + 1
            call values(sc, key, kind, size, lo, hi, nvals)
        end do
        if (.not. ended) call cli%fail(pre//": the group &"//group//" that starts at line "// &
            itoa(start_line)//" has no terminator '/' before the end of the file")
        call split_lines(sc%text, lines)
    contains
        !> The rest of the current line (for messages).
        function snippet(s) result(t)
            type(scanner), intent(in) :: s
            character(len=:), allocatable :: t
            integer :: e
            e = index(s%text(s%pos:), new_line("a"))
            if (e == 0) then
                e = len(s%text)
            else
                e = s%pos + e - 2
            end if
            t = s%text(s%pos:min(e, s%pos + 60))
        end function snippet

        !> A name at the current position (letters, digits, underscores).
        function word(s) result(w)
            type(scanner), intent(inout) :: s
            character(len=:), allocatable :: w
            integer :: a
            a = s%pos
            do while (s%pos <= len(s%text))
                if (.not. is_name_char(s%text(s%pos:s%pos))) exit
                s%pos = s%pos + 1
            end do
            w = s%text(a:s%pos - 1)
        end function word

        !> key(i) or key(i:j): bounds within 1..size of an array key.
        subroutine subscript(s, key, kind, size, lo, hi)
            type(scanner), intent(inout) :: s
            character(len=*), intent(in) :: key
            character, intent(in) :: kind
            integer, intent(in) :: size
            integer, intent(out) :: lo, hi
            integer :: e, colon
            logical :: ok
            character(len=:), allocatable :: sub
            e = index(s%text(s%pos:), ")")
            if (e == 0) call cli%fail(pre//" line "//itoa(s%line)//": "//key// &
                ": unclosed subscript '"//snippet(s)//"'")
            sub = s%text(s%pos + 1:s%pos + e - 2)
            s%pos = s%pos + e
            if (kind /= "r" .or. size == 0) call cli%fail(pre//" line "//itoa(s%line)// &
                ": "//key//"("//sub//"): '"//key//"' is not an array")
            colon = index(sub, ":")
            if (colon == 0) then
                call int_field(sub, lo, ok)
                hi = lo
            else
                call int_field(sub(:colon - 1), lo, ok)
                if (ok) call int_field(sub(colon + 1:), hi, ok)
            end if
            if (.not. ok) call cli%fail(pre//" line "//itoa(s%line)//": "//key//"("//sub// &
                "): the subscript must be an integer or a range i:j")
            if (lo < 1 .or. hi > size .or. lo > hi) call cli%fail(pre//" line "// &
                itoa(s%line)//": "//key//"("//sub//"): index out of range 1.."//itoa(size))
        end subroutine subscript

        !> The values after `key =`, up to the next key, '/' or the end.
        subroutine values(s, key, kind, size, lo, hi, n)
            type(scanner), intent(inout) :: s
            character(len=*), intent(in) :: key
            character, intent(in) :: kind
            integer, intent(in) :: size, lo, hi
            integer, intent(out) :: n
            character(len=:), allocatable :: tok, val
            integer :: reps, star, room, vline
            logical :: ok, quoted, seen_comma
            n = 0
            seen_comma = .false.
            ! an array takes up to its size (from a subscript: the subscript's range), a
            ! scalar or one array element one value
            room = 1
            if (kind == "r" .and. size > 0) room = hi - lo + 1
            do
                ! blanks; a comma ends a value (two commas: a null value)
                do while (s%pos <= len(s%text))
                    if (s%text(s%pos:s%pos) == ",") then
                        if (seen_comma) n = n + 1
                        seen_comma = .true.
                    else if (s%text(s%pos:s%pos) == "!") then
                        call skip(s, .false.)
                        cycle
                    else if (.not. is_blank(s%text(s%pos:s%pos))) then
                        exit
                    else if (s%text(s%pos:s%pos) == new_line("a")) then
                        s%line = s%line + 1
                    end if
                    s%pos = s%pos + 1
                end do
                if (s%pos > len(s%text)) return
                if (index("/&$", s%text(s%pos:s%pos)) > 0) return
                if (next_is_key(s)) return
                vline = s%line
                call token(s, tok, quoted)
                seen_comma = .false.
                ! repeat count r*value (r* alone: r null values)
                reps = 1
                star = 0
                if (.not. quoted) star = index(tok, "*")
                if (star > 0) then
                    call int_field(tok(:star - 1), reps, ok)
                    if (.not. ok .or. reps < 1) call cli%fail(pre//" line "//itoa(vline)// &
                        ": "//key//" = "//tok//": a repeat count must be a positive integer")
                    val = tok(star + 1:)
                    if (len(val) == 0 .and. s%pos <= len(s%text)) then
                        if (s%text(s%pos:s%pos) == "'" .or. s%text(s%pos:s%pos) == '"') then
                            call token(s, val, quoted)
                        end if
                    end if
                else
                    val = tok
                end if
                if (len(val) > 0 .or. quoted) call check_value(key, kind, size, val, &
                                                                quoted, vline)
                n = n + reps
                if (n > room) then
                    if (kind == "r" .and. size > 0 .and. room > 1) then
                        call cli%fail(pre//" line "//itoa(vline)//": "//key//" = "//tok// &
                            ": too many values (at most "//itoa(room)//" here; "//key// &
                            " has "//itoa(size)//" entries)")
                    else
                        call cli%fail(pre//" line "//itoa(vline)//": "//key//" = "//tok// &
                            ": '"//key//"' takes one value (is a comma or a quote missing?)")
                    end if
                end if
            end do
        end subroutine values

        !> Is the text at the position a key followed by '=' (or a subscript and '=')?
        logical function next_is_key(s)
            type(scanner), intent(in) :: s
            integer :: p, depth
            next_is_key = .false.
            p = s%pos
            if (.not. is_name_char(s%text(p:p))) return
            if (s%text(p:p) >= "0" .and. s%text(p:p) <= "9") return
            do while (p <= len(s%text))
                if (.not. is_name_char(s%text(p:p))) exit
                p = p + 1
            end do
            do while (p <= len(s%text))
                if (.not. is_blank(s%text(p:p))) exit
                p = p + 1
            end do
            if (p > len(s%text)) return
            if (s%text(p:p) == "(") then
                depth = index(s%text(p:), ")")
                if (depth == 0) return
                p = p + depth
                do while (p <= len(s%text))
                    if (.not. is_blank(s%text(p:p))) exit
                    p = p + 1
                end do
                if (p > len(s%text)) return
            end if
            next_is_key = s%text(p:p) == "="
        end function next_is_key

        !> One value token: a quoted string (quotes doubled inside) or a run of
        !! characters up to a blank, a comma, a slash or a comment.
        subroutine token(s, tok, quoted)
            type(scanner), intent(inout) :: s
            character(len=:), allocatable, intent(out) :: tok
            logical, intent(out) :: quoted
            character :: q
            integer :: a
            quoted = .false.
            q = s%text(s%pos:s%pos)
            if (q == "'" .or. q == '"') then
                quoted = .true.
                tok = ""
                s%pos = s%pos + 1
                do
                    if (s%pos > len(s%text)) call cli%fail(pre//" line "//itoa(s%line)// &
                        ": a string starting with "//q//" is not closed")
                    if (s%text(s%pos:s%pos) == q) then
                        if (s%pos < len(s%text)) then
                            if (s%text(s%pos + 1:s%pos + 1) == q) then
                                tok = tok//q
                                s%pos = s%pos + 2
                                cycle
                            end if
                        end if
                        s%pos = s%pos + 1
                        exit
                    end if
                    if (s%text(s%pos:s%pos) == new_line("a")) s%line = s%line + 1
                    tok = tok//s%text(s%pos:s%pos)
                    s%pos = s%pos + 1
                end do
                return
            end if
            a = s%pos
            do while (s%pos <= len(s%text))
                if (is_blank(s%text(s%pos:s%pos)) .or. index(",/!", s%text(s%pos:s%pos)) > 0) &
                    exit
                if (s%text(s%pos:s%pos) == "*" .and. s%pos + 1 <= len(s%text)) then
                    if (index("'"//'"', s%text(s%pos + 1:s%pos + 1)) > 0) then
                        s%pos = s%pos + 1
                        exit
                    end if
                end if
                s%pos = s%pos + 1
            end do
            tok = s%text(a:s%pos - 1)
        end subroutine token

        !> A value of the key's type.
        subroutine check_value(key, kind, size, val, quoted, vline)
            character(len=*), intent(in) :: key, val
            character, intent(in) :: kind
            integer, intent(in) :: size, vline
            logical, intent(in) :: quoted
            integer :: iv
            real(dp) :: x
            logical :: ok
            character(len=:), allocatable :: shown, where
            shown = val
            if (quoted) shown = "'"//val//"'"
            where = pre//" line "//itoa(vline)//": "//key//" = "//shown//": "
            select case (kind)
            case ("i")
                ok = .not. quoted
                if (ok) call int_field(val, iv, ok)
                if (.not. ok) call cli%fail(where//"not an integer (digits, e.g. "//key// &
                                            " = 10)")
            case ("r")
                ok = .not. quoted
                if (ok) call parse_real(val, x, ok)
                if (.not. ok) call cli%fail(where//"not a finite number")
            case ("l")
                select case (lower(val))
                case ("t", "f", ".t.", ".f.", ".true.", ".false.", ".t", ".f")
                    ok = .not. quoted
                case default
                    ok = .false.
                end select
                if (.not. ok) call cli%fail(where//"not a logical (.true. or .false.)")
            case ("s")
                if (.not. quoted) call cli%fail(where//"a string must be in quotes ("// &
                    key//" = '"//val//"')")
                if (size > 0 .and. len(val) > size) call cli%fail(where//"too long (at "// &
                    "most "//itoa(size)//" characters)")
            end select
        end subroutine check_value
    end subroutine check_namelist

    !> An integer written as digits with an optional sign (what a namelist READ takes).
    subroutine int_field(s, v, ok)
        character(len=*), intent(in) :: s
        integer, intent(out) :: v
        logical, intent(out) :: ok
        character(len=:), allocatable :: t
        integer :: i, ios, a
        v = 0
        t = trim(adjustl(s))
        ok = len(t) > 0
        if (.not. ok) return
        a = 1
        if (t(1:1) == "+" .or. t(1:1) == "-") a = 2
        ok = len(t) >= a .and. len(t) - a < 10
        if (.not. ok) return
        do i = a, len(t)
            if (t(i:i) < "0" .or. t(i:i) > "9") then
                ok = .false.
                return
            end if
        end do
        read (t, *, iostat=ios) v
        ok = ios == 0
    end subroutine int_field

    !> The lines of a text (without their newlines and carriage returns).
    subroutine split_lines(text, lines)
        character(len=*), intent(in) :: text
        character(len=:), allocatable, intent(out) :: lines(:)
        integer :: n, a, b, k, w
        n = count_lines(text) + 1
        w = 1
        a = 1
        do k = 1, n
            b = index(text(a:), new_line("a"))
            b = merge(len(text) + 1, a + b - 1, b == 0)
            w = max(w, b - a)
            a = b + 1
        end do
        allocate (character(len=w) :: lines(n))
        a = 1
        do k = 1, n
            b = index(text(a:), new_line("a"))
            b = merge(len(text) + 1, a + b - 1, b == 0)
            lines(k) = text(a:b - 1)
            if (b - 1 >= a) then
                if (text(b - 1:b - 1) == achar(13)) lines(k) = text(a:b - 2)
            end if
            a = b + 1
        end do
    end subroutine split_lines

    integer function count_lines(s) result(n)
        character(len=*), intent(in) :: s
        integer :: i
        n = 0
        do i = 1, len(s)
            if (s(i:i) == new_line("a")) n = n + 1
        end do
    end function count_lines

    !> The whole file as text.
    subroutine read_text(cli, file, text)
        type(cli_parser), intent(inout) :: cli
        character(len=*), intent(in) :: file
        character(len=:), allocatable, intent(out) :: text
        integer :: u, ios
        integer(int64) :: sz
        character(len=256) :: msg
        open (newunit=u, file=file, access="stream", form="unformatted", action="read", &
              status="old", iostat=ios, iomsg=msg)
        if (ios /= 0) call cli%fail("cannot open --input "//file//": "//trim(msg))
        inquire (unit=u, size=sz)
        if (sz > max_bytes) call cli%fail("--input "//file//": larger than 1 MB: not a "// &
                                          "namelist input file")
        allocate (character(len=max(sz, 0_int64)) :: text)
        if (sz > 0) read (u, iostat=ios, iomsg=msg) text
        close (u)
        if (ios /= 0) call cli%fail("cannot read --input "//file//": "//trim(msg))
    end subroutine read_text

end module app_namelist
