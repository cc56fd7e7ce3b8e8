!> The explicit Runge-Kutta stepper (RK4, DOPRI5, DOP853, VERNER98) on the integrator
!! contract of conmech_ode_stepper: one object holds the whole state of an integration (t,
!! y, the stages, the step size and the controller's memory), advanced one accepted step at
!! a time. The anchors are FLINT's ERK class and SciPy's OdeSolver:
!!
!! - `setup`     (the contract's `init`) checks the options and sets up the method (no
!!               evaluation of f);
!! - `start`     evaluates f(t0, y0) and chooses the initial step (Hairer's hinit);
!! - `step`      attempts steps until one is accepted (Hairer's step control), then
!!               advances: (t_old, y_old) is the start of that step, (t, y) its end;
!! - `dense`     builds the continuous extension of the last step (extra stages for
!!               DOP853 and Verner); `eval` evaluates it (the contract's default);
!! - `refresh_f` re-evaluates f after a step hook changed y.
!!
!! The FSAL stage of an accepted step is moved into k(:, 1) lazily, at the start of the
!! next step, so that the last step's stages stay available for its dense output.
!! Step-size control follows Hairer's dopri5.f/dop853.f: safety 0.9, step ratio bounds
!! [0.2, 10] (DOPRI5, with Lund stabilisation beta = 0.04) and [1/3, 6] (DOP853,
!! VERNER98), no growth right after a rejection, at most `max_steps` attempted steps.
!! The smallest step is SciPy's (`min_step_at`: 10 spacings of t): a step proposed below
!! it is raised to it once, an attempt below it (after rejections, or when max_step is
!! below it) ends the run. All state is in the object: thread-safe.
module conmech_rk_stepper
    use, intrinsic :: iso_fortran_env, only: int64
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_text, only: rtoa
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: ode_options, METHOD_RK4, METHOD_DOPRI5, &
        METHOD_DOP853, METHOD_VERNER98
    use conmech_ode_stepper, only: ode_stepper, stepper_init, check_first_step, &
        tolerance_vectors, FORM_HAIRER, FORM_POWER, min_step_at, MSG_STEP_TOO_SMALL, &
        MSG_TOO_MANY_STEPS
    use conmech_state_packer, only: state_packer
    use conmech_fixed_grid, only: grid_steps
    use conmech_rk_tableaus, only: rk_tableau, set_dopri5_tableau, set_dop853_tableau, &
        set_verner98_tableau
    use conmech_rk_kernels, only: rk4_attempt, dopri5_attempt, dop853_attempt, &
        verner_attempt
    implicit none
    private
    public :: rk_stepper, rk_init, rk_start, rk_step

    !> State of an explicit Runge-Kutta integration (beyond the contract's common state).
    type, extends(ode_stepper) :: rk_stepper
        integer :: ifsal = 0              !! column of k holding f at the step's end
        logical :: adaptive = .true.      !! false: fixed step (RK4)
        !> the tableau (allocatable: a new stepper object, as every step of the Python
        !! objects makes, copies no 6 kB template; set_method fills it in place)
        type(rk_tableau), allocatable :: tab
        real(dp) :: hmax = 0.0_dp         !! largest |h|
        real(dp) :: h_fixed = 0.0_dp      !! RK4's step
        real(dp) :: safe = 0.9_dp, facc1 = 5.0_dp, facc2 = 0.1_dp, beta = 0.0_dp
        !> a step that would end within (stretch - 1) h before its target is stretched onto
        !! it (Hairer's 1.01; 1: SciPy's rule, a step is only cut where it passes the target)
        real(dp) :: stretch = 1.01_dp
        real(dp) :: expo1 = 0.2_dp, facold = 1.0e-4_dp
        real(dp) :: first_step = 0.0_dp   !! 0: Hairer's heuristic
        integer :: nsteps = 0             !! attempted steps
        integer :: max_steps = 100000
        integer :: n_nonfinite = 0        !! consecutive non-finite error estimates
        logical :: reject = .false.       !! the previous attempt was rejected
        logical :: fsal_pending = .false. !! k(:, ifsal) is f(t, y), not yet in k(:, 1)
        logical :: h_capped = .false.     !! h was cut to hmax after the last step
        real(dp), allocatable :: ynew(:), ytmp(:), sk(:)
        real(dp), allocatable :: rtol(:), atol(:)
        real(dp), allocatable :: k(:, :)  !! stages, (n, 21)
    contains
        procedure :: setup => rk_setup
        procedure :: start => rk_start_impl
        procedure :: step => rk_step_impl
        procedure :: transfer_state => rk_transfer
        procedure :: dense => rk_dense
        procedure :: refresh_f => rk_refresh_f
        procedure :: f_finite => rk_f_finite
    end type rk_stepper

    !> The contract's procedures under the stepper's own names: `rk_init(stp, ...)` is
    !! `stp%init(...)`, and so on.
    interface rk_init
        module procedure stepper_init
    end interface rk_init
    interface rk_start
        module procedure rk_start_impl
    end interface rk_start
    interface rk_step
        module procedure rk_step_impl
    end interface rk_step

contains

    !> The method's part of init: its options (tolerances, step control; RK4's fixed step)
    !! and arrays, at the common state set by the contract's init (no evaluation of f).
    subroutine rk_setup(self, opt, info, msg)
        class(rk_stepper), intent(inout) :: self
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        if (opt%method < METHOD_RK4 .or. opt%method > METHOD_VERNER98) then
            info = CM_BAD_INPUT
            msg = "bad input: unknown method"
            return
        end if
        if (opt%method == METHOD_RK4) then
            call check_first_step(self, opt, info, msg, fixed="RK4")
        else
            call check_first_step(self, opt, info, msg)
        end if
        if (info /= CM_SUCCESS) return
        call tolerance_vectors(opt, self%n, self%rtol, self%atol, info, msg)
        if (info /= CM_SUCCESS) return
        call set_method(self, opt%method)
        self%safe = 0.9_dp
        self%facold = 1.0e-4_dp
        self%nsteps = 0
        self%n_nonfinite = 0
        self%reject = .false.
        self%fsal_pending = .false.
        self%stretch = 1.01_dp
        if (opt%stretch >= 0.0_dp) self%stretch = 1.0_dp + opt%stretch
        if (self%adaptive) then
            if (opt%beta >= 0.0_dp) self%beta = opt%beta
            if (opt%method == METHOD_DOPRI5) then
                self%expo1 = 0.2_dp - self%beta*0.75_dp
            else if (opt%method == METHOD_VERNER98) then
                self%expo1 = 1.0_dp/9.0_dp - self%beta*0.2_dp
            else
                self%expo1 = 1.0_dp/8.0_dp - self%beta*0.2_dp
            end if
        end if
        if (opt%safety > 0.0_dp) self%safe = opt%safety
        if (opt%fac_min > 0.0_dp) self%facc1 = 1.0_dp/opt%fac_min
        if (opt%fac_max > 0.0_dp) self%facc2 = 1.0_dp/opt%fac_max
        self%hmax = min(abs(opt%max_step), abs(self%tf - self%t))
        self%first_step = opt%first_step
        self%max_steps = opt%max_steps
        call allocate_work(self)
        self%k = 0.0_dp
    end subroutine rk_setup

    !> The method's constants: tableau, dense degree and form, FSAL column, the default
    !! step-ratio bounds and Lund stabilisation (from the method code alone, so that an
    !! unpacked state rebuilds them).
    subroutine set_method(self, method)
        type(rk_stepper), intent(inout) :: self
        integer, intent(in) :: method
        self%adaptive = .true.
        self%form = FORM_HAIRER
        self%beta = 0.0_dp
        if (allocated(self%tab)) deallocate (self%tab)
        allocate (self%tab)                 ! default-initialized: all zero
        select case (method)
        case (METHOD_RK4)
            self%adaptive = .false.
            self%nf = 3
            self%tab%stages = 4
            self%ifsal = 13
        case (METHOD_DOPRI5)
            call set_dopri5_tableau(self%tab)
            self%nf = 4
            self%ifsal = 7
            self%facc1 = 1.0_dp/0.2_dp; self%facc2 = 1.0_dp/10.0_dp; self%beta = 0.04_dp
        case (METHOD_VERNER98)
            call set_verner98_tableau(self%tab)
            self%nf = 8
            self%form = FORM_POWER
            self%ifsal = 17
            self%facc1 = 1.0_dp/0.333_dp; self%facc2 = 1.0_dp/6.0_dp
        case default
            call set_dop853_tableau(self%tab)
            self%nf = 7
            self%ifsal = 13
            self%facc1 = 1.0_dp/0.333_dp; self%facc2 = 1.0_dp/6.0_dp
        end select
    end subroutine set_method

    !> Work arrays and stages for dimension self%n.
    subroutine allocate_work(self)
        type(rk_stepper), intent(inout) :: self
        integer :: n
        n = self%n
        if (allocated(self%ynew)) deallocate (self%ynew, self%ytmp, self%sk)
        if (allocated(self%k)) deallocate (self%k)
        allocate (self%ynew(n), self%ytmp(n), self%sk(n), self%k(n, 21))
    end subroutine allocate_work

    !> The whole state, for the step-by-step use from Python (conmech_state_packer). The
    !! tableau and the method's constants are rebuilt from the method code.
    subroutine rk_transfer(self, p)
        class(rk_stepper), intent(inout) :: self
        type(state_packer), intent(inout) :: p
        real(dp) :: facc1, facc2, beta
        call self%transfer_base(p)
        facc1 = self%facc1
        facc2 = self%facc2
        beta = self%beta
        if (p%reading()) then
            call set_method(self, self%method)
            call allocate_work(self)
            self%ynew = self%y
            self%ytmp = 0.0_dp
            self%sk = 0.0_dp
        end if
        call p%item(self%hmax)
        call p%item(self%h_fixed)
        call p%item(self%safe)
        call p%item(facc1)
        call p%item(facc2)
        call p%item(beta)
        call p%item(self%expo1)
        call p%item(self%stretch)
        call p%item(self%facold)
        call p%item(self%first_step)
        call p%item(self%nsteps)
        call p%item(self%max_steps)
        call p%item(self%n_nonfinite)
        call p%item(self%reject)
        call p%item(self%fsal_pending)
        call p%item(self%h_capped)
        call p%column(self%rtol)
        call p%column(self%atol)
        call p%columns(self%k, 1, 21)
        self%facc1 = facc1
        self%facc2 = facc2
        self%beta = beta
    end subroutine rk_transfer

    !> Evaluate f at the initial point and choose the first step.
    subroutine rk_start_impl(self, sys, info, msg)
        class(rk_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: nsteps
        info = CM_SUCCESS
        msg = "success"
        call sys%rhs(self%t, self%y, self%k(:, 1))
        self%st%nfev = self%st%nfev + 1
        if (.not. all(abs(self%k(:, 1)) <= huge(1.0_dp))) then
            info = CM_NONFINITE
            msg = "the right-hand side is not finite at the initial point"
            return
        end if
        if (self%adaptive) then
            if (self%first_step > 0.0_dp) then
                self%h = min(self%first_step, self%hmax)*self%posneg
            else
                call hinit(self, sys)
            end if
        else
            nsteps = max(1, grid_steps(self%t, self%tf, self%first_step))
            self%h = (self%tf - self%t)/real(nsteps, dp)
        end if
        self%h_fixed = self%h
        self%facold = 1.0e-4_dp
        self%reject = .false.
        self%h_capped = .false.
    end subroutine rk_start_impl

    !> Hairer's initial step size (hinit of dopri5.f / dop853.f), with scale-safe norms.
    subroutine hinit(self, sys)
        class(rk_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        real(dp) :: hh, dnf, dny, der2, der12, h1, nf, ny
        associate (sk => self%sk, y => self%y, k => self%k, ytmp => self%ytmp)
            ! Hairer's sums of squares; where they overflow (|f/sk| ~ 1e155), scaled norms
            sk = self%atol + self%rtol*abs(y)
            dnf = sum((k(:, 1)/sk)**2)
            dny = sum((y/sk)**2)
            if (dnf <= huge(1.0_dp) .and. dny <= huge(1.0_dp)) then
                nf = sqrt(dnf)
                ny = sqrt(dny)
            else
                ytmp = k(:, 1)/sk
                nf = scaled_norm(ytmp)
                ytmp = y/sk
                ny = scaled_norm(ytmp)
                dnf = nf**2
                dny = ny**2
            end if
            if (dnf <= 1.0e-10_dp .or. dny <= 1.0e-10_dp) then
                hh = 1.0e-6_dp
            else if (dnf <= huge(1.0_dp) .and. dny <= huge(1.0_dp)) then
                hh = sqrt(dny/dnf)*0.01_dp
            else
                hh = (ny/nf)*0.01_dp
            end if
            hh = min(hh, self%hmax)*self%posneg
            ytmp = y + hh*k(:, 1)
            call sys%rhs(self%t + hh, ytmp, k(:, 2))
            self%st%nfev = self%st%nfev + 1
            der2 = sum(((k(:, 2) - k(:, 1))/sk)**2)
            if (der2 <= huge(1.0_dp)) then
                der2 = sqrt(der2)/abs(hh)
            else if (der2 == der2) then
                ytmp = (k(:, 2) - k(:, 1))/sk
                der2 = scaled_norm(ytmp)/abs(hh)
            end if
            if (der2 /= der2) der2 = huge(1.0_dp)
            der12 = max(abs(der2), nf)
            if (der12 <= 1.0e-15_dp) then
                h1 = max(1.0e-6_dp, abs(hh)*1.0e-3_dp)
            else
                h1 = (0.01_dp/der12)**(1.0_dp/real(self%tab%order, dp))
            end if
            self%h = min(100.0_dp*abs(hh), h1, self%hmax)*self%posneg
        end associate
    end subroutine hinit

    !> Euclidean norm without overflow or underflow: m sqrt(sum((x/m)^2)), m = max|x_i|
    !! (NaN if x has a NaN). Written out, not NORM2, so that every build rounds alike.
    pure real(dp) function scaled_norm(x) result(r)
        real(dp), intent(in) :: x(:)
        real(dp) :: m, s
        integer :: i
        m = 0.0_dp
        do i = 1, size(x)
            if (.not. abs(x(i)) <= m) m = abs(x(i))     ! NaN propagates into m
        end do
        if (m == 0.0_dp .or. .not. m <= huge(1.0_dp)) then
            r = m
            return
        end if
        s = 0.0_dp
        do i = 1, size(x)
            s = s + (x(i)/m)**2
        end do
        r = m*sqrt(s)
    end function scaled_norm

    !> Attempt steps until one is accepted, then advance to its end. `target` is the point
    !! a step lands on if it reaches it (tf, or the next output point; Hairer's rule:
    !! a step is stretched by up to 1 % to reach it, `stretch`; SciPy's RK45 only cuts a
    !! step that would pass it). info: CM_SUCCESS after an accepted
    !! step, else the failure (too many steps, step too small, non-finite values).
    subroutine rk_step_impl(self, sys, target, info, msg)
        class(rk_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: target
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        real(dp) :: err, fac11, fac, hnew, h_unclipped, t_new, hmin
        real(dp), allocatable :: yswap(:)
        integer :: n
        logical :: defer, first_try
        n = self%n
        info = CM_SUCCESS
        if (self%fsal_pending) then
            self%k(:, 1) = self%k(:, self%ifsal)
            self%fsal_pending = .false.
        end if
        first_try = .true.
        do
            if (self%nsteps >= self%max_steps) then
                info = CM_TOO_MANY_STEPS
                msg = MSG_TOO_MANY_STEPS//rtoa(self%t)
                return
            end if
            ! the smallest step (SciPy's min_step <= 10 eps |t|: the cheap test first)
            if (self%adaptive .and. (abs(self%h) <= 10.0_dp*epsilon(1.0_dp)*abs(self%t) &
                                     .or. abs(self%h) < tiny(1.0_dp))) then
                hmin = min_step_at(self%t, self%posneg)
                if (first_try .and. .not. self%h_capped .and. self%n_nonfinite == 0) &
                    self%h = self%posneg*max(abs(self%h), hmin)
                if (abs(self%h) < hmin .or. abs(self%h) < tiny(1.0_dp)) then
                    if (self%n_nonfinite > 0) then
                        info = CM_NONFINITE
                        msg = "non-finite values in the right-hand side near t ="//rtoa(self%t)
                    else
                        info = CM_STEP_TOO_SMALL
                        msg = MSG_STEP_TOO_SMALL//rtoa(self%t)
                    end if
                    return
                end if
            else if (.not. self%adaptive .and. (0.1_dp*abs(self%h) <= abs(self%t)* &
                                                epsilon(1.0_dp) .or. abs(self%h) < tiny(1.0_dp))) then
                info = CM_STEP_TOO_SMALL
                msg = "step size too small at t ="//rtoa(self%t)
                return
            end if
            first_try = .false.
            self%hit = .false.
            h_unclipped = self%h
            if (self%adaptive) then
                if ((self%t + self%stretch*self%h - target)*self%posneg > 0.0_dp) then
                    self%h = target - self%t
                    self%hit = .true.
                end if
            else
                self%h = self%h_fixed
                if ((target - self%t)*self%posneg <= abs(self%h)*(1.0_dp + 1.0e-8_dp)) then
                    self%h = target - self%t
                    self%hit = .true.
                end if
            end if
            self%last = self%hit .and. target == self%tf
            self%nsteps = self%nsteps + 1

            select case (self%method)
            case (METHOD_RK4)
                call rk4_attempt(sys, n, self%t, self%h, self%y, self%k, self%ynew, &
                                 self%ytmp, err)
                self%st%nfev = self%st%nfev + 3
            case (METHOD_DOPRI5)
                call dopri5_attempt(sys, n, self%tab, self%t, self%h, self%y, self%k, &
                                    self%ynew, self%ytmp, self%rtol, self%atol, err)
                self%st%nfev = self%st%nfev + 6
            case (METHOD_VERNER98)
                call verner_attempt(sys, n, self%tab, self%t, self%h, self%y, self%k, &
                                    self%ynew, self%ytmp, self%rtol, self%atol, err)
                self%st%nfev = self%st%nfev + 15
            case default
                call dop853_attempt(sys, n, self%tab, self%t, self%h, self%y, self%k, &
                                    self%ynew, self%ytmp, self%sk, self%rtol, self%atol, err)
                self%st%nfev = self%st%nfev + 11
            end select

            if (.not. (err <= 1.0_dp)) then
                ! ------------------------------------------------ rejected step
                if (.not. self%adaptive) then
                    info = CM_NONFINITE
                    msg = "non-finite state in a fixed step from t ="//rtoa(self%t)
                    return
                end if
                if ((err /= err) .or. err > huge(1.0_dp)) then
                    ! non-finite error estimate: cut the step hard
                    self%n_nonfinite = self%n_nonfinite + 1
                    if (self%n_nonfinite > 40) then
                        info = CM_NONFINITE
                        msg = "non-finite values in the right-hand side near t ="//rtoa(self%t)
                        return
                    end if
                    self%h = self%h*0.1_dp
                else
                    self%n_nonfinite = 0
                    fac11 = err_power(self, err)
                    self%h = self%h/min(self%facc1, fac11/self%safe)
                end if
                self%reject = .true.
                if (self%st%naccept >= 1) self%st%nreject = self%st%nreject + 1
                cycle
            end if
            exit
        end do

        ! ---------------------------------------------------- accepted step
        self%n_nonfinite = 0
        self%st%naccept = self%st%naccept + 1
        if (self%adaptive) then
            fac11 = err_power(self, err)
            fac = fac11
            if (self%beta /= 0.0_dp) fac = fac11/self%facold**self%beta
            fac = max(self%facc2, min(self%facc1, fac/self%safe))
            hnew = self%h/fac
            self%facold = max(err, 1.0e-4_dp)
            ! a step shortened to land on a point does not shrink the next one
            if (self%hit) hnew = self%posneg*max(abs(hnew), abs(h_unclipped))
        else
            hnew = self%h_fixed
        end if
        t_new = self%t + self%h
        if (self%hit) t_new = target
        ! f at the step's end (FSAL): DOPRI5 has it from the attempt; the others evaluate
        ! it unless a hook follows that changes y (the driver's defer_f)
        defer = self%defer_f .and. self%method /= METHOD_DOPRI5
        if (self%method /= METHOD_DOPRI5 .and. .not. defer) then
            call sys%rhs(t_new, self%ynew, self%k(:, self%ifsal))
            self%st%nfev = self%st%nfev + 1
        end if
        self%fsal_pending = .not. defer
        self%f_stale = defer
        self%dense_ready = .false.
        ! (y_old, y, ynew) <- (y, ynew, y_old): a rotation of the buffers, no copies
        call move_alloc(self%y_old, yswap)
        call move_alloc(self%y, self%y_old)
        call move_alloc(self%ynew, self%y)
        call move_alloc(yswap, self%ynew)
        self%t_old = self%t
        self%t = t_new
        self%h_done = self%h
        if (self%adaptive) then
            self%h_capped = abs(hnew) > self%hmax
            if (self%h_capped) hnew = self%posneg*self%hmax
            if (self%reject) hnew = self%posneg*min(abs(hnew), abs(self%h))
        end if
        self%reject = .false.
        self%h = hnew
    end subroutine rk_step_impl

    !> err**expo1, by square roots when expo1 = 1/8 (DOP853's exponent without
    !! stabilisation: a few instructions instead of a call to pow).
    pure real(dp) function err_power(self, err) result(p)
        class(rk_stepper), intent(in) :: self
        real(dp), intent(in) :: err
        if (self%expo1 == 0.125_dp) then
            p = sqrt(sqrt(sqrt(err)))
        else
            p = err**self%expo1
        end if
    end function err_power

    !> Coefficients of the continuous extension of the last accepted step (into fc; DOP853
    !! and VERNER98 evaluate their extra stages here).
    subroutine rk_dense(self, sys)
        class(rk_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        integer :: s, j, i, n
        real(dp) :: h
        if (self%dense_ready) return
        n = self%n
        h = self%h_done
        associate (fc => self%fc, k => self%k, y0 => self%y_old, ytmp => self%ytmp, &
                   tb => self%tab)
            fc(:, 0) = y0
            fc(:, 1) = self%y - y0
            select case (self%method)
            case (METHOD_RK4)
                fc(:, 2) = h*k(:, 1) - fc(:, 1)
                fc(:, 3) = 2.0_dp*fc(:, 1) - h*(k(:, 1) + k(:, 13))
            case (METHOD_DOPRI5)
                fc(:, 2) = h*k(:, 1) - fc(:, 1)
                fc(:, 3) = 2.0_dp*fc(:, 1) - h*(k(:, 1) + k(:, 7))
                fc(:, 4) = 0.0_dp
                do j = 1, 7
                    if (tb%d(1, j) /= 0.0_dp) fc(:, 4) = fc(:, 4) + (h*tb%d(1, j))*k(:, j)
                end do
            case (METHOD_VERNER98)
                ! stages 18..21 (stage 17 is the FSAL stage), then the power-form weights
                call extra_stages(18, 21)
                do j = 1, 8
                    fc(:, j) = 0.0_dp
                    do i = 1, 21
                        if (tb%p(i, j) /= 0.0_dp) fc(:, j) = fc(:, j) + (h*tb%p(i, j))*k(:, i)
                    end do
                end do
            case default
                ! three extra stages 14..16 (they use the FSAL stage 13)
                call extra_stages(14, 16)
                fc(:, 2) = h*k(:, 1) - fc(:, 1)
                fc(:, 3) = 2.0_dp*fc(:, 1) - h*(k(:, 13) + k(:, 1))
                do i = 1, 4
                    fc(:, 3 + i) = 0.0_dp
                    do j = 1, 16
                        if (tb%d(i, j) /= 0.0_dp) &
                            fc(:, 3 + i) = fc(:, 3 + i) + (h*tb%d(i, j))*k(:, j)
                    end do
                end do
            end select
        end associate
        self%dense_ready = .true.
    contains
        subroutine extra_stages(s1, s2)
            integer, intent(in) :: s1, s2
            do s = s1, s2
                self%ytmp = self%y_old
                do j = 1, s - 1
                    if (self%tab%a(s, j) /= 0.0_dp) &
                        self%ytmp = self%ytmp + (h*self%tab%a(s, j))*self%k(:, j)
                end do
                call sys%rhs(self%t_old + self%tab%c(s)*h, self%ytmp, self%k(:, s))
            end do
            self%st%nfev = self%st%nfev + (s2 - s1 + 1)
        end subroutine extra_stages
    end subroutine rk_dense

    !> Re-evaluate f at the current point (after a step hook changed y, or deferred FSAL).
    subroutine rk_refresh_f(self, sys)
        class(rk_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        call sys%rhs(self%t, self%y, self%k(:, 1))
        self%st%nfev = self%st%nfev + 1
        self%fsal_pending = .false.
        self%f_stale = .false.
    end subroutine rk_refresh_f

    !> Whether f at the current point is finite.
    logical function rk_f_finite(self)
        class(rk_stepper), intent(in) :: self
        if (self%fsal_pending) then
            rk_f_finite = all_finite(self%n, self%k(:, self%ifsal))
        else
            rk_f_finite = all_finite(self%n, self%k(:, 1))
        end if
    end function rk_f_finite

    !> All of x finite: a count over the whole vector (vectorises; no early exit).
    pure logical function all_finite(n, x)
        integer, intent(in) :: n
        real(dp), intent(in) :: x(n)
        integer :: i
        integer(int64) :: bad     ! 64-bit lanes like the compared doubles: no repacking
        bad = 0_int64
        do i = 1, n
            if (.not. abs(x(i)) <= huge(1.0_dp)) bad = bad + 1_int64
        end do
        all_finite = bad == 0_int64
    end function all_finite

end module conmech_rk_stepper
