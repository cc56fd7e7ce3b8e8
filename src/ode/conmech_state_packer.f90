!> Packing a stepper's whole state into plain arrays and back, from ONE list per stepper.
!!
!! A stepper's `transfer_state` names every piece of its state once, in order:
!!
!!     call p%item(self%t)                 ! a real, integer or logical scalar
!!     call p%column(self%y)               ! a vector of length n: one column of w
!!     call p%columns(self%fc, 0, self%nf) ! an (n, lo:hi) matrix: hi - lo + 1 columns
!!     call p%ints(self%ipiv, self%n)      ! an integer vector of length m
!!     call p%complex_columns(self%e2, self%n)   ! an (n, m) complex matrix: 2 m columns
!!
!! The same list writes (mode PACK_WRITE: the packer's arrays grow as needed) and reads
!! (mode PACK_READ: from arrays given to `packer_read`; allocatable targets are allocated
!! with the shape named in the call). Packing is therefore its own inverse by
!! construction, and the sizes of a state are those of one write. The arrays are real
!! scalars r(:), integers iv(:) (logicals as 0/1) and columns w(n, :) of the state's
!! dimension n: plain arrays that a caller (the Python stepper objects) keeps between calls,
!! so that nothing is kept in Fortran.
module conmech_state_packer
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    implicit none
    private

    integer, parameter, public :: PACK_WRITE = 1   !! state -> arrays
    integer, parameter, public :: PACK_READ = 2    !! arrays -> state

    public :: state_packer, packer_write, packer_read

    !> The arrays of a packed state and the position in them.
    type :: state_packer
        integer :: mode = PACK_WRITE
        integer :: n = 0                     !! length of the columns of w
        integer :: nr = 0, ni = 0, nw = 0    !! entries written (or read) so far
        integer :: info = CM_SUCCESS         !! CM_BAD_INPUT after reading past the end
        real(dp), allocatable :: r(:)        !! real scalars
        integer, allocatable :: iv(:)        !! integers and logicals
        real(dp), allocatable :: w(:, :)     !! columns of length n
    contains
        procedure, private :: item_real, item_int, item_logical
        generic :: item => item_real, item_int, item_logical
        procedure :: column => pack_column
        procedure :: columns => pack_columns
        procedure :: ints => pack_ints
        procedure :: complex_columns => pack_complex_columns
        procedure :: reading => packer_reading
    end type state_packer

contains

    !> A packer that writes a state of column length n (arrays grow as needed; the sizes
    !! of the state are p%nr, p%ni, p%nw afterwards).
    subroutine packer_write(p, n)
        type(state_packer), intent(out) :: p
        integer, intent(in) :: n
        p%mode = PACK_WRITE
        p%n = n
        allocate (p%r(32), p%iv(32), p%w(n, 8))
    end subroutine packer_write

    !> A packer that reads the state in (r, iv, w) (copied).
    subroutine packer_read(p, r, iv, w)
        type(state_packer), intent(out) :: p
        real(dp), intent(in) :: r(:)
        integer, intent(in) :: iv(:)
        real(dp), intent(in) :: w(:, :)
        p%mode = PACK_READ
        p%n = size(w, 1)
        p%r = r
        p%iv = iv
        p%w = w
    end subroutine packer_read

    logical function packer_reading(p)
        class(state_packer), intent(in) :: p
        packer_reading = p%mode == PACK_READ
    end function packer_reading

    !> Room for k more reals (write) or k more to read (else info = CM_BAD_INPUT).
    logical function room_r(p, k)
        class(state_packer), intent(inout) :: p
        integer, intent(in) :: k
        real(dp), allocatable :: tmp(:)
        room_r = .true.
        if (p%nr + k <= size(p%r)) return
        if (p%mode == PACK_READ) then
            p%info = CM_BAD_INPUT
            room_r = .false.
            return
        end if
        allocate (tmp(max(2*size(p%r), p%nr + k)))
        tmp(1:p%nr) = p%r(1:p%nr)
        call move_alloc(tmp, p%r)
    end function room_r

    logical function room_i(p, k)
        class(state_packer), intent(inout) :: p
        integer, intent(in) :: k
        integer, allocatable :: tmp(:)
        room_i = .true.
        if (p%ni + k <= size(p%iv)) return
        if (p%mode == PACK_READ) then
            p%info = CM_BAD_INPUT
            room_i = .false.
            return
        end if
        allocate (tmp(max(2*size(p%iv), p%ni + k)))
        tmp(1:p%ni) = p%iv(1:p%ni)
        call move_alloc(tmp, p%iv)
    end function room_i

    logical function room_w(p, k)
        class(state_packer), intent(inout) :: p
        integer, intent(in) :: k
        real(dp), allocatable :: tmp(:, :)
        room_w = .true.
        if (p%nw + k <= size(p%w, 2)) return
        if (p%mode == PACK_READ) then
            p%info = CM_BAD_INPUT
            room_w = .false.
            return
        end if
        allocate (tmp(p%n, max(2*size(p%w, 2), p%nw + k)))
        tmp(:, 1:p%nw) = p%w(:, 1:p%nw)
        call move_alloc(tmp, p%w)
    end function room_w

    subroutine item_real(p, x)
        class(state_packer), intent(inout) :: p
        real(dp), intent(inout) :: x
        if (.not. room_r(p, 1)) return
        p%nr = p%nr + 1
        if (p%mode == PACK_READ) then
            x = p%r(p%nr)
        else
            p%r(p%nr) = x
        end if
    end subroutine item_real

    subroutine item_int(p, k)
        class(state_packer), intent(inout) :: p
        integer, intent(inout) :: k
        if (.not. room_i(p, 1)) return
        p%ni = p%ni + 1
        if (p%mode == PACK_READ) then
            k = p%iv(p%ni)
        else
            p%iv(p%ni) = k
        end if
    end subroutine item_int

    subroutine item_logical(p, l)
        class(state_packer), intent(inout) :: p
        logical, intent(inout) :: l
        if (.not. room_i(p, 1)) return
        p%ni = p%ni + 1
        if (p%mode == PACK_READ) then
            l = p%iv(p%ni) /= 0
        else
            p%iv(p%ni) = merge(1, 0, l)
        end if
    end subroutine item_logical

    !> A vector of length n as one column of w.
    subroutine pack_column(p, a)
        class(state_packer), intent(inout) :: p
        real(dp), allocatable, intent(inout) :: a(:)
        if (.not. room_w(p, 1)) return
        p%nw = p%nw + 1
        if (p%mode == PACK_READ) then
            if (allocated(a)) then
                if (size(a) /= p%n) deallocate (a)
            end if
            if (.not. allocated(a)) allocate (a(p%n))
            a = p%w(:, p%nw)
        else
            p%w(:, p%nw) = a
        end if
    end subroutine pack_column

    !> An (n, lo:hi) matrix as hi - lo + 1 columns of w.
    subroutine pack_columns(p, a, lo, hi)
        class(state_packer), intent(inout) :: p
        real(dp), allocatable, intent(inout) :: a(:, :)
        integer, intent(in) :: lo, hi
        integer :: k
        k = hi - lo + 1
        if (.not. room_w(p, k)) return
        if (p%mode == PACK_READ) then
            if (allocated(a)) then
                if (size(a, 2) /= k .or. lbound(a, 2) /= lo) deallocate (a)
            end if
            if (.not. allocated(a)) allocate (a(p%n, lo:hi))
            a(:, lo:hi) = p%w(:, p%nw + 1:p%nw + k)
        else
            p%w(:, p%nw + 1:p%nw + k) = a(:, lo:hi)
        end if
        p%nw = p%nw + k
    end subroutine pack_columns

    !> An integer vector of length m into iv.
    subroutine pack_ints(p, a, m)
        class(state_packer), intent(inout) :: p
        integer, allocatable, intent(inout) :: a(:)
        integer, intent(in) :: m
        if (.not. room_i(p, m)) return
        if (p%mode == PACK_READ) then
            if (allocated(a)) then
                if (size(a) /= m) deallocate (a)
            end if
            if (.not. allocated(a)) allocate (a(m))
            a = p%iv(p%ni + 1:p%ni + m)
        else
            p%iv(p%ni + 1:p%ni + m) = a(1:m)
        end if
        p%ni = p%ni + m
    end subroutine pack_ints

    !> An (n, m) complex matrix as 2 m columns of w (real parts, then imaginary parts).
    subroutine pack_complex_columns(p, a, m)
        class(state_packer), intent(inout) :: p
        complex(dp), allocatable, intent(inout) :: a(:, :)
        integer, intent(in) :: m
        if (.not. room_w(p, 2*m)) return
        if (p%mode == PACK_READ) then
            if (allocated(a)) then
                if (size(a, 2) /= m) deallocate (a)
            end if
            if (.not. allocated(a)) allocate (a(p%n, m))
            a = cmplx(p%w(:, p%nw + 1:p%nw + m), p%w(:, p%nw + m + 1:p%nw + 2*m), kind=dp)
        else
            p%w(:, p%nw + 1:p%nw + m) = real(a, dp)
            p%w(:, p%nw + m + 1:p%nw + 2*m) = aimag(a)
        end if
        p%nw = p%nw + 2*m
    end subroutine pack_complex_columns

end module conmech_state_packer
