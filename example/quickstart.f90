!> Quickstart: define your own system with its parameters, integrate it with DOP853,
!! get output at chosen times, find events, and evaluate the dense output.
!!   fpm run --example quickstart
module quickstart_system
    use conmech
    implicit none
    private
    public :: damped_oscillator, zero_crossing

    !> x'' + 2 zeta omega x' + omega^2 x = 0, y = [x, x'].
    type, extends(ode_system) :: damped_oscillator
        real(dp) :: omega = 1.0_dp
        real(dp) :: zeta = 0.1_dp
    contains
        procedure :: rhs => damped_rhs
    end type damped_oscillator

    !> One event function: x = 0.
    type, extends(ode_events) :: zero_crossing
    contains
        procedure :: eval => crossing_eval
    end type zero_crossing

contains

    subroutine damped_rhs(self, t, y, dydt)
        class(damped_oscillator), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        dydt(1) = y(2)
        dydt(2) = -2.0_dp*self%zeta*self%omega*y(2) - self%omega**2*y(1)
    end subroutine damped_rhs

    subroutine crossing_eval(self, t, y, g)
        class(zero_crossing), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: g(:)
        g(1) = y(1)
    end subroutine crossing_eval

end module quickstart_system

program quickstart
    use conmech
    use quickstart_system
    implicit none
    type(damped_oscillator) :: sys
    type(zero_crossing) :: ev
    type(ode_options) :: opt
    type(ode_result) :: res
    real(dp) :: y(2), wd
    integer :: i

    sys%omega = 2.0_dp
    sys%zeta = 0.05_dp
    opt%method = METHOD_DOP853
    opt%rtol = 1.0e-10_dp
    opt%atol = 1.0e-10_dp
    opt%dense_output = .true.
    ev%direction = [-1]          ! downward crossings only
    ev%terminal = [.false.]

    call ode_solve(sys, [0.0_dp, 10.0_dp], [1.0_dp, 0.0_dp], opt, res, &
                   t_eval=[(real(i, dp), i=0, 10)], events=ev)
    if (.not. res%success) then
        write (*, '(a)') "integration failed: "//res%message
        stop 1
    end if
    write (*, '(a)') "     t            x            x'"
    do i = 1, res%nt
        write (*, '(f6.2,2es14.5)') res%t(i), res%y(:, i)
    end do
    wd = sys%omega*sqrt(1.0_dp - sys%zeta**2)
    write (*, '(/,a,i0,a)') "downward zero crossings (", res%nev, "):"
    write (*, '(a,f16.12,a,f16.12)') "  first at t =", res%ev_t(1), &
        ",  spacing ", res%ev_t(2) - res%ev_t(1)
    write (*, '(a,f16.12)') "  damped period 2 pi / omega_d =", 2.0_dp*pi/wd
    call res%sol%eval(2.5_dp, y)
    write (*, '(/,a,2es14.5)') "dense output at t = 2.5:", y
    write (*, '(a,i0,a,i0,a,i0)') "nfev = ", res%stats%nfev, ", accepted = ", &
        res%stats%naccept, ", rejected = ", res%stats%nreject
end program quickstart
