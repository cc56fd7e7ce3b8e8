!> Ensembles: the periods of 2,000 pendulums of different amplitudes in one call, in OpenMP
!! threads (build with --flag -fopenmp; serial otherwise, same results), from the first
!! event of each member; and pendulums of different lengths through `ensemble_members`.
!!   fpm run --example ensemble_quickstart [--flag -fopenmp]
module ensemble_quickstart_members
    use conmech
    implicit none
    private
    public :: lengths

    !> Member i: the pendulum of length ls(i).
    type, extends(ensemble_members) :: lengths
        real(dp), allocatable :: ls(:)
    contains
        procedure :: count => lengths_count
        procedure :: system => lengths_system
    end type lengths

contains

    integer function lengths_count(self)
        class(lengths), intent(in) :: self
        lengths_count = size(self%ls)
    end function lengths_count

    subroutine lengths_system(self, i, sys, info, msg)
        class(lengths), intent(in) :: self
        integer, intent(in) :: i
        class(ode_system), allocatable, intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        allocate (sys, source=pendulum_theta(g=9.81_dp, l=self%ls(i)))
        info = CM_SUCCESS
        msg = "success"
    end subroutine lengths_system

end module ensemble_quickstart_members

program ensemble_quickstart
    use conmech
    use ensemble_quickstart_members, only: lengths
    implicit none
    integer, parameter :: m = 2000
    type(pendulum_theta) :: pend
    type(ode_options) :: opt
    type(ensemble_result) :: ens
    type(crossing_events) :: rest
    type(lengths) :: family
    real(dp) :: y0(2, m), amp, kk, a, b, c
    integer :: i, j

    ! amplitudes 0.01 .. 3 rad, released at rest; theta' (negative at first) rises through
    ! zero at half a period: the first event, terminal
    do i = 1, m
        y0(:, i) = [0.01_dp + (3.0_dp - 0.01_dp)*(i - 1)/(m - 1), 0.0_dp]
    end do
    rest%component = [2]
    rest%value = [0.0_dp]
    rest%direction = [1]
    rest%terminal = [.false.]
    opt%method = METHOD_DOP853
    opt%rtol = 1.0e-10_dp
    opt%atol = 1.0e-10_dp
    call ode_ensemble(pend, [0.0_dp, 100.0_dp], y0, opt, ens, events=rest, &
                      ens_options=ensemble_options(max_events=1, terminal=.true.))
    if (ens%status /= CM_SUCCESS) error stop ens%message
    write (*, '(a,i0,a,i0,a)') "periods of ", m, " pendulums (", sum(ens%nfev), &
        " evaluations); exact: 4 sqrt(l/g) K(sin(amp/2))"
    do i = 1, m, 400
        amp = y0(1, i)
        ! K(k) by the arithmetic-geometric mean
        kk = sin(0.5_dp*amp)
        a = 1.0_dp
        b = sqrt(1.0_dp - kk**2)
        do j = 1, 30
            c = 0.5_dp*(a + b)
            b = sqrt(a*b)
            a = c
        end do
        write (*, '(a,f6.3,a,f14.10,a,es9.2)') "  amplitude ", amp, "  period ", &
            2.0_dp*ens%t_final(i), "  error ", &
            abs(2.0_dp*ens%t_final(i) - 4.0_dp*sqrt(1.0_dp/9.81_dp)*acos(-1.0_dp)/(2.0_dp*a))
    end do

    ! parameters per member: lengths 0.25 .. 4, one shared initial state
    family%ls = [0.25_dp, 0.5_dp, 1.0_dp, 2.0_dp, 4.0_dp]
    call ode_ensemble(family, [0.0_dp, 100.0_dp], reshape([0.1_dp, 0.0_dp], [2, 1]), opt, &
                      ens, events=rest, ens_options=ensemble_options(terminal=.true.))
    if (ens%status /= CM_SUCCESS) error stop ens%message
    write (*, '(a)') "small oscillations (0.1 rad): period / (2 pi sqrt(l/g))"
    do i = 1, size(family%ls)
        write (*, '(a,f5.2,a,f12.8)') "  l = ", family%ls(i), "  ", &
            2.0_dp*ens%t_final(i)/(2.0_dp*acos(-1.0_dp)*sqrt(family%ls(i)/9.81_dp))
    end do
end program ensemble_quickstart
