!> Radau IIA on the constrained layer: the equations of motion as an index-2
!! differential-algebraic system in mass-matrix form (the stabilised formulation of
!! Gear, Gupta and Leimkuhler), y = [q, v, lambda, mu]:
!!
!!     q' = v + G^T mu                     (mass rows I)
!!     M v' = Q(t, q, v) + C^T lambda      (mass rows M, constant)
!!     0 = C v + c0                        (velocity constraints, index 2)
!!     0 = phi(t, q)                       (position constraints, index 2)
!!
!! with C = [G; A], c0 = [phi_t; b] (holonomic and non-holonomic constraints) and the
!! extra multiplier mu (zero on exact solutions) that keeps the positions on phi = 0.
!! Both constraint levels hold at every step end to the Newton tolerance: no drift, no
!! projection. Solved by `radau_solve` with the block-diagonal mass matrix
!! diag(I, M, 0, 0), lambda and mu as index-2 components, a finite-difference Jacobian.
!! The mass matrix must be constant (it is checked at every output); t_eval points come
!! from the collocation polynomial. Events are functions of (t, [q; v]), located by
!! `radau_solve` on its dense output (so event states are on the constraints to the
!! tolerance, not to round-off). Result: `constrained_result`, diagnostics from the
!! KKT system at the outputs as `constrained_solve`.
module conmech_rattle_dae
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system, ode_events
    use conmech_ode_solver, only: ode_options, ode_result, METHOD_RADAU5
    use conmech_radau, only: radau_solve
    use conmech_constrained_system, only: constrained_system, constrained_accel, &
        constraint_matrix, constraint_residuals
    use conmech_constrained_solver, only: constrained_options, constrained_result, &
        consistent_initial, take_events
    implicit none
    private

    public :: radau_constrained_solve

    !> The stabilised index-2 right-hand side of a constrained system.
    type, extends(ode_system) :: ggl_system
        class(constrained_system), allocatable :: mech
    contains
        procedure :: rhs => ggl_rhs
    end type ggl_system

    !> Events of (t, [q; v]) seen from y = [q, v, lambda, mu].
    type, extends(ode_events) :: ggl_events
        class(ode_events), allocatable :: inner
        integer :: n = 0
    contains
        procedure :: eval => ggl_event_eval
    end type ggl_events

