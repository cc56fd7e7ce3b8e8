!> Transverse models (`transverse_model`) of conmech's mechanical systems.
!!
!! - `generalized_model`: a system in generalized coordinates, x = [q, v]; its energy
!!   (when it defines one) for the reduction.
!! - `constrained_model`: a system in excessive coordinates, x = [q, v], integrated in the
!!   index-1 form (`constrained_ode`). The motion lies on the invariant manifold
!!   phi(q) = 0, G(q) v = 0, A(q) v + b(q) = 0, whose normals are the rows
!!
!!       [G, 0],   [d(G v)/dq, G],   [d(A v + b)/dq, A]
!!
!!   (2 n_hol + n_nh rows). d(G v)/dq and d(A v + b)/dq are fourth-order central
!!   differences of G and A, b (step eps^(1/5) max(|q_j|, 1)). Rheonomic constraints make
!!   the system non-autonomous: refused by the callers.
!! - `constrained_index1`: the index-1 form with the Jacobian of the accelerations by
!!   implicit differentiation of the KKT system M a = Q + C^T lam, C a = gamma:
!!   [M, -C^T; C, 0] [da; dlam] = -dF/dx at fixed (a, lam), where dF/dx comes from
!!   fourth-order differences of the constituents M, Q, C, gamma (low-degree polynomials
!!   or trigonometric terms of q and v, so the differences are accurate to ~1e-13, where
!!   differences of the accelerations themselves, solutions of a linear system with
!!   large higher derivatives, reach only ~1e-10).
module conmech_transverse_mech
    use conmech_kinds, only: dp, nan_dp
    use conmech_status, only: CM_SUCCESS
    use conmech_lapack, only: la_solve
    use conmech_generalized, only: generalized_system
    use conmech_constrained_system, only: constrained_system, constrained_accel, &
                                          constraint_matrix, constraint_residuals
    use conmech_constrained_solver, only: constrained_ode
    use conmech_transverse_model, only: transverse_model
    implicit none
    private
    public :: generalized_model, constrained_model, constrained_index1

    !> The index-1 first-order form with an accurate Jacobian (see the module notes).
    type, extends(constrained_ode) :: constrained_index1
    contains
        procedure :: jacobian => ci_jacobian
        procedure :: has_jacobian => ci_has_jacobian
    end type constrained_index1

    !> A generalized-coordinate system's energy.
    type, extends(transverse_model) :: generalized_model
        class(generalized_system), allocatable :: mech
    contains
        procedure :: has_energy => gm_has_energy
        procedure :: energy => gm_energy
    end type generalized_model

    !> A constrained system's manifold normals and energy.
    type, extends(transverse_model) :: constrained_model
        class(constrained_system), allocatable :: mech
    contains
        procedure :: n_normals => cm_n_normals
        procedure :: normals => cm_normals
        procedure :: manifold_residual => cm_manifold_residual
        procedure :: has_energy => cm_has_energy
        procedure :: energy => cm_energy
    end type constrained_model

