!> Integrators for constrained mechanical systems: `constrained_solve`, one front (checks,
!! a consistent initial state, the multipliers and the rank at t0), the one driver loop
!! (conmech_ode_driver) with the method's stepper, and one result builder
!! (conmech_constrained_result) for every method (options%ode%method):
!! - RK4 / DOPRI5 / DOP853 / Verner 9(8) on the index-1 form (accelerations from the KKT
!!   system; conmech_constrained_ode) with
!!   - no stabilisation (PROJ_NONE: the constraints drift, |phi| ~ h^p (A t + B t^2)),
!!   - velocity projection after each accepted step (PROJ_VELOCITY),
!!   - mass-weighted position projection (simplified Newton) then velocity projection
!!     (PROJ_POSITION_VELOCITY, Hairer-Lubich-Wanner; the default),
!!   - Baumgarte stabilisation (PROJ_BAUMGARTE): C a = gamma - 2 alpha (C v + c0) -
!!     beta^2 phi.
!!   The projection is the driver's step hook (`projection_hook`) after each accepted step
!!   (or every k steps); the right-hand side is evaluated once per step, at the projected
!!   state. Outputs are the accepted steps, or the points of `t_eval`, which the steps hit
!!   exactly (`hit_t_eval`: every output point is a projected point). Events (functions of
!!   (t, [q; v])) are located on the dense output of the steps (Brent's method) and the
!!   located states projected like the steps (position+velocity or velocity; not with
!!   "none" or Baumgarte), so event states are on the constraints to `proj_tol` and the
!!   event functions vanish there to the integration tolerance.
!! - RATTLE (METHOD_RATTLE, holonomic constraints, fixed step first_step;
!!   conmech_rattle_stepper): constraints solved to round-off every step (dependent rows in
!!   the minimum-norm least-squares sense: redundant constraints are fine); t_eval points
!!   and events on its side step from the grid point before (on the manifold to round-off).
!! - Radau IIA (METHOD_RADAU5, adaptive) on a DAE form of the equations (no drift, no
!!   projection; any mass matrix M(t, q)): the stabilised index-2 (GGL) form [q, v,
!!   lambda, mu] (options%dae_index = 2, the default; conmech_constrained_dae) or the
!!   index-3 form [q, v, a, lambda] of the Bari test set (dae_index = 3;
!!   conmech_constrained_index3), with the exact Jacobian where the system provides its
!!   derivatives. Both need independent constraints: redundant ones (a rank deficiency
!!   that persists along the motion) are reduced to an independent subset of rows
!!   (conmech_constrained_rows) and the results evaluated on the full set; a singular
!!   configuration at t0 (the rank grows a short way along the motion) is refused before
!!   the first step.
!! Every result holds the accelerations, multipliers and reaction forces at its outputs
!! (conmech_constrained_result).
!! A terminal event ends the run at the event state. The initial state is made consistent
!! first (position then velocity projection; the distances moved are reported).
module conmech_constrained_solver
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_text, only: itoa
    use conmech_ode_system, only: ode_events
    use conmech_ode_options, only: ode_options, METHOD_RATTLE, METHOD_RADAU5
    use conmech_ode_result, only: ode_result
    use conmech_ode_solver, only: ode_solve
    use conmech_radau_stepper, only: radau_stepper
    use conmech_constrained_system
    use conmech_constrained_result
    use conmech_constrained_ode, only: constrained_ode, projection_hook, consistent_initial
    use conmech_constrained_dae, only: ggl_system, dae_events, ggl_setup
    use conmech_constrained_index3, only: index3_system, index3_setup
    use conmech_rattle_stepper, only: rattle_stepper
    use conmech_constrained_rows, only: row_subset, select_rows
    use conmech_rank, only: singular_values
    implicit none
    private

    public :: PROJ_NONE, PROJ_VELOCITY, PROJ_POSITION_VELOCITY, PROJ_BAUMGARTE
    public :: constrained_ode, constrained_options, constrained_result, projection_hook
    public :: constrained_solve, consistent_initial, projection_from_name, take_events
    public :: build_constrained_result

contains

    !> Integrate the constrained system from (q0, v0) over t_span (forward or backward)
    !! with options%ode%method (see the module documentation); the diagnostics
    !! (multipliers, reactions, residuals, energy, reaction power) at every output.
    subroutine constrained_solve(sys, t_span, q0, v0, options, res, t_eval, events)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: q0(:), v0(:)
        type(constrained_options), intent(in) :: options
        type(constrained_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)
        !> event functions of (t, [q; v]) (see the module documentation)
        class(ode_events), intent(in), optional :: events

        real(dp), allocatable :: q(:), v(:), acc(:), lam(:)
        type(row_subset) :: sub
        logical :: use_subset
        integer :: n, m, info, iters, rank0
        character(len=:), allocatable :: msg

        n = sys%n
        m = sys%n_hol + sys%n_nh
        use_subset = .false.
        ! ------------------------------------------------------------ validation
        ! (the integrator options and t_eval are checked by the driver)
        info = CM_BAD_INPUT
        if (n < 1 .or. sys%n_hol < 0 .or. sys%n_nh < 0) then
            msg = "bad input: the system needs n >= 1 coordinates, n_hol, n_nh >= 0"
        else if (size(q0) /= n .or. size(v0) /= n) then
            msg = "bad input: q0 and v0 must have n = "//itoa(n)//" elements"
        else if (.not. (all(abs(q0) <= huge(1.0_dp)) .and. all(abs(v0) <= huge(1.0_dp)))) then
            msg = "bad input: q0 or v0 contains NaN or Inf"
        else if (options%projection < PROJ_NONE .or. options%projection > PROJ_BAUMGARTE) then
            msg = "bad input: unknown projection"
        else if (options%every < 1 .or. options%proj_max_iter < 1 .or. &
                 .not. options%proj_tol > 0.0_dp) then
            msg = "bad input: every, proj_max_iter and proj_tol must be positive"
        else if (options%ode%method == METHOD_RATTLE .and. sys%n_nh /= 0) then
            msg = "bad input: RATTLE handles holonomic constraints only (n_nh = 0)"
        else if (options%ode%method == METHOD_RADAU5 .and. options%dae_index /= 2 .and. &
                 options%dae_index /= 3) then
            msg = "bad input: dae_index must be 2 (the stabilised index-2 form) or 3 (the "// &
                  "index-3 form) for Radau"
        else
            info = CM_SUCCESS
        end if
        if (info /= CM_SUCCESS) then
            call empty_constrained_result(res, n, m, info, msg)
            return
        end if

        ! ------------------------------------------------------------ consistent start
        allocate (q(n), v(n), acc(n), lam(m))
        q = q0
        v = v0
        if (options%project_initial) then
            call consistent_initial(sys, t_span(1), q, v, options%proj_tol, &
                                    options%proj_max_iter, res%dq0, res%dv0, iters, info, msg)
            res%proj_iter = iters
            res%proj_iter_max = iters
            if (info /= CM_SUCCESS) then
                call empty_constrained_result(res, n, m, info, msg)
                return
            end if
        end if
        call constrained_accel(sys, t_span(1), q, v, acc, lam, info, msg, rank=res%rank)
        if (info /= CM_SUCCESS) then
            call empty_constrained_result(res, n, m, info, msg)
            return
        end if
        rank0 = res%rank
        if (m > 0 .and. res%rank == 0) then
            call empty_constrained_result(res, n, m, CM_BAD_INPUT, "bad input: the "// &
                                          "constraint Jacobian is zero at the initial "// &
                                          "state (rank 0): the constraints cannot be enforced")
            return
        end if
        if (m > 0 .and. res%rank < m .and. options%ode%method == METHOD_RADAU5) then
            ! dependent rows: Radau runs on an independent subset when the deficiency is
            ! structural (redundant constraints), refuses a singular configuration
            call select_rows(sys, t_span(1), q, v, acc, res%rank, options%proj_tol, sub, &
                             info, msg)
            if (info /= CM_SUCCESS) then
                call empty_constrained_result(res, n, m, info, msg)
                return
            end if
            use_subset = .true.
        end if

        ! ------------------------------------------------------------ the method
        select case (options%ode%method)
        case (METHOD_RATTLE)
            call solve_rattle()
        case (METHOD_RADAU5)
            if (use_subset) then
                call solve_dae(sub)
            else
                call solve_dae(sys)
            end if
        case default
            call solve_projected()
        end select
        res%success = res%status >= 0

    contains

        !> Runge-Kutta on the index-1 (or Baumgarte) form with the projection hook.
        subroutine solve_projected()
            type(constrained_ode) :: f
            type(projection_hook) :: hk
            type(ode_options) :: opt
            type(ode_result) :: ores
            allocate (f%mech, source=sys)
            call prepare_mass(f%mech, t_span(1), q)     ! a constant M: factorised once
            f%baumgarte = options%projection == PROJ_BAUMGARTE
            f%alpha = options%alpha
            f%beta = options%beta
            allocate (hk%mech, source=sys)
            call prepare_mass(hk%mech, t_span(1), q)
            hk%projection = options%projection
            hk%every = options%every
            hk%proj_tol = options%proj_tol
            hk%proj_max_iter = options%proj_max_iter
            hk%project_events = .true.
            opt = options%ode
            opt%hit_t_eval = .true.
            opt%dense_output = .false.
            opt%save_steps = options%save_steps
            call ode_solve(f, t_span, [q, v], opt, ores, t_eval=t_eval, events=events, hook=hk)
            if (f%baumgarte) then
                call build_constrained_result(res, ores, sys, f%mech, options%alpha, &
                                              options%beta)
            else
                call build_constrained_result(res, ores, sys, f%mech)
            end if
            if (ores%status == CM_NONFINITE) res%message = ores%message// &
                " (a singular mass matrix or KKT system gives NaN accelerations)"
            call add_projections(hk%nproj, hk%proj_iter, hk%proj_iter_max)
        end subroutine solve_projected

        !> RATTLE on its grid (the first-order form is only the driver's system argument).
        subroutine solve_rattle()
            type(constrained_ode) :: f
            type(rattle_stepper) :: rs
            type(ode_options) :: opt
            type(ode_result) :: ores
            allocate (f%mech, source=sys)
            allocate (rs%mech, source=sys)
            rs%proj_tol = options%proj_tol
            rs%proj_max_iter = options%proj_max_iter
            opt = options%ode
            opt%dense_output = .false.
            opt%save_steps = options%save_steps
            call ode_solve(f, t_span, [q, v], opt, ores, t_eval=t_eval, events=events, &
                           stepper=rs)
            call build_constrained_result(res, ores, sys, sys)
            call add_projections(rs%wk%nproj, rs%wk%proj_iter, rs%wk%proj_iter_max)
            if (rs%wk%nfallback > 0) res%message = res%message//" ("// &
                itoa(rs%wk%nfallback)//" position solves near a singular configuration "// &
                "needed Newton with the constraint Jacobian at every iterate)"
        end subroutine solve_rattle

        !> Radau IIA on the index-2 (GGL) or the index-3 form of dsys (sys itself, or
        !! sys restricted to independent rows); the results are evaluated on sys.
        subroutine solve_dae(dsys)
            class(constrained_system), intent(in) :: dsys
            type(ggl_system) :: g2
            type(index3_system) :: g3
            type(dae_events) :: gev
            type(radau_stepper) :: rstp
            type(ode_options) :: opt
            type(ode_result) :: ores
            real(dp), allocatable :: y0(:), lam_d(:)
            integer :: inf_d
            opt = options%ode
            opt%dense_output = .false.
            opt%save_steps = options%save_steps
            if (allocated(opt%rtol_vec)) deallocate (opt%rtol_vec)
            if (allocated(opt%atol_vec)) deallocate (opt%atol_vec)
            allocate (lam_d(dsys%n_hol + dsys%n_nh))
            if (use_subset) then
                call constrained_accel(dsys, t_span(1), q, v, acc, lam_d, inf_d)
            else
                lam_d = lam
            end if
            if (options%dae_index == 3) then
                call index3_setup(dsys, q, v, acc, lam_d, g3, y0, rstp)
            else
                call ggl_setup(dsys, t_span(1), q, v, lam_d, opt%rtol, opt%atol, g2, y0, &
                               rstp, opt%rtol_vec, opt%atol_vec)
            end if
            if (present(events)) then
                allocate (gev%inner, source=events)
                gev%n = n
                if (allocated(events%direction)) gev%direction = events%direction
                if (allocated(events%terminal)) gev%terminal = events%terminal
                if (allocated(events%count)) gev%count = events%count
                gev%zero_at_t0 = events%zero_at_t0
                if (options%dae_index == 3) then
                    call ode_solve(g3, t_span, y0, opt, ores, t_eval=t_eval, events=gev, &
                                   stepper=rstp)
                else
                    call ode_solve(g2, t_span, y0, opt, ores, t_eval=t_eval, events=gev, &
                                   stepper=rstp)
                end if
            else if (options%dae_index == 3) then
                call ode_solve(g3, t_span, y0, opt, ores, t_eval=t_eval, stepper=rstp)
            else
                call ode_solve(g2, t_span, y0, opt, ores, t_eval=t_eval, stepper=rstp)
            end if
            call build_constrained_result(res, ores, sys, sys)
            call explain_newton_failure(rstp%t, rstp%y(1:2*n))
        end subroutine solve_dae

        !> A step-size failure of Radau: say why when it can be seen. (1) The constraints
        !! are becoming dependent where the run stopped (a singular configuration ahead,
        !! e.g. a parallelogram linkage approaching its flat position; seen as the
        !! rank0-th singular value of the constraint Jacobian relative to the largest
        !! fallen below a quarter of its value at the start): Radau IIA needs independent
        !! constraints all along, and its steps shrink until they fail before it. (2) Tolerances near round-off: velocities of size |v|
        !! carry a round-off of about eps |v| (more where they couple); a component that
        !! crosses zero with atol far below it cannot converge.
        subroutine explain_newton_failure(ts, y)
            real(dp), intent(in) :: ts
            real(dp), intent(in) :: y(:)
            character(len=12) :: b1, b2
            real(dp) :: c_s(m, n), c0_s(m), sv(min(m, n)), ratio, ratio0
            integer :: inf_s
            if (res%status /= CM_STEP_TOO_SMALL) return
            if (m > 0 .and. rank0 <= min(m, n)) then
                ! the smallest of the rank0 leading singular values of the constraint
                ! Jacobian relative to the largest, where the run stopped and at the start
                call constraint_matrix(sys, ts, y(1:n), c_s, c0_s)
                call singular_values(c_s, sv, inf_s)
                ratio = sv(rank0)/max(sv(1), tiny(1.0_dp))
                if (inf_s == CM_SUCCESS) then
                    call constraint_matrix(sys, t_span(1), q, c_s, c0_s)
                    call singular_values(c_s, sv, inf_s)
                    ratio0 = sv(rank0)/max(sv(1), tiny(1.0_dp))
                end if
                if (inf_s == CM_SUCCESS .and. ratio <= 0.25_dp*ratio0) then
                    write (b1, '(es9.2)') ratio
                    write (b2, '(es9.2)') ratio0
                    res%message = res%message//"; the constraints are becoming dependent "// &
                                  "there (singular value "//itoa(rank0)//" of the "// &
                                  "constraint Jacobian over the largest:"//trim(b1)// &
                                  ", at the start"//trim(b2)//": a singular "// &
                                  "configuration ahead), which Radau IIA cannot pass; "// &
                                  "RATTLE and the projected methods (the default DOP853) can"
                    return
                end if
            end if
            if (index(res%message, "Newton") == 0) return
            if (options%ode%atol >= 1.0e3_dp*epsilon(1.0_dp)*maxval(abs(y))) return
            write (b1, '(es9.2)') options%ode%atol
            write (b2, '(es9.2)') maxval(abs(y))
            res%message = res%message//"; atol ="//trim(b1)//" is near the round-off of "// &
                          "a state of size"//trim(b2)//": a larger atol lets the Newton "// &
                          "iteration converge"
        end subroutine explain_newton_failure

        !> The method's name for messages.
        function method_label() result(label)
            character(len=:), allocatable :: label
            label = "RATTLE"
            if (options%ode%method == METHOD_RADAU5) label = "Radau IIA"
        end function method_label

        !> The projections of the run, after those of the consistent start.
        subroutine add_projections(nproj, iters_run, iters_max)
            integer, intent(in) :: nproj, iters_run, iters_max
            res%nproj = nproj
            res%proj_iter = res%proj_iter + iters_run
            res%proj_iter_max = max(res%proj_iter_max, iters_max)
        end subroutine add_projections

    end subroutine constrained_solve

end module conmech_constrained_solver
