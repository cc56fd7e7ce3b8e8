!> Packing a stepper's whole state into plain arrays and back, from ONE list per stepper.
!!
!! A stepper's `transfer_state` names every piece of its state once, in order:
!!
!!     call p%item(self%t)                 ! a real, integer or logical scalar
!!     call p%column(self%y)               ! a vector of length n: one column of w
!!     call p%columns(self%fc, 0, self%nf) ! an (n, lo:hi) matrix: hi - lo + 1 columns
!!     call p%ints(self%ipiv, self%n)      ! an integer vector of length m
!!     call p%complex_columns(self%e2, self%n)   ! an (n, m) complex matrix: 2 m columns
!!     call p%reals(self%q, m)             ! a real vector of any length m: into r
!!     call p%real_matrix(self%g, m1, m2)  ! an (m1, m2) real matrix: into r
!!
!! The same list counts the sizes (mode PACK_COUNT), writes (PACK_WRITE, into arrays of
!! the counted sizes) and reads (PACK_READ: from arrays given to `packer_read`;
!! allocatable targets are allocated with the shape named in the call). Packing is
!! therefore its own inverse by construction. The arrays are real
!! scalars r(:), integers iv(:) (logicals as 0/1) and columns w(n, :) of the state's
!! dimension n: plain arrays that a caller (the Python stepper objects) keeps between calls,
!! so that nothing is kept in Fortran.
!!
!! The packer either owns its arrays (`packer_write` + `packer_ready`, `packer_read`: the
!! components r, iv, w) or works in place on the caller's (`packer_attach_read`,
!! `packer_attach_write`: their capacity checked), which costs no allocation and no copy
!! beyond the state's own: `stepper_unpack` and `stepper_pack_into` use it.
module conmech_state_packer
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    implicit none
    private

    integer, parameter, public :: PACK_COUNT = 0   !! sizes of the state only
    integer, parameter, public :: PACK_WRITE = 1   !! state -> arrays
    integer, parameter, public :: PACK_READ = 2    !! arrays -> state

    public :: state_packer, packer_write, packer_ready, packer_read
    public :: packer_attach_read, packer_attach_write

    !> The arrays of a packed state and the position in them.
    type :: state_packer
        integer :: mode = PACK_COUNT
        integer :: n = 0                     !! length of the columns of w
        integer :: nr = 0, ni = 0, nw = 0    !! entries counted, written or read so far
        !> CM_BAD_INPUT after reading past the end, or writing past the caller's capacity
        !! (in place; the counts then go on: nr, ni, nw are the sizes needed)
        integer :: info = CM_SUCCESS
        real(dp), allocatable :: r(:)        !! real scalars
        integer, allocatable :: iv(:)        !! integers and logicals
        real(dp), allocatable :: w(:, :)     !! columns of length n
        logical :: inplace = .false.         !! the caller's arrays below, not r, iv, w
        real(dp), pointer, contiguous :: rx(:) => null()
        integer, pointer, contiguous :: ivx(:) => null()
        real(dp), pointer, contiguous :: wx(:, :) => null()
    contains
        procedure, private :: item_real, item_int, item_logical
        generic :: item => item_real, item_int, item_logical
        procedure :: column => pack_column
        procedure :: columns => pack_columns
        procedure :: ints => pack_ints
        procedure :: complex_columns => pack_complex_columns
        procedure :: reals => pack_reals
        procedure :: real_matrix => pack_real_matrix
        procedure :: reading => packer_reading
    end type state_packer

    !> An allocatable target of a read given the shape named in the call (reallocated
    !! only when its shape differs).
    interface fit
        module procedure fit_reals, fit_ints, fit_real_matrix, fit_complex_matrix
    end interface fit

