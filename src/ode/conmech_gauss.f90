!> Gauss-Legendre collocation (implicit Runge-Kutta) with s = 2 and s = 3 stages, of
!! orders 4 and 6, as a stepper of the integrator contract (conmech_ode_stepper):
!! symplectic and symmetric, it keeps quadratic invariants (angular momentum) exactly and
!! the energy error of Hamiltonian systems bounded over long times.
!!
!! - Fixed step: h = (tf - t0)/N with N = ceil(|tf - t0|/first_step), the grid t0 + k h
!!   (the last step ends on tf exactly); output points between grid points come from the
!!   continuous extension (the stepper does not shorten steps onto them).
!! - Stage equations Z_i = h sum_j a_ij f(t + c_j h, y + Z_j) solved by fixed-point
!!   iteration to round-off (Hairer-Lubich-Wanner, GNI VIII.6): iterate until the
!!   correction vanishes or stops decreasing at the round-off level; starting
!!   values from the collocation polynomial of the previous step. At most 50 iterations:
!!   otherwise (h too large for the iteration to contract, e.g. a stiff system) the run
!!   stops with CM_NO_CONVERGENCE and the time.
!! - Compensated (Kahan) summation of y_{n+1} = y_n + h sum_i b_i f_i, so that round-off
!!   does not random-walk the invariants.
!! - Continuous extension: the collocation polynomial (degree s, power basis).
module conmech_gauss
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_text, only: rtoa
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: ode_options, METHOD_GAUSS4, METHOD_GAUSS6
    use conmech_ode_dense, only: power_basis_matrix
    use conmech_ode_stepper, only: ode_stepper, check_first_step, FORM_POWER
    use conmech_state_packer, only: state_packer
    use conmech_fixed_grid, only: grid_steps, check_grid_steps, grid_time
    implicit none
    private

    public :: gauss_stepper, gauss_tableau

    integer, parameter :: MAX_ITER = 50

    !> The state of a Gauss-Legendre integration on its fixed grid.
    type, extends(ode_stepper) :: gauss_stepper
        integer :: s = 0                      !! stages (2 or 3)
        integer :: kdone = 0                  !! grid steps done
        integer :: nsteps = 0                 !! grid steps of the run
        integer :: max_steps = 100000
        real(dp) :: t_start = 0.0_dp          !! t0 of the grid
        real(dp) :: first_step = 0.0_dp       !! the option: the step asked for
        logical :: have_poly = .false.        !! fc holds the last step's polynomial
        real(dp), allocatable :: a(:, :), b(:), c(:), pmat(:, :)   !! tableau, basis
        real(dp), allocatable :: comp(:)      !! compensation of the summation
        real(dp), allocatable :: z(:, :), znew(:, :), f(:, :), incr(:), tmp(:)
    contains
        procedure :: setup => gauss_setup
        procedure :: start => gauss_start
        procedure :: step => gauss_step
        procedure :: transfer_state => gauss_transfer
        procedure :: refresh_f => gauss_refresh_f
    end type gauss_stepper

