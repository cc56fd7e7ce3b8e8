!> Mechanical systems given by compiled C-ABI functions: generalized coordinates
!! (`c_generalized_system`) and excessive coordinates with constraints
!! (`c_constrained_system`). The C signatures (column-major matrices, `p` the run-time
!! parameters):
!!
!!     /* <generated: tools/generate_slots.py mechanics signatures> */
!!     /* the mass matrix M(t, q) */
!!     void mass(double t, const double *q, double *M, const double *p);
!!     /* the forces Q(t, q, q') */
!!     void forces(double t, const double *q, const double *v, double *Q, const double *p);
!!     /* [dQ/dq - d(M a)/dq, dQ/dv], the Jacobian of the force balance at accelerations a
!!        (optional) */
!!     void forces_jac(double t, const double *q, const double *v, const double *a,
!!                     double *R, const double *p);
!!     /* the energy (a first integral) (optional) */
!!     double energy(double t, const double *q, const double *v, const double *p);
!!     /* the holonomic constraints phi(t, q) (n_hol; required when n_hol > 0) (optional) */
!!     void phi(double t, const double *q, double *c, const double *p);
!!     /* G = dphi/dq (n_hol x n) (optional) */
!!     void phi_jac(double t, const double *q, double *G, const double *p);
!!     /* dphi/dt (rheonomic constraints) (optional) */
!!     void phi_t(double t, const double *q, double *pt, const double *p);
!!     /* gamma_h = -d/dt [G v + phi_t] at fixed v (optional) */
!!     void phi_gamma(double t, const double *q, const double *v, double *g,
!!                    const double *p);
!!     /* the Pfaffian constraints A(t, q) q' + b(t, q) = 0 (required when n_nh > 0)
!!        (optional) */
!!     void nh_matrix(double t, const double *q, double *A, double *b, const double *p);
!!     /* gamma_n = -d/dt [A v + b] at fixed v (optional) */
!!     void nh_gamma(double t, const double *q, const double *v, double *g, const double *p);
!!     /* M and Q in one call (shared subexpressions) (optional) */
!!     void mass_forces(double t, const double *q, const double *v, double *M, double *Q,
!!                      const double *p);
!!     /* the accelerations a = M^-1 Q directly (e.g. the articulated-body algorithm);
!!        non-finite where M is not positive definite (optional) */
!!     void accel(double t, const double *q, const double *v, double *a, const double *p);
!!     /* hl = d(C^T lam)/dq, hv = d(C v + c0)/dq: with forces_jac the exact Jacobian of
!!        Radau IIA on the constrained equations (optional) */
!!     void constraint_hessian(double t, const double *q, const double *v, const double *lam,
!!                             double *hl, double *hv, const double *p);
!!     /* a and its Jacobian d a/d[q, v] (ndof x 2 ndof) (optional) */
!!     void accel_jac(double t, const double *q, const double *v, double *a, double *jac,
!!                    const double *p);
!!     /* </generated> */
!!
!! Only `mass` and `forces` are required; a missing optional function falls back to the
!! finite-difference default of the parent type (see conmech_constrained_system).
module conmech_c_mechanics
    use, intrinsic :: iso_c_binding, only: c_double, c_associated, c_f_procpointer
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_generalized, only: generalized_system
    use conmech_c_entries, only: c_mech_pointers
    use conmech_c_system, only: c_rhs_fn, &  ! mass, phi, phi_jac, phi_t: f(t, q) into one array
                                c_parameters
    use conmech_constrained_system, only: constrained_system, fd_phi_jac, fd_phi_t, &
                                          fd_phi_gamma, fd_nh_gamma, fd_forces_jacobian, &
                                          fd_constraint_hessian
    implicit none
    private

    public :: c_generalized_system, c_constrained_system, c_mech_pointers, c_mech_core
    public :: make_c_generalized, make_c_constrained

    abstract interface
        subroutine c_qv_fn(t, q, v, f, p) bind(c)   ! forces, phi_gamma, nh_gamma
            import :: c_double
            real(c_double), value :: t
            real(c_double), intent(in) :: q(*), v(*)
            real(c_double), intent(out) :: f(*)
            real(c_double), intent(in) :: p(*)
        end subroutine c_qv_fn
        subroutine c_mf_fn(t, q, v, m, f, p) bind(c)   ! mass_forces
            import :: c_double
            real(c_double), value :: t
            real(c_double), intent(in) :: q(*), v(*)
            real(c_double), intent(out) :: m(*), f(*)
            real(c_double), intent(in) :: p(*)
        end subroutine c_mf_fn
        subroutine c_fjac_fn(t, q, v, a, r, p) bind(c)
            import :: c_double
            real(c_double), value :: t
            real(c_double), intent(in) :: q(*), v(*), a(*)
            real(c_double), intent(out) :: r(*)
            real(c_double), intent(in) :: p(*)
        end subroutine c_fjac_fn
        function c_energy_fn(t, q, v, p) result(e) bind(c)
            import :: c_double
            real(c_double), value :: t
            real(c_double), intent(in) :: q(*), v(*)
            real(c_double), intent(in) :: p(*)
            real(c_double) :: e
        end function c_energy_fn
        subroutine c_hess_fn(t, q, v, lam, hl, hv, p) bind(c)
            import :: c_double
            real(c_double), value :: t
            real(c_double), intent(in) :: q(*), v(*), lam(*)
            real(c_double), intent(out) :: hl(*), hv(*)
            real(c_double), intent(in) :: p(*)
        end subroutine c_hess_fn
        subroutine c_nh_fn(t, q, a, b, p) bind(c)
            import :: c_double
            real(c_double), value :: t
            real(c_double), intent(in) :: q(*)
            real(c_double), intent(out) :: a(*), b(*)
            real(c_double), intent(in) :: p(*)
        end subroutine c_nh_fn
    end interface

    !> The compiled functions that both kinds of system have: M(t, q), Q(t, q, q'), the
    !! Jacobian of the force balance and the energy (the last two optional), with the
    !! parameters passed to each.
    type :: c_mech_core
        real(dp), allocatable :: p(:)   !! parameters (at least 1 entry)
        procedure(c_rhs_fn), pointer, nopass :: mass_f => null()
        procedure(c_qv_fn), pointer, nopass :: forces_f => null()
        procedure(c_fjac_fn), pointer, nopass :: fjac_f => null()
        procedure(c_energy_fn), pointer, nopass :: energy_f => null()
    contains
        procedure :: connect => core_connect
        procedure :: energy => core_energy
    end type c_mech_core

    !> M(t, q) q'' = Q(t, q, q') from compiled functions.
    type, extends(generalized_system) :: c_generalized_system
        type(c_mech_core) :: core
        procedure(c_mf_fn), pointer, nopass :: mf_f => null()
        procedure(c_qv_fn), pointer, nopass :: accel_f => null()
        procedure(c_mf_fn), pointer, nopass :: accel_jac_f => null()
    contains
        procedure :: mass => cg_mass
        procedure :: accelerations_jacobian => cg_accelerations_jacobian
        procedure :: has_accelerations_jacobian => cg_has_accelerations_jacobian
        procedure :: accelerations => cg_accelerations
        procedure :: has_accelerations => cg_has_accelerations
        procedure :: mass_forces => cg_mass_forces
        procedure :: forces => cg_forces
        procedure :: energy => cg_energy
        procedure :: has_energy => cg_has_energy
        procedure :: forces_jacobian => cg_forces_jacobian
        procedure :: has_forces_jacobian => cg_has_forces_jacobian
    end type c_generalized_system

    !> A constrained system in excessive coordinates from compiled functions.
    type, extends(constrained_system) :: c_constrained_system
        type(c_mech_core) :: core
        procedure(c_rhs_fn), pointer, nopass :: phi_f => null()
        procedure(c_rhs_fn), pointer, nopass :: phi_jac_f => null()
        procedure(c_rhs_fn), pointer, nopass :: phi_t_f => null()
        procedure(c_qv_fn), pointer, nopass :: phi_gamma_f => null()
        procedure(c_nh_fn), pointer, nopass :: nh_f => null()
        procedure(c_qv_fn), pointer, nopass :: nh_gamma_f => null()
        procedure(c_hess_fn), pointer, nopass :: hess_f => null()
    contains
        procedure :: forces_jacobian => cc_forces_jacobian
        procedure :: has_forces_jacobian => cc_has_forces_jacobian
        procedure :: constraint_hessian => cc_constraint_hessian
        procedure :: has_constraint_hessian => cc_has_constraint_hessian
        procedure :: mass => cc_mass
        procedure :: forces => cc_forces
        procedure :: energy => cc_energy
        procedure :: has_energy => cc_has_energy
        procedure :: phi => cc_phi
        procedure :: phi_jac => cc_phi_jac
        procedure :: phi_t => cc_phi_t
        procedure :: phi_gamma => cc_phi_gamma
        procedure :: nh_matrix => cc_nh_matrix
        procedure :: nh_gamma => cc_nh_gamma
    end type c_constrained_system

contains

    !> Take the required mass and forces functions, the optional forces_jac and energy, and
    !! a copy of the parameters (at least one entry, f2py/C never see an empty array).
    subroutine core_connect(self, fp, params, info, msg)
        class(c_mech_core), intent(inout) :: self
        type(c_mech_pointers), intent(in) :: fp
        real(dp), intent(in) :: params(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        info = CM_BAD_INPUT
        if (.not. (c_associated(fp%mass) .and. c_associated(fp%forces))) then
            msg = "bad input: the mass and forces function pointers must not be null"
            return
        end if
        call c_f_procpointer(fp%mass, self%mass_f)
        call c_f_procpointer(fp%forces, self%forces_f)
        if (c_associated(fp%forces_jac)) call c_f_procpointer(fp%forces_jac, self%fjac_f)
        if (c_associated(fp%energy)) call c_f_procpointer(fp%energy, self%energy_f)
        self%p = c_parameters(params)
        info = CM_SUCCESS
        msg = "success"
    end subroutine core_connect

    !> The energy, 0 without an energy function.
    function core_energy(self, t, q, v) result(e)
        class(c_mech_core), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.0_dp
        if (associated(self%energy_f)) e = self%energy_f(t, q, v, self%p)
    end function core_energy

    !> Build a compiled generalized system with `ndof` coordinates. Required: mass, forces.
    subroutine make_c_generalized(ndof, fp, params, sys, info, msg)
        integer, intent(in) :: ndof
        type(c_mech_pointers), intent(in) :: fp
        real(dp), intent(in) :: params(:)
        type(c_generalized_system), intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        info = CM_BAD_INPUT
        if (ndof < 1) then
            msg = "bad input: the number of coordinates of a compiled system must be positive"
            return
        end if
        call sys%core%connect(fp, params, info, msg)
        if (info /= CM_SUCCESS) return
        sys%ndof = ndof
        if (c_associated(fp%mass_forces)) call c_f_procpointer(fp%mass_forces, sys%mf_f)
        if (c_associated(fp%accel)) call c_f_procpointer(fp%accel, sys%accel_f)
        if (c_associated(fp%accel_jac)) call c_f_procpointer(fp%accel_jac, sys%accel_jac_f)
    end subroutine make_c_generalized

    !> Build a compiled constrained system: n coordinates, n_hol holonomic and n_nh
    !! non-holonomic constraints. Required: mass, forces; phi when n_hol > 0, nh_matrix
    !! when n_nh > 0.
    subroutine make_c_constrained(n, n_hol, n_nh, rheonomic, fp, params, sys, info, msg)
        integer, intent(in) :: n, n_hol, n_nh
        logical, intent(in) :: rheonomic
        type(c_mech_pointers), intent(in) :: fp
        real(dp), intent(in) :: params(:)
        type(c_constrained_system), intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        info = CM_BAD_INPUT
        ! as many constraints as coordinates, or more, is legitimate when they are
        ! redundant (an over-constrained mechanism such as Bricard's: the rank-revealing
        ! KKT solve finds its motion); the caller decides whether to allow it
        if (n < 1 .or. n_hol < 0 .or. n_nh < 0) then
            msg = "bad input: a compiled constrained system needs n >= 1 coordinates and " &
                  //"n_hol, n_nh >= 0 constraints"
            return
        end if
        call sys%core%connect(fp, params, info, msg)
        if (info /= CM_SUCCESS) return
        info = CM_BAD_INPUT
        if (n_hol > 0 .and. .not. c_associated(fp%phi)) then
            msg = "bad input: holonomic constraints need the phi function"
            return
        end if
        if (n_nh > 0 .and. .not. c_associated(fp%nh_matrix)) then
            msg = "bad input: non-holonomic constraints need the nh_matrix function"
            return
        end if
        sys%n = n
        sys%n_hol = n_hol
        sys%n_nh = n_nh
        sys%rheonomic = rheonomic
        if (c_associated(fp%phi)) call c_f_procpointer(fp%phi, sys%phi_f)
        if (c_associated(fp%phi_jac)) call c_f_procpointer(fp%phi_jac, sys%phi_jac_f)
        if (c_associated(fp%phi_t)) call c_f_procpointer(fp%phi_t, sys%phi_t_f)
        if (c_associated(fp%phi_gamma)) call c_f_procpointer(fp%phi_gamma, sys%phi_gamma_f)
        if (c_associated(fp%nh_matrix)) call c_f_procpointer(fp%nh_matrix, sys%nh_f)
        if (c_associated(fp%nh_gamma)) call c_f_procpointer(fp%nh_gamma, sys%nh_gamma_f)
        if (c_associated(fp%constraint_hessian)) &
            call c_f_procpointer(fp%constraint_hessian, sys%hess_f)
        info = CM_SUCCESS
    end subroutine make_c_constrained

    ! ------------------------------------------------------------ generalized system

    subroutine cg_mass(self, t, q, mm)
        class(c_generalized_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        call self%core%mass_f(t, q, mm, self%core%p)
    end subroutine cg_mass

    subroutine cg_mass_forces(self, t, q, v, mm, f)
        class(c_generalized_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: mm(:, :), f(:)
        if (associated(self%mf_f)) then
            call self%mf_f(t, q, v, mm, f, self%core%p)
        else
            call self%core%mass_f(t, q, mm, self%core%p)
            call self%core%forces_f(t, q, v, f, self%core%p)
        end if
    end subroutine cg_mass_forces

    subroutine cg_accelerations(self, t, q, v, a)
        class(c_generalized_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: a(:)
        call self%accel_f(t, q, v, a, self%core%p)
    end subroutine cg_accelerations

    logical function cg_has_accelerations(self)
        class(c_generalized_system), intent(in) :: self
        cg_has_accelerations = associated(self%accel_f)
    end function cg_has_accelerations

    subroutine cg_accelerations_jacobian(self, t, q, v, a, jac)
        class(c_generalized_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: a(:), jac(:, :)
        call self%accel_jac_f(t, q, v, a, jac, self%core%p)
    end subroutine cg_accelerations_jacobian

    logical function cg_has_accelerations_jacobian(self)
        class(c_generalized_system), intent(in) :: self
        cg_has_accelerations_jacobian = associated(self%accel_jac_f)
    end function cg_has_accelerations_jacobian

    subroutine cg_forces(self, t, q, v, f)
        class(c_generalized_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        call self%core%forces_f(t, q, v, f, self%core%p)
    end subroutine cg_forces

    function cg_energy(self, t, q, v) result(e)
        class(c_generalized_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = self%core%energy(t, q, v)
    end function cg_energy

    logical function cg_has_energy(self)
        class(c_generalized_system), intent(in) :: self
        cg_has_energy = associated(self%core%energy_f)
    end function cg_has_energy

    subroutine cg_forces_jacobian(self, t, q, v, a, r)
        class(c_generalized_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:), a(:)
        real(dp), intent(out) :: r(:, :)
        call self%core%fjac_f(t, q, v, a, r, self%core%p)
    end subroutine cg_forces_jacobian

    logical function cg_has_forces_jacobian(self)
        class(c_generalized_system), intent(in) :: self
        cg_has_forces_jacobian = associated(self%core%fjac_f)
    end function cg_has_forces_jacobian

    ! ------------------------------------------------------------ constrained system

    subroutine cc_mass(self, t, q, mm)
        class(c_constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        call self%core%mass_f(t, q, mm, self%core%p)
    end subroutine cc_mass

    subroutine cc_forces(self, t, q, v, f)
        class(c_constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        call self%core%forces_f(t, q, v, f, self%core%p)
    end subroutine cc_forces

    function cc_energy(self, t, q, v) result(e)
        class(c_constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = self%core%energy(t, q, v)
    end function cc_energy

    logical function cc_has_energy(self)
        class(c_constrained_system), intent(in) :: self
        cc_has_energy = associated(self%core%energy_f)
    end function cc_has_energy

    subroutine cc_phi(self, t, q, c)
        class(c_constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        if (associated(self%phi_f)) then
            call self%phi_f(t, q, c, self%core%p)
        else
            c = 0.0_dp
        end if
    end subroutine cc_phi

    subroutine cc_phi_jac(self, t, q, g)
        class(c_constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        if (associated(self%phi_jac_f)) then
            call self%phi_jac_f(t, q, g, self%core%p)
        else
            call fd_phi_jac(self, t, q, g)
        end if
    end subroutine cc_phi_jac

    subroutine cc_phi_t(self, t, q, pt)
        class(c_constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: pt(:)
        if (associated(self%phi_t_f)) then
            call self%phi_t_f(t, q, pt, self%core%p)
        else
            call fd_phi_t(self, t, q, pt)
        end if
    end subroutine cc_phi_t

    subroutine cc_phi_gamma(self, t, q, v, gam)
        class(c_constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        if (associated(self%phi_gamma_f)) then
            call self%phi_gamma_f(t, q, v, gam, self%core%p)
        else
            call fd_phi_gamma(self, t, q, v, gam)
        end if
    end subroutine cc_phi_gamma

    subroutine cc_nh_matrix(self, t, q, a, b)
        class(c_constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: a(:, :)
        real(dp), intent(out) :: b(:)
        if (associated(self%nh_f)) then
            call self%nh_f(t, q, a, b, self%core%p)
        else
            a = 0.0_dp
            b = 0.0_dp
        end if
    end subroutine cc_nh_matrix

    subroutine cc_nh_gamma(self, t, q, v, gam)
        class(c_constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        if (associated(self%nh_gamma_f)) then
            call self%nh_gamma_f(t, q, v, gam, self%core%p)
        else
            call fd_nh_gamma(self, t, q, v, gam)
        end if
    end subroutine cc_nh_gamma

    subroutine cc_forces_jacobian(self, t, q, v, a, r)
        class(c_constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:), a(:)
        real(dp), intent(out) :: r(:, :)
        if (associated(self%core%fjac_f)) then
            call self%core%fjac_f(t, q, v, a, r, self%core%p)
        else
            call fd_forces_jacobian(self, t, q, v, a, r)
        end if
    end subroutine cc_forces_jacobian

    logical function cc_has_forces_jacobian(self)
        class(c_constrained_system), intent(in) :: self
        cc_has_forces_jacobian = associated(self%core%fjac_f)
    end function cc_has_forces_jacobian

    subroutine cc_constraint_hessian(self, t, q, v, lam, hl, hv)
        class(c_constrained_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:), lam(:)
        real(dp), intent(out) :: hl(:, :), hv(:, :)
        if (associated(self%hess_f) .and. self%n_hol + self%n_nh > 0) then
            call self%hess_f(t, q, v, lam, hl, hv, self%core%p)
        else
            call fd_constraint_hessian(self, t, q, v, lam, hl, hv)
        end if
    end subroutine cc_constraint_hessian

    logical function cc_has_constraint_hessian(self)
        class(c_constrained_system), intent(in) :: self
        cc_has_constraint_hessian = associated(self%hess_f)
    end function cc_has_constraint_hessian

end module conmech_c_mechanics
