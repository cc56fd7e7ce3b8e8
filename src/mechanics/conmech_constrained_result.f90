!> Options and result of `constrained_solve`, and the ONE result builder of every
!! constrained method: the outputs of the driver (states y = [q; v; ...] at the output
!! times, the events) become the constrained result with its diagnostics at every output,
!! from the acceleration-level KKT system: accelerations, multipliers, reaction forces
!! C^T lambda, the position and velocity residuals, the energy (if the system defines one)
!! and the power of the reactions.
module conmech_constrained_result
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_options, only: ode_options
    use conmech_ode_result, only: ode_result
    use conmech_constrained_system, only: constrained_system, constrained_accel, &
        constraint_reaction, constraint_residuals
    implicit none
    private

    integer, parameter, public :: PROJ_NONE = 0               !! plain index-1 form
    integer, parameter, public :: PROJ_VELOCITY = 1           !! velocity projection only
    integer, parameter, public :: PROJ_POSITION_VELOCITY = 2  !! position, then velocity
    integer, parameter, public :: PROJ_BAUMGARTE = 3          !! Baumgarte stabilisation

    public :: constrained_options, constrained_result, projection_from_name
    public :: build_constrained_result, take_events, empty_constrained_result

    !> Options of `constrained_solve`.
    type :: constrained_options
        type(ode_options) :: ode                   !! method, rtol, atol, first_step, ...
        integer :: projection = PROJ_POSITION_VELOCITY
        integer :: every = 1                       !! project every k accepted steps
        real(dp) :: alpha = 5.0_dp                 !! Baumgarte damping
        real(dp) :: beta = 5.0_dp                  !! Baumgarte stiffness
        real(dp) :: proj_tol = 1.0e-14_dp          !! target max|phi| of the projection
        integer :: proj_max_iter = 10              !! simplified Newton iterations
        logical :: project_initial = .true.        !! make (q0, v0) consistent first
        logical :: save_steps = .true.             !! without t_eval: keep every step
        !> Radau IIA's formulation: 2 the stabilised index-2 (GGL) form
        !! (conmech_constrained_dae), 3 the index-3 form with the accelerations and
        !! multipliers as algebraic variables (conmech_constrained_index3)
        integer :: dae_index = 2
    end type constrained_options

    !> Result of `constrained_solve`: columns are output times.
    type :: constrained_result
        integer :: status = CM_BAD_INPUT
        character(len=:), allocatable :: message
        logical :: success = .false.
        integer :: nt = 0
        real(dp), allocatable :: t(:)              !! (nt)
        real(dp), allocatable :: q(:, :), v(:, :)  !! (n, nt)
        !> (n, nt) accelerations q'' (from the KKT system at (t, q, v); with Baumgarte
        !! stabilisation those of the stabilised equations)
        real(dp), allocatable :: acc(:, :)
        real(dp), allocatable :: lam(:, :)         !! (n_hol + n_nh, nt) multipliers
        real(dp), allocatable :: reaction(:, :)    !! (n, nt) reaction forces C^T lambda
        real(dp), allocatable :: res_pos(:)        !! (nt) max |phi|
        real(dp), allocatable :: res_vel(:)        !! (nt) max |C v + c0|
        real(dp), allocatable :: energy(:)         !! (nt) if the system defines it, else 0
        real(dp), allocatable :: power(:)          !! (nt) reaction . v
        integer :: rank = 0                        !! rank of the constraints (at t0)
        integer :: nfev = 0, naccept = 0, nreject = 0
        integer :: nproj = 0                       !! projections performed
        integer :: proj_iter = 0                   !! total position-projection iterations
        integer :: proj_iter_max = 0               !! largest iteration count of one
        real(dp) :: dq0 = 0.0_dp                   !! |q0 moved| by the initial projection
        real(dp) :: dv0 = 0.0_dp                   !! |v0 moved| by the initial projection
        ! events (event functions of [q; v])
        integer :: nev = 0                         !! number of events found
        real(dp), allocatable :: ev_t(:)           !! (nev) event times
        real(dp), allocatable :: ev_q(:, :), ev_v(:, :)  !! (n, nev) states at the events
        integer, allocatable :: ev_id(:)           !! (nev) which event function
    end type constrained_result

