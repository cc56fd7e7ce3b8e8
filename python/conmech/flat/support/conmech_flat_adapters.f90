!> The adapters of the flat f2py layer to conmech's abstract contracts, in one place
!! (compiled into the extension, not wrapped: it holds derived types).
!!
!! Each type extends one of the contracts (`ode_system`, `ode_events`,
!! `sparse_jacobian_system`, `constrained_system`, `feedback_law`, `periodic_lq`,
!! `branch_energy`, `planar_natural_system`, `transverse_model`, `ensemble_progress`). Most
!! forward the deferred bindings to external procedures with an implicit interface (f2py
!! call-backs into Python, set as procedure-pointer components by the flat routines); the
!! rest are the few fixed implementations the flat routines need (a compiled or zero
!! feedback law, the reduced dynamics' event functions). One adapter per need, so that a
!! flat routine of any topic reuses the same forwarding code. Calling conventions (all
!! arguments by reference; real(c_double) values, integer(c_int) sizes):
!!
!!     fun(t, y, dydt, n)  or  fun(t, y, p, dydt, n)       callback_system (parametric: p)
!!     jac(t, y, dfdy, n)  or  jac(t, y, p, dfdy, n)       callback_jac_system
!!     events(t, y, g, n, ne)                              callback_events
!!     jvals(t, y, jval, n, nnz)                           callback_sparse_jac_system
!!     mass(t, q, mm, n), forces(t, q, v, f, n), phi(t, q, c, n, mh), jac(t, q, g, n, mh),
!!     gamma(t, q, v, gam, n, mh), nh(t, q, a, b, n, mn), nhgamma(t, q, v, gam, n, mn)
!!                                                         callback_constrained
!!     law(t, x, u, n, m)                                  callback_law
!!     afun(t, a, k), bfun(t, b, k, m)                     callback_lq
!!     energy(y, p, e, n)                                  callback_energy
!!     phi(t, p)                                           callback_hill (Hill's Phi(t))
!!     pot(q, v, g, h)                                     callback_natural
!!     egrad(t, y, g, n)                                   callback_energy_model
!!     progress(done, total, cancel)                       callback_progress
!!     void law(double t, const double *x, double *u, const double *p)  c_law (compiled)
module conmech_flat_adapters
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_funptr, c_null_funptr, &
                                           c_f_procpointer
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT, CM_NONFINITE
    use conmech_lapack, only: la_finite
    use conmech_ode_system, only: ode_system, ode_events
    use conmech_sparse_jacobian_system, only: sparse_jacobian_system
    use conmech_constrained_system, only: constrained_system, fd_phi_jac, fd_phi_gamma, &
                                          fd_nh_gamma
    use conmech_control_system, only: feedback_law
    use conmech_periodic_riccati, only: periodic_lq
    use conmech_continuation, only: branch_energy
    use conmech_transverse, only: planar_natural_system
    use conmech_transverse_model, only: transverse_model
    use conmech_ensemble, only: ensemble_progress
    implicit none
    private
    public :: callback_system, callback_jac_system, callback_events
    public :: callback_sparse_jac_system, make_sparse_jac_system
    public :: callback_constrained, callback_law, callback_lq, callback_energy, callback_hill
    public :: callback_natural, callback_energy_model, callback_progress
    public :: c_law, zero_law, velocity_zero, energy_zero

    !> A system whose right-hand side is an external fun(t, y, dydt, n), or, when
    !! `parametric`, fun(t, y, p, dydt, n) at the parameter value p (continuation sets p).
    type, extends(ode_system) :: callback_system
        procedure(), pointer, nopass :: f => null()
        integer(c_int) :: n = 0
        logical :: parametric = .false.
        real(c_double) :: p = 0.0_c_double
    contains
        procedure :: rhs => callback_rhs
    end type callback_system

    !> The same with its exact Jacobian from jac(t, y, dfdy, n) (or jac(t, y, p, dfdy, n)).
    type, extends(callback_system) :: callback_jac_system
        procedure(), pointer, nopass :: jac => null()
    contains
        procedure :: jacobian => callback_jacobian
        procedure :: has_jacobian => callback_has_jacobian
    end type callback_jac_system

    !> Event functions given by one external procedure events(t, y, g, n, ne).
    type, extends(ode_events) :: callback_events
        procedure(), pointer, nopass :: g => null()
        integer(c_int) :: n = 0
        integer(c_int) :: ne = 0
    contains
        procedure :: eval => callback_eval
    end type callback_events

    !> fun(t, y, dydt, n) with the Jacobian's values on a fixed pattern, jvals(t, y, jval,
    !! n, nnz) (the k-th value for the k-th entry of the pattern, compressed by columns), so
    !! that a scipy.sparse matrix reaches Radau's sparse LUs without an n x n array.
    type, extends(sparse_jacobian_system) :: callback_sparse_jac_system
        procedure(), pointer, nopass :: f => null()
        procedure(), pointer, nopass :: jv => null()
        integer(c_int) :: n = 0
        integer(c_int) :: nnz = 0
    contains
        procedure :: rhs => sparse_callback_rhs
        procedure :: jacobian_values => sparse_callback_values
    end type callback_sparse_jac_system

    !> A constrained mechanical system from external procedures; the constraint Jacobian and
    !! the gamma terms by finite differences where has_jac / has_gamma / has_nh_gamma is off.
    type, extends(constrained_system) :: callback_constrained
        procedure(), pointer, nopass :: fmass => null()
        procedure(), pointer, nopass :: fforces => null()
        procedure(), pointer, nopass :: fphi => null()
        procedure(), pointer, nopass :: fjac => null()
        procedure(), pointer, nopass :: fgamma => null()
        procedure(), pointer, nopass :: fnh => null()
        procedure(), pointer, nopass :: fnhgamma => null()
        logical :: has_jac = .false., has_gamma = .false., has_nh_gamma = .false.
    contains
        procedure :: mass => cb_mass
        procedure :: forces => cb_forces
        procedure :: phi => cb_phi
        procedure :: phi_jac => cb_jac
        procedure :: phi_gamma => cb_gamma
        procedure :: nh_matrix => cb_nh
        procedure :: nh_gamma => cb_nh_gamma
    end type callback_constrained

    !> u from an external procedure law(t, x, u, n, m).
    type, extends(feedback_law) :: callback_law
        procedure(), pointer, nopass :: f => null()
        integer(c_int) :: n = 0
    contains
        procedure :: eval => law_eval
    end type callback_law

    !> A(t), B(t) of a periodic linear system from afun(t, a, k) and bfun(t, b, k, m).
    type, extends(periodic_lq) :: callback_lq
        procedure(), pointer, nopass :: fa => null()
        procedure(), pointer, nopass :: fb => null()
    contains
        procedure :: coefficients => lq_coefficients
    end type callback_lq

    !> An energy(y, p, e, n) along a branch of periodic orbits.
    type, extends(branch_energy) :: callback_energy
        procedure(), pointer, nopass :: f => null()
        integer(c_int) :: n = 0
    contains
        procedure :: value => energy_value
    end type callback_energy

    !> Hill's equation N'' + Phi(t) N = 0 as y = [N, N'], Phi from an external phi(t, p);
    !! its Jacobian is exact (the equation is linear in y).
    type, extends(ode_system) :: callback_hill
        procedure(), pointer, nopass :: g => null()
    contains
        procedure :: rhs => hill_rhs
        procedure :: jacobian => hill_jacobian
        procedure :: has_jacobian => hill_has_jacobian
    end type callback_hill

    !> V, grad V, Hess V of a planar natural system from pot(q(2), v, g(2), h(2, 2)).
    type, extends(planar_natural_system) :: callback_natural
        procedure(), pointer, nopass :: pot => null()
    contains
        procedure :: potential => natural_potential
    end type callback_natural

    !> A transverse model whose energy gradient is an external egrad(t, y, g, n) (no
    !! energy when `present` is off).
    type, extends(transverse_model) :: callback_energy_model
        procedure(), pointer, nopass :: egrad => null()
        logical :: present = .false.
        integer(c_int) :: n = 0
    contains
        procedure :: has_energy => model_has_energy
        procedure :: energy_gradient => model_energy_gradient
    end type callback_energy_model

    !> An ensemble's progress reports relayed to progress(done, total, cancel), all
    !! integer(c_int) (called by the calling thread between chunks only).
    type, extends(ensemble_progress) :: callback_progress
        procedure(), pointer, nopass :: f => null()
    contains
        procedure :: report => progress_report
    end type callback_progress

    abstract interface
        subroutine c_law_fun(t, x, u, p) bind(c)
            import :: c_double
            real(c_double), value :: t
            real(c_double), intent(in) :: x(*), p(*)
            real(c_double), intent(out) :: u(*)
        end subroutine c_law_fun
    end interface

    !> u from a compiled function with parameters.
    type, extends(feedback_law) :: c_law
        type(c_funptr) :: fp = c_null_funptr
        real(dp), allocatable :: p(:)
    contains
        procedure :: eval => c_eval
    end type c_law

    !> u = 0.
    type, extends(feedback_law) :: zero_law
    contains
        procedure :: eval => z_eval
    end type zero_law

    !> g = theta' (the second component).
    type, extends(ode_events) :: velocity_zero
    contains
        procedure :: eval => vz_eval
    end type velocity_zero

    !> g = E (the first component).
    type, extends(ode_events) :: energy_zero
    contains
        procedure :: eval => ez_eval
    end type energy_zero

