!> A constrained system whose dependent holonomic constraints are replaced by independent
!! combinations of them: the form Radau IIA integrates when a mechanism's constraints are
!! redundant.
!!
!! Redundant constraints (Bricard's mechanism: five loop equations of rank four on the
!! whole motion; a constraint written twice) make the Newton matrix of a DAE form
!! singular: the multipliers of dependent rows are not determined. Where the rank r <
!! n_hol is the same all along the motion, the constraints are equivalent near the
!! manifold to r independent combinations of them, and the DAE on those has the same
!! solution with unique multipliers. `select_rows` takes the combinations comb phi with
!! comb the left singular vectors of G(q0) of its r nonzero singular values (comb G keeps
!! full rank as long as the dependency w(q) of the rows, w^T G = 0, stays away from
!! orthogonal to w(q0): more robust than a subset of rows, which fails where the
!! dropped row's weight in w vanishes) and checks that the deficiency is structural: a
!! short way along the motion (the velocity, or the acceleration from rest) the full
!! constraint set must still have rank r. If the rank grows there the initial state is a
!! singular configuration (a parallelogram linkage flat, where two branches of the motion
!! cross), which no fixed combination describes: then it refuses. The run's results are
!! evaluated on the full system (every residual, minimum-norm multipliers of every row),
!! so a constraint that stopped holding would show.
module conmech_constrained_rows
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_text, only: itoa
    use conmech_rank, only: svd
    use conmech_constrained_system, only: constrained_system, constrained_accel, &
        project_position
    implicit none
    private

    public :: row_subset, select_rows

    !> `inner` with its holonomic constraints replaced by r independent combinations
    !! comb phi (all its non-holonomic rows kept).
    type, extends(constrained_system) :: row_subset
        class(constrained_system), allocatable :: inner
        !> (r x n_hol) orthonormal combinations of the rows: the left singular vectors of
        !! G(q0) of its nonzero singular values
        real(dp), allocatable :: comb(:, :)
    contains
        procedure :: mass => rs_mass
        procedure :: forces => rs_forces
        procedure :: mass_diagonal => rs_mass_diagonal
        procedure :: phi => rs_phi
        procedure :: phi_jac => rs_phi_jac
        procedure :: phi_t => rs_phi_t
        procedure :: phi_gamma => rs_phi_gamma
        procedure :: nh_matrix => rs_nh_matrix
        procedure :: nh_gamma => rs_nh_gamma
        procedure :: energy => rs_energy
        procedure :: has_energy => rs_has_energy
        procedure :: forces_jacobian => rs_forces_jacobian
        procedure :: has_forces_jacobian => rs_has_forces_jacobian
        procedure :: constraint_hessian => rs_constraint_hessian
        procedure :: has_constraint_hessian => rs_has_constraint_hessian
    end type row_subset

contains

    !> Choose independent combinations of the holonomic rows of sys at the consistent
    !! state (t, q, v) (rank: that of the full constraint set there) and build the
    !! reduced system sub.
    !! info = CM_BAD_INPUT with `msg` when the deficiency is not structural (a singular
    !! configuration) or lies in the non-holonomic rows.
    subroutine select_rows(sys, t, q, v, acc, rank, proj_tol, sub, info, msg)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t, q(:), v(:), acc(:)
        integer, intent(in) :: rank
        real(dp), intent(in) :: proj_tol
        type(row_subset), intent(out) :: sub
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        real(dp) :: g(sys%n_hol, sys%n), u(sys%n_hol, sys%n_hol), vt(sys%n, sys%n)
        real(dp) :: sv(min(sys%n, sys%n_hol))
        real(dp) :: q1(sys%n), d(sys%n), a1(sys%n), l1(sys%n_hol + sys%n_nh), dn
        integer :: n, mh, lainfo, r_hol, r1, iters, i
        character(len=:), allocatable :: m2
        n = sys%n
        mh = sys%n_hol
        info = CM_BAD_INPUT
        ! rank and range of the holonomic rows alone (SVD of G)
        call sys%phi_jac(t, q, g)
        call svd(g, u, sv, vt, lainfo)
        r_hol = 0
        if (lainfo == CM_SUCCESS) then
            do i = 1, size(sv)
                if (sv(i) > 1.0e-11_dp*sv(1)) r_hol = r_hol + 1
            end do
        end if
        if (r_hol == 0) then
            msg = "bad input: the holonomic constraint Jacobian has no independent row"
            return
        end if
        ! a short way along the motion on the full constraint set: still rank deficient?
        d = v
        if (maxval(abs(d)) == 0.0_dp) d = acc
        dn = maxval(abs(d))
        if (dn > 0.0_dp) then
            q1 = q + (1.0e-4_dp*max(1.0_dp, maxval(abs(q)))/dn)*d
            call project_position(sys, t, q1, proj_tol, 50, iters, info, m2, newton=.true.)
            if (info == CM_SUCCESS) then
                call constrained_accel(sys, t, q1, 0.0_dp*v, a1, l1, info, m2, rank=r1)
            end if
            if (info /= CM_SUCCESS) then
                info = CM_BAD_INPUT
                msg = "bad input: Radau IIA needs independent constraints, but at the "// &
                      "initial state their rank is "//itoa(rank)//" of "// &
                      itoa(mh + sys%n_nh)//" and no nearby state along the motion "// &
                      "could be checked (a singular configuration?); the projected "// &
                      "methods (the default DOP853) and RATTLE handle it with "// &
                      "minimum-norm multipliers"
                return
            end if
            if (r1 > rank) then
                info = CM_BAD_INPUT
                msg = "bad input: Radau IIA cannot start from a singular configuration: "// &
                      "the constraints' rank is "//itoa(rank)//" of "// &
                      itoa(mh + sys%n_nh)//" at the initial state but "//itoa(r1)// &
                      " a short way along the motion (the rows become independent: "// &
                      "no subset of them describes the motion there); the projected "// &
                      "methods (the default DOP853) pass it with minimum-norm "// &
                      "multipliers"
                return
            end if
        end if
        info = CM_SUCCESS
        allocate (sub%inner, source=sys)
        sub%comb = transpose(u(:, 1:r_hol))
        sub%n = n
        sub%n_hol = r_hol
        sub%n_nh = sys%n_nh
        sub%rheonomic = sys%rheonomic
        sub%diagonal_mass = sys%diagonal_mass
        sub%constant_mass = sys%constant_mass
        sub%jac_width = 0
        sub%nh_width = 0
    end subroutine select_rows

    subroutine rs_mass(self, t, q, mm)
        class(row_subset), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        call self%inner%mass(t, q, mm)
    end subroutine rs_mass

    subroutine rs_forces(self, t, q, v, f)
        class(row_subset), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        call self%inner%forces(t, q, v, f)
    end subroutine rs_forces

    subroutine rs_mass_diagonal(self, t, q, d)
        class(row_subset), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: d(:)
        call self%inner%mass_diagonal(t, q, d)
    end subroutine rs_mass_diagonal

    subroutine rs_phi(self, t, q, c)
        class(row_subset), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        real(dp) :: cf(self%inner%n_hol)
        call self%inner%phi(t, q, cf)
        c = matmul(self%comb, cf)
    end subroutine rs_phi

    subroutine rs_phi_jac(self, t, q, g)
        class(row_subset), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        real(dp) :: gf(self%inner%n_hol, self%n)
        call self%inner%phi_jac(t, q, gf)
        g = matmul(self%comb, gf)
    end subroutine rs_phi_jac

    subroutine rs_phi_t(self, t, q, pt)
        class(row_subset), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: pt(:)
        real(dp) :: pf(self%inner%n_hol)
        call self%inner%phi_t(t, q, pf)
        pt = matmul(self%comb, pf)
    end subroutine rs_phi_t

    subroutine rs_phi_gamma(self, t, q, v, gam)
        class(row_subset), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        real(dp) :: gf(self%inner%n_hol)
        call self%inner%phi_gamma(t, q, v, gf)
        gam = matmul(self%comb, gf)
    end subroutine rs_phi_gamma

    subroutine rs_nh_matrix(self, t, q, a, b)
        class(row_subset), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: a(:, :)
        real(dp), intent(out) :: b(:)
        call self%inner%nh_matrix(t, q, a, b)
    end subroutine rs_nh_matrix

    subroutine rs_nh_gamma(self, t, q, v, gam)
        class(row_subset), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        call self%inner%nh_gamma(t, q, v, gam)
    end subroutine rs_nh_gamma

    function rs_energy(self, t, q, v) result(e)
        class(row_subset), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = self%inner%energy(t, q, v)
    end function rs_energy

    logical function rs_has_energy(self)
        class(row_subset), intent(in) :: self
        rs_has_energy = self%inner%has_energy()
    end function rs_has_energy

    subroutine rs_forces_jacobian(self, t, q, v, a, r)
        class(row_subset), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:), a(:)
        real(dp), intent(out) :: r(:, :)
        call self%inner%forces_jacobian(t, q, v, a, r)
    end subroutine rs_forces_jacobian

    logical function rs_has_forces_jacobian(self)
        class(row_subset), intent(in) :: self
        rs_has_forces_jacobian = self%inner%has_forces_jacobian()
    end function rs_has_forces_jacobian

    !> The inner system's second derivatives for the combinations: lam_full = comb^T lam.
    subroutine rs_constraint_hessian(self, t, q, v, lam, hl, hv)
        class(row_subset), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:), lam(:)
        real(dp), intent(out) :: hl(:, :), hv(:, :)
        real(dp) :: lf(self%inner%n_hol + self%n_nh)
        real(dp) :: hvf(self%inner%n_hol + self%n_nh, self%n)
        integer :: mh, mf
        mh = self%n_hol
        mf = self%inner%n_hol
        lf = 0.0_dp
        lf(1:mf) = matmul(lam(1:mh), self%comb)
        lf(mf + 1:) = lam(mh + 1:)
        call self%inner%constraint_hessian(t, q, v, lf, hl, hvf)
        hv(1:mh, :) = matmul(self%comb, hvf(1:mf, :))
        hv(mh + 1:, :) = hvf(mf + 1:, :)
    end subroutine rs_constraint_hessian

    logical function rs_has_constraint_hessian(self)
        class(row_subset), intent(in) :: self
        rs_has_constraint_hessian = self%inner%has_constraint_hessian()
    end function rs_has_constraint_hessian

end module conmech_constrained_rows
