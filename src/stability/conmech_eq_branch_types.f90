!> The types of the continuation of equilibria (conmech_equilibrium_continuation): its
!! options, the points of a branch, its special points (folds and Hopf points) and the
!! branch itself.
module conmech_eq_branch_types
    use conmech_kinds, only: dp
    use conmech_branch_outcome, only: branch_outcome
    use conmech_code_names, only: code_name
    use conmech_status
    implicit none
    private

    integer, parameter, public :: EQ_FOLD = 1   !! fold (limit point) in the parameter
    integer, parameter, public :: EQ_HOPF = 2   !! a complex pair through the imaginary axis

    !> Why a special point is not located (eq_special%reason).
    integer, parameter, public :: EQ_LOCATED = 0          !! located to the tolerances
    integer, parameter, public :: EQ_CORRECTOR_FAILED = 1 !! the corrector failed inside
    integer, parameter, public :: EQ_NOT_RESOLVED = 2     !! iterations ran out first

    public :: eq_options, eq_point, eq_special, eq_branch, eq_special_name

    !> Options of `continue_equilibria`.
    type :: eq_options
        real(dp) :: ds = 0.01_dp              !! first step length (arclength in [y, p])
        real(dp) :: ds_min = 1.0e-8_dp        !! smallest step before giving up
        real(dp) :: ds_max = 0.1_dp           !! largest step
        integer :: max_points = 200           !! points on the branch (the start included)
        real(dp) :: p_min = -huge(1.0_dp)     !! the branch ends on p = p_min or p_max
        real(dp) :: p_max = huge(1.0_dp)
        integer :: direction = 1              !! first step towards larger (+1) or smaller p
        integer :: max_iter = 10              !! corrector iterations
        real(dp) :: tol = 1.0e-12_dp          !! corrector: |dX| <= tol max(1, |X|)
        real(dp) :: res_tol = 1.0e-10_dp      !! and max |f| <= res_tol at the result
        real(dp) :: fd_step = 6.0e-6_dp       !! relative step of df/dp (central)
        real(dp) :: rcond = 1.0e-13_dp        !! rank threshold of the Newton matrices
        logical :: locate = .true.            !! locate folds and Hopf points
        real(dp) :: locate_tol = 1.0e-12_dp   !! bracket in arclength when locating
        real(dp) :: test_tol = 1.0e-13_dp     !! |test| at which a point counts as found
        real(dp) :: l1_tol = 1.0e-6_dp        !! |l1| <= l1_tol scale: a degenerate Hopf
        real(dp) :: t = 0.0_dp                !! time at which f(t, y) is evaluated
    end type eq_options

    !> A point of the branch.
    type :: eq_point
        real(dp) :: p = 0.0_dp                !! parameter
        real(dp), allocatable :: y(:)         !! the equilibrium
        real(dp), allocatable :: wr(:), wi(:) !! eigenvalues of df/dy there
        real(dp) :: psi(3) = 0.0_dp           !! tests: fold (t_p), Hopf (Re of the complex
                                              !! pair nearest the imaginary axis, 0 if none),
                                              !! sign of prod_{i<j} (lambda_i + lambda_j)
        integer :: n_unstable = 0             !! eigenvalues with Re > 0
        real(dp) :: residual = 0.0_dp         !! max |f(y, p)| at the point
        real(dp) :: ds = 0.0_dp               !! step length that reached it
        integer :: iterations = 0
    end type eq_point

    !> A special point: a fold or a Hopf point.
    type :: eq_special
        integer :: kind = 0                   !! EQ_FOLD, EQ_HOPF
        integer :: index = 0                  !! between points index and index + 1
        type(eq_point) :: point               !! the point (an equilibrium to res_tol)
        logical :: located = .false.          !! the test function met test_tol, or its
                                              !! bracket locate_tol, at a corrected point
        integer :: reason = EQ_LOCATED        !! EQ_CORRECTOR_FAILED, EQ_NOT_RESOLVED
        real(dp) :: test = 0.0_dp             !! the test function at the point
        real(dp) :: bracket = 0.0_dp          !! the last bracket in arclength
        real(dp) :: omega = 0.0_dp            !! Hopf: the pair +-i omega
        real(dp) :: l1 = 0.0_dp               !! Hopf: first Lyapunov coefficient
        real(dp) :: l1_scale = 0.0_dp         !! Hopf: size of its terms
        real(dp) :: l1_error = 0.0_dp         !! Hopf: error estimate of l1
        integer :: criticality = 0            !! Hopf: conmech_hopf's HOPF_* codes
        complex(dp), allocatable :: q(:)      !! Hopf: A q = i omega q, <q, q> = 1
        complex(dp), allocatable :: adj(:)    !! Hopf: A^T p = -i omega p, <p, q> = 1
    end type eq_special

    !> A branch of equilibria: its points and special points, the status and a message.
    type, extends(branch_outcome) :: eq_branch
        type(eq_point), allocatable :: points(:)
        type(eq_special), allocatable :: special(:)
    end type eq_branch

contains

    !> Name of a special-point kind.
    pure function eq_special_name(kind) result(s)
        integer, intent(in) :: kind
        character(len=:), allocatable :: s
        s = code_name(kind, [EQ_FOLD, EQ_HOPF], [character(len=4) :: "fold", "Hopf"], "unknown")
    end function eq_special_name

end module conmech_eq_branch_types
