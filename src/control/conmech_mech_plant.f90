!> A mechanical system in generalized coordinates with inputs,
!!
!!     M(t, q) q'' = Q(t, q, q') + B(t, q) u,     x = [q, q'],  u in R^m,
!!
!! as a `control_system`. B is a constant ndof x m matrix (e.g. the columns e_i of the
!! actuated coordinates) or a compiled function with the C signature
!! `void B(double t, const double *q, double *b, const double *p)` (column-major
!! ndof x m). The accelerations come from a Cholesky factorisation of M; a mass matrix
!! that is not positive definite gives NaN (the integrators then stop). The input matrix
!! dF/du = [0; M^-1 B] is exact.
module conmech_mech_plant
    use, intrinsic :: iso_c_binding, only: c_funptr, c_null_funptr, c_associated, &
                                           c_f_procpointer, c_double
    use conmech_kinds, only: dp, nan_dp
    use conmech_status, only: CM_SUCCESS
    use conmech_lapack, only: dpotrs
    use conmech_generalized, only: generalized_system, mass_cholesky
    use conmech_control_system, only: control_system
    implicit none
    private
    public :: mech_plant

    abstract interface
        subroutine c_input_matrix(t, q, b, p) bind(c)
            import :: c_double
            real(c_double), value :: t
            real(c_double), intent(in) :: q(*), p(*)
            real(c_double), intent(out) :: b(*)
        end subroutine c_input_matrix
    end interface

    !> M q'' = Q + B u (see the module notes).
    type, extends(control_system) :: mech_plant
        class(generalized_system), allocatable :: mech
        real(dp), allocatable :: b(:, :)            !! (ndof, m) constant input matrix
        type(c_funptr) :: bfun = c_null_funptr      !! or B(t, q) compiled
        real(dp), allocatable :: p(:)               !! parameters of bfun
    contains
        procedure :: rhs_u => mp_rhs_u
        procedure :: input_matrix => mp_input_matrix
        procedure :: inputs => mp_inputs
    end type mech_plant

contains

    !> bq = B(t, q) (ndof x m).
    subroutine mp_inputs(self, t, q, bq)
        class(mech_plant), intent(in) :: self
        real(dp), intent(in) :: t, q(:)
        real(dp), intent(out) :: bq(:, :)
        procedure(c_input_matrix), pointer :: f
        real(c_double) :: pdum(1)
        if (c_associated(self%bfun)) then
            call c_f_procpointer(self%bfun, f)
            if (allocated(self%p)) then
                if (size(self%p) > 0) then
                    call f(t, q, bq, self%p)
                    return
                end if
            end if
            pdum = 0.0_c_double
            call f(t, q, bq, pdum)
        else
            bq = self%b
        end if
    end subroutine mp_inputs

    subroutine mp_rhs_u(self, t, x, u, dxdt)
        class(mech_plant), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: x(:), u(:)
        real(dp), intent(out) :: dxdt(:)
        real(dp) :: mm(self%mech%ndof, self%mech%ndof), qf(self%mech%ndof, 1)
        real(dp) :: bq(self%mech%ndof, self%n_inputs)
        integer :: nd, info
        nd = self%mech%ndof
        call self%mech%mass_forces(t, x(1:nd), x(nd + 1:2*nd), mm, qf(:, 1))
        call self%inputs(t, x(1:nd), bq)
        qf(:, 1) = qf(:, 1) + matmul(bq, u)
        dxdt(1:nd) = x(nd + 1:2*nd)
        call mass_cholesky(mm, info)
        if (info /= CM_SUCCESS) then
            dxdt(nd + 1:2*nd) = nan_dp
            return
        end if
        call dpotrs('U', nd, 1, mm, nd, qf, nd, info)
        dxdt(nd + 1:2*nd) = qf(:, 1)
    end subroutine mp_rhs_u

    !> bx = [0; M^-1 B] (independent of u).
    subroutine mp_input_matrix(self, t, x, u, bx)
        class(mech_plant), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: x(:), u(:)
        real(dp), intent(out) :: bx(:, :)
        real(dp) :: mm(self%mech%ndof, self%mech%ndof), bq(self%mech%ndof, self%n_inputs)
        integer :: nd, info
        nd = self%mech%ndof
        call self%mech%mass(t, x(1:nd), mm)
        call self%inputs(t, x(1:nd), bq)
        bx(1:nd, :) = 0.0_dp
        call mass_cholesky(mm, info)
        if (info /= CM_SUCCESS) then
            bx(nd + 1:2*nd, :) = nan_dp
            return
        end if
        call dpotrs('U', nd, self%n_inputs, mm, nd, bq, nd, info)
        bx(nd + 1:2*nd, :) = bq
    end subroutine mp_input_matrix

end module conmech_mech_plant
