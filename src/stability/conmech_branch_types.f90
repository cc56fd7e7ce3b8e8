!> The types of a continuation: its options, the points of a branch, the located special
!! points and the branch itself (see conmech_continuation).
module conmech_branch_types
    use conmech_kinds, only: dp
    use conmech_branch_outcome, only: branch_outcome
    use conmech_code_names, only: code_name
    use conmech_status
    use conmech_ode_solver, only: METHOD_DOP853
    implicit none
    private

    integer, parameter, public :: SP_FOLD = 1  !! fold (limit point) in the parameter
    integer, parameter, public :: SP_BP = 2    !! a multiplier through +1 (branch point)
    integer, parameter, public :: SP_PD = 3    !! a multiplier through -1 (period doubling)
    integer, parameter, public :: SP_NS = 4    !! a complex pair through |mu| = 1

    !> Outcomes of the location of a special point (special_point%reason).
    integer, parameter, public :: SPR_LOCATED = 0      !! the bracket shrank below locate_tol
    integer, parameter, public :: SPR_CORRECTOR = 1    !! a trial's corrector failed
    integer, parameter, public :: SPR_LEFT_BRANCH = 2  !! a trial left the branch
    integer, parameter, public :: SPR_LIMIT = 3        !! the iteration limit

    public :: cont_options, cont_point, special_point, branch, special_name

    !> Options of `continue_orbits`.
    type :: cont_options
        real(dp) :: ds = 0.01_dp              !! first step length (arclength in X)
        real(dp) :: ds_min = 1.0e-8_dp        !! smallest step before giving up
        real(dp) :: ds_max = 0.1_dp           !! largest step
        integer :: max_points = 200           !! points on the branch (the start included)
        real(dp) :: p_min = -huge(1.0_dp)     !! the branch ends exactly at p_min or p_max
        real(dp) :: p_max = huge(1.0_dp)
        real(dp) :: period_min = -huge(1.0_dp)  !! ... at period_min or period_max
        real(dp) :: period_max = huge(1.0_dp)
        real(dp) :: energy_min = -huge(1.0_dp)  !! ... at energy_min or energy_max (with an
        real(dp) :: energy_max = huge(1.0_dp)   !! energy function)
        integer :: direction = 0              !! first step towards larger (+1) or smaller
                                              !! (-1) p; 0: +1 unless that walks into an
                                              !! equilibrium (then -1)
        integer :: discretisation = 1         !! ORBIT_SINGLE, _MULTIPLE, _COLLOCATION
        integer :: segments = 8               !! multiple shooting segments
        integer :: degree = 4                 !! collocation: Gauss points per interval
        integer :: intervals = 40             !! collocation: mesh intervals
        integer :: max_iter = 12              !! corrector iterations
        real(dp) :: tol = 1.0e-10_dp          !! corrector: |dX| <= tol max(1, |X|)
        real(dp) :: res_tol = 1.0e-8_dp       !! and max |G| <= res_tol
        integer :: integrator = METHOD_DOP853 !! of the orbits and their STMs (or TAYLOR)
        real(dp) :: rtol = 1.0e-11_dp         !! its tolerances
        real(dp) :: atol = 1.0e-11_dp
        real(dp) :: rcond = 1.0e-12_dp        !! rank threshold of the Newton matrices
        real(dp) :: fd_step = 1.0e-5_dp       !! relative step of the parameter derivative
        logical :: autonomous = .true.        !! phase condition and trivial multiplier 1
        logical :: fixed_period = .false.     !! the period is not an unknown
        logical :: conservative = .false.     !! a second trivial multiplier (energy)
        logical :: in_period = .false.        !! continue in the period T (no parameter):
                                              !! the families of conservative systems
        logical :: locate = .true.            !! locate the special points
        real(dp) :: locate_tol = 1.0e-11_dp   !! bracket in arclength when locating
    end type cont_options

    !> A point of the branch.
    type :: cont_point
        real(dp) :: p = 0.0_dp                !! parameter
        real(dp) :: period = 0.0_dp
        real(dp), allocatable :: y0(:)        !! initial state
        real(dp), allocatable :: mr(:), mi(:) !! multipliers
        real(dp) :: stability_index = 0.0_dp  !! S (conservative 4 x 4) or max |mu| nontrivial
        real(dp) :: psi(4) = 0.0_dp           !! test functions: fold, bp, pd, ns
        real(dp), allocatable :: merr(:)      !! error estimates of the multipliers
        real(dp) :: accuracy = 0.0_dp         !! largest merr/max(1, |mu|)
        real(dp) :: residual = 0.0_dp         !! max |G| one Newton step before it (a bound)
        real(dp) :: ds = 0.0_dp               !! step length that reached it
        integer :: iterations = 0
    end type cont_point

    !> A special point. `located`: the locator converged (the bracket in arclength below
    !! locate_tol, every trial a corrected orbit); otherwise `point` is the bracketing
    !! orbit nearer the sign change (a true orbit, never an interpolated state) and
    !! `message` says why. `test` is the test function at `point`, `closure` the point's
    !! true closure (an independent integration of the state alone), `p_bracket` the
    !! parameter values at the ends of the final bracket (around the sign change; both on
    !! one side of a fold).
    type :: special_point
        integer :: kind = 0                   !! SP_FOLD, SP_BP, SP_PD, SP_NS
        integer :: index = 0                  !! between points index and index + 1
        type(cont_point) :: point
        logical :: located = .false.
        integer :: reason = SPR_LOCATED       !! why the location stopped (SPR_*)
        real(dp) :: test = 0.0_dp
        real(dp) :: closure = huge(1.0_dp)
        real(dp) :: p_bracket(2) = 0.0_dp
        character(len=:), allocatable :: message
    end type special_point

    !> A branch: its points and special points, the status and a message.
    type, extends(branch_outcome) :: branch
        integer :: direction = 1              !! the side the branch was continued to
        type(cont_point), allocatable :: points(:)
        type(special_point), allocatable :: special(:)
    end type branch

contains

    !> Name of a special-point kind.
    pure function special_name(kind) result(s)
        integer, intent(in) :: kind
        character(len=:), allocatable :: s
        s = code_name(kind, [SP_FOLD, SP_BP, SP_PD, SP_NS], &
                      [character(len=15) :: "fold", "branch point", "period doubling", &
                       "Neimark-Sacker"], "unknown")
    end function special_name

end module conmech_branch_types
