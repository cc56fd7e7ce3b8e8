!> Taylor's method with the coefficients the system supplies (`taylor_size`, `taylor_jet` of
!! conmech_ode_system; generated from the model by `conmech.symbolic`).
!!
!! Each step expands the solution about the current point to order p,
!! y(t + s) = sum_k y^[k] s^k, and evaluates the polynomial at s = h. Order and step follow
!! Jorba and Zou (2005), as heyoka does:
!!
!! - p = ceil(-ln(eps)/2 + 1) for the tolerance eps = max(rtol, atol) (the smallest
!!   components of vector tolerances), at least 2 (order 15 at 1e-12, 20 at 1e-16);
!! - rho = min over k = p - 1, p of (1/N_k)^(1/k), N_k = max_i |y_i^[k]| eps/E_i with
!!   E_i = max(atol_i, rtol_i ||y||_inf) (the radius of convergence seen by the last two
!!   coefficients; rtol = atol = eps gives Jorba and Zou's mixed absolute/relative norm);
!!   h = rho exp(-2) exp(-0.7/(p - 1)): the terms of order p - 1 and p stay below E_i.
!!
!! Safety check of the step: the coefficients at the step's end are computed at once (the
!! next step needs them), so f(t + h, y(t + h)) = y^[1] there is known for free; it is
!! compared with the derivative of the step's polynomial at h. The difference times h is
!! about (p + 1) times the local error; a step whose estimate exceeds 10 E_i (plus a rounding
!! floor) is rejected and retried from the same expansion with a shorter step. This guards
!! against accidentally small last coefficients (symmetries, a passage near a
!! singularity), where the Jorba-Zou estimate alone would be too optimistic.
!!
!! The continuous extension of a step is its Taylor polynomial itself (degree p, the
!! accuracy of the step anywhere in it): fc(:, k) = y^[k] h^k in the power form.
!! All state is in the object (thread-safe). nfev counts the expansions (one per step,
!! plus one at the start and one per rejected step).
module conmech_taylor_stepper
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: ode_options, ode_stats
    implicit none
    private

    public :: taylor_stepper, taylor_order, taylor_init, taylor_start, taylor_step
    public :: taylor_propagate

    real(dp), parameter :: CHECK_MAX = 10.0_dp   !! rejected above 10 x the tolerance

    !> State of a Taylor integration (the common fields of conmech's steppers, and the two
    !! expansions: at the current point and at the start of the last step).
    type :: taylor_stepper
        integer :: n = 0                  !! dimension of y (n + n**2 for kind 1)
        integer :: nblock = 0             !! first block of y (the state; the rest: Phi)
        integer :: kind = 0               !! 0 the system, 1 its variational system
        integer :: order = 0              !! p
        integer :: nw = 0                 !! columns of the work arrays
        integer :: nf = 0                 !! degree of the continuous extension (p)
        real(dp) :: t = 0.0_dp, t_old = 0.0_dp, tf = 0.0_dp, posneg = 1.0_dp
        real(dp) :: t_lo = 0.0_dp         !! t + t_lo: the time in double length
        real(dp) :: h = 0.0_dp            !! step proposed from the current expansion
        real(dp) :: h_done = 0.0_dp       !! last accepted step (signed)
        real(dp) :: hmax = huge(1.0_dp)
        real(dp) :: first_step = 0.0_dp
        real(dp) :: eps = 0.0_dp          !! tolerance that set the order
        real(dp) :: err = 0.0_dp          !! safety-check ratio of the last accepted step
        integer :: nsteps = 0, max_steps = 100000
        logical :: last = .false., hit = .false., dense_ready = .false.
        type(ode_stats) :: st
        real(dp), allocatable :: y(:), y_old(:), rtol(:), atol(:), dy(:)
        real(dp), allocatable :: jet(:, :)    !! (0:p, nw) expansion at (t, y)
        real(dp), allocatable :: jold(:, :)   !! (0:p, nw) expansion at (t_old, y_old)
        real(dp), allocatable :: fc(:, :)     !! (n, 0:p) extension, power form
    contains
        procedure :: dense => taylor_dense
        procedure :: eval => taylor_eval
        procedure :: refresh_f => taylor_refresh
        procedure :: f_finite => taylor_f_finite
    end type taylor_stepper

