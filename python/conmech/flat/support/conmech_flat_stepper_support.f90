!> Support of the flat stepper routines (python/conmech/flat/flat_stepper.f90): the whole
!! state of an `rk_stepper` packed into plain arrays owned by the caller (the Python
!! object), so that a step can be taken from Python without any state kept in Fortran
!! between calls (thread-safe). The tableau is rebuilt from the method code.
!!
!! Layout: r(NR_STATE) real scalars, iv(NI_STATE) integers (logicals as 0/1),
!! w(n, NW_STATE) columns: y, y_old, rtol, atol, the 21 stages k, the dense coefficients
!! fc(:, 0:8).
module conmech_flat_stepper_support
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: ode_options, METHOD_DOPRI5, METHOD_DOP853, &
        METHOD_VERNER98
    use conmech_rk_tableaus, only: dopri5_tableau, dop853_tableau, verner98_tableau
    use conmech_rk_stepper, only: rk_stepper, rk_init, rk_start, rk_step
    use conmech_flat_ode_support, only: METHOD_RK45_SCIPY, scipy_first_step
    implicit none
    private
    public :: NR_STATE, NI_STATE, NW_STATE, stepper_pack, stepper_unpack, stepper_action

    integer, parameter :: NR_STATE = 20, NI_STATE = 20, NW_STATE = 34
    integer, parameter :: CY = 1, CYOLD = 2, CRTOL = 3, CATOL = 4, CK = 5, CFC = 26

