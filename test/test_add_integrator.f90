!> Adding an integrator, as docs/guide/adding_an_integrator.rst says: Heun's 2(1) pair
!! (explicit trapezoidal rule with Euler's method as the embedded estimate, f at the step's
!! end shared with the next step, cubic Hermite extension) as one type extending
!! `ode_stepper`, handed to ode_solve at run time (`stepper=`). Asserts its observed order
!! (the local error of one step falls as h^3: order 2), that it runs through ode_solve
!! with t_eval and events (harmonic oscillator: the exact solution at the points, the
!! zeros of x at the odd multiples of pi/2), and that its packed state
!! continues the run bit for bit.
module heun_stepper_mod
    use conmech
    implicit none
    private
    public :: heun_stepper, METHOD_HEUN

    !> The toy method's code (outside the table's: it is handed to ode_solve at run time).
    integer, parameter :: METHOD_HEUN = 100

    !> Heun's method with its own step control; the contract's common state plus this.
    type, extends(ode_stepper) :: heun_stepper
        real(dp) :: first_step = 0.0_dp, hmax = 0.0_dp
        real(dp), allocatable :: rtol(:), atol(:), f0(:), f1(:), k2(:), ynew(:)
    contains
        procedure :: setup => heun_setup
        procedure :: start => heun_start
        procedure :: step => heun_step
        procedure :: transfer_state => heun_transfer
    end type heun_stepper

