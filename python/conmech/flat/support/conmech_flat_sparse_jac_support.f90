!> Support of the flat routines with a sparse Python Jacobian (flat_sparse_jac.f90): a
!! system whose right-hand side is fun(t, y, dydt, n) and whose Jacobian is given by its
!! values on a fixed pattern, jvals(t, y, jval, n, nnz) (the k-th value for the k-th entry
!! of the pattern, compressed by columns), so that a scipy.sparse matrix returned by the
!! user's jac reaches Radau's sparse LUs without an n x n array on either side.
module conmech_flat_sparse_jac_support
    use, intrinsic :: iso_c_binding, only: c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_sparse_jacobian_system, only: sparse_jacobian_system
    implicit none
    private

    public :: callback_sparse_jac_system, make_sparse_jac_system

    !> fun and jvals as a sparse_jacobian_system.
    type, extends(sparse_jacobian_system) :: callback_sparse_jac_system
        procedure(), pointer, nopass :: f => null()
        procedure(), pointer, nopass :: jv => null()
        integer(c_int) :: n = 0
        integer(c_int) :: nnz = 0
    contains
        procedure :: rhs => sparse_callback_rhs
        procedure :: jacobian_values => sparse_callback_values
    end type callback_sparse_jac_system

contains

    !> The system of fun and jvals with the pattern (sp_ptr(n + 1), sp_idx(nnz), 1-based,
    !! by columns); CM_BAD_INPUT when the pattern is not one (the structure's own checks
    !! follow in set_jacobian_structure).
    subroutine make_sparse_jac_system(fun, jvals, n, nnz, sp_ptr, sp_idx, sys, info, msg)
        procedure() :: fun, jvals
        integer(c_int), intent(in) :: n, nnz, sp_ptr(:), sp_idx(:)
        type(callback_sparse_jac_system), intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        info = CM_BAD_INPUT
        if (n < 1 .or. nnz < 0 .or. size(sp_ptr) < n + 1 .or. size(sp_idx) < nnz) then
            msg = "bad input: the sparse Jacobian's pattern arrays are too short"
            return
        end if
        sys%f => fun
        sys%jv => jvals
        sys%n = n
        sys%nnz = nnz
        sys%col_ptr = sp_ptr(1:n + 1)
        sys%row_idx = sp_idx(1:nnz)
        info = CM_SUCCESS
        msg = "success"
    end subroutine make_sparse_jac_system

    subroutine sparse_callback_rhs(self, t, y, dydt)
        class(callback_sparse_jac_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        call self%f(t, y, dydt, self%n)
    end subroutine sparse_callback_rhs

    subroutine sparse_callback_values(self, t, y, jval)
        class(callback_sparse_jac_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: jval(:)
        ! an empty pattern: J = 0, nothing to ask
        if (self%nnz > 0) call self%jv(t, y, jval, self%n, self%nnz)
    end subroutine sparse_callback_values

end module conmech_flat_sparse_jac_support