contains

    !> Butcher tableau (a, b, c) of the s-stage Gauss-Legendre method, s = 2 or 3.
    pure subroutine gauss_tableau(s, a, b, c)
        integer, intent(in) :: s
        real(dp), intent(out) :: a(s, s), b(s), c(s)
        real(dp) :: r3, r15
        if (s == 2) then
            r3 = sqrt(3.0_dp)
            c = [0.5_dp - r3/6.0_dp, 0.5_dp + r3/6.0_dp]
            b = [0.5_dp, 0.5_dp]
            a(1, :) = [0.25_dp, 0.25_dp - r3/6.0_dp]
            a(2, :) = [0.25_dp + r3/6.0_dp, 0.25_dp]
        else
            r15 = sqrt(15.0_dp)
            c = [0.5_dp - r15/10.0_dp, 0.5_dp, 0.5_dp + r15/10.0_dp]
            b = [5.0_dp/18.0_dp, 4.0_dp/9.0_dp, 5.0_dp/18.0_dp]
            a(1, :) = [5.0_dp/36.0_dp, 2.0_dp/9.0_dp - r15/15.0_dp, 5.0_dp/36.0_dp - r15/30.0_dp]
            a(2, :) = [5.0_dp/36.0_dp + r15/24.0_dp, 2.0_dp/9.0_dp, 5.0_dp/36.0_dp - r15/24.0_dp]
            a(3, :) = [5.0_dp/36.0_dp + r15/30.0_dp, 2.0_dp/9.0_dp + r15/15.0_dp, 5.0_dp/36.0_dp]
        end if
    end subroutine gauss_tableau

    !> The stages from the method code, the tableau, the basis and the work arrays.
    subroutine set_method(self, method, n)
        type(gauss_stepper), intent(inout) :: self
        integer, intent(in) :: method, n
        integer :: s
        s = merge(2, 3, method == METHOD_GAUSS4)
        self%s = s
        if (allocated(self%a)) deallocate (self%a, self%b, self%c, self%pmat, self%z, &
                                           self%znew, self%f, self%incr, self%tmp)
        allocate (self%a(s, s), self%b(s), self%c(s), self%pmat(s, s), self%z(n, s), &
                  self%znew(n, s), self%f(n, s), self%incr(n), self%tmp(n))
        call gauss_tableau(s, self%a, self%b, self%c)
        self%pmat = power_basis_matrix(self%c)
        self%z = 0.0_dp
    end subroutine set_method

    !> The method's part of init: the stages, the step option, the grid (no evaluation).
    subroutine gauss_setup(self, opt, info, msg)
        class(gauss_stepper), intent(inout) :: self
        type(ode_options), intent(in) :: opt
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        real(dp) :: t0, tf
        if (opt%method /= METHOD_GAUSS4 .and. opt%method /= METHOD_GAUSS6) then
            info = CM_BAD_INPUT
            msg = "bad input: Gauss methods have s = 2 or 3 stages (METHOD_GAUSS4, " &
                  //"METHOD_GAUSS6)"
            return
        end if
        call check_first_step(self, opt, info, msg, fixed="Gauss")
        if (info /= CM_SUCCESS) return
        call set_method(self, opt%method, self%n)
        t0 = self%t
        tf = self%tf
        self%nf = self%s
        self%form = FORM_POWER
        self%lands_on_target = .false.
        self%t_start = t0
        self%first_step = opt%first_step
        self%max_steps = opt%max_steps
        self%kdone = 0
        self%have_poly = .false.
        self%comp = self%y
        self%comp = 0.0_dp
        self%nsteps = grid_steps(t0, tf, opt%first_step)
        if (self%nsteps > 0) self%h = (tf - t0)/real(self%nsteps, dp)
    end subroutine gauss_setup

    !> The grid is fixed: only its length is checked against max_steps (no evaluation).
    subroutine gauss_start(self, sys, info, msg)
        class(gauss_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        msg = "success"
        call check_grid_steps(self%nsteps, self%max_steps, info, msg)
    end subroutine gauss_start

    !> The next step of the grid (`target` is not used: the grid ends on tf).
    subroutine gauss_step(self, sys, target, info, msg)
        class(gauss_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: target
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        real(dp) :: xi, dyno, dynold, scale, h, tnew
        integer :: i, j, it, k, s
        logical :: converged
        info = CM_SUCCESS
        s = self%s
        h = self%h
        k = self%kdone + 1
        associate (z => self%z, f => self%f, fc => self%fc, y => self%y, c => self%c)
            ! starting values: the previous collocation polynomial, u(1 + c_i) - u(1)
            if (self%have_poly) then
                do i = 1, s
                    xi = 1.0_dp + c(i)
                    z(:, i) = 0.0_dp
                    do j = 1, s
                        z(:, i) = z(:, i) + fc(:, j)*(xi**j - 1.0_dp)
                    end do
                end do
            end if
            scale = max(maxval(abs(y)), tiny(1.0_dp))
            dynold = huge(1.0_dp)
            converged = .false.
            do it = 1, MAX_ITER
                do i = 1, s
                    call sys%rhs(self%t + c(i)*h, y + z(:, i), f(:, i))
                end do
                self%st%nfev = self%st%nfev + s
                if (.not. all(abs(f) <= huge(1.0_dp))) exit
                self%znew = h*matmul(f, transpose(self%a))
                dyno = maxval(abs(self%znew - z))
                z = self%znew
                ! converged when the correction vanishes or stops decreasing at the
                ! round-off level (GNI's criterion)
                if (dyno == 0.0_dp) then
                    converged = .true.
                    exit
                end if
                if (it >= 2 .and. dyno >= dynold .and. &
                    dyno <= 1.0e3_dp*epsilon(1.0_dp)*scale) then
                    converged = .true.
                    exit
                end if
                dynold = dyno
            end do
            if (.not. converged) then
                info = CM_NO_CONVERGENCE
                msg = "the fixed-point iteration of the Gauss stages did not converge at t =" &
                      //rtoa(self%t)//" (step too large, or a stiff or non-finite right-hand side)"
                return
            end if
            ! collocation polynomial: u(0) = y, u(c_i) = y + z_i
            fc(:, 0) = y
            do j = 1, s
                fc(:, j) = matmul(z, self%pmat(j, :))
            end do
            ! compensated summation of y + h sum b_i f_i
            self%incr = h*matmul(f, self%b)
            self%tmp = self%incr + self%comp
            self%y_old = y
            y = y + self%tmp
            self%comp = (self%y_old - y) + self%tmp
        end associate
        self%have_poly = .true.
        self%dense_ready = .true.
        tnew = grid_time(self%t_start, self%tf, h, k, self%nsteps)
        self%kdone = k
        self%last = k == self%nsteps
        self%t_old = self%t
        self%h_done = tnew - self%t
        self%t = tnew
        self%st%naccept = self%st%naccept + 1
    end subroutine gauss_step

    !> After a hook changed y: the compensation of the summation no longer applies.
    subroutine gauss_refresh_f(self, sys)
        class(gauss_stepper), intent(inout) :: self
        class(ode_system), intent(in) :: sys
        self%comp = 0.0_dp
        self%f_stale = .false.
    end subroutine gauss_refresh_f

    !> The whole state (conmech_state_packer); the tableau is rebuilt from the method.
    subroutine gauss_transfer(self, p)
        class(gauss_stepper), intent(inout) :: self
        type(state_packer), intent(inout) :: p
        call self%transfer_base(p)
        if (p%reading()) call set_method(self, self%method, self%n)
        call p%item(self%kdone)
        call p%item(self%nsteps)
        call p%item(self%max_steps)
        call p%item(self%t_start)
        call p%item(self%first_step)
        call p%item(self%have_poly)
        call p%column(self%comp)
        call p%columns(self%z, 1, self%s)
    end subroutine gauss_transfer

end module conmech_gauss