contains

    !> The options (tolerances, first_step not longer than the interval), the degree and
    !! form of the extension (cubic, power basis), the arrays.
    subroutine heun_setup(self, opt, info, msg)
        class(heun_stepper), intent(inout) :: self
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        call check_first_step(self, opt, info, msg)
        if (info /= CM_SUCCESS) return
        call tolerance_vectors(opt, self%n, self%rtol, self%atol, info, msg)
        if (info /= CM_SUCCESS) return
        self%method = METHOD_HEUN
        self%nf = 3
        self%form = FORM_POWER
        self%first_step = opt%first_step
        self%hmax = min(opt%max_step, abs(self%tf - self%t))
        self%f0 = self%y           ! (work arrays of y's size, allocated on assignment)
        self%f1 = self%y
        self%k2 = self%y
        self%ynew = self%y
    end subroutine heun_setup

    !> f at t0; the first step given or 1e-3 of the interval.
    subroutine heun_start(self, sys, info, msg)
        class(heun_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        call sys%rhs(self%t, self%y, self%f1)
        self%st%nfev = self%st%nfev + 1
        self%h = self%first_step
        if (self%h == 0.0_dp) self%h = 1.0e-3_dp*abs(self%tf - self%t)
        self%h = sign(min(self%h, self%hmax), self%posneg)
        info = CM_SUCCESS
        msg = "success"
    end subroutine heun_start

    !> Attempts until the error estimate h/2 |f(t+h, y+h f0) - f0| passes the tolerance.
    subroutine heun_step(self, sys, target, info, msg)
        class(heun_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: target
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        real(dp) :: err, h, dy(self%n)
        info = CM_SUCCESS
        self%f0 = self%f1
        do
            h = self%h
            self%hit = (self%t + 1.01_dp*h - target)*self%posneg > 0.0_dp
            if (self%hit) h = target - self%t
            call sys%rhs(self%t + h, self%y + h*self%f0, self%k2)
            self%ynew = self%y + 0.5_dp*h*(self%f0 + self%k2)
            self%st%nfev = self%st%nfev + 1
            err = sqrt(sum((0.5_dp*h*(self%k2 - self%f0)/(self%atol + self%rtol* &
                                                           max(abs(self%y), abs(self%ynew))))**2)/self%n)
            self%h = sign(min(self%hmax, abs(h)*min(5.0_dp, max(0.2_dp, &
                                                                 0.9_dp/sqrt(max(err, 1.0e-10_dp))))), self%posneg)
            if (err <= 1.0_dp) exit
            self%st%nreject = self%st%nreject + 1
            if (abs(self%h) <= 4.0_dp*epsilon(1.0_dp)*abs(self%t)) then
                info = CM_STEP_TOO_SMALL
                msg = "step size too small"
                return
            end if
        end do
        self%t_old = self%t
        self%y_old = self%y
        self%h_done = h
        self%t = self%t + h
        if (self%hit) self%t = target
        self%y = self%ynew
        self%last = self%hit .and. target == self%tf
        call sys%rhs(self%t, self%y, self%f1)        ! the next step's f0
        self%st%nfev = self%st%nfev + 1
        self%st%naccept = self%st%naccept + 1
        ! cubic Hermite in x = (s - t_old)/h from y, f at both ends (power basis)
        dy = self%y - self%y_old
        self%fc(:, 0) = self%y_old
        self%fc(:, 1) = h*self%f0
        self%fc(:, 2) = 3.0_dp*dy - h*(2.0_dp*self%f0 + self%f1)
        self%fc(:, 3) = h*(self%f0 + self%f1) - 2.0_dp*dy
        self%dense_ready = .true.
    end subroutine heun_step

    !> Everything the next step needs, named once.
    subroutine heun_transfer(self, p)
        class(heun_stepper), intent(inout) :: self
        type(state_packer), intent(inout) :: p
        call self%transfer_base(p)
        call p%item(self%first_step)
        call p%item(self%hmax)
        call p%column(self%rtol)
        call p%column(self%atol)
        call p%column(self%f1)
        if (p%reading()) then
            self%f0 = self%y
            self%k2 = self%y
            self%ynew = self%y
        end if
    end subroutine heun_transfer

end module heun_stepper_mod

!> The events of the test: x = 0.
module heun_events_mod
    use conmech
    implicit none
    type, extends(ode_events) :: x_zero
    contains
        procedure :: eval => x_zero_eval
    end type x_zero
contains
    subroutine x_zero_eval(self, t, y, g)
        class(x_zero), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: g(:)
        g(1) = y(1)
    end subroutine x_zero_eval
end module heun_events_mod

program test_add_integrator
    use conmech
    use conmech_testing, only: test_suite
    use heun_stepper_mod, only: heun_stepper, METHOD_HEUN
    use heun_events_mod, only: x_zero
    implicit none
    type(test_suite) :: ts
    type(ode_function) :: f
    type(ode_options) :: opt
    type(ode_result) :: r
    type(heun_stepper) :: hs
    type(heun_stepper), allocatable :: h1, h2
    type(x_zero) :: ev
    type(state_packer) :: pk
    real(dp) :: err(2), t_eval(21)
    integer :: k, info
    character(len=:), allocatable :: msg

    ts%name = "test_add_integrator"
    f%f => osc

    ! observed order: one step of h and of h/2 from (1, 0) (tolerances that accept it)
    opt%rtol = 1.0_dp
    opt%atol = 1.0_dp
    do k = 1, 2
        opt%first_step = 0.1_dp/2**k
        call hs%init(0.0_dp, 1.0_dp, [1.0_dp, 0.0_dp], opt, info, msg)
        call hs%start(f, info, msg)
        call hs%step(f, 1.0_dp, info, msg)
        err(k) = maxval(abs(hs%y - [cos(hs%t), -sin(hs%t)]))
    end do
    call ts%check_close(log(err(1)/err(2))/log(2.0_dp), 3.0_dp, 0.1_dp, &
                        "local error ~ h^3 (order 2)")

    ! through ode_solve with t_eval and events: a stepper handed over at run time
    opt%rtol = 1.0e-9_dp
    opt%atol = 1.0e-9_dp
    opt%first_step = 0.0_dp
    t_eval = [(0.5_dp*k, k=0, 20)]
    allocate (ev%direction(1), ev%terminal(1))
    ev%direction = 0
    ev%terminal = .false.
    call ode_solve(f, [0.0_dp, 10.0_dp], [1.0_dp, 0.0_dp], opt, r, t_eval=t_eval, &
                   events=ev, stepper=hs)
    call ts%check(r%success .and. r%nt == 21 .and. all(r%t == t_eval), &
                  "ode_solve with the new stepper: the t_eval points: "//r%message)
    call ts%check_less(maxval(abs(r%y(1, :) - cos(t_eval))), 1.0e-5_dp, &
                       "x at t_eval = cos t")
    call ts%check(r%nev == 3, "three zeros of x in [0, 10]")
    call ts%check_less(maxval(abs(r%ev_t(1:r%nev) - [(pi*(k - 0.5_dp), k=1, 3)])), &
                       1.0e-5_dp, "the zeros at (k - 1/2) pi")
    call ts%check(r%stats%naccept > 100 .and. r%stats%nfev == 2*r%stats%naccept + &
                  r%stats%nreject + 1, "two evaluations per accepted step")

    ! the packed state continues the run bit for bit
    opt%first_step = 0.0_dp
    call ode_solve(f, [0.0_dp, 3.0_dp], [1.0_dp, 0.0_dp], opt, r, stepper=hs)
    allocate (h1)
    call h1%init(0.0_dp, 3.0_dp, [1.0_dp, 0.0_dp], opt, info, msg)
    call h1%start(f, info, msg)
    do k = 2, r%nt
        call stepper_pack(h1, pk)
        allocate (h2)
        call stepper_unpack(h2, METHOD_HEUN, pk%r(1:pk%nr), pk%iv(1:pk%ni), pk%w(:, 1:pk%nw), info, &
                            msg)
        call move_alloc(h2, h1)
        call h1%step(f, 3.0_dp, info, msg)
        if (h1%t /= r%t(k) .or. any(h1%y /= r%y(:, k))) exit
    end do
    call ts%check(k == r%nt + 1 .and. h1%last .and. h1%st%nfev == r%stats%nfev, &
                  "packed and unpacked at every step: ode_solve's steps, bit for bit")
    call ts%finish()
    deallocate (h1)         ! (main-program allocatables are not freed at exit)
    if (allocated(msg)) deallocate (msg)

contains

    subroutine osc(t, y, dydt)
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        dydt = [y(2), -y(1)]
    end subroutine osc

end program test_add_integrator
