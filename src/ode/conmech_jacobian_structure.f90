!> What an implicit method knows of the structure of df/dy beyond its values: whether it is
!! constant (given once, never re-evaluated: SciPy's constant `jac`), and its sparsity
!! pattern, from which a Jacobian by forward differences takes one evaluation of f per
!! GROUP of columns instead of one per column (Curtis, Powell and Reid, J. Inst. Maths
!! Applics 13 (1974) 117-119): columns that share no row are perturbed together, and each
!! difference quotient is read back on the rows of its own column.
!!
!! The groups are the greedy ones of Curtis-Powell-Reid: a group takes, in column order,
!! every remaining column whose rows meet none of the group's rows so far. For a banded
!! pattern of bandwidth w (lower + upper + 1) this gives w groups; SciPy's
!! `group_columns` is the same greedy rule.
!!
!! The pattern is stored by columns (compressed sparse column: the rows of column j are
!! row_idx(col_ptr(j) : col_ptr(j + 1) - 1)), and the groups as the list of columns of
!! each group (gcols(gptr(g) : gptr(g + 1) - 1)).
module conmech_jacobian_structure
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_state_packer, only: state_packer
    implicit none
    private

    public :: jacobian_structure, LU_AUTO, LU_DENSE, LU_SPARSE

    !> The linear algebra of an implicit method with a sparsity pattern: chosen by the
    !! dimension and the density of the pattern (conmech_radau_sparse's rule) ...
    integer, parameter :: LU_AUTO = 0
    !> ... dense LAPACK factorisations always ...
    integer, parameter :: LU_DENSE = 1
    !> ... or sparse ones always.
    integer, parameter :: LU_SPARSE = 2

    !> The structure of df/dy known to the caller.
    type :: jacobian_structure
        !> df/dy is a constant matrix (the system's `jacobian` is read once)
        logical :: constant = .false.
        !> dense or sparse factorisations with a pattern (LU_AUTO, LU_DENSE, LU_SPARSE)
        integer :: lu = LU_AUTO
        integer :: n = 0                       !! dimension (0: no sparsity pattern)
        integer :: ngroups = 0                 !! Curtis-Powell-Reid groups (0: dense)
        integer, allocatable :: col_ptr(:)     !! (n + 1) start of each column in row_idx
        integer, allocatable :: row_idx(:)     !! (nnz) rows of the nonzero entries
        integer, allocatable :: gptr(:)        !! (ngroups + 1) start of each group in gcols
        integer, allocatable :: gcols(:)       !! (n) the columns, group by group
    contains
        !> Set the sparsity pattern (compressed by columns, 1-based rows) and group its
        !! columns; CM_BAD_INPUT with a message on a malformed pattern.
        procedure :: set_pattern => structure_set_pattern
        !> Whether differences are grouped (a pattern is set).
        procedure :: grouped => structure_grouped
        !> Forward differences of f by groups of columns into jac.
        procedure :: fd_jacobian => structure_fd_jacobian
        !> Forward differences of f by groups of columns into the values on the pattern.
        procedure :: fd_values => structure_fd_values
        !> The entries of a dense matrix on the pattern.
        procedure :: gather => structure_gather
        !> Pack or unpack (conmech_state_packer).
        procedure :: transfer => structure_transfer
    end type jacobian_structure

contains

    subroutine structure_set_pattern(self, n, col_ptr, row_idx, info, msg)
        class(jacobian_structure), intent(inout) :: self
        integer, intent(in) :: n
        integer, intent(in) :: col_ptr(:), row_idx(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer, allocatable :: group(:), mark(:)
        integer :: j, k, g, nnz, left, ngr, pos
        logical :: free
        info = CM_BAD_INPUT
        if (n < 1 .or. size(col_ptr) /= n + 1) then
            msg = "bad input: jac_sparsity: the column pointers must have n + 1 entries"
            return
        end if
        nnz = size(row_idx)
        if (col_ptr(1) /= 1 .or. col_ptr(n + 1) /= nnz + 1 .or. &
            any(col_ptr(2:n + 1) < col_ptr(1:n))) then
            msg = "bad input: jac_sparsity: the column pointers are not increasing from 1 "// &
                  "to nnz + 1"
            return
        end if
        if (nnz > 0) then
            if (any(row_idx < 1) .or. any(row_idx > n)) then
                msg = "bad input: jac_sparsity: a row index is outside 1..n"
                return
            end if
        end if
        ! greedy grouping: mark(i) = the group that last used row i
        allocate (group(n), mark(n))
        group = 0
        mark = 0
        left = n
        ngr = 0
        do while (left > 0)
            ngr = ngr + 1
            do j = 1, n
                if (group(j) /= 0) cycle
                free = .true.
                do k = col_ptr(j), col_ptr(j + 1) - 1
                    if (mark(row_idx(k)) == ngr) then
                        free = .false.
                        exit
                    end if
                end do
                if (.not. free) cycle
                group(j) = ngr
                left = left - 1
                do k = col_ptr(j), col_ptr(j + 1) - 1
                    mark(row_idx(k)) = ngr
                end do
            end do
        end do
        self%n = n
        self%ngroups = ngr
        self%col_ptr = col_ptr
        self%row_idx = row_idx
        if (allocated(self%gptr)) deallocate (self%gptr)
        if (allocated(self%gcols)) deallocate (self%gcols)
        allocate (self%gptr(ngr + 1), self%gcols(n))
        pos = 1
        do g = 1, ngr
            self%gptr(g) = pos
            do j = 1, n
                if (group(j) /= g) cycle
                self%gcols(pos) = j
                pos = pos + 1
            end do
        end do
        self%gptr(ngr + 1) = pos
        info = CM_SUCCESS
        msg = "success"
    end subroutine structure_set_pattern

    logical function structure_grouped(self)
        class(jacobian_structure), intent(in) :: self
        structure_grouped = self%ngroups > 0
    end function structure_grouped

    !> jac = df/dy at (t, y) by forward differences, f0 = f(t, y) given: each group of
    !! columns is perturbed at once (step sqrt(uround max(1e-5, |y_j|)) for column j, as
    !! Hairer's dense differences), one evaluation of f per group (added to nfev); the
    !! entries outside the pattern are zero (with every entry in the pattern, the dense
    !! differences exactly). yw, fw: work arrays of length n.
    subroutine structure_fd_jacobian(self, sys, t, y, f0, uround, jac, yw, fw, nfev)
        class(jacobian_structure), intent(in) :: self
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t, y(:), f0(:), uround
        real(dp), intent(out) :: jac(:, :)
        real(dp), intent(inout) :: yw(:), fw(:)
        integer, intent(inout) :: nfev
        real(dp), allocatable :: jval(:)
        integer :: j, k
        allocate (jval(size(self%row_idx)))
        call self%fd_values(sys, t, y, f0, uround, jval, yw, fw, nfev)
        jac = 0.0_dp
        do j = 1, self%n
            do k = self%col_ptr(j), self%col_ptr(j + 1) - 1
                jac(self%row_idx(k), j) = jval(k)
            end do
        end do
    end subroutine structure_fd_jacobian

    !> jval(k) = df_i/dy_j for the k-th entry (i, j) of the pattern (column by column), by
    !! the grouped forward differences of `fd_jacobian` (the same quotients, no n x n
    !! array).
    subroutine structure_fd_values(self, sys, t, y, f0, uround, jval, yw, fw, nfev)
        class(jacobian_structure), intent(in) :: self
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t, y(:), f0(:), uround
        real(dp), intent(out) :: jval(:)
        real(dp), intent(inout) :: yw(:), fw(:)
        integer, intent(inout) :: nfev
        integer :: g, p, j, k
        real(dp) :: delt
        yw = y
        do g = 1, self%ngroups
            do p = self%gptr(g), self%gptr(g + 1) - 1
                j = self%gcols(p)
                yw(j) = y(j) + sqrt(uround*max(1.0e-5_dp, abs(y(j))))
            end do
            call sys%rhs(t, yw, fw)
            nfev = nfev + 1
            do p = self%gptr(g), self%gptr(g + 1) - 1
                j = self%gcols(p)
                delt = sqrt(uround*max(1.0e-5_dp, abs(y(j))))
                do k = self%col_ptr(j), self%col_ptr(j + 1) - 1
                    jval(k) = (fw(self%row_idx(k)) - f0(self%row_idx(k)))/delt
                end do
                yw(j) = y(j)
            end do
        end do
    end subroutine structure_fd_values

    !> jval(k) = a(i, j) for the k-th entry (i, j) of the pattern.
    subroutine structure_gather(self, a, jval)
        class(jacobian_structure), intent(in) :: self
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(out) :: jval(:)
        integer :: j, k
        do j = 1, self%n
            do k = self%col_ptr(j), self%col_ptr(j + 1) - 1
                jval(k) = a(self%row_idx(k), j)
            end do
        end do
    end subroutine structure_gather

    subroutine structure_transfer(self, p)
        class(jacobian_structure), intent(inout) :: self
        type(state_packer), intent(inout) :: p
        integer :: nnz
        call p%item(self%constant)
        call p%item(self%lu)
        call p%item(self%n)
        call p%item(self%ngroups)
        if (self%ngroups == 0) return
        nnz = 0
        if (allocated(self%row_idx)) nnz = size(self%row_idx)
        call p%item(nnz)
        call p%ints(self%col_ptr, self%n + 1)
        call p%ints(self%row_idx, nnz)
        call p%ints(self%gptr, self%ngroups + 1)
        call p%ints(self%gcols, self%n)
    end subroutine structure_transfer

end module conmech_jacobian_structure