contains

    !> Projection code from a name: "none", "velocity", "position+velocity", "baumgarte";
    !! -1 if unknown.
    pure function projection_from_name(name) result(p)
        character(len=*), intent(in) :: name
        integer :: p
        select case (trim(adjustl(name)))
        case ("none", "index1")
            p = PROJ_NONE
        case ("velocity")
            p = PROJ_VELOCITY
        case ("position+velocity", "position", "projection")
            p = PROJ_POSITION_VELOCITY
        case ("baumgarte")
            p = PROJ_BAUMGARTE
        case default
            p = -1
        end select
    end function projection_from_name

    !> A result with no output (for a run that stops before the driver): status, message,
    !! empty arrays for n coordinates and m multipliers.
    subroutine empty_constrained_result(res, n, m, code, text)
        type(constrained_result), intent(inout) :: res
        integer, intent(in) :: n, m, code
        character(len=*), intent(in) :: text
        res%status = code
        res%message = text
        res%success = .false.
        call allocate_outputs(res, max(n, 0), max(m, 0), 0)
        if (.not. allocated(res%ev_t)) allocate (res%ev_t(0), res%ev_q(max(n, 0), 0), &
                                                 res%ev_v(max(n, 0), 0), res%ev_id(0))
    end subroutine empty_constrained_result

    subroutine allocate_outputs(res, n, m, nt)
        type(constrained_result), intent(inout) :: res
        integer, intent(in) :: n, m, nt
        res%nt = nt
        allocate (res%t(nt), res%q(n, nt), res%v(n, nt), res%acc(n, nt), res%lam(m, nt), &
                  res%reaction(n, nt), res%res_pos(nt), res%res_vel(nt), &
                  res%energy(nt), res%power(nt))
    end subroutine allocate_outputs

    !> Copy the events of a driver result (states y = [q, v, ...]) into `res`.
    subroutine take_events(ores, n, res)
        type(ode_result), intent(in) :: ores
        integer, intent(in) :: n
        type(constrained_result), intent(inout) :: res
        integer :: k
        k = ores%nev
        res%nev = k
        res%ev_t = ores%ev_t(1:k)
        res%ev_q = ores%ev_y(1:n, 1:k)
        res%ev_v = ores%ev_y(n + 1:2*n, 1:k)
        res%ev_id = ores%ev_id(1:k)
    end subroutine take_events

    !> The constrained result of a driver run `ores` of sys (states [q; v; ...]): status,
    !! message, counters, events, and at every output the state and its diagnostics, the
    !! multipliers from `mech`'s KKT system (sys itself, or its copy with the mass
    !! factorised once; Baumgarte's acceleration constraint when alpha and beta are given).
    !! A failed diagnostic sets the status of a run that had succeeded.
    subroutine build_constrained_result(res, ores, sys, mech, alpha, beta)
        type(constrained_result), intent(inout) :: res
        type(ode_result), intent(in) :: ores
        class(constrained_system), intent(in) :: sys, mech
        real(dp), intent(in), optional :: alpha, beta
        real(dp) :: q(sys%n), v(sys%n), acc(sys%n), lam(sys%n_hol + sys%n_nh), t
        integer :: n, m, j, inf2
        character(len=:), allocatable :: m2
        n = sys%n
        m = sys%n_hol + sys%n_nh
        res%status = ores%status
        res%message = ores%message
        res%nfev = ores%stats%nfev
        res%naccept = ores%stats%naccept
        res%nreject = ores%stats%nreject
        call take_events(ores, n, res)
        call allocate_outputs(res, n, m, ores%nt)
        do j = 1, ores%nt
            t = ores%t(j)
            q = ores%y(1:n, j)
            v = ores%y(n + 1:2*n, j)
            res%t(j) = t
            res%q(:, j) = q
            res%v(:, j) = v
            if (present(alpha) .and. present(beta)) then
                call constrained_accel(mech, t, q, v, acc, lam, inf2, m2, alpha=alpha, &
                                       beta=beta)
            else
                call constrained_accel(mech, t, q, v, acc, lam, inf2, m2)
            end if
            if (inf2 /= CM_SUCCESS .and. res%status >= 0) then
                res%status = inf2
                res%message = m2
            end if
            res%acc(:, j) = acc
            res%lam(:, j) = lam
            call constraint_reaction(mech, t, q, lam, res%reaction(:, j))
            call constraint_residuals(sys, t, q, v, res%res_pos(j), res%res_vel(j))
            res%energy(j) = 0.0_dp
            if (sys%has_energy()) res%energy(j) = sys%energy(t, q, v)
            res%power(j) = dot_product(res%reaction(:, j), v)
        end do
        res%success = res%status >= 0
    end subroutine build_constrained_result

end module conmech_constrained_result