contains

    !> A packer that counts a state of column length n (p%nr, p%ni, p%nw afterwards):
    !! `stepper_pack` counts first, then writes into arrays of exactly those sizes.
    subroutine packer_write(p, n)
        type(state_packer), intent(out) :: p
        integer, intent(in) :: n
        p%mode = PACK_COUNT
        p%n = n
    end subroutine packer_write

    !> After counting: arrays of the counted sizes, positions back to the start, write mode.
    subroutine packer_ready(p)
        type(state_packer), intent(inout) :: p
        allocate (p%r(p%nr), p%iv(p%ni), p%w(p%n, p%nw))
        p%nr = 0
        p%ni = 0
        p%nw = 0
        p%mode = PACK_WRITE
    end subroutine packer_ready

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

    !> A packer that reads the state from the caller's arrays in place (no copy); they
    !! must stay while the packer is in use.
    subroutine packer_attach_read(p, r, iv, w)
        type(state_packer), intent(out) :: p
        real(dp), intent(in), target, contiguous :: r(:)
        integer, intent(in), target, contiguous :: iv(:)
        real(dp), intent(in), target, contiguous :: w(:, :)
        p%mode = PACK_READ
        p%n = size(w, 1)
        p%inplace = .true.
        p%rx => r
        p%ivx => iv
        p%wx => w
    end subroutine packer_attach_read

    !> A packer that writes the state into the caller's arrays in place, their sizes the
    !! capacity (p%info = CM_BAD_INPUT when the state does not fit; p%nr, p%ni, p%nw are
    !! then the sizes it needs).
    subroutine packer_attach_write(p, r, iv, w)
        type(state_packer), intent(out) :: p
        real(dp), intent(inout), target, contiguous :: r(:)
        integer, intent(inout), target, contiguous :: iv(:)
        real(dp), intent(inout), target, contiguous :: w(:, :)
        p%mode = PACK_WRITE
        p%n = size(w, 1)
        p%inplace = .true.
        p%rx => r
        p%ivx => iv
        p%wx => w
    end subroutine packer_attach_write

    logical function packer_reading(p)
        class(state_packer), intent(in) :: p
        packer_reading = p%mode == PACK_READ
    end function packer_reading

    !> Take kr reals, ki integers and kw columns: true when they are there to move (write,
    !! read); in count mode only counted (false); reading past the end sets info, and so
    !! does writing in place past the caller's capacity (then only counted).
    logical function take(p, kr, ki, kw)
        class(state_packer), intent(inout) :: p
        integer, intent(in) :: kr, ki, kw
        take = p%mode /= PACK_COUNT
        if (p%inplace) then
            if (p%nr + kr > size(p%rx) .or. p%ni + ki > size(p%ivx) .or. &
                p%nw + kw > size(p%wx, 2)) then
                p%info = CM_BAD_INPUT
                take = .false.
                if (p%mode == PACK_READ) return
            end if
        else if (p%mode == PACK_READ) then
            if (p%nr + kr > size(p%r) .or. p%ni + ki > size(p%iv) .or. &
                p%nw + kw > size(p%w, 2)) then
                p%info = CM_BAD_INPUT
                take = .false.
                return
            end if
        end if
        if (.not. take) then
            p%nr = p%nr + kr
            p%ni = p%ni + ki
            p%nw = p%nw + kw
        end if
    end function take

    ! In place with room (every step of the Python steppers) an item goes straight to its
    ! entry; otherwise take() checks the mode and the room and grows the counts first.

    subroutine item_real(p, x)
        class(state_packer), intent(inout) :: p
        real(dp), intent(inout) :: x
        if (.not. in_place_room(p, .true.)) then
            if (.not. take(p, 1, 0, 0)) return
        end if
        p%nr = p%nr + 1
        if (p%inplace) then
            if (p%mode == PACK_READ) then
                x = p%rx(p%nr)
            else
                p%rx(p%nr) = x
            end if
        else if (p%mode == PACK_READ) then
            x = p%r(p%nr)
        else
            p%r(p%nr) = x
        end if
    end subroutine item_real

    subroutine item_int(p, k)
        class(state_packer), intent(inout) :: p
        integer, intent(inout) :: k
        if (.not. in_place_room(p, .false.)) then
            if (.not. take(p, 0, 1, 0)) return
        end if
        p%ni = p%ni + 1
        if (p%inplace) then
            if (p%mode == PACK_READ) then
                k = p%ivx(p%ni)
            else
                p%ivx(p%ni) = k
            end if
        else if (p%mode == PACK_READ) then
            k = p%iv(p%ni)
        else
            p%iv(p%ni) = k
        end if
    end subroutine item_int

    !> Packing in place, without error, with room in the in-place array for one more real
    !! (`real_item`) or integer entry.
    pure logical function in_place_room(p, real_item)
        class(state_packer), intent(in) :: p
        logical, intent(in) :: real_item
        in_place_room = .false.
        if (.not. (p%inplace .and. p%info == CM_SUCCESS .and. p%mode /= PACK_COUNT)) return
        if (real_item) then
            in_place_room = p%nr < size(p%rx)
        else
            in_place_room = p%ni < size(p%ivx)
        end if
    end function in_place_room

    subroutine item_logical(p, l)
        class(state_packer), intent(inout) :: p
        logical, intent(inout) :: l
        integer :: k
        k = merge(1, 0, l)
        call item_int(p, k)
        if (p%mode == PACK_READ) l = k /= 0
    end subroutine item_logical

    !> A vector of length n as one column of w.
    subroutine pack_column(p, a)
        class(state_packer), intent(inout) :: p
        real(dp), allocatable, intent(inout) :: a(:)
        if (.not. take(p, 0, 0, 1)) return
        p%nw = p%nw + 1
        if (p%mode == PACK_READ) then
            call fit(a, p%n)
            if (p%inplace) then
                a = p%wx(:, p%nw)
            else
                a = p%w(:, p%nw)
            end if
        else if (p%inplace) then
            p%wx(:, p%nw) = a
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
        if (.not. take(p, 0, 0, k)) return
        if (p%mode == PACK_READ) then
            call fit(a, p%n, lo, hi)
            if (p%inplace) then
                a(:, lo:hi) = p%wx(:, p%nw + 1:p%nw + k)
            else
                a(:, lo:hi) = p%w(:, p%nw + 1:p%nw + k)
            end if
        else if (p%inplace) then
            p%wx(:, p%nw + 1:p%nw + k) = a(:, lo:hi)
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
        if (.not. take(p, 0, m, 0)) return
        if (p%mode == PACK_READ) then
            call fit(a, m)
            if (p%inplace) then
                a = p%ivx(p%ni + 1:p%ni + m)
            else
                a = p%iv(p%ni + 1:p%ni + m)
            end if
        else if (p%inplace) then
            p%ivx(p%ni + 1:p%ni + m) = a(1:m)
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
        if (.not. take(p, 0, 0, 2*m)) return
        if (p%mode == PACK_READ) then
            call fit(a, p%n, m)
            if (p%inplace) then
                a = cmplx(p%wx(:, p%nw + 1:p%nw + m), p%wx(:, p%nw + m + 1:p%nw + 2*m), &
                          kind=dp)
            else
                a = cmplx(p%w(:, p%nw + 1:p%nw + m), p%w(:, p%nw + m + 1:p%nw + 2*m), &
                          kind=dp)
            end if
        else if (p%inplace) then
            p%wx(:, p%nw + 1:p%nw + m) = real(a, dp)
            p%wx(:, p%nw + m + 1:p%nw + 2*m) = aimag(a)
        else
            p%w(:, p%nw + 1:p%nw + m) = real(a, dp)
            p%w(:, p%nw + m + 1:p%nw + 2*m) = aimag(a)
        end if
        p%nw = p%nw + 2*m
    end subroutine pack_complex_columns

    !> A real vector of length m (any m) into r.
    subroutine pack_reals(p, a, m)
        class(state_packer), intent(inout) :: p
        real(dp), allocatable, intent(inout) :: a(:)
        integer, intent(in) :: m
        if (.not. take(p, m, 0, 0)) return
        if (p%mode == PACK_READ) then
            call fit(a, m)
            if (p%inplace) then
                a = p%rx(p%nr + 1:p%nr + m)
            else
                a = p%r(p%nr + 1:p%nr + m)
            end if
        else if (p%inplace) then
            p%rx(p%nr + 1:p%nr + m) = a(1:m)
        else
            p%r(p%nr + 1:p%nr + m) = a(1:m)
        end if
        p%nr = p%nr + m
    end subroutine pack_reals

    !> A real (m1, m2) matrix into r (column by column).
    subroutine pack_real_matrix(p, a, m1, m2)
        class(state_packer), intent(inout) :: p
        real(dp), allocatable, intent(inout) :: a(:, :)
        integer, intent(in) :: m1, m2
        if (.not. take(p, m1*m2, 0, 0)) return
        if (p%mode == PACK_READ) then
            call fit(a, m1, 1, m2)
            if (p%inplace) then
                a = reshape(p%rx(p%nr + 1:p%nr + m1*m2), [m1, m2])
            else
                a = reshape(p%r(p%nr + 1:p%nr + m1*m2), [m1, m2])
            end if
        else if (p%inplace) then
            p%rx(p%nr + 1:p%nr + m1*m2) = reshape(a(1:m1, 1:m2), [m1*m2])
        else
            p%r(p%nr + 1:p%nr + m1*m2) = reshape(a(1:m1, 1:m2), [m1*m2])
        end if
        p%nr = p%nr + m1*m2
    end subroutine pack_real_matrix

    subroutine fit_reals(a, m)
        real(dp), allocatable, intent(inout) :: a(:)
        integer, intent(in) :: m
        if (allocated(a)) then
            if (size(a) /= m) deallocate (a)
        end if
        if (.not. allocated(a)) allocate (a(m))
    end subroutine fit_reals

    subroutine fit_ints(a, m)
        integer, allocatable, intent(inout) :: a(:)
        integer, intent(in) :: m
        if (allocated(a)) then
            if (size(a) /= m) deallocate (a)
        end if
        if (.not. allocated(a)) allocate (a(m))
    end subroutine fit_ints

    !> Shape (m, lo:hi).
    subroutine fit_real_matrix(a, m, lo, hi)
        real(dp), allocatable, intent(inout) :: a(:, :)
        integer, intent(in) :: m, lo, hi
        if (allocated(a)) then
            if (size(a, 1) /= m .or. size(a, 2) /= hi - lo + 1 .or. lbound(a, 2) /= lo) &
                deallocate (a)
        end if
        if (.not. allocated(a)) allocate (a(m, lo:hi))
    end subroutine fit_real_matrix

    subroutine fit_complex_matrix(a, m1, m2)
        complex(dp), allocatable, intent(inout) :: a(:, :)
        integer, intent(in) :: m1, m2
        if (allocated(a)) then
            if (size(a, 1) /= m1 .or. size(a, 2) /= m2) deallocate (a)
        end if
        if (.not. allocated(a)) allocate (a(m1, m2))
    end subroutine fit_complex_matrix

end module conmech_state_packer