contains

    subroutine ggl_event_eval(self, t, y, g)
        class(ggl_events), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: g(:)
        call self%inner%eval(t, y(1:2*self%n), g)
    end subroutine ggl_event_eval

    subroutine ggl_rhs(self, t, y, dydt)
        class(ggl_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: c(self%mech%n_hol + self%mech%n_nh, self%mech%n)
        real(dp) :: c0(self%mech%n_hol + self%mech%n_nh)
        integer :: n, m, mh
        n = self%mech%n
        mh = self%mech%n_hol
        m = mh + self%mech%n_nh
        call self%mech%forces(t, y(1:n), y(n + 1:2*n), dydt(n + 1:2*n))
        dydt(1:n) = y(n + 1:2*n)
        if (m == 0) return
        call constraint_matrix(self%mech, t, y(1:n), c, c0)
        dydt(n + 1:2*n) = dydt(n + 1:2*n) + matmul(y(2*n + 1:2*n + m), c)
        if (mh > 0) dydt(1:n) = dydt(1:n) + matmul(y(2*n + m + 1:2*n + m + mh), c(1:mh, :))
        dydt(2*n + 1:2*n + m) = matmul(c, y(n + 1:2*n)) + c0
        if (mh > 0) call self%mech%phi(t, y(1:n), dydt(2*n + m + 1:2*n + m + mh))
    end subroutine ggl_rhs

    !> Integrate a constrained system with Radau IIA (order 5, adaptive: options%ode%rtol,
    !! atol, first_step, max_step, max_steps) in the stabilised index-2 form (see the
    !! module documentation). The projection options are not used.
    subroutine radau_constrained_solve(sys, t_span, q0, v0, options, res, t_eval, events)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: q0(:), v0(:)
        type(constrained_options), intent(in) :: options
        type(constrained_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)
        !> event functions of (t, [q; v])
        class(ode_events), intent(in), optional :: events

        type(ggl_system) :: f
        type(ode_options) :: opt
        type(ode_result) :: ores
        type(ggl_events) :: gev
        real(dp), allocatable :: q(:), v(:), acc(:), lam(:), y0(:), mass(:, :), m0(:, :)
        real(dp), allocatable :: mt(:, :)
        logical, allocatable :: idx2(:)
        integer :: n, m, mh, nd, info, iters, j, i
        character(len=:), allocatable :: msg
        character(len=32) :: buf

        n = sys%n
        mh = sys%n_hol
        m = mh + sys%n_nh
        nd = 2*n + m + mh
        res%status = CM_BAD_INPUT
        if (n < 1 .or. sys%n_hol < 0 .or. sys%n_nh < 0) then
            res%message = "bad input: the system needs n >= 1 coordinates, n_hol, n_nh >= 0"
        else if (size(q0) /= n .or. size(v0) /= n) then
            write (buf, '(i0)') n
            res%message = "bad input: q0 and v0 must have n = "//trim(buf)//" elements"
        else if (.not. (all(ieee_is_finite(q0)) .and. all(ieee_is_finite(v0)))) then
            res%message = "bad input: q0 or v0 contains NaN or Inf"
        else
            res%status = CM_SUCCESS
            res%message = "success"
        end if
        if (res%status /= CM_SUCCESS) then
            call allocate_outputs(0)
            return
        end if
        allocate (q(n), v(n), acc(n), lam(m), m0(n, n), mt(n, n))
        q = q0
        v = v0
        if (options%project_initial) then
            call consistent_initial(sys, t_span(1), q, v, options%proj_tol, &
                                    options%proj_max_iter, res%dq0, res%dv0, iters, info, msg)
            if (info /= CM_SUCCESS) then
                call fail(info, msg)
                return
            end if
        end if
        call constrained_accel(sys, t_span(1), q, v, acc, lam, info, msg, rank=res%rank)
        if (info /= CM_SUCCESS) then
            call fail(info, msg)
            return
        end if
        call sys%mass(t_span(1), q, m0)
        allocate (y0(nd), mass(nd, nd), idx2(nd))
        y0 = 0.0_dp
        y0(1:n) = q
        y0(n + 1:2*n) = v
        y0(2*n + 1:2*n + m) = lam
        mass = 0.0_dp
        do i = 1, n
            mass(i, i) = 1.0_dp
        end do
        mass(n + 1:2*n, n + 1:2*n) = m0
        idx2 = .false.
        idx2(2*n + 1:nd) = .true.

        allocate (f%mech, source=sys)
        opt = options%ode
        opt%method = METHOD_RADAU5
        opt%dense_output = .false.
        opt%save_steps = options%save_steps
        if (allocated(opt%rtol_vec)) deallocate (opt%rtol_vec)
        if (allocated(opt%atol_vec)) deallocate (opt%atol_vec)
        if (present(events)) then
            allocate (gev%inner, source=events)
            gev%n = n
            if (allocated(events%direction)) gev%direction = events%direction
            if (allocated(events%terminal)) gev%terminal = events%terminal
            call radau_solve(f, t_span, y0, opt, ores, t_eval=t_eval, events=gev, &
                             mass=mass, index2=idx2)
        else
            call radau_solve(f, t_span, y0, opt, ores, t_eval=t_eval, mass=mass, index2=idx2)
        end if
        call take_events(ores, n, res)
        res%status = ores%status
        res%message = ores%message
        res%nfev = ores%stats%nfev
        res%naccept = ores%stats%naccept
        res%nreject = ores%stats%nreject
        if (.not. allocated(ores%t)) then
            call allocate_outputs(0)
            res%success = .false.
            return
        end if
        call allocate_outputs(ores%nt)
        do j = 1, ores%nt
            call store(j)
        end do
        res%success = res%status >= 0

    contains

        subroutine fail(code, text)
            integer, intent(in) :: code
            character(len=*), intent(in) :: text
            res%status = code
            res%message = text
            res%success = .false.
            call allocate_outputs(0)
        end subroutine fail

        subroutine allocate_outputs(nt)
            integer, intent(in) :: nt
            res%nt = nt
            allocate (res%t(nt), res%q(n, nt), res%v(n, nt), res%lam(m, nt), &
                      res%reaction(n, nt), res%res_pos(nt), res%res_vel(nt), &
                      res%energy(nt), res%power(nt))
        end subroutine allocate_outputs

        subroutine store(jj)
            integer, intent(in) :: jj
            integer :: inf2
            real(dp) :: c(m, n), c0(m), tt
            character(len=:), allocatable :: m2
            tt = ores%t(jj)
            q = ores%y(1:n, jj)
            v = ores%y(n + 1:2*n, jj)
            res%t(jj) = tt
            res%q(:, jj) = q
            res%v(:, jj) = v
            call sys%mass(tt, q, mt)
            if (any(abs(mt - m0) > 1.0e-12_dp*maxval(abs(m0))) .and. res%status >= 0) then
                res%status = CM_BAD_INPUT
                res%message = "bad input: Radau on a constrained system needs a constant " &
                              //"mass matrix (use RATTLE or a projected method)"
            end if
            call constrained_accel(sys, tt, q, v, acc, lam, inf2, m2)
            if (inf2 /= CM_SUCCESS .and. res%status >= 0) then
                res%status = inf2
                res%message = m2
            end if
            res%lam(:, jj) = lam
            res%reaction(:, jj) = 0.0_dp
            if (m > 0) then
                call constraint_matrix(sys, tt, q, c, c0)
                res%reaction(:, jj) = matmul(lam, c)
            end if
            call constraint_residuals(sys, tt, q, v, res%res_pos(jj), res%res_vel(jj))
            res%energy(jj) = 0.0_dp
            if (sys%has_energy()) res%energy(jj) = sys%energy(tt, q, v)
            res%power(jj) = dot_product(res%reaction(:, jj), v)
        end subroutine store

    end subroutine radau_constrained_solve

end module conmech_rattle_dae
