!> Events of a RATTLE run (`events`, functions g(t, y) of y = [q; v], `ode_events`): a
!! sign change of g between grid points (with the event's direction) is located by
!! Brent's method on the RATTLE side step of length tau from the grid point before it (a
!! continuous extension of the step whose states are on the constraint manifold to
!! round-off; its local error is O(h^3), so event times have the method's second order).
!! Events of one step are recorded in time order up to the first terminal one, which
!! stops the run there (`stopped`, `t_stop`).
module conmech_rattle_events
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_constrained_system, only: constrained_system
    use conmech_ode_system, only: ode_events
    use conmech_brent, only: brent_state, brent_init, brent_step, brent_take
    use conmech_rattle_step, only: rattle_state, rattle_work, rattle_step
    implicit none
    private

    public :: rattle_event_log, rattle_events_ok, rattle_events_init, rattle_find_events

    !> The event functions at the current grid point and the events found so far.
    type :: rattle_event_log
        integer :: ne = 0                     !! number of event functions
        integer :: nev = 0                    !! events found
        logical :: stopped = .false.          !! a terminal event occurred
        real(dp) :: t_stop = 0.0_dp           !! its time
        real(dp), allocatable :: g_old(:), g_new(:), yev(:), gv(:)
        real(dp), allocatable :: evt(:)       !! times of the events (capacity >= nev)
        real(dp), allocatable :: evq(:, :)    !! their positions (n x capacity)
        real(dp), allocatable :: evv(:, :)    !! their velocities
        integer, allocatable :: evid(:)       !! which function
    end type rattle_event_log

contains

    !> True when the events (ne functions) have direction and terminal arrays of ne
    !! elements (always for ne = 0).
    logical function rattle_events_ok(events, ne)
        class(ode_events), intent(in), optional :: events
        integer, intent(in) :: ne
        rattle_events_ok = .true.
        if (ne == 0) return
        if (.not. (allocated(events%direction) .and. allocated(events%terminal))) then
            rattle_events_ok = .false.
        else
            rattle_events_ok = size(events%direction) == ne .and. &
                               size(events%terminal) == ne
        end if
    end function rattle_events_ok

    !> An empty event log for ne event functions of a run of n coordinates from (t0, q, v) to
    !! tf (g at t0 evaluated when ne > 0).
    subroutine rattle_events_init(evl, events, ne, n, t0, tf, q, v)
        type(rattle_event_log), intent(out) :: evl
        class(ode_events), intent(in), optional :: events
        integer, intent(in) :: ne, n
        real(dp), intent(in) :: t0, tf, q(:), v(:)
        evl%ne = ne
        evl%nev = 0
        evl%stopped = .false.
        evl%t_stop = tf
        allocate (evl%g_old(ne), evl%g_new(ne), evl%yev(2*n), evl%gv(ne), evl%evt(8), &
                  evl%evq(n, 8), evl%evv(n, 8), evl%evid(8))
        if (ne > 0) call events%eval(t0, [q, v], evl%g_old)
    end subroutine rattle_events_init

    !> Sign changes of the event functions between s0 and s1 (a step of length hs),
    !! each root by Brent's method on the side step from s0 (side: its scratch state);
    !! events recorded in time order (posneg: the direction of integration) up to the
    !! first terminal one (then stopped, t_stop).
    subroutine rattle_find_events(evl, events, sys, wk, s0, s1, hs, posneg, side, inf, mg)
        type(rattle_event_log), intent(inout) :: evl
        class(ode_events), intent(in) :: events
        class(constrained_system), intent(in) :: sys
        type(rattle_work), intent(inout) :: wk
        type(rattle_state), intent(in) :: s0, s1
        real(dp), intent(in) :: hs, posneg
        type(rattle_state), intent(inout) :: side
        integer, intent(out) :: inf
        character(len=:), allocatable, intent(out) :: mg
        real(dp) :: times(evl%ne)
        integer :: ids(evl%ne), nf, i, j, jj, it, n
        logical :: cross, done
        type(brent_state) :: bs
        n = size(s1%q)
        inf = CM_SUCCESS
        evl%yev(1:n) = s1%q
        evl%yev(n + 1:) = s1%v
        call events%eval(s1%t, evl%yev, evl%g_new)
        nf = 0
        do i = 1, evl%ne
            cross = (evl%g_old(i) < 0.0_dp .and. evl%g_new(i) >= 0.0_dp .and. &
                     events%direction(i) >= 0) .or. &
                    (evl%g_old(i) > 0.0_dp .and. evl%g_new(i) <= 0.0_dp .and. &
                     events%direction(i) <= 0)
            if (.not. cross) cycle
            nf = nf + 1
            ids(nf) = i
            times(nf) = s1%t
            if (evl%g_new(i) == 0.0_dp) cycle
            call brent_init(bs, evl%g_old(i), evl%g_new(i), s0%t, hs)
            do it = 1, 200
                call brent_step(bs, done)
                if (done) exit
                call rattle_step(sys, wk, s0, bs%b*hs, side, inf, mg)
                if (inf /= CM_SUCCESS) return
                evl%yev(1:n) = side%q
                evl%yev(n + 1:) = side%v
                call events%eval(side%t, evl%yev, evl%gv)
                call brent_take(bs, evl%gv(i))
            end do
            times(nf) = s0%t + bs%b*hs
        end do
        evl%g_old = evl%g_new
        ! time order (insertion sort, few events)
        do i = 2, nf
            j = i
            do while (j > 1)
                if ((times(j) - times(j - 1))*posneg >= 0.0_dp) exit
                times(j - 1:j) = [times(j), times(j - 1)]
                ids(j - 1:j) = [ids(j), ids(j - 1)]
                j = j - 1
            end do
        end do
        do jj = 1, nf
            if (evl%stopped .and. (times(jj) - evl%t_stop)*posneg > 0.0_dp) exit
            if (times(jj) == s1%t) then
                call push_event(evl, times(jj), s1%q, s1%v, ids(jj))
            else
                call rattle_step(sys, wk, s0, times(jj) - s0%t, side, inf, mg)
                if (inf /= CM_SUCCESS) return
                call push_event(evl, times(jj), side%q, side%v, ids(jj))
            end if
            if (events%terminal(ids(jj)) .and. .not. evl%stopped) then
                evl%stopped = .true.
                evl%t_stop = times(jj)
            end if
        end do
    end subroutine rattle_find_events

    subroutine push_event(evl, tt, qq, vv, id)
        type(rattle_event_log), intent(inout) :: evl
        real(dp), intent(in) :: tt, qq(:), vv(:)
        integer, intent(in) :: id
        real(dp), allocatable :: t2(:), q2(:, :), v2(:, :)
        integer, allocatable :: i2(:)
        integer :: cap, n, nev
        cap = size(evl%evt)
        n = size(qq)
        nev = evl%nev
        if (nev >= cap) then
            allocate (t2(2*cap), q2(n, 2*cap), v2(n, 2*cap), i2(2*cap))
            t2(1:nev) = evl%evt(1:nev)
            q2(:, 1:nev) = evl%evq(:, 1:nev)
            v2(:, 1:nev) = evl%evv(:, 1:nev)
            i2(1:nev) = evl%evid(1:nev)
            call move_alloc(t2, evl%evt)
            call move_alloc(q2, evl%evq)
            call move_alloc(v2, evl%evv)
            call move_alloc(i2, evl%evid)
        end if
        nev = nev + 1
        evl%nev = nev
        evl%evt(nev) = tt
        evl%evq(:, nev) = qq
        evl%evv(:, nev) = vv
        evl%evid(nev) = id
    end subroutine push_event

end module conmech_rattle_events
