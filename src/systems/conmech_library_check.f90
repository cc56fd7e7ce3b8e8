!> Structural check of a shared library file before it is loaded with dlopen.
!!
!! dlopen maps a library's segments as its program headers describe them; a segment that
!! reaches past the end of a truncated file is mapped anyway and the first access to it
!! kills the process with SIGBUS. A foreign file (text, a library for another machine, one
!! without conmech's entry points) gives at best an obscure message. `check_shared_library`
!! reads the ELF headers (never maps or runs anything) and fails with a message naming the
!! file and the problem unless
!!
!! - the file is an ELF shared object (ET_DYN) of this process's class (64-bit), byte
!!   order and architecture (the machine field of /proc/self/exe, when readable);
!! - the ELF header, every program header and every section header lie inside the file,
!!   and so does the file image of every segment (p_offset + p_filesz) and of every section
!!   with contents (sh_offset + sh_size);
!! - the dynamic symbol table defines every requested symbol.
!!
!! The message returned is the reason alone ("truncated: segment 2 ends at byte 8524, the
!! file has 7000"); callers name the file.
!!
!! The Python package makes the same checks (conmech/_core/elf.py) before ctypes loads a model.
module conmech_library_check
    use, intrinsic :: iso_fortran_env, only: int8, int32, int64
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_text, only: itoa
    implicit none
    private

    public :: check_shared_library

    integer(int64), parameter :: ET_DYN = 3, PT_LOAD = 1, SHT_NOBITS = 8, SHT_DYNSYM = 11
    integer(int64), parameter :: EHDR = 64, PHDR = 56, SHDR = 64, SYM = 24
    !> Largest file read (a model library is far smaller).
    integer(int64), parameter :: MAX_BYTES = 2_int64**31

contains

    !> Unsigned little-endian integer of `n` bytes at byte offset `off` (0-based).
    pure integer(int64) function le(buf, off, n) result(v)
        integer(int8), intent(in) :: buf(0:)
        integer(int64), intent(in) :: off
        integer, intent(in) :: n
        integer :: k
        v = 0
        do k = n - 1, 0, -1
            v = ior(ishft(v, 8), iand(int(buf(off + k), int64), 255_int64))
        end do
    end function le

    !> The bytes of a file (info /= 0 with a message if it cannot be read).
    subroutine read_bytes(path, buf, info, msg)
        character(len=*), intent(in) :: path
        integer(int8), allocatable, intent(out) :: buf(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: u, ios
        integer(int64) :: sz
        character(len=256) :: iomsg
        info = CM_BAD_INPUT
        open (newunit=u, file=path, access="stream", form="unformatted", action="read", &
              status="old", iostat=ios, iomsg=iomsg)
        if (ios /= 0) then
            msg = reason(iomsg)
            allocate (buf(0))
            return
        end if
        inquire (unit=u, size=sz)
        if (sz < 0 .or. sz > MAX_BYTES) then
            close (u)
            msg = "not a regular file of a readable size"
            allocate (buf(0))
            return
        end if
        allocate (buf(sz))
        if (sz > 0) read (u, iostat=ios, iomsg=iomsg) buf
        close (u)
        if (ios /= 0) then
            msg = reason(iomsg)
            return
        end if
        info = CM_SUCCESS
        msg = "success"
    end subroutine read_bytes

    !> The system's reason in an I/O message ("Cannot open file 'x': No such file or
    !! directory" -> "No such file or directory").
    function reason(iomsg) result(s)
        character(len=*), intent(in) :: iomsg
        character(len=:), allocatable :: s
        integer :: k
        k = index(iomsg, ": ", back=.true.)
        s = trim(iomsg(k + 1:))
        if (k > 0) s = trim(iomsg(k + 2:))
        if (index(s, "Is a directory") > 0 .or. len(s) == 0) s = "not a regular file ("// &
            trim(iomsg)//")"
    end function reason

    !> The ELF machine of the running executable (-1 if unknown).
    integer(int64) function host_machine() result(m)
        integer(int8) :: head(0:19)
        integer :: u, ios
        m = -1
        open (newunit=u, file="/proc/self/exe", access="stream", form="unformatted", &
              action="read", status="old", iostat=ios)
        if (ios /= 0) return
        read (u, iostat=ios) head
        close (u)
        if (ios /= 0) return
        if (head(0) == 127_int8 .and. head(1) == 69_int8 .and. head(2) == 76_int8 .and. &
            head(3) == 70_int8) m = le(head, 18_int64, 2)
    end function host_machine

    !> Is the NUL-terminated string at strtab offset `off` equal to `name`?
    pure logical function name_is(buf, off, last, name)
        integer(int8), intent(in) :: buf(0:)
        integer(int64), intent(in) :: off, last
        character(len=*), intent(in) :: name
        integer :: k
        name_is = .false.
        if (off + len(name) > last) return
        do k = 1, len(name)
            if (buf(off + k - 1) /= int(ichar(name(k:k)), int8)) return
        end do
        name_is = buf(off + len(name)) == 0_int8
    end function name_is

    !> "" if the `bytes` bytes from offset `first` lie in a file of sz bytes, else the
    !! message that the file is truncated where `what` (e.g. "segment 2 ends").
    pure function extent_message(what, first, bytes, sz) result(msg)
        character(len=*), intent(in) :: what
        integer(int64), intent(in) :: first, bytes, sz
        character(len=:), allocatable :: msg
        msg = ""
        if (first < 0 .or. bytes < 0 .or. first + bytes > sz) &
            msg = "truncated: "//what//" at byte "//itoa(first + bytes)//", the file has "// &
                  itoa(sz)
    end function extent_message

    !> Check the shared library `path` before dlopen (see the module documentation);
    !! `symbols` (blank-padded names) must be defined in its dynamic symbol table.
    !! info = CM_BAD_INPUT and a message naming the file and the problem otherwise.
    subroutine check_shared_library(path, symbols, info, msg)
        character(len=*), intent(in) :: path
        character(len=*), intent(in) :: symbols(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer(int8), allocatable :: buf(:)
        integer(int64) :: sz, phoff, shoff, phnum, shnum, k, off, ptype, poff, pfsz, pmsz
        integer(int64) :: stype, soff, ssize, slink, sent, str_off, str_size, j, st_name
        integer(int64) :: st_shndx, m
        logical, allocatable :: found(:)
        integer :: i
        call read_bytes(path, buf, info, msg)
        if (info /= CM_SUCCESS) return
        info = CM_BAD_INPUT
        sz = size(buf, kind=int64)
        if (sz == 0) then
            msg = "empty (0 bytes)"
            return
        end if
        if (sz < 16) then
            msg = "not an ELF file ("//itoa(sz)//" bytes)"
            return
        end if
        if (.not. (buf(1) == 127_int8 .and. buf(2) == 69_int8 .and. buf(3) == 76_int8 .and. &
                   buf(4) == 70_int8)) then
            msg = "not an ELF file"
            return
        end if
        if (buf(5) /= 2_int8 .or. buf(6) /= little_endian()) then
            msg = "not a 64-bit ELF file of this machine's byte order"
            return
        end if
        if (sz < EHDR) then
            msg = "truncated ("//itoa(sz)//" bytes: the ELF header alone takes 64)"
            return
        end if
        if (le(buf, 16_int64, 2) /= ET_DYN) then
            msg = "an ELF file of type "//itoa(le(buf, 16_int64, 2))// &
                  ", not a shared object"
            return
        end if
        m = host_machine()
        if (m >= 0 .and. le(buf, 18_int64, 2) /= m) then
            msg = "built for another architecture (ELF machine "// &
                  itoa(le(buf, 18_int64, 2))//", this one is "//itoa(m)//")"
            return
        end if
        phoff = le(buf, 32_int64, 8)
        shoff = le(buf, 40_int64, 8)
        phnum = le(buf, 56_int64, 2)
        shnum = le(buf, 60_int64, 2)
        if (le(buf, 52_int64, 2) /= EHDR .or. (phnum > 0 .and. le(buf, 54_int64, 2) /= PHDR) &
            .or. (shnum > 0 .and. le(buf, 58_int64, 2) /= SHDR)) then
            msg = "inconsistent ELF header sizes"
            return
        end if
        if (phnum == 0) then
            msg = "no program headers"
            return
        end if
        msg = extent_message("the program headers end", phoff, phnum*PHDR, sz)
        if (len(msg) > 0) return
        do k = 0, phnum - 1
            off = phoff + k*PHDR
            ptype = le(buf, off, 4)
            poff = le(buf, off + 8, 8)
            pfsz = le(buf, off + 32, 8)
            pmsz = le(buf, off + 40, 8)
            msg = extent_message("segment "//itoa(k)//" ends", poff, pfsz, sz)
            if (len(msg) > 0) return
            if (ptype == PT_LOAD .and. pfsz > pmsz) then
                msg = "segment "//itoa(k)//" is larger in the file than in memory"
                return
            end if
        end do
        if (shnum == 0 .or. shoff == 0) then
            msg = "no section headers (its symbols cannot be checked)"
            return
        end if
        msg = extent_message("the section headers end", shoff, shnum*SHDR, sz)
        if (len(msg) > 0) return
        allocate (found(size(symbols)))
        found = .false.
        do k = 0, shnum - 1
            off = shoff + k*SHDR
            stype = le(buf, off + 4, 4)
            soff = le(buf, off + 24, 8)
            ssize = le(buf, off + 32, 8)
            if (stype == SHT_NOBITS) cycle   ! no bytes in the file
            msg = extent_message("section "//itoa(k)//" ends", soff, ssize, sz)
            if (len(msg) > 0) return
        end do
        do k = 0, shnum - 1
            off = shoff + k*SHDR
            if (le(buf, off + 4, 4) /= SHT_DYNSYM) cycle
            soff = le(buf, off + 24, 8)
            ssize = le(buf, off + 32, 8)
            slink = le(buf, off + 40, 4)
            sent = le(buf, off + 56, 8)
            if (sent /= SYM .or. slink >= shnum) then
                msg = "invalid dynamic symbol table"
                return
            end if
            str_off = le(buf, shoff + slink*SHDR + 24, 8)
            str_size = le(buf, shoff + slink*SHDR + 32, 8)
            if (str_off < 0 .or. str_size < 1 .or. str_off + str_size > sz &
                .or. soff + ssize > sz) then
                msg = "invalid dynamic string table"
                return
            end if
            do j = 0, ssize/SYM - 1
                st_name = le(buf, soff + j*SYM, 4)
                st_shndx = le(buf, soff + j*SYM + 6, 2)
                if (st_shndx == 0 .or. (st_shndx >= 65280 .and. st_shndx /= 65521)) cycle
                if (st_name >= str_size) cycle
                do i = 1, size(symbols)
                    if (.not. found(i)) found(i) = name_is(buf, str_off + st_name, &
                                                           str_off + str_size - 1, &
                                                           trim(symbols(i)))
                end do
            end do
        end do
        do i = 1, size(symbols)
            if (.not. found(i)) then
                msg = "it does not define "//trim(symbols(i))
                if (i == 1 .and. .not. any(found)) msg = msg//" (not a conmech model library?)"
                return
            end if
        end do
        info = CM_SUCCESS
        msg = "success"
    end subroutine check_shared_library

    !> ELF byte-order code of this machine (1 little-endian, 2 big-endian).
    pure integer(int8) function little_endian() result(code)
        integer(int8) :: b(4)
        b = transfer(1_int32, b)
        code = merge(1_int8, 2_int8, b(1) == 1_int8)
    end function little_endian

end module conmech_library_check
