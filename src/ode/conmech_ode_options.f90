!> Options, counters and method codes of conmech's integrators (shared by the steppers, the
!! driver and the flat layer). The method table (conmech_ode_methods) maps each code to its
!! names and its stepper type.
module conmech_ode_options
    use conmech_kinds, only: dp
    implicit none
    private

    integer, parameter, public :: METHOD_RK4 = 1     !! classical RK4, fixed step
    integer, parameter, public :: METHOD_DOPRI5 = 2  !! Dormand-Prince 5(4), dense order 4
    integer, parameter, public :: METHOD_DOP853 = 3  !! Dormand-Prince 8(5,3), dense order 7
    integer, parameter, public :: METHOD_VERNER98 = 4 !! Verner 9(8), dense order 8
    integer, parameter, public :: METHOD_RADAU5 = 5  !! Radau IIA order 5, stiff, adaptive
    integer, parameter, public :: METHOD_GAUSS4 = 6  !! Gauss-Legendre s = 2, fixed step
    integer, parameter, public :: METHOD_GAUSS6 = 7  !! Gauss-Legendre s = 3, fixed step
    integer, parameter, public :: METHOD_RATTLE = 8  !! constrained systems only (constrained_solve)
    integer, parameter, public :: METHOD_TAYLOR = 9  !! Taylor's method (conmech_taylor_stepper)

    public :: ode_options, ode_stats, tolerance_options

    !> Options of the integrators. Zero means "use the method's default" for
    !! first_step, safety, fac_min, fac_max; beta < 0 means the default.
    type :: ode_options
        integer :: method = METHOD_DOP853
        real(dp) :: rtol = 1.0e-3_dp               !! relative tolerance (scalar)
        real(dp) :: atol = 1.0e-6_dp               !! absolute tolerance (scalar)
        real(dp), allocatable :: rtol_vec(:)       !! per-component rtol (overrides rtol)
        real(dp), allocatable :: atol_vec(:)       !! per-component atol (overrides atol)
        real(dp) :: first_step = 0.0_dp            !! initial step (RK4: the step); 0 = auto
        real(dp) :: max_step = huge(1.0_dp)        !! largest |h|
        integer :: max_steps = 100000              !! attempted steps before giving up
        real(dp) :: safety = 0.0_dp                !! Hairer's safe (default 0.9)
        real(dp) :: fac_min = 0.0_dp               !! smallest step ratio hnew/h
        real(dp) :: fac_max = 0.0_dp               !! largest step ratio hnew/h
        real(dp) :: beta = -1.0_dp                 !! Lund stabilisation exponent
        !> explicit Runge-Kutta methods: a step ending within stretch*h before its target
        !! (tf, an output point) is stretched onto it; < 0 means Hairer's 0.01, 0 is SciPy's
        !! rule (a step is only cut where it would pass the target)
        real(dp) :: stretch = -1.0_dp
        logical :: dense_output = .false.          !! keep a dense_solution in the result
        logical :: save_steps = .true.             !! without t_eval: store every step
        logical :: hit_t_eval = .false.            !! shorten steps to land on t_eval points
                                                   !! (outputs are step ends, not interpolated)
        !> ode_solve's output arrays cut to their counts at the end (false: they may keep
        !! room beyond res%nt and res%nev, for a caller that copies the points out anyway
        !! and would otherwise pay for a copy of them)
        logical :: trim_outputs = .true.
    end type ode_options

    !> Counters of one integration.
    type :: ode_stats
        integer :: nfev = 0       !! right-hand side evaluations
        integer :: naccept = 0    !! accepted steps
        integer :: nreject = 0    !! rejected steps
        real(dp) :: h_next = 0.0_dp   !! step size proposed for a continuation
        integer :: njev = 0       !! Jacobian evaluations (implicit methods)
        integer :: nlu = 0        !! LU decompositions (implicit methods)
    end type ode_stats

contains

    !> Options at rtol = atol = `rtol` when present, else `default` (all else at the
    !! defaults of ode_options).
    pure function tolerance_options(default, rtol) result(opt)
        real(dp), intent(in) :: default
        real(dp), intent(in), optional :: rtol
        type(ode_options) :: opt
        opt%rtol = default
        if (present(rtol)) opt%rtol = rtol
        opt%atol = opt%rtol
    end function tolerance_options

end module conmech_ode_options