contains

    !> Jorba and Zou's order for the tolerance eps: ceil(-ln(eps)/2 + 1), at least 2.
    pure integer function taylor_order(eps)
        real(dp), intent(in) :: eps
        taylor_order = max(2, ceiling(-0.5_dp*log(max(eps, tiny(1.0_dp))) + 1.0_dp))
    end function taylor_order

    !> Check the options and set up at (t0, y0) on [t0, tf]; kind 0 integrates the system,
    !! kind 1 its variational system (y0 of length n + n**2: the state, then Phi
    !! column-major). No evaluation yet. A system without Taylor coefficients is
    !! CM_BAD_INPUT with a message saying so.
    subroutine taylor_init(self, sys, t0, tf, y0, opt, info, msg, kind, allow_inf)
        type(taylor_stepper), intent(out) :: self
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t0, tf, y0(:)
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer, intent(in), optional :: kind
        logical, intent(in), optional :: allow_inf
        integer :: n, k
        logical :: inf_ok
        real(dp) :: rmin, amin
        k = 0
        if (present(kind)) k = kind
        inf_ok = .false.
        if (present(allow_inf)) inf_ok = allow_inf
        n = size(y0)
        info = CM_BAD_INPUT
        if (n < 1) then
            msg = "bad input: y0 is empty"
        else if (.not. all(ieee_is_finite(y0))) then
            msg = "bad input: y0 contains NaN or Inf"
        else if (.not. (ieee_is_finite(t0) .and. (ieee_is_finite(tf) .or. &
                                                  (inf_ok .and. tf == tf)))) then
            msg = "bad input: t_span must be finite"
        else if (sys%taylor_size(k) < n) then
            msg = "bad input: the system has no Taylor coefficients (method TAYLOR needs a "// &
                  "system from conmech.symbolic with smooth right-hand side, or a type "// &
                  "that overrides taylor_size and taylor_jet)"
        else if (.not. opt%max_step > 0.0_dp) then
            msg = "bad input: max_step must be positive"
        else if (.not. opt%first_step >= 0.0_dp) then
            msg = "bad input: first_step must be positive"
        else if (opt%first_step > abs(tf - t0) .and. tf /= t0) then
            msg = "bad input: first_step exceeds the length of t_span"
        else if (opt%max_steps < 1) then
            msg = "bad input: max_steps must be positive"
        else
            info = CM_SUCCESS
            msg = "success"
        end if
        if (info /= CM_SUCCESS) return
        allocate (self%rtol(n), self%atol(n))
        if (allocated(opt%rtol_vec)) then
            if (size(opt%rtol_vec) /= n) then
                info = CM_BAD_INPUT
                msg = "bad input: rtol must be a scalar or have the size of y0"
                return
            end if
            self%rtol = opt%rtol_vec
        else
            self%rtol = opt%rtol
        end if
        if (allocated(opt%atol_vec)) then
            if (size(opt%atol_vec) /= n) then
                info = CM_BAD_INPUT
                msg = "bad input: atol must be a scalar or have the size of y0"
                return
            end if
            self%atol = opt%atol_vec
        else
            self%atol = opt%atol
        end if
        if (.not. (all(self%rtol >= 0.0_dp) .and. all(self%atol >= 0.0_dp))) then
            info = CM_BAD_INPUT
            msg = "bad input: rtol and atol must be non-negative"
            return
        end if
        ! Taylor's method reaches round-off: rtol may go down to the unit round-off
        self%rtol = max(self%rtol, epsilon(1.0_dp))
        rmin = minval(self%rtol)
        amin = minval(self%atol)
        self%eps = max(rmin, amin)
        self%order = taylor_order(self%eps)
        self%kind = k
        self%n = n
        self%nblock = n
        if (k == 1) self%nblock = nint((sqrt(4.0_dp*n + 1.0_dp) - 1.0_dp)/2.0_dp)
        self%nw = sys%taylor_size(k)
        self%nf = self%order
        self%t = t0
        self%t_old = t0
        self%tf = tf
        self%posneg = sign(1.0_dp, tf - t0)
        self%hmax = min(abs(opt%max_step), abs(tf - t0))
        if (.not. ieee_is_finite(self%hmax)) self%hmax = huge(1.0_dp)
        self%first_step = opt%first_step
        self%max_steps = opt%max_steps
        allocate (self%y(n), self%y_old(n), self%dy(n), self%fc(n, 0:self%order))
        allocate (self%jet(0:self%order, self%nw), self%jold(0:self%order, self%nw))
        self%y = y0
        self%y_old = y0
        self%jet = 0.0_dp
        self%jold = 0.0_dp
        self%fc = 0.0_dp
    end subroutine taylor_init

    !> The expansion at the initial point and the first step.
    subroutine taylor_start(self, sys, info, msg)
        type(taylor_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        info = CM_SUCCESS
        msg = "success"
        call expand(self, sys, self%jet, self%t, self%y)
        if (.not. all(ieee_is_finite(self%jet(1, 1:self%n)))) then
            info = CM_NONFINITE
            msg = "the right-hand side is not finite at the initial point"
            return
        end if
        call propose(self)
        if (self%first_step > 0.0_dp) self%h = min(self%first_step, self%hmax)*self%posneg
    end subroutine taylor_start

    subroutine expand(self, sys, w, t, y)
        type(taylor_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        real(dp), intent(inout) :: w(0:, :)
        real(dp), intent(in) :: t, y(:)
        w(0, 1:self%n) = y
        call sys%taylor_jet(self%kind, t, self%order, self%nw, w)
        self%st%nfev = self%st%nfev + 1
    end subroutine expand

    !> The tolerance scale E_i = max(atol_i, rtol_i ||y||_inf) (per block: state, Phi):
    !! Jorba and Zou's absolute control for small states, relative for large ones.
    pure subroutine scales(self, y, e)
        type(taylor_stepper), intent(in) :: self
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: e(:)
        real(dp) :: y1, y2
        integer :: nb
        nb = self%nblock
        y1 = maxval(abs(y(1:nb)))
        e(1:nb) = max(self%atol(1:nb), self%rtol(1:nb)*y1)
        if (self%n > nb) then
            y2 = maxval(abs(y(nb + 1:)))
            e(nb + 1:) = max(self%atol(nb + 1:), self%rtol(nb + 1:)*y2)
        end if
        e = max(e, tiny(1.0_dp))
    end subroutine scales

    !> Jorba and Zou's step from the current expansion (unsigned, at most hmax).
    subroutine propose(self)
        type(taylor_stepper), intent(inout) :: self
        real(dp) :: e(self%n), s1, s2, rho
        integer :: p, i
        p = self%order
        call scales(self, self%y, e)
        s1 = 0.0_dp
        s2 = 0.0_dp
        do i = 1, self%n
            s1 = max(s1, abs(self%jet(p - 1, i))/e(i))
            s2 = max(s2, abs(self%jet(p, i))/e(i))
        end do
        s1 = s1*self%eps
        s2 = s2*self%eps
        rho = huge(1.0_dp)
        if (s1 > 0.0_dp) rho = s1**(-1.0_dp/real(p - 1, dp))
        if (s2 > 0.0_dp) rho = min(rho, s2**(-1.0_dp/real(p, dp)))
        if (rho < huge(1.0_dp)) rho = rho*exp(-2.0_dp - 0.7_dp/real(p - 1, dp))
        self%h = min(rho, self%hmax)*self%posneg
    end subroutine propose

    !> One accepted step towards `target` (landing on it if the step would pass it).
    subroutine taylor_step(self, sys, target, info, msg)
        type(taylor_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: target
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        real(dp) :: h, ynew(self%n), e(self%n), err, d
        integer :: i, k, p
        character(len=32) :: buf
        real(dp), allocatable :: tmp(:, :)
        info = CM_SUCCESS
        msg = "success"
        p = self%order
        h = self%h
        self%hit = .false.
        self%last = .false.
        call scales(self, self%y, e)
        do
            if (self%nsteps >= self%max_steps) then
                info = CM_TOO_MANY_STEPS
                write (buf, '(es14.6)') self%t
                msg = "more than max_steps steps, at t ="//trim(buf)
                return
            end if
            if (0.1_dp*abs(h) <= abs(self%t)*epsilon(1.0_dp) .or. h == 0.0_dp) then
                info = CM_STEP_TOO_SMALL
                write (buf, '(es14.6)') self%t
                msg = "step size too small at t ="//trim(buf)
                return
            end if
            self%hit = .false.
            if ((self%t + h - target)*self%posneg >= 0.0_dp) then
                h = (target - self%t) - self%t_lo
                self%hit = .true.
            end if
            self%nsteps = self%nsteps + 1
            ! y(t + h) and the polynomial's derivative there (Horner)
            do i = 1, self%n
                ynew(i) = self%jet(p, i)
                self%dy(i) = real(p, dp)*self%jet(p, i)
                do k = p - 1, 1, -1
                    ynew(i) = self%jet(k, i) + h*ynew(i)
                    self%dy(i) = real(k, dp)*self%jet(k, i) + h*self%dy(i)
                end do
                ynew(i) = self%jet(0, i) + h*ynew(i)
            end do
            call expand(self, sys, self%jold, self%t + h, ynew)
            ! safety check: h (P'(h) - f(t + h, P(h))) ~ (p + 1) x local error
            err = 0.0_dp
            do i = 1, self%n
                d = abs(h*(self%dy(i) - self%jold(1, i)))
                err = max(err, d/(real(p + 1, dp)*(e(i) + 16.0_dp*epsilon(1.0_dp)* &
                                                   (abs(ynew(i)) + abs(h*self%dy(i))))))
            end do
            if (err <= CHECK_MAX) exit
            ! rejected (or not finite): a shorter step from the same expansion
            self%st%nreject = self%st%nreject + 1
            if (err == err .and. err <= huge(1.0_dp)) then
                h = h*max(0.1_dp, min(0.5_dp, 0.8_dp*(CHECK_MAX/err)**(1.0_dp/real(p + 1, dp))))
            else
                h = 0.1_dp*h
            end if
        end do
        ! accept: the new expansion becomes the current one, the old the step's polynomial
        self%err = err
        call move_alloc(self%jet, tmp)
        call move_alloc(self%jold, self%jet)
        call move_alloc(tmp, self%jold)
        self%st%naccept = self%st%naccept + 1
        self%t_old = self%t
        self%y_old = self%y
        if (self%hit) then
            self%t = target
            self%t_lo = 0.0_dp
        else
            call add_time(self%t, self%t_lo, h)
        end if
        self%y = ynew
        self%h_done = h
        self%dense_ready = .false.
        self%last = self%hit .and. target == self%tf
        call propose(self)
        self%st%h_next = self%h
    end subroutine taylor_step

    !> (t, t_lo) += h in double length (Knuth's TwoSum): the time of a long run keeps its
    !! last bits, so the state (propagated by the exact sum of the steps) and t agree.
    pure subroutine add_time(t, t_lo, h)
        real(dp), intent(inout) :: t, t_lo
        real(dp), intent(in) :: h
        real(dp) :: s, bb, lo
        s = t + h
        bb = s - t
        lo = (t - (s - bb)) + (h - bb)
        lo = lo + t_lo
        t = s + lo
        t_lo = lo - (t - s)
    end subroutine add_time

    !> The continuous extension of the last step: fc(:, k) = y^[k] h^k (power form in
    !! x = (s - t_old)/h_done).
    subroutine taylor_dense(self, sys)
        class(taylor_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        real(dp) :: hk
        integer :: k
        hk = 1.0_dp
        do k = 0, self%order
            self%fc(:, k) = self%jold(k, 1:self%n)*hk
            hk = hk*self%h_done
        end do
        self%dense_ready = .true.
    end subroutine taylor_dense

    !> The last step's Taylor polynomial at tt (in [t_old, t]).
    subroutine taylor_eval(self, tt, yout)
        class(taylor_stepper), intent(inout) :: self
        real(dp), intent(in) :: tt
        real(dp), intent(out) :: yout(:)
        real(dp) :: s
        integer :: i, k
        s = tt - self%t_old
        do i = 1, self%n
            yout(i) = self%jold(self%order, i)
            do k = self%order - 1, 0, -1
                yout(i) = self%jold(k, i) + s*yout(i)
            end do
        end do
    end subroutine taylor_eval

    !> After a hook changed y: the expansion at the new point (and a new step).
    subroutine taylor_refresh(self, sys)
        class(taylor_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        call expand(self, sys, self%jet, self%t, self%y)
        call propose(self)
    end subroutine taylor_refresh

    logical function taylor_f_finite(self)
        class(taylor_stepper), intent(in) :: self
        taylor_f_finite = all(ieee_is_finite(self%jet(1, 1:self%n)))
    end function taylor_f_finite

    !> Advance y from t0 to t1 in place by Taylor's method (kind 0: the system, kind 1: its
    !! variational system), storing nothing: the lean path for shooting and ensembles.
    subroutine taylor_propagate(sys, t0, t1, y, opt, info, stats, msg, kind)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t0, t1
        real(dp), intent(inout) :: y(:)
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        type(ode_stats), intent(out) :: stats
        character(len=:), allocatable, intent(out) :: msg
        integer, intent(in), optional :: kind
        type(taylor_stepper) :: stp
        character(len=32) :: buf
        stats = ode_stats()
        call taylor_init(stp, sys, t0, t1, y, opt, info, msg, kind)
        if (info /= CM_SUCCESS .or. t1 == t0) return
        call taylor_start(stp, sys, info, msg)
        if (info /= CM_SUCCESS) then
            stats = stp%st
            return
        end if
        do
            call taylor_step(stp, sys, t1, info, msg)
            if (info /= CM_SUCCESS) exit
            if (.not. stp%f_finite()) then
                info = CM_NONFINITE
                write (buf, '(es14.6)') stp%t
                msg = "non-finite right-hand side at t ="//trim(buf)
                exit
            end if
            if (stp%last) exit
        end do
        y = stp%y
        stats = stp%st
    end subroutine taylor_propagate

end module conmech_taylor_stepper
