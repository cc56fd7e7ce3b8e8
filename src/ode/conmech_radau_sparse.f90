!> The two Radau IIA iteration matrices gamma/h I - J (real) and (alpha + i beta)/h I - J
!! (complex) held and factorised sparsely, for a Jacobian with a known sparsity pattern
!! (conmech_jacobian_structure): the pattern of J with the diagonal added, a reverse
!! Cuthill-McKee column order computed once for the pattern (conmech_sparse_order), and a
!! Gilbert-Peierls LU of each matrix at every factorisation (conmech_sparse_lu) with the
!! diagonal kept as pivot when it is within a factor 10 of the largest candidate (the
!! matrices are dominated by their diagonal for small h; threshold pivoting keeps the
!! order's fill reduction). J is held as its values on the pattern (jval), so no n x n array
!! is formed: memory and work grow with the entries of J and of its factors, not with n^2.
module conmech_radau_sparse
    use conmech_kinds, only: dp
    use conmech_jacobian_structure, only: jacobian_structure
    use conmech_sparse_lu, only: sparse_lu_real, sparse_lu_complex
    use conmech_sparse_order, only: rcm_order
    implicit none
    private

    public :: radau_sparse_lu, SPARSE_MIN_N, SPARSE_MAX_DENSITY

    !> The sparse path is taken automatically from this dimension on ...
    integer, parameter :: SPARSE_MIN_N = 100
    !> ... when at most this fraction of the n^2 entries of J (with its diagonal) is in
    !! the pattern.
    real(dp), parameter :: SPARSE_MAX_DENSITY = 0.1_dp
    !> Threshold of the diagonal preference in the pivot choice.
    real(dp), parameter :: PIVOT_TOL = 0.1_dp

    !> The pattern of the iteration matrices, their values and their LU factors.
    type :: radau_sparse_lu
        integer :: n = 0
        integer, allocatable :: ap(:), ai(:)   !! pattern of J + I (CSC, 1-based)
        integer, allocatable :: jpos(:)        !! position in ai of each entry of J
        integer, allocatable :: dpos(:)        !! position in ai of each diagonal entry
        integer, allocatable :: q(:)           !! the column order
        real(dp), allocatable :: ax(:)         !! gamma/h I - J
        complex(dp), allocatable :: zx(:)      !! (alpha + i beta)/h I - J
        type(sparse_lu_real) :: lu1
        type(sparse_lu_complex) :: lu2
    contains
        !> The pattern from the Jacobian's structure and the column order.
        procedure :: build => sparse_build
        !> Assemble and factorise both matrices from J's values; info /= 0: singular.
        procedure :: decompose => sparse_decompose
        !> Solve with the real matrix in place.
        procedure :: solve_real => sparse_solve_real
        !> Solve with the complex matrix in place.
        procedure :: solve_complex => sparse_solve_complex
    end type radau_sparse_lu

contains

    subroutine sparse_build(self, js)
        class(radau_sparse_lu), intent(inout) :: self
        type(jacobian_structure), intent(in) :: js
        integer :: n, j, k, pos
        logical :: has_diag
        n = js%n
        self%n = n
        if (allocated(self%ap)) deallocate (self%ap, self%ai, self%jpos, self%dpos, self%q, &
                                            self%ax, self%zx)
        allocate (self%ap(n + 1), self%ai(size(js%row_idx) + n), &
                  self%jpos(size(js%row_idx)), self%dpos(n), self%q(n))
        pos = 0
        self%ap(1) = 1
        do j = 1, n
            has_diag = .false.
            do k = js%col_ptr(j), js%col_ptr(j + 1) - 1
                if (js%row_idx(k) == j) has_diag = .true.
            end do
            if (.not. has_diag) then
                pos = pos + 1
                self%ai(pos) = j
                self%dpos(j) = pos
            end if
            do k = js%col_ptr(j), js%col_ptr(j + 1) - 1
                pos = pos + 1
                self%ai(pos) = js%row_idx(k)
                self%jpos(k) = pos
                if (js%row_idx(k) == j) self%dpos(j) = pos
            end do
            self%ap(j + 1) = pos + 1
        end do
        self%ai = self%ai(1:pos)
        allocate (self%ax(pos), self%zx(pos))
        call rcm_order(n, self%ap, self%ai, self%q)
    end subroutine sparse_build

    subroutine sparse_decompose(self, jval, fac1, sig, info1, info2)
        class(radau_sparse_lu), intent(inout) :: self
        real(dp), intent(in) :: jval(:), fac1
        complex(dp), intent(in) :: sig
        integer, intent(out) :: info1, info2
        integer :: k
        self%ax = 0.0_dp
        do k = 1, size(jval)
            self%ax(self%jpos(k)) = -jval(k)
        end do
        self%zx = cmplx(self%ax, 0.0_dp, kind=dp)
        do k = 1, self%n
            self%ax(self%dpos(k)) = self%ax(self%dpos(k)) + fac1
            self%zx(self%dpos(k)) = self%zx(self%dpos(k)) + sig
        end do
        info2 = 0
        call self%lu1%factor(self%ap, self%ai, self%ax, self%q, PIVOT_TOL, info1)
        if (info1 /= 0) return
        call self%lu2%factor(self%ap, self%ai, self%zx, self%q, PIVOT_TOL, info2)
    end subroutine sparse_decompose

    subroutine sparse_solve_real(self, x)
        class(radau_sparse_lu), intent(inout) :: self
        real(dp), intent(inout) :: x(:)
        call self%lu1%solve(x)
    end subroutine sparse_solve_real

    subroutine sparse_solve_complex(self, z)
        class(radau_sparse_lu), intent(inout) :: self
        complex(dp), intent(inout) :: z(:)
        call self%lu2%solve(z)
    end subroutine sparse_solve_complex

end module conmech_radau_sparse