contains

    subroutine callback_rhs(self, t, y, dydt)
        class(callback_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        if (self%parametric) then
            call self%f(t, y, self%p, dydt, self%n)
        else
            call self%f(t, y, dydt, self%n)
        end if
    end subroutine callback_rhs

    subroutine callback_jacobian(self, t, y, dfdy)
        class(callback_jac_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        if (self%parametric) then
            call self%jac(t, y, self%p, dfdy, self%n)
        else
            call self%jac(t, y, dfdy, self%n)
        end if
    end subroutine callback_jacobian

    logical function callback_has_jacobian(self)
        class(callback_jac_system), intent(in) :: self
        callback_has_jacobian = associated(self%jac)
    end function callback_has_jacobian

    subroutine callback_eval(self, t, y, g)
        class(callback_events), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: g(:)
        call self%g(t, y, g, self%n, self%ne)
    end subroutine callback_eval

    !> The system of fun and jvals with the pattern (sp_ptr(n + 1), sp_idx(nnz), 1-based,
    !! by columns); CM_BAD_INPUT when the pattern is not one (the structure's own checks
    !! follow in set_jacobian_structure), with the flat routine's `message`.
    subroutine make_sparse_jac_system(fun, jvals, n, nnz, sp_ptr, sp_idx, sys, info, message)
        procedure() :: fun, jvals
        integer(c_int), intent(in) :: n, nnz, sp_ptr(:), sp_idx(:)
        type(callback_sparse_jac_system), intent(out) :: sys
        integer, intent(out) :: info
        character(len=*), intent(out) :: message
        info = CM_BAD_INPUT
        if (n < 1 .or. nnz < 0 .or. size(sp_ptr) < n + 1 .or. size(sp_idx) < nnz) then
            message = "bad input: the sparse Jacobian's pattern arrays are too short"
            return
        end if
        sys%f => fun
        sys%jv => jvals
        sys%n = n
        sys%nnz = nnz
        sys%col_ptr = sp_ptr(1:n + 1)
        sys%row_idx = sp_idx(1:nnz)
        info = CM_SUCCESS
        message = "success"
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

    subroutine cb_mass(self, t, q, mm)
        class(callback_constrained), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        call self%fmass(t, q, mm, int(self%n, c_int))
    end subroutine cb_mass

    subroutine cb_forces(self, t, q, v, f)
        class(callback_constrained), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        call self%fforces(t, q, v, f, int(self%n, c_int))
    end subroutine cb_forces

    subroutine cb_phi(self, t, q, c)
        class(callback_constrained), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        call self%fphi(t, q, c, int(self%n, c_int), int(self%n_hol, c_int))
    end subroutine cb_phi

    subroutine cb_jac(self, t, q, g)
        class(callback_constrained), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        if (self%has_jac) then
            call self%fjac(t, q, g, int(self%n, c_int), int(self%n_hol, c_int))
        else
            call fd_phi_jac(self, t, q, g)
        end if
    end subroutine cb_jac

    subroutine cb_gamma(self, t, q, v, gam)
        class(callback_constrained), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        if (self%has_gamma) then
            call self%fgamma(t, q, v, gam, int(self%n, c_int), int(self%n_hol, c_int))
        else
            call fd_phi_gamma(self, t, q, v, gam)
        end if
    end subroutine cb_gamma

    subroutine cb_nh(self, t, q, a, b)
        class(callback_constrained), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: a(:, :), b(:)
        call self%fnh(t, q, a, b, int(self%n, c_int), int(self%n_nh, c_int))
    end subroutine cb_nh

    subroutine cb_nh_gamma(self, t, q, v, gam)
        class(callback_constrained), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        if (self%has_nh_gamma) then
            call self%fnhgamma(t, q, v, gam, int(self%n, c_int), int(self%n_nh, c_int))
        else
            call fd_nh_gamma(self, t, q, v, gam)
        end if
    end subroutine cb_nh_gamma

    subroutine law_eval(self, t, x, u)
        class(callback_law), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: u(:)
        real(c_double) :: tt, xx(size(x)), uu(size(u))
        tt = t
        xx = x
        call self%f(tt, xx, uu, self%n, int(self%n_inputs, c_int))
        u = uu
    end subroutine law_eval

    subroutine lq_coefficients(self, t, a, b, info)
        class(callback_lq), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(out) :: a(:, :), b(:, :)
        integer, intent(out) :: info
        real(c_double) :: tt, aa(self%k, self%k), bb(self%k, self%m)
        tt = t
        call self%fa(tt, aa, int(self%k, c_int))
        call self%fb(tt, bb, int(self%k, c_int), int(self%m, c_int))
        a = aa
        b(:, 1:self%m) = bb
        info = CM_SUCCESS
        if (.not. (la_finite(aa) .and. la_finite(bb))) info = CM_NONFINITE
    end subroutine lq_coefficients

    function energy_value(self, y, p) result(e)
        class(callback_energy), intent(in) :: self
        real(dp), intent(in) :: y(:), p
        real(dp) :: e
        real(c_double) :: yy(self%n)
        yy = y
        e = 0.0_dp
        call self%f(yy, p, e, self%n)
    end function energy_value

    subroutine hill_rhs(self, t, y, dydt)
        class(callback_hill), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(c_double) :: p
        call self%g(t, p)
        dydt(1) = y(2)
        dydt(2) = -p*y(1)
    end subroutine hill_rhs

    subroutine hill_jacobian(self, t, y, dfdy)
        class(callback_hill), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(c_double) :: p
        call self%g(t, p)
        dfdy = reshape([0.0_dp, -p, 1.0_dp, 0.0_dp], [2, 2])
    end subroutine hill_jacobian

    logical function hill_has_jacobian(self)
        class(callback_hill), intent(in) :: self
        hill_has_jacobian = .true.
    end function hill_has_jacobian

    subroutine natural_potential(self, q, v, g, h)
        class(callback_natural), intent(in) :: self
        real(dp), intent(in) :: q(2)
        real(dp), intent(out) :: v, g(2), h(2, 2)
        call self%pot(q, v, g, h)
    end subroutine natural_potential

    logical function model_has_energy(self)
        class(callback_energy_model), intent(in) :: self
        model_has_energy = self%present
    end function model_has_energy

    subroutine model_energy_gradient(self, t, x, g)
        class(callback_energy_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        real(dp), intent(out) :: g(:)
        real(c_double) :: tt, xx(size(x)), gg(size(x))
        tt = t
        xx = x
        call self%egrad(tt, xx, gg, self%n)
        g = gg
    end subroutine model_energy_gradient

    subroutine progress_report(self, done, total, cancel)
        class(callback_progress), intent(inout) :: self
        integer, intent(in) :: done, total
        logical, intent(out) :: cancel
        integer(c_int) :: d, t, c
        d = done
        t = total
        c = 0
        call self%f(d, t, c)
        cancel = c /= 0
    end subroutine progress_report

    subroutine c_eval(self, t, x, u)
        class(c_law), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: u(:)
        procedure(c_law_fun), pointer :: f
        real(c_double) :: pdum(1)
        call c_f_procpointer(self%fp, f)
        if (size(self%p) > 0) then
            call f(t, x, u, self%p)
        else
            pdum = 0.0_c_double
            call f(t, x, u, pdum)
        end if
    end subroutine c_eval

    subroutine z_eval(self, t, x, u)
        class(zero_law), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: u(:)
        u = 0.0_dp
    end subroutine z_eval

    subroutine vz_eval(self, t, y, g)
        class(velocity_zero), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: g(:)
        g(1) = y(2)
    end subroutine vz_eval

    subroutine ez_eval(self, t, y, g)
        class(energy_zero), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: g(:)
        g(1) = y(1)
    end subroutine ez_eval

end module conmech_flat_adapters
