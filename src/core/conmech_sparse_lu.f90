!> Sparse LU factorisation of a square matrix in compressed sparse column form, real and
!! complex: P A Q = L U with a column order Q given by the caller (a fill-reducing order,
!! conmech_sparse_order) and the row order P chosen by threshold partial pivoting as the
!! factorisation proceeds.
!!
!! The factorisation is Gilbert and Peierls' left-looking one (SIAM J. Sci. Stat. Comput. 9
!! (1988) 862-874; the algorithm of Davis' CSparse `cs_lu`): column k of L and U is a sparse
!! triangular solve with the columns of L already computed, whose nonzero pattern is found
!! by a depth-first search in the graph of L. Pivoting: the entry of largest modulus among
!! the rows not yet pivotal, unless the diagonal entry A(q(k), q(k)) is at least `tol` times
!! it (tol = 1: pure partial pivoting; a smaller tol keeps the diagonal of diagonally
!! dominant matrices such as the Radau iteration matrices, which preserves the column
!! order's fill reduction). L has a unit diagonal (stored first in each column), U's
!! diagonal is stored last in each column.
!!
!! The factors and the work arrays live in the object and are reused (grown when needed)
!! from one factorisation to the next: a stiff integrator refactorises the same pattern many
!! times.
module conmech_sparse_lu
    use conmech_kinds, only: dp
    implicit none
    private

    public :: sparse_lu_real, sparse_lu_complex

    !> The integer part of a sparse LU: pattern of L and U, permutations, work arrays.
    type, abstract :: sparse_lu_base
        integer :: n = 0                       !! dimension of the last factorisation
        integer, allocatable :: lp(:), li(:)   !! L by columns (rows by pivot position)
        integer, allocatable :: up(:), ui(:)   !! U by columns
        integer, allocatable :: pinv(:)        !! pinv(i): the pivot position of row i
        integer, allocatable :: q(:)           !! the column order
        integer, allocatable :: xi(:), stack(:), pstack(:), mark(:)   !! search work
    contains
        !> Number of stored entries of L and U (a measure of fill).
        procedure :: factor_nnz => base_factor_nnz
        procedure :: prepare_base => base_prepare
    end type sparse_lu_base

    !> Sparse LU of a real matrix.
    type, extends(sparse_lu_base) :: sparse_lu_real
        real(dp), allocatable :: lx(:), ux(:), x(:)
    contains
        !> Factorise A (CSC: ap(n + 1), ai, ax, 1-based rows) with column order q;
        !! info = 0, or k > 0: no nonzero pivot at step k (A singular).
        procedure :: factor => real_factor
        !> Solve A x = b in place (after a successful `factor`).
        procedure :: solve => real_solve
        procedure :: prepare => real_prepare
        procedure :: grow => real_grow
    end type sparse_lu_real

    !> Sparse LU of a complex matrix.
    type, extends(sparse_lu_base) :: sparse_lu_complex
        complex(dp), allocatable :: lx(:), ux(:), x(:)
    contains
        !> Factorise A (CSC: ap(n + 1), ai, ax, 1-based rows) with column order q;
        !! info = 0, or k > 0: no nonzero pivot at step k (A singular).
        procedure :: factor => complex_factor
        !> Solve A x = b in place (after a successful `factor`).
        procedure :: solve => complex_solve
        procedure :: prepare => complex_prepare
        procedure :: grow => complex_grow
    end type sparse_lu_complex

contains

    integer function base_factor_nnz(self)
        class(sparse_lu_base), intent(in) :: self
        base_factor_nnz = 0
        if (self%n > 0) base_factor_nnz = self%lp(self%n + 1) + self%up(self%n + 1) - 2
    end function base_factor_nnz

    !> Integer arrays for dimension n (kept if already of that size); the first capacity of
    !! the factors: 4 nnz(A) + n each (grown by doubling while factorising).
    subroutine base_prepare(self, n, nnz, cap)
        class(sparse_lu_base), intent(inout) :: self
        integer, intent(in) :: n, nnz
        integer, intent(out) :: cap
        cap = 4*nnz + n
        if (allocated(self%lp)) then
            if (size(self%lp) == n + 1) then
                cap = size(self%li)
                return
            end if
            deallocate (self%lp, self%li, self%up, self%ui, self%pinv, self%q, self%xi, &
                        self%stack, self%pstack, self%mark)
        end if
        allocate (self%lp(n + 1), self%li(cap), self%up(n + 1), self%ui(cap), self%pinv(n), &
                  self%q(n), self%xi(n), self%stack(n), self%pstack(n), self%mark(n))
        self%pstack = 0
    end subroutine base_prepare

    subroutine grow_int(a, m)
        integer, allocatable, intent(inout) :: a(:)
        integer, intent(in) :: m
        integer, allocatable :: b(:)
        allocate (b(m))
        b(1:size(a)) = a
        call move_alloc(b, a)
    end subroutine grow_int

    subroutine real_prepare(self, n, nnz)
        class(sparse_lu_real), intent(inout) :: self
        include "conmech_sparse_lu_prepare.inc"
    end subroutine real_prepare

    subroutine real_grow(self, ml, mu)
        class(sparse_lu_real), intent(inout) :: self
        real(dp), allocatable :: b(:)
        include "conmech_sparse_lu_grow.inc"
    end subroutine real_grow

    subroutine complex_prepare(self, n, nnz)
        class(sparse_lu_complex), intent(inout) :: self
        include "conmech_sparse_lu_prepare.inc"
    end subroutine complex_prepare

    subroutine complex_grow(self, ml, mu)
        class(sparse_lu_complex), intent(inout) :: self
        complex(dp), allocatable :: b(:)
        include "conmech_sparse_lu_grow.inc"
    end subroutine complex_grow

    subroutine real_factor(self, ap, ai, ax, q, tol, info)
        class(sparse_lu_real), intent(inout) :: self
        integer, intent(in) :: ap(:), ai(:), q(:)
        real(dp), intent(in) :: ax(:)
        real(dp), intent(in) :: tol
        integer, intent(out) :: info
        real(dp) :: xj, pivot, amax
        integer :: n, k, col, lnz, unz, top, head, p, pp, px, i, j, jj, ipiv
        logical :: done
        include "conmech_sparse_lu_factor.inc"
    end subroutine real_factor

    subroutine complex_factor(self, ap, ai, ax, q, tol, info)
        class(sparse_lu_complex), intent(inout) :: self
        integer, intent(in) :: ap(:), ai(:), q(:)
        complex(dp), intent(in) :: ax(:)
        real(dp), intent(in) :: tol
        integer, intent(out) :: info
        complex(dp) :: xj, pivot
        real(dp) :: amax
        integer :: n, k, col, lnz, unz, top, head, p, pp, px, i, j, jj, ipiv
        logical :: done
        include "conmech_sparse_lu_factor.inc"
    end subroutine complex_factor

    subroutine real_solve(self, b)
        class(sparse_lu_real), intent(inout) :: self
        real(dp), intent(inout) :: b(:)
        real(dp) :: yj
        integer :: n, i, j, k, p
        include "conmech_sparse_lu_solve.inc"
    end subroutine real_solve

    subroutine complex_solve(self, b)
        class(sparse_lu_complex), intent(inout) :: self
        complex(dp), intent(inout) :: b(:)
        complex(dp) :: yj
        integer :: n, i, j, k, p
        include "conmech_sparse_lu_solve.inc"
    end subroutine complex_solve

end module conmech_sparse_lu