contains

    logical function ci_has_jacobian(self)
        class(constrained_index1), intent(in) :: self
        ci_has_jacobian = .true.
    end function ci_has_jacobian

    !> The KKT residual F = [M a - Q - C^T lam; C a - gamma] at x = [q, v] for fixed a, lam.
    subroutine kkt_residual(mech, t, x, a, lam, r)
        class(constrained_system), intent(in) :: mech
        real(dp), intent(in) :: t, x(:), a(:), lam(:)
        real(dp), intent(out) :: r(:)
        real(dp) :: mm(mech%n, mech%n), qf(mech%n)
        real(dp) :: c(max(mech%n_hol + mech%n_nh, 1), mech%n), c0(max(mech%n_hol + mech%n_nh, 1))
        real(dp) :: gam(max(mech%n_hol + mech%n_nh, 1))
        integer :: n, m, mh
        n = mech%n
        mh = mech%n_hol
        m = mh + mech%n_nh
        call mech%mass(t, x(1:n), mm)
        call mech%forces(t, x(1:n), x(n + 1:2*n), qf)
        r(1:n) = matmul(mm, a) - qf
        if (m > 0) then
            call constraint_matrix(mech, t, x(1:n), c(1:m, :), c0(1:m))
            if (mh > 0) call mech%phi_gamma(t, x(1:n), x(n + 1:2*n), gam(1:mh))
            if (mech%n_nh > 0) call mech%nh_gamma(t, x(1:n), x(n + 1:2*n), gam(mh + 1:m))
            r(1:n) = r(1:n) - matmul(transpose(c(1:m, :)), lam)
            r(n + 1:n + m) = matmul(c(1:m, :), a) - gam(1:m)
        end if
    end subroutine kkt_residual

    subroutine ci_jacobian(self, t, y, dfdy)
        class(constrained_index1), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(dp), parameter :: off(4) = [2.0_dp, 1.0_dp, -1.0_dp, -2.0_dp]
        real(dp), parameter :: wt(4) = [-1.0_dp, 8.0_dp, -8.0_dp, 1.0_dp]
        real(dp) :: a(self%mech%n), lam(self%mech%n_hol + self%mech%n_nh)
        real(dp) :: kk(self%mech%n + self%mech%n_hol + self%mech%n_nh, &
                      self%mech%n + self%mech%n_hol + self%mech%n_nh)
        real(dp) :: df(self%mech%n + self%mech%n_hol + self%mech%n_nh, 2*self%mech%n)
        real(dp) :: dx(self%mech%n + self%mech%n_hol + self%mech%n_nh, 2*self%mech%n)
        real(dp) :: r(self%mech%n + self%mech%n_hol + self%mech%n_nh), yp(size(y)), h
        real(dp) :: mm(self%mech%n, self%mech%n)
        real(dp) :: c(max(self%mech%n_hol + self%mech%n_nh, 1), self%mech%n)
        real(dp) :: c0(max(self%mech%n_hol + self%mech%n_nh, 1))
        integer :: n, m, j, i, info
        n = self%mech%n
        m = self%mech%n_hol + self%mech%n_nh
        call constrained_accel(self%mech, t, y(1:n), y(n + 1:2*n), a, lam, info)
        if (info /= CM_SUCCESS) then
            dfdy = nan_dp
            return
        end if
        call self%mech%mass(t, y(1:n), mm)
        kk = 0.0_dp
        kk(1:n, 1:n) = mm
        if (m > 0) then
            call constraint_matrix(self%mech, t, y(1:n), c(1:m, :), c0(1:m))
            kk(1:n, n + 1:n + m) = -transpose(c(1:m, :))
            kk(n + 1:n + m, 1:n) = c(1:m, :)
        end if
        yp = y
        do j = 1, 2*n
            h = epsilon(1.0_dp)**0.2_dp*max(abs(y(j)), 1.0_dp)
            df(:, j) = 0.0_dp
            do i = 1, 4
                yp(j) = y(j) + off(i)*h
                call kkt_residual(self%mech, t, yp, a, lam, r)
                df(:, j) = df(:, j) + wt(i)*r
            end do
            df(:, j) = -df(:, j)/(12.0_dp*h)
            yp(j) = y(j)
        end do
        call la_solve(kk, df, dx, info, rcond_min=1.0e-14_dp)
        dfdy = 0.0_dp
        do j = 1, n
            dfdy(j, n + j) = 1.0_dp
        end do
        if (info /= CM_SUCCESS) then
            dfdy(n + 1:2*n, :) = nan_dp
            return
        end if
        dfdy(n + 1:2*n, :) = dx(1:n, :)
    end subroutine ci_jacobian

    logical function gm_has_energy(self)
        class(generalized_model), intent(in) :: self
        gm_has_energy = self%mech%has_energy()
    end function gm_has_energy

    real(dp) function gm_energy(self, t, x) result(e)
        class(generalized_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        integer :: nd
        nd = self%mech%ndof
        e = self%mech%energy(t, x(1:nd), x(nd + 1:2*nd))
    end function gm_energy

    integer function cm_n_normals(self)
        class(constrained_model), intent(in) :: self
        cm_n_normals = 2*self%mech%n_hol + self%mech%n_nh
    end function cm_n_normals

    subroutine cm_normals(self, t, x, c)
        class(constrained_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        real(dp), intent(out) :: c(:, :)
        real(dp), parameter :: off(4) = [2.0_dp, 1.0_dp, -1.0_dp, -2.0_dp]
        real(dp), parameter :: wt(4) = [-1.0_dp, 8.0_dp, -8.0_dp, 1.0_dp]
        real(dp) :: q(self%mech%n), v(self%mech%n), qp(self%mech%n)
        real(dp) :: g(max(self%mech%n_hol, 1), self%mech%n)
        real(dp) :: a(max(self%mech%n_nh, 1), self%mech%n), b(max(self%mech%n_nh, 1))
        real(dp) :: h
        integer :: n, mh, mn, j, i
        n = self%mech%n
        mh = self%mech%n_hol
        mn = self%mech%n_nh
        q = x(1:n)
        v = x(n + 1:2*n)
        c(1:2*mh + mn, :) = 0.0_dp
        if (mh > 0) then
            call self%mech%phi_jac(t, q, g(1:mh, :))
            c(1:mh, 1:n) = g(1:mh, :)
            c(mh + 1:2*mh, n + 1:2*n) = g(1:mh, :)
        end if
        if (mn > 0) then
            call self%mech%nh_matrix(t, q, a(1:mn, :), b(1:mn))
            c(2*mh + 1:2*mh + mn, n + 1:2*n) = a(1:mn, :)
        end if
        qp = q
        do j = 1, n
            h = epsilon(1.0_dp)**0.2_dp*max(abs(q(j)), 1.0_dp)
            do i = 1, 4
                qp(j) = q(j) + off(i)*h
                if (mh > 0) then
                    call self%mech%phi_jac(t, qp, g(1:mh, :))
                    c(mh + 1:2*mh, j) = c(mh + 1:2*mh, j) + wt(i)*matmul(g(1:mh, :), v)/ &
                                        (12.0_dp*h)
                end if
                if (mn > 0) then
                    call self%mech%nh_matrix(t, qp, a(1:mn, :), b(1:mn))
                    c(2*mh + 1:2*mh + mn, j) = c(2*mh + 1:2*mh + mn, j) + &
                                               wt(i)*(matmul(a(1:mn, :), v) + b(1:mn))/ &
                                               (12.0_dp*h)
                end if
            end do
            qp(j) = q(j)
        end do
    end subroutine cm_normals

    !> max(|phi|, |C v + c0|) at x = [q, v].
    real(dp) function cm_manifold_residual(self, t, x) result(r)
        class(constrained_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        real(dp) :: rpos, rvel
        integer :: n
        n = self%mech%n
        call constraint_residuals(self%mech, t, x(1:n), x(n + 1:2*n), rpos, rvel)
        r = max(rpos, rvel)
    end function cm_manifold_residual

    logical function cm_has_energy(self)
        class(constrained_model), intent(in) :: self
        cm_has_energy = self%mech%has_energy()
    end function cm_has_energy

    real(dp) function cm_energy(self, t, x) result(e)
        class(constrained_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        integer :: n
        n = self%mech%n
        e = self%mech%energy(t, x(1:n), x(n + 1:2*n))
    end function cm_energy

end module conmech_transverse_mech
