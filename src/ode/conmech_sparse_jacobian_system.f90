!> A first-order system whose Jacobian df/dy is given by its values on a fixed sparsity
!! pattern, never as an n x n array.
!!
!! The pattern is the system's own, compressed by columns: the rows of column j are
!! row_idx(col_ptr(j) : col_ptr(j + 1) - 1) (1-based), and `jacobian_values` fills
!! jval(k) = df_i/dy_j for the k-th entry (i, j) in that order. An implicit method that
!! holds the same pattern (Radau's sparse LU path, conmech_radau_sparse) reads the values
!! directly, so a large sparse system is never densified: memory and work stay with the
!! entries. A method that factorises densely (small n, a dense pattern) calls the dense
!! `jacobian`, which scatters the values into the n x n array (zero off the pattern).
module conmech_sparse_jacobian_system
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_system
    implicit none
    private

    public :: sparse_jacobian_system

    !> A system with its Jacobian on a fixed sparsity pattern (extend it and implement
    !! `rhs` and `jacobian_values`; set col_ptr and row_idx before the first use).
    type, abstract, extends(ode_system) :: sparse_jacobian_system
        integer, allocatable :: col_ptr(:)   !! (n + 1) start of each column in row_idx
        integer, allocatable :: row_idx(:)   !! (nnz) rows of the entries, by columns
    contains
        !> jval(k) = df_i/dy_j at (t, y) for the k-th entry (i, j) of the pattern.
        procedure(sparse_values), deferred :: jacobian_values
        !> The dense Jacobian: the values scattered into dfdy (zero off the pattern).
        procedure :: jacobian => sparse_dense_jacobian
        !> True: the values are exact (not finite differences).
        procedure :: has_jacobian => sparse_has_jacobian
        !> Whether the pattern is (col_ptr, row_idx), so that values line up with it.
        procedure :: same_pattern => sparse_same_pattern
    end type sparse_jacobian_system

    abstract interface
        subroutine sparse_values(self, t, y, jval)
            import :: sparse_jacobian_system, dp
            class(sparse_jacobian_system), intent(in) :: self
            real(dp), intent(in) :: t
            real(dp), intent(in) :: y(:)
            real(dp), intent(out) :: jval(:)
        end subroutine sparse_values
    end interface

contains

    subroutine sparse_dense_jacobian(self, t, y, dfdy)
        class(sparse_jacobian_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(dp), allocatable :: jval(:)
        integer :: j, k
        allocate (jval(size(self%row_idx)))
        call self%jacobian_values(t, y, jval)
        dfdy = 0.0_dp
        do j = 1, size(self%col_ptr) - 1
            do k = self%col_ptr(j), self%col_ptr(j + 1) - 1
                dfdy(self%row_idx(k), j) = dfdy(self%row_idx(k), j) + jval(k)
            end do
        end do
    end subroutine sparse_dense_jacobian

    logical function sparse_has_jacobian(self)
        class(sparse_jacobian_system), intent(in) :: self
        sparse_has_jacobian = allocated(self%row_idx)
    end function sparse_has_jacobian

    logical function sparse_same_pattern(self, col_ptr, row_idx)
        class(sparse_jacobian_system), intent(in) :: self
        integer, intent(in) :: col_ptr(:), row_idx(:)
        sparse_same_pattern = .false.
        if (.not. (allocated(self%col_ptr) .and. allocated(self%row_idx))) return
        if (size(col_ptr) /= size(self%col_ptr) .or. size(row_idx) /= size(self%row_idx)) &
            return
        sparse_same_pattern = all(col_ptr == self%col_ptr) .and. all(row_idx == self%row_idx)
    end function sparse_same_pattern

end module conmech_sparse_jacobian_system
