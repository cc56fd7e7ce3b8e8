!> The types shared by the periodic-orbit solvers: shooting options (with the choice of
!! discretisation: single shooting, multiple shooting, orthogonal collocation), the orbit
!! result, and the procedure interfaces of an energy function and of a parameter setter.
!! conmech_shooting re-exports all of them.
module conmech_orbit_types
    use conmech_kinds, only: dp
    use conmech_outcome, only: outcome
    use conmech_code_names, only: code_name
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: METHOD_DOP853
    use conmech_floquet, only: floquet_result
    use conmech_periodic_multipliers, only: multiplier_set
    implicit none
    private

    integer, parameter, public :: PO_FREE_PERIOD = 1
    integer, parameter, public :: PO_FIXED_PERIOD = 2
    integer, parameter, public :: PO_FIXED_ENERGY = 3

    !> Discretisations of the periodic boundary-value problem.
    integer, parameter, public :: ORBIT_SINGLE = 1       !! single shooting
    integer, parameter, public :: ORBIT_MULTIPLE = 2     !! multiple shooting
    integer, parameter, public :: ORBIT_COLLOCATION = 3  !! orthogonal collocation

    public :: shooting_options, periodic_orbit, energy_fun, set_parameter_proc
    public :: no_parameter, orbit_method_name

    !> Options of the periodic-orbit solvers.
    type :: shooting_options
        integer :: method = METHOD_DOP853     !! integrator of the variational equations
        real(dp) :: rtol = 1.0e-12_dp         !! its relative tolerance
        real(dp) :: atol = 1.0e-12_dp         !! its absolute tolerance
        integer :: max_steps = 100000         !! its step limit per integration
        integer :: max_iter = 30              !! Newton iterations
        real(dp) :: tol = 1.0e-10_dp          !! converged when |residual| and |step| <= tol
        real(dp) :: rcond = 1.0e-10_dp        !! rank threshold of the Newton matrix
        logical :: monodromy = .true.         !! integrate the monodromy on success
        integer :: discretisation = ORBIT_SINGLE  !! ORBIT_SINGLE, _MULTIPLE, _COLLOCATION
        integer :: segments = 8               !! multiple shooting: segments of the orbit
        integer :: degree = 4                 !! collocation: Gauss points per interval
        integer :: intervals = 40             !! collocation: mesh intervals
        integer :: adapt = 2                  !! collocation: mesh adaptations
        integer :: mono_segments = 1          !! single shooting: pieces of the monodromy
    end type shooting_options

    !> A periodic orbit.
    type, extends(outcome) :: periodic_orbit
        real(dp), allocatable :: y0(:)          !! initial state
        real(dp) :: period = 0.0_dp
        real(dp), allocatable :: monodromy(:, :)  !! the formed product of the segment STMs
        type(floquet_result) :: floquet         !! multipliers (from `multipliers`)
        type(multiplier_set) :: multipliers     !! periodic-QR multipliers and their errors
        real(dp) :: residual = 0.0_dp           !! max |residual| at the solution
        integer :: iterations = 0
        integer :: discretisation = ORBIT_SINGLE
        real(dp), allocatable :: nodes(:, :)    !! states at the segment/mesh nodes
        real(dp), allocatable :: node_times(:)  !! their times
        integer :: degree = 0                   !! collocation degree (0 otherwise)
    end type periodic_orbit

    abstract interface
        !> Energy (or any first integral) E(y).
        function energy_fun(y) result(e)
            import :: dp
            real(dp), intent(in) :: y(:)
            real(dp) :: e
        end function energy_fun
        !> Set the continuation parameter of a system.
        subroutine set_parameter_proc(sys, p)
            import :: ode_system, dp
            class(ode_system), intent(inout) :: sys
            real(dp), intent(in) :: p
        end subroutine set_parameter_proc
    end interface

contains

    !> A `set_parameter_proc` that changes nothing (orbits at a fixed parameter).
    subroutine no_parameter(sys, p)
        class(ode_system), intent(inout) :: sys
        real(dp), intent(in) :: p
    end subroutine no_parameter

    !> "single", "multiple" or "collocation".
    pure function orbit_method_name(method) result(s)
        integer, intent(in) :: method
        character(len=:), allocatable :: s
        s = code_name(method, [ORBIT_SINGLE, ORBIT_MULTIPLE, ORBIT_COLLOCATION], &
                      [character(len=11) :: "single", "multiple", "collocation"], "unknown")
    end function orbit_method_name

end module conmech_orbit_types
