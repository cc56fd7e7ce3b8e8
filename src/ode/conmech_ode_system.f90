!> The system interface of conmech's integrators.
!!
!! A first-order system y' = f(t, y) is an extension of the abstract type `ode_system`:
!! users add their parameters as components and implement `rhs`. The Jacobian df/dy is
!! optional: the default `jacobian` is a central finite difference (step
!! h_j = eps^(1/3) * max(|y_j|, 1)), and `has_jacobian` tells whether an analytic one exists.
!!
!! `rhs_jacobian` gives both at once (used by the variational equations); its default calls
!! `rhs` and `jacobian`, a system may override it to share their common work.
!!
!! `jacobian_product` gives jx = J(t, y) x for an n x k block x (explicit shapes, so the
!! arrays are contiguous and passed without descriptors), `rhs_jacobian_product` gives f
!! and J x at once. Their defaults form the dense J (`jacobian`) and multiply; a system
!! that knows J's structure (constant entries, zero blocks) overrides both and
!! `has_jacobian_product` (default .false.): `integrate_stm` then evaluates
!! z' = [f; J Phi] through one `rhs_jacobian_product` call, never forming J.
!!
!! For simple use, `ode_function` wraps a plain procedure `f(t, y, dydt)` (and optionally
!! `jac(t, y, dfdy)`) without a derived type of one's own.
!!
!! Events are an extension of `ode_events`: `eval` fills g(1:n_events) at (t, y); the
!! components `direction` (+1 rising only, -1 falling only, 0 both) and `terminal` say which
!! zero crossings count and which stop the integration. The optional `resolution` sets, per
!! event, the largest spacing in t at which the event is sampled on each step's continuous
!! extension (0 or unallocated: only at the step's ends, SciPy's rule, which misses two
!! crossings inside one step).
module conmech_ode_system
    use conmech_kinds, only: dp
    implicit none
    private

    public :: ode_system, ode_function, ode_events, ode_step_hook, rhs_proc, jac_proc
    public :: ode_fd_jacobian, ode_jacobian_product

    type, abstract :: ode_system
    contains
        procedure(ode_rhs), deferred :: rhs
        procedure :: jacobian => ode_fd_jacobian
        procedure :: has_jacobian => ode_no_jacobian
        procedure :: rhs_jacobian => ode_rhs_jacobian
        procedure :: has_jacobian_product => ode_no_jacobian_product
        procedure :: jacobian_product => ode_jacobian_product
        procedure :: rhs_jacobian_product => ode_rhs_jacobian_product
    end type ode_system

    abstract interface
        !> dydt = f(t, y).
        subroutine ode_rhs(self, t, y, dydt)
            import :: ode_system, dp
            class(ode_system), intent(in) :: self
            real(dp), intent(in) :: t
            real(dp), intent(in) :: y(:)
            real(dp), intent(out) :: dydt(:)
        end subroutine ode_rhs
        !> Plain right-hand side procedure.
        subroutine rhs_proc(t, y, dydt)
            import :: dp
            real(dp), intent(in) :: t
            real(dp), intent(in) :: y(:)
            real(dp), intent(out) :: dydt(:)
        end subroutine rhs_proc
        !> Plain Jacobian procedure: dfdy(i, j) = d f_i / d y_j.
        subroutine jac_proc(t, y, dfdy)
            import :: dp
            real(dp), intent(in) :: t
            real(dp), intent(in) :: y(:)
            real(dp), intent(out) :: dfdy(:, :)
        end subroutine jac_proc
    end interface

    !> A system given by plain procedures.
    type, extends(ode_system) :: ode_function
        procedure(rhs_proc), pointer, nopass :: f => null()
        procedure(jac_proc), pointer, nopass :: jac => null()
    contains
        procedure :: rhs => function_rhs
        procedure :: jacobian => function_jacobian
        procedure :: has_jacobian => function_has_jacobian
    end type ode_function

    type, abstract :: ode_events
        integer, allocatable :: direction(:)   !! +1 rising, -1 falling, 0 both
        logical, allocatable :: terminal(:)    !! stop the integration at this event
        !> largest spacing in t of the samples of the event on each step's continuous
        !! extension, so that crossings farther apart than it are told apart (0 or
        !! unallocated: the step's ends only, SciPy's rule)
        real(dp), allocatable :: resolution(:)
    contains
        procedure(event_eval), deferred :: eval
        procedure :: n_events => events_count
    end type ode_events

    abstract interface
        !> g(1:n_events) = event functions at (t, y).
        subroutine event_eval(self, t, y, g)
            import :: ode_events, dp
            class(ode_events), intent(in) :: self
            real(dp), intent(in) :: t
            real(dp), intent(in) :: y(:)
            real(dp), intent(out) :: g(:)
        end subroutine event_eval
    end interface

    !> A procedure called after every accepted step (Hairer's `solout`, generalised): it may
    !! change the state (projection onto a manifold, a reset), count, or stop the run.
    !! If it sets `changed`, the integrator re-evaluates f at the new state (one more
    !! evaluation) before the next step. `info` < 0 stops the integration with that
    !! status and the hook's `message`; `info` > 0 stops it as a success (like a terminal
    !! event, status CM_EVENT_STOP).
    !! `at_event` is called with every located event state before it is stored (default:
    !! nothing): a projection hook puts it on the manifold like the step ends; `info` < 0
    !! stops the integration with the hook's `message`.
    type, abstract :: ode_step_hook
        character(len=:), allocatable :: message   !! set by the hook when it fails
    contains
        procedure(hook_after_step), deferred :: after_step
        procedure :: at_event => hook_no_event_action
    end type ode_step_hook

    abstract interface
        subroutine hook_after_step(self, t, y, changed, info)
            import :: ode_step_hook, dp
            class(ode_step_hook), intent(inout) :: self
            real(dp), intent(in) :: t
            real(dp), intent(inout) :: y(:)
            logical, intent(out) :: changed
            integer, intent(out) :: info
        end subroutine hook_after_step
    end interface

