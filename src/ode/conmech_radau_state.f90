!> The state of a Radau IIA integration (`radau_state`: the current point, the Jacobian and
!! the two LU factorisations, the stage increments, the collocation polynomial, the
!! step-size controller's memory and flags) and its packing into plain arrays for the
!! step-by-step use (conmech_radau_stepper, the flat f2py layer).
module conmech_radau_state
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_options, only: ode_stats
    use conmech_radau_collocation, only: radau_collocation_basis
    implicit none
    private

    public :: radau_state, radau_state_allocate, radau_state_pack, radau_state_unpack
    public :: RADAU_NR, RADAU_NI, RADAU_NW

    !> Sizes of the packed state of a step-by-step integration (radau_solve with r_state,
    !! i_state, w_state and action; conmech_radau_stepper): r(RADAU_NR) reals,
    !! iv(RADAU_NI + 2 n) integers (the last 2 n: LU pivots), w(n, RADAU_NW + 4 n) columns
    !! (y, f(t, y), scale, rtol, atol, the collocation polynomial of the last step
    !! fc(:, 0:3) in x = (s - t_old)/h_old, then J, the real LU, the complex LU's real and
    !! imaginary parts).
    integer, parameter :: RADAU_NR = 20, RADAU_NI = 20, RADAU_NW = 9
    !> Positions in the packed state read by the callers (r: t, t_old, h_old; w: y, fc).
    integer, parameter, public :: RADAU_RT = 3, RADAU_RTOLD = 18, RADAU_RHOLD = 13
    integer, parameter, public :: RADAU_WY = 1, RADAU_WFC = 6
    !> Positions of the counters in iv: nfev, njev, nlu, naccept, nreject.
    integer, parameter, public :: RADAU_IFEV = 5

    !> Everything a Radau IIA integration carries from step to step, and its work arrays.
    type :: radau_state
        integer :: n = 0                      !! dimension
        real(dp) :: t0 = 0, tf = 0            !! the interval
        real(dp) :: t = 0, h = 0              !! current time and step
        real(dp) :: hmax = 0, posneg = 1      !! largest |h|, direction of integration
        real(dp) :: uround = 0, fnewt = 0     !! unit roundoff, Newton tolerance
        real(dp) :: faccon = 1, theta = 0     !! Newton contraction memory and rate
        real(dp) :: hacc = 0, erracc = 1      !! last accepted step and error (Gustafsson)
        real(dp) :: hold = 0, t_prev = 0      !! step and start of the last accepted step
        real(dp) :: safe = 0.9_dp             !! safety factor
        real(dp) :: facl = 5, facr = 0.125_dp !! bounds of h/h_new
        real(dp) :: cfac = 0                  !! safe (1 + 2 NIT)
        real(dp) :: err = 0                   !! scaled error estimate of the last step
        real(dp) :: hnew = 0                  !! proposed next step
        real(dp) :: pmat(3, 3) = 0, cvec(3) = 0   !! collocation basis (nodes, power basis)
        integer :: newt = 0                   !! Newton iterations of the last step
        integer :: nsteps = 0, nsing = 0, nfail = 0   !! steps, singular LUs, Newton failures
        logical :: first = .true.             !! no step accepted yet
        logical :: reject = .false.           !! the last attempt was rejected
        logical :: last = .false.             !! the step ends at tf
        logical :: caljac = .false.           !! the Jacobian is current
        logical :: need_jac = .true.          !! evaluate the Jacobian before the step
        logical :: need_lu = .true.           !! factorise before the step
        logical :: have_cont = .false.        !! fc holds a polynomial
        logical :: newton_failed = .false.    !! the last Newton iteration failed
        logical :: converged = .false.        !! the last Newton iteration converged
        real(dp), allocatable :: y(:), f0(:), scal(:), scal0(:), rtolv(:), atolv(:)
        real(dp), allocatable :: jac(:, :), e1(:, :)    !! J and the LU of gamma/h M - J
        complex(dp), allocatable :: e2(:, :)            !! LU of (alpha + i beta)/h M - J
        integer, allocatable :: ip1(:), ip2(:)          !! pivots of e1, e2
        real(dp), allocatable :: z1(:), z2(:), z3(:), w1(:), w2(:), w3(:)
        real(dp), allocatable :: a1(:), a2(:), a3(:), b1(:), b2(:), b3(:), cont(:)
        complex(dp), allocatable :: zc(:)
        real(dp), allocatable :: fc(:, :)               !! collocation polynomial fc(:, 0:3)
        real(dp), allocatable :: ynew(:), ystop(:)
    end type radau_state

contains

    !> Allocate the arrays of s for dimension n (rtolv, atolv when `tolerances`).
    subroutine radau_state_allocate(s, n, tolerances)
        type(radau_state), intent(inout) :: s
        integer, intent(in) :: n
        logical, intent(in) :: tolerances
        s%n = n
        allocate (s%y(n), s%f0(n), s%jac(n, n), s%e1(n, n), s%z1(n), s%z2(n), s%z3(n), &
                  s%w1(n), s%w2(n), s%w3(n), s%a1(n), s%a2(n), s%a3(n), s%scal(n), &
                  s%cont(n), s%fc(n, 0:3), s%ynew(n), s%ystop(n), s%e2(n, n), s%zc(n), &
                  s%ip1(n), s%ip2(n), s%scal0(n), s%b1(n), s%b2(n), s%b3(n))
        if (tolerances) allocate (s%rtolv(n), s%atolv(n))
    end subroutine radau_state_allocate

    !> Pack the state of the integration and the counters into (r, iv, w).
    subroutine radau_state_pack(s, stats, r, iv, w)
        type(radau_state), intent(in) :: s
        type(ode_stats), intent(in) :: stats
        real(dp), intent(inout) :: r(:)
        integer, intent(inout) :: iv(:)
        real(dp), intent(inout) :: w(:, :)
        integer :: n
        n = s%n
        r = 0.0_dp
        r(1:RADAU_NR) = [s%t0, s%tf, s%t, s%h, s%hmax, s%posneg, s%uround, s%fnewt, &
                         s%faccon, s%theta, s%hacc, s%erracc, s%hold, s%safe, s%facl, &
                         s%facr, s%cfac, s%t_prev, 0.0_dp, 0.0_dp]
        iv(1:RADAU_NI) = [n, s%nsteps, s%nsing, s%nfail, stats%nfev, stats%njev, &
                          stats%nlu, stats%naccept, stats%nreject, l2i(s%first), &
                          l2i(s%reject), l2i(s%last), l2i(s%caljac), l2i(s%need_jac), &
                          l2i(s%need_lu), l2i(s%have_cont), l2i(s%newton_failed), 1, 0, 0]
        iv(RADAU_NI + 1:RADAU_NI + n) = s%ip1
        iv(RADAU_NI + n + 1:RADAU_NI + 2*n) = s%ip2
        w(:, 1) = s%y
        w(:, 2) = s%f0
        w(:, 3) = s%scal0
        w(:, 4) = s%rtolv
        w(:, 5) = s%atolv
        w(:, 6:9) = s%fc
        w(:, RADAU_NW + 1:RADAU_NW + n) = s%jac
        w(:, RADAU_NW + n + 1:RADAU_NW + 2*n) = s%e1
        w(:, RADAU_NW + 2*n + 1:RADAU_NW + 3*n) = real(s%e2, dp)
        w(:, RADAU_NW + 3*n + 1:RADAU_NW + 4*n) = aimag(s%e2)
    end subroutine radau_state_pack

    !> Unpack the state written by radau_state_pack into s (allocated for iv(1) = n) and
    !! the counters; info = CM_BAD_INPUT with a message if (r, iv, w) was not started.
    subroutine radau_state_unpack(s, stats, r, iv, w, info, message)
        type(radau_state), intent(inout) :: s
        type(ode_stats), intent(inout) :: stats
        real(dp), intent(in) :: r(:)
        integer, intent(in) :: iv(:)
        real(dp), intent(in) :: w(:, :)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(inout) :: message
        integer :: n
        n = s%n
        if (iv(1) /= n .or. iv(18) /= 1) then
            info = CM_BAD_INPUT
            message = "bad input: the Radau state was not started (action 0 first)"
            return
        end if
        info = CM_SUCCESS
        s%t0 = r(1); s%tf = r(2); s%t = r(3); s%h = r(4)
        s%hmax = r(5); s%posneg = r(6); s%uround = r(7); s%fnewt = r(8)
        s%faccon = r(9); s%theta = r(10); s%hacc = r(11)
        s%erracc = r(12); s%hold = r(13); s%safe = r(14); s%facl = r(15)
        s%facr = r(16); s%cfac = r(17); s%t_prev = r(18)
        s%nsteps = iv(2); s%nsing = iv(3); s%nfail = iv(4)
        stats%nfev = iv(5); stats%njev = iv(6)
        stats%nlu = iv(7); stats%naccept = iv(8)
        stats%nreject = iv(9)
        s%first = iv(10) /= 0; s%reject = iv(11) /= 0; s%last = iv(12) /= 0
        s%caljac = iv(13) /= 0; s%need_jac = iv(14) /= 0
        s%need_lu = iv(15) /= 0; s%have_cont = iv(16) /= 0
        s%newton_failed = iv(17) /= 0
        s%ip1 = iv(RADAU_NI + 1:RADAU_NI + n)
        s%ip2 = iv(RADAU_NI + n + 1:RADAU_NI + 2*n)
        s%y = w(:, 1)
        s%f0 = w(:, 2)
        s%scal0 = w(:, 3)
        s%rtolv = w(:, 4)
        s%atolv = w(:, 5)
        s%fc = w(:, 6:9)
        s%jac = w(:, RADAU_NW + 1:RADAU_NW + n)
        s%e1 = w(:, RADAU_NW + n + 1:RADAU_NW + 2*n)
        s%e2 = cmplx(w(:, RADAU_NW + 2*n + 1:RADAU_NW + 3*n), &
                     w(:, RADAU_NW + 3*n + 1:RADAU_NW + 4*n), kind=dp)
        call radau_collocation_basis(s%cvec, s%pmat)
    end subroutine radau_state_unpack

    pure integer function l2i(l)
        logical, intent(in) :: l
        l2i = merge(1, 0, l)
    end function l2i

end module conmech_radau_state