contains

    !> Copy the stepper's state into (r, iv, w).
    subroutine stepper_pack(s, n, r, iv, w)
        type(rk_stepper), intent(in) :: s
        integer(c_int), intent(in) :: n
        real(c_double), intent(out) :: r(NR_STATE), w(n, NW_STATE)
        integer(c_int), intent(out) :: iv(NI_STATE)
        r = 0.0_dp
        iv = 0
        w = 0.0_dp
        r(1:16) = [s%t, s%t_old, s%tf, s%posneg, s%h, s%h_done, s%hmax, s%h_fixed, s%safe, &
                   s%facc1, s%facc2, s%beta, s%expo1, s%facold, s%first_step, s%st%h_next]
        iv(1:19) = [s%method, s%n, s%nf, s%form, s%ifsal, l2i(s%adaptive), s%nsteps, &
                    s%max_steps, s%n_nonfinite, l2i(s%reject), l2i(s%fsal_pending), &
                    l2i(s%defer_fsal), l2i(s%dense_ready), l2i(s%hit), l2i(s%last), &
                    s%st%nfev, s%st%naccept, s%st%nreject, s%tab%order]
        w(:, CY) = s%y
        w(:, CYOLD) = s%y_old
        w(:, CRTOL) = s%rtol
        w(:, CATOL) = s%atol
        w(:, CK:CK + 20) = s%k
        w(:, CFC:CFC + s%nf) = s%fc
    contains
        integer function l2i(l)
            logical, intent(in) :: l
            l2i = merge(1, 0, l)
        end function l2i
    end subroutine stepper_pack

    !> Rebuild a stepper from (r, iv, w) as written by `stepper_pack`.
    subroutine stepper_unpack(s, n, r, iv, w)
        type(rk_stepper), intent(out) :: s
        integer(c_int), intent(in) :: n
        real(c_double), intent(in) :: r(NR_STATE), w(n, NW_STATE)
        integer(c_int), intent(in) :: iv(NI_STATE)
        s%method = iv(1)
        select case (s%method)
        case (METHOD_DOPRI5)
            s%tab = dopri5_tableau()
        case (METHOD_DOP853)
            s%tab = dop853_tableau()
        case (METHOD_VERNER98)
            s%tab = verner98_tableau()
        case default
            s%tab%stages = 4
        end select
        s%t = r(1); s%t_old = r(2); s%tf = r(3); s%posneg = r(4); s%h = r(5)
        s%h_done = r(6); s%hmax = r(7); s%h_fixed = r(8); s%safe = r(9); s%facc1 = r(10)
        s%facc2 = r(11); s%beta = r(12); s%expo1 = r(13); s%facold = r(14)
        s%first_step = r(15); s%st%h_next = r(16)
        s%n = iv(2); s%nf = iv(3); s%form = iv(4); s%ifsal = iv(5); s%adaptive = iv(6) /= 0
        s%nsteps = iv(7); s%max_steps = iv(8); s%n_nonfinite = iv(9); s%reject = iv(10) /= 0
        s%fsal_pending = iv(11) /= 0; s%defer_fsal = iv(12) /= 0
        s%dense_ready = iv(13) /= 0; s%hit = iv(14) /= 0; s%last = iv(15) /= 0
        s%st%nfev = iv(16); s%st%naccept = iv(17); s%st%nreject = iv(18)
        allocate (s%y(n), s%y_old(n), s%ynew(n), s%ytmp(n), s%sk(n), s%rtol(n), s%atol(n), &
                  s%k(n, 21), s%fc(n, 0:s%nf))
        s%y = w(:, CY)
        s%y_old = w(:, CYOLD)
        s%rtol = w(:, CRTOL)
        s%atol = w(:, CATOL)
        s%k = w(:, CK:CK + 20)
        s%fc = w(:, CFC:CFC + s%nf)
        s%ynew = s%y
        s%ytmp = 0.0_dp
        s%sk = 0.0_dp
    end subroutine stepper_unpack

    !> One action on a packed stepper: 0 init (rk_init + rk_start at t0, y0), 1 one
    !! accepted step towards t_bound, 2 dense coefficients of the last step (w's fc
    !! columns). info: CM_SUCCESS or the failure; the state is written back in every case.
    !! method METHOD_RK45_SCIPY (12): DOPRI5 with SciPy's step control (no Lund
    !! stabilisation) and, without first_step, SciPy's initial step (its two evaluations
    !! counted in nfev), as solve_ivp(method="RK45") runs it.
    subroutine stepper_action(sys, action, n, t0, t_bound, y0, method, rtol, atol, &
                              first_step, max_step, max_steps, r, iv, w, info, message)
        class(ode_system), intent(in) :: sys
        integer(c_int), intent(in) :: action, n, method, max_steps
        real(c_double), intent(in) :: t0, t_bound, y0(n), rtol(n), atol(n)
        real(c_double), intent(in) :: first_step, max_step
        real(c_double), intent(inout) :: r(NR_STATE), w(n, NW_STATE)
        integer(c_int), intent(inout) :: iv(NI_STATE)
        integer(c_int), intent(out) :: info
        character(len=*), intent(out) :: message
        type(rk_stepper) :: s
        type(ode_options) :: opt
        character(len=:), allocatable :: msg
        integer :: inf
        integer(c_int) :: nfev0
        msg = "success"
        select case (action)
        case (0)
            opt%method = method
            opt%rtol_vec = rtol
            opt%atol_vec = atol
            opt%first_step = first_step
            opt%max_step = max_step
            opt%max_steps = max_steps
            nfev0 = 0
            if (method == METHOD_RK45_SCIPY) then
                opt%method = METHOD_DOPRI5
                opt%beta = 0.0_dp
                if (.not. first_step > 0.0_c_double .and. t_bound /= t0 .and. &
                    all(y0 == y0) .and. all(abs(y0) <= huge(1.0_dp))) then
                    call scipy_first_step(sys, [t0, t_bound], y0, &
                                          max(rtol, 100.0_dp*epsilon(1.0_dp)), atol, &
                                          max_step, 4, opt%first_step, nfev0)
                end if
            end if
            call rk_init(s, t0, t_bound, y0, opt, inf, msg, allow_inf=.true.)
            if (inf == CM_SUCCESS .and. t_bound /= t0) call rk_start(s, sys, inf, msg)
            if (allocated(s%y)) s%st%nfev = s%st%nfev + nfev0
            if (inf == CM_SUCCESS .or. allocated(s%y)) call stepper_pack(s, n, r, iv, w)
        case (1)
            call stepper_unpack(s, n, r, iv, w)
            call rk_step(s, sys, s%tf, inf, msg)
            call stepper_pack(s, n, r, iv, w)
        case (2)
            call stepper_unpack(s, n, r, iv, w)
            call s%dense(sys)
            call stepper_pack(s, n, r, iv, w)
            inf = CM_SUCCESS
        case default
            inf = CM_BAD_INPUT
            msg = "bad input: unknown stepper action"
        end select
        info = inf
        if (.not. allocated(msg)) msg = "success"
        message = msg
    end subroutine stepper_action

end module conmech_flat_stepper_support
