!> Ensembles: every member is bit for bit its own ode_solve; parameters through an
!! ensemble_members object; events (first k, terminal at the k-th); progress and cancel;
!! bad input.
module test_ensemble_members
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_systems_basic, only: pendulum_theta
    use conmech_ensemble, only: ensemble_members, ensemble_progress
    implicit none
    private
    public :: pendulum_lengths, stop_after

    !> Pendulums of lengths ls(i) (g = 9.81); a negative length cannot be built.
    type, extends(ensemble_members) :: pendulum_lengths
        real(dp), allocatable :: ls(:)
    contains
        procedure :: count => lengths_count
        procedure :: system => lengths_system
    end type pendulum_lengths

    !> Records the reports and cancels once `limit` members are done.
    type, extends(ensemble_progress) :: stop_after
        integer :: limit = huge(1)
        integer :: calls = 0
        integer :: last_done = 0
    contains
        procedure :: report => stop_report
    end type stop_after

contains

    integer function lengths_count(self)
        class(pendulum_lengths), intent(in) :: self
        lengths_count = size(self%ls)
    end function lengths_count

    subroutine lengths_system(self, i, sys, info, msg)
        class(pendulum_lengths), intent(in) :: self
        integer, intent(in) :: i
        class(ode_system), allocatable, intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(pendulum_theta) :: p
        if (self%ls(i) <= 0.0_dp) then
            info = CM_BAD_INPUT
            msg = "bad input: the length must be positive"
            return
        end if
        p%l = self%ls(i)
        allocate (sys, source=p)
        info = CM_SUCCESS
        msg = "success"
    end subroutine lengths_system

    subroutine stop_report(self, done, total, cancel)
        class(stop_after), intent(inout) :: self
        integer, intent(in) :: done, total
        logical, intent(out) :: cancel
        self%calls = self%calls + 1
        self%last_done = done
        cancel = done >= self%limit .and. done < total
    end subroutine stop_report

end module test_ensemble_members