contains

    !> Default: event states are stored as located.
    subroutine hook_no_event_action(self, t, y, info)
        class(ode_step_hook), intent(inout) :: self
        real(dp), intent(in) :: t
        real(dp), intent(inout) :: y(:)
        integer, intent(out) :: info
        info = 0
    end subroutine hook_no_event_action

    !> Central finite-difference Jacobian, step h_j = eps^(1/3) max(|y_j|, 1).
    subroutine ode_fd_jacobian(self, t, y, dfdy)
        class(ode_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(dp) :: yp(size(y)), fp(size(y)), fm(size(y)), h
        integer :: j
        yp = y
        do j = 1, size(y)
            h = epsilon(1.0_dp)**(1.0_dp/3.0_dp)*max(abs(y(j)), 1.0_dp)
            yp(j) = y(j) + h
            call self%rhs(t, yp, fp)
            yp(j) = y(j) - h
            call self%rhs(t, yp, fm)
            yp(j) = y(j)
            dfdy(:, j) = (fp - fm)/(2.0_dp*h)
        end do
    end subroutine ode_fd_jacobian

    !> f and df/dy at one point (default: `rhs`, then `jacobian`).
    subroutine ode_rhs_jacobian(self, t, y, dydt, dfdy)
        class(ode_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp), intent(out) :: dfdy(:, :)
        call self%rhs(t, y, dydt)
        call self%jacobian(t, y, dfdy)
    end subroutine ode_rhs_jacobian

    !> jx = J(t, y) x for an n x k block x (default: the dense J from `jacobian`, times x).
    subroutine ode_jacobian_product(self, t, n, k, y, x, jx)
        class(ode_system), intent(in) :: self
        real(dp), intent(in) :: t
        integer, intent(in) :: n, k
        real(dp), intent(in) :: y(n), x(n, k)
        real(dp), intent(out) :: jx(n, k)
        real(dp), allocatable :: jac(:, :)
        integer :: j, l
        allocate (jac(n, n))
        call self%jacobian(t, y, jac)
        do j = 1, k
            jx(:, j) = 0.0_dp
            do l = 1, n
                jx(:, j) = jx(:, j) + jac(:, l)*x(l, j)
            end do
        end do
    end subroutine ode_jacobian_product

    !> f(t, y) and jx = J(t, y) x at one point (default: `rhs`, then `jacobian_product`).
    subroutine ode_rhs_jacobian_product(self, t, n, k, y, dydt, x, jx)
        class(ode_system), intent(in) :: self
        real(dp), intent(in) :: t
        integer, intent(in) :: n, k
        real(dp), intent(in) :: y(n), x(n, k)
        real(dp), intent(out) :: dydt(n), jx(n, k)
        call self%rhs(t, y, dydt)
        call self%jacobian_product(t, n, k, y, x, jx)
    end subroutine ode_rhs_jacobian_product

    !> Default: no structure-aware product (`integrate_stm` forms J and multiplies).
    logical function ode_no_jacobian_product(self)
        class(ode_system), intent(in) :: self
        ode_no_jacobian_product = .false.
    end function ode_no_jacobian_product

    logical function ode_no_jacobian(self)
        class(ode_system), intent(in) :: self
        ode_no_jacobian = .false.
    end function ode_no_jacobian

    subroutine function_rhs(self, t, y, dydt)
        class(ode_function), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        call self%f(t, y, dydt)
    end subroutine function_rhs

    subroutine function_jacobian(self, t, y, dfdy)
        class(ode_function), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        if (associated(self%jac)) then
            call self%jac(t, y, dfdy)
        else
            call ode_fd_jacobian(self, t, y, dfdy)
        end if
    end subroutine function_jacobian

    logical function function_has_jacobian(self)
        class(ode_function), intent(in) :: self
        function_has_jacobian = associated(self%jac)
    end function function_has_jacobian

    integer function events_count(self)
        class(ode_events), intent(in) :: self
        events_count = 0
        if (allocated(self%direction)) events_count = size(self%direction)
    end function events_count

end module conmech_ode_system