program test_ensemble
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_solver, only: ode_options, ode_result, ode_solve, METHOD_DOP853, &
        METHOD_DOPRI5
    use conmech_systems_basic, only: kepler_2d, pendulum_theta
    use conmech_ensemble
    use conmech_testing, only: test_suite
    use test_ensemble_members, only: pendulum_lengths, stop_after
    implicit none
    type(test_suite) :: suite
    integer, parameter :: m = 12
    type(kepler_2d) :: kep
    type(ode_options) :: opt
    type(ode_result) :: r
    type(ensemble_result) :: ens, ens1
    type(ensemble_options) :: eo
    type(crossing_events) :: cross
    type(pendulum_lengths) :: lengths
    type(stop_after) :: prog
    real(dp) :: y0(4, m), e, t_eval(7), pi
    integer :: i, j
    logical :: same, same_ev

    suite%name = "test_ensemble"
    pi = acos(-1.0_dp)
    opt%method = METHOD_DOP853
    opt%rtol = 1.0e-9_dp
    opt%atol = 1.0e-9_dp
    do i = 1, m
        e = 0.05_dp*(i - 1)
        y0(:, i) = [1.0_dp - e, 0.0_dp, 0.0_dp, sqrt((1.0_dp + e)/(1.0_dp - e))]
    end do
    t_eval = [(1.0_dp*j, j=0, 6)]

    ! ---- final states: each member is its own ode_solve, bit for bit
    call ode_ensemble(kep, [0.0_dp, 2.0_dp*pi], y0, opt, ens)
    call suite%check(ens%status == CM_SUCCESS .and. ens%done == m, "Kepler ensemble succeeds")
    same = .true.
    do i = 1, m
        call ode_solve(kep, [0.0_dp, 2.0_dp*pi], y0(:, i), opt, r)
        same = same .and. all(r%y(:, r%nt) == ens%y_final(:, i)) .and. &
               r%t(r%nt) == ens%t_final(i) .and. r%stats%nfev == ens%nfev(i) .and. &
               r%stats%naccept == ens%naccept(i) .and. r%stats%nreject == ens%nreject(i)
    end do
    call suite%check(same, "final states, nfev, steps equal the single solves bit for bit")
    call suite%check(maxval(abs(ens%y_final(1, :) - y0(1, :))) < 1.0e-6_dp, &
                     "every orbit closes after one period")

    ! ---- t_eval, two threads, DOPRI5
    opt%method = METHOD_DOPRI5
    eo%threads = 2
    call ode_ensemble(kep, [0.0_dp, 6.0_dp], y0, opt, ens, t_eval=t_eval, ens_options=eo)
    eo%threads = 1
    call ode_ensemble(kep, [0.0_dp, 6.0_dp], y0, opt, ens1, t_eval=t_eval, ens_options=eo)
    same = .true.
    do i = 1, m
        call ode_solve(kep, [0.0_dp, 6.0_dp], y0(:, i), opt, r, t_eval=t_eval)
        same = same .and. all(r%y == ens%y(:, :, i)) .and. r%stats%nfev == ens%nfev(i) &
               .and. ens%t_final(i) == 6.0_dp
    end do
    call suite%check(same, "states at t_eval equal the single solves bit for bit")
    call suite%check(all(ens%y == ens1%y) .and. all(ens%y_final == ens1%y_final) .and. &
                     all(ens%nfev == ens1%nfev), "1 and 2 threads give identical results")

    ! ---- events: crossings of y = 0 upwards (first 2 kept), terminal at the 2nd
    opt%method = METHOD_DOP853
    cross%component = [2]
    cross%value = [0.0_dp]
    cross%direction = [1]
    cross%terminal = [.false.]
    eo%max_events = 2
    eo%terminal = .false.
    call ode_ensemble(kep, [0.0_dp, 20.0_dp], y0, opt, ens, events=cross, ens_options=eo)
    same_ev = ens%status == CM_SUCCESS
    do i = 1, m
        call ode_solve(kep, [0.0_dp, 20.0_dp], y0(:, i), opt, r, events=cross)
        same_ev = same_ev .and. ens%nev(i) == min(2, r%nev) .and. r%nev >= 2
        do j = 1, ens%nev(i)
            same_ev = same_ev .and. ens%ev_t(j, i) == r%ev_t(j) .and. &
                      all(ens%ev_y(:, j, i) == r%ev_y(:, j)) .and. ens%ev_id(j, i) == 1
        end do
        same_ev = same_ev .and. all(ens%y_final(:, i) == r%y(:, r%nt))
    end do
    call suite%check(same_ev, "first two events of each member equal the single solve's")
    ! the first upward crossing of y = 0 after t = 0 is at one period, 2 pi
    call suite%check_close(ens%ev_t(1, 1), 2.0_dp*pi, 1.0e-7_dp, "circular orbit: period")

    ! terminal at the first event: the same as ode_solve with a terminal event
    eo%max_events = 1
    eo%terminal = .true.
    call ode_ensemble(kep, [0.0_dp, 20.0_dp], y0, opt, ens, t_eval=t_eval, events=cross, &
                      ens_options=eo)
    cross%terminal = [.true.]
    same_ev = .true.
    do i = 1, m
        call ode_solve(kep, [0.0_dp, 20.0_dp], y0(:, i), opt, r, t_eval=t_eval, events=cross)
        same_ev = same_ev .and. ens%member_status(i) == CM_EVENT_STOP .and. &
                  r%status == CM_EVENT_STOP .and. ens%t_final(i) == r%ev_t(1) .and. &
                  all(ens%y_final(:, i) == r%ev_y(:, 1)) .and. ens%nfev(i) == r%stats%nfev
        do j = 1, 7
            if (j <= r%nt) then
                same_ev = same_ev .and. all(ens%y(:, j, i) == r%y(:, j))
            else
                same_ev = same_ev .and. all(ens%y(:, j, i) /= ens%y(:, j, i))
            end if
        end do
    end do
    call suite%check(same_ev, "terminal: each member stops as ode_solve with a terminal event")
    ! terminal at the second event: one period further than the first
    eo%max_events = 2
    call ode_ensemble(kep, [0.0_dp, 20.0_dp], y0, opt, ens, events=cross, ens_options=eo)
    call suite%check(all(ens%member_status == CM_EVENT_STOP) .and. all(ens%nev == 2), &
                     "terminal at the 2nd event: every member stops there")
    call suite%check(all(ens%t_final == ens%ev_t(2, :)) .and. &
                     all(abs(ens%y_final(2, :)) < 1.0e-9_dp), "it ends on the section y = 0")

    ! ---- parameters: pendulums of several lengths, periods from the events
    lengths%ls = [0.5_dp, 1.0_dp, 2.0_dp, 4.0_dp]
    cross%component = [2]
    cross%direction = [1]
    eo = ensemble_options(max_events=1, terminal=.true.)
    call ode_ensemble(lengths, [0.0_dp, 10.0_dp], reshape([0.01_dp, 0.0_dp], [2, 1]), opt, &
                      ens, events=cross, ens_options=eo)
    call suite%check(ens%status == CM_SUCCESS, "pendulum lengths: success")
    ! theta' (negative at first) rises through 0 at half a period: pi sqrt(l/g), small amplitude
    call suite%check(maxval(abs(ens%t_final/(pi*sqrt(lengths%ls/9.81_dp)) - 1.0_dp)) &
                     < 1.0e-4_dp, "half periods pi sqrt(l/g)")

    ! ---- a member that cannot be built: its status, the others run
    lengths%ls = [1.0_dp, -1.0_dp, 2.0_dp]
    call ode_ensemble(lengths, [0.0_dp, 1.0_dp], reshape([0.1_dp, 0.0_dp], [2, 1]), opt, ens)
    call suite%check(ens%status == CM_BAD_INPUT .and. ens%member_status(2) == CM_BAD_INPUT &
                     .and. ens%member_status(3) == CM_SUCCESS .and. &
                     index(ens%message, "member 2") > 0, "a bad member is reported by index")

    ! ---- progress: reports between chunks; cancel skips the rest
    prog%limit = 4
    eo = ensemble_options(chunk=4)
    call ode_ensemble(kep, [0.0_dp, 1.0_dp], y0, opt, ens, ens_options=eo, progress=prog)
    call suite%check(prog%calls == 1 .and. prog%last_done == 4 .and. ens%done == 4 .and. &
                     ens%status == CM_USER_ERROR .and. all(ens%member_status(1:4) == 0) .and. &
                     all(ens%member_status(5:) == ENSEMBLE_NOT_RUN), &
                     "cancel after the first chunk: 4 members run, the rest not")
    prog = stop_after()
    call ode_ensemble(kep, [0.0_dp, 1.0_dp], y0, opt, ens, ens_options=eo, progress=prog)
    call suite%check(prog%calls == 3 .and. prog%last_done == m .and. &
                     ens%status == CM_SUCCESS, "three chunks, three reports")

    ! ---- bad input
    call ode_ensemble(kep, [0.0_dp, 1.0_dp], y0(:, 1:0), opt, ens)
    call suite%check(ens%status == CM_BAD_INPUT .and. index(ens%message, "no members") > 0, &
                     "no members: bad input")
    cross%component = [5]
    eo = ensemble_options()
    call ode_ensemble(kep, [0.0_dp, 1.0_dp], y0, opt, ens, events=cross, ens_options=eo)
    call suite%check(ens%status == CM_BAD_INPUT .and. index(ens%message, "component") > 0, &
                     "event component out of range: bad input")
    cross%component = [2]
    eo%max_events = 0
    call ode_ensemble(kep, [0.0_dp, 1.0_dp], y0, opt, ens, events=cross, ens_options=eo)
    call suite%check(ens%status == CM_BAD_INPUT .and. index(ens%message, "max_events") > 0, &
                     "max_events 0: bad input")
    lengths%ls = [1.0_dp, 2.0_dp]
    call ode_ensemble(lengths, [0.0_dp, 1.0_dp], reshape([0.1_dp, 0.0_dp, 0.1_dp, 0.0_dp, &
                      0.2_dp, 0.0_dp], [2, 3]), opt, ens)
    call suite%check(ens%status == CM_BAD_INPUT .and. index(ens%message, "column") > 0, &
                     "y0 columns neither 1 nor m: bad input")
    opt%rtol = -1.0_dp
    call ode_ensemble(kep, [0.0_dp, 1.0_dp], y0, opt, ens)
    call suite%check(ens%status == CM_BAD_INPUT .and. index(ens%message, "rtol") > 0, &
                     "negative rtol: bad input, message names rtol")
    call suite%finish()
end program test_ensemble
