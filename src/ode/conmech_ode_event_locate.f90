!> Event location on the last step of any stepper: sign changes of the event functions
!! (with each event's direction), each root found by Brent's method on the step's
!! continuous extension (`eval_unit`, to near machine precision in t), reported in the
!! order of time (ties in the order the roots were found: by event index for the events
!! without a resolution, as SciPy's) up to the one that ends the run: a
!! terminal event at the occurrence that brings its remaining count to zero (SciPy's
!! handle_events: nothing after it is reported, not even an event at the same time).
!!
!! With `zero_at_t0`, an event exactly zero at t0 is a root at t0 of the first step when
!! the step's end moves it in its direction (SciPy's find_active_events with g_old = 0).
!!
!! By default an event is compared at the step's two ends only (SciPy's rule): one sign
!! change per step and event, so two crossings inside one step cancel and are missed. An
!! event with a `resolution` r > 0 (conmech_ode_system) is also sampled on the continuous
!! extension at m - 1 interior points x = k/m, m = ceiling(|h|/r): every sign change
!! between consecutive samples is located, so crossings more than r apart are all found.
!! The samples cost event evaluations and evaluations of the extension, no evaluation of
!! f and no change of the steps.
module conmech_ode_event_locate
    use, intrinsic :: iso_fortran_env, only: int64
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT, CM_NONFINITE
    use conmech_text, only: itoa, rtoa
    use conmech_ode_system, only: ode_events, ode_step_hook
    use conmech_ode_result, only: ode_result, push_event
    use conmech_ode_stepper, only: ode_stepper
    use conmech_brent, only: brent_state, brent_init, brent_step, brent_take
    implicit none
    private
    public :: find_events, check_events, event_counts

    !> the largest count of sub-intervals of one step (half the int64 range)
    integer(int64), parameter :: M_MAX = ishft(huge(1_int64), -1)

contains

    !> Check the event settings: terminal and direction allocated with one entry per
    !! event, resolution (if allocated) as many entries, each >= 0 and not NaN, count (if
    !! allocated) as many entries, each >= 1.
    subroutine check_events(events, info, msg)
        class(ode_events), intent(in) :: events
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        info = CM_BAD_INPUT
        if (.not. allocated(events%terminal)) then
            msg = "bad input: events%terminal must be allocated"
        else if (size(events%terminal) /= size(events%direction)) then
            msg = "bad input: events%terminal and events%direction differ in size"
        else if (.not. resolution_ok()) then
            msg = "bad input: events%resolution must have one entry per event, each >= 0"
        else if (.not. count_ok()) then
            msg = "bad input: events%count must have one entry per event, each >= 1"
        else
            info = CM_SUCCESS
            msg = "success"
        end if
    contains
        logical function resolution_ok()
            resolution_ok = .true.
            if (.not. allocated(events%resolution)) return
            resolution_ok = size(events%resolution) == size(events%direction)
            if (.not. resolution_ok) return
            resolution_ok = .not. (any(events%resolution /= events%resolution) .or. &
                                   any(events%resolution < 0.0_dp))
        end function resolution_ok
        logical function count_ok()
            count_ok = .true.
            if (.not. allocated(events%count)) return
            count_ok = size(events%count) == size(events%direction)
            if (count_ok) count_ok = all(events%count >= 1)
        end function count_ok
    end subroutine check_events

    !> The occurrences left before each event ends the run, at the start of a run (checked
    !! settings): its count for a terminal event (1 if unallocated), 0 for the others
    !! (never ending it). The run decrements them in `find_events`.
    pure function event_counts(events) result(left)
        class(ode_events), intent(in) :: events
        integer :: left(size(events%direction))
        left = 0
        where (events%terminal) left = 1
        if (allocated(events%count)) where (events%terminal) left = events%count
    end function event_counts

    !> Locate the zero crossings of the event functions in the accepted step of stp
    !! (g_old: the functions at its start, updated to its end; at_start: the events that
    !! are roots at the step's start if its end moves them in their direction, SciPy's rule
    !! at t0). Each event state is passed to hook%at_event (if present) and stored in res
    !! (if present); left (see `event_counts`) counts the occurrences down. At the one that
    !! brings an entry to zero: stop_now, its time t_stop and state y_stop; later events of
    !! the step are dropped. info /= CM_SUCCESS (with msg) when the extension or the hook
    !! fails.
    subroutine find_events(stp, events, g_old, at_start, left, stop_now, t_stop, y_stop, &
                           info, msg, res, hook)
        class(ode_stepper), intent(inout) :: stp
        class(ode_events), intent(in) :: events
        real(dp), intent(inout) :: g_old(:)
        logical, intent(in) :: at_start(:)
        integer, intent(inout) :: left(:)
        logical, intent(inout) :: stop_now
        real(dp), intent(inout) :: t_stop
        real(dp), intent(inout) :: y_stop(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(inout) :: msg
        type(ode_result), intent(inout), optional :: res
        class(ode_step_hook), intent(inout), optional :: hook
        real(dp) :: g_new(size(g_old)), ye(stp%n), posneg, te
        real(dp), allocatable :: ev_times(:)
        integer, allocatable :: ev_ids(:), order(:)
        integer :: ne, ie, iev, i, j, nfound
        integer(int64) :: m
        info = CM_SUCCESS
        ne = size(g_old)
        posneg = stp%posneg
        nfound = 0
        ! the end first: the first call after t0 is always g at the first step's end
        call events%eval(stp%t, stp%y, g_new)
        ! a NaN has no sign: no crossing can be told, so the run stops here (and a Python
        ! event function that raised, whose value is NaN from then on, ends the run at once)
        do i = 1, ne
            if (g_new(i) /= g_new(i)) then
                info = CM_NONFINITE
                msg = "event function "//itoa(i)//" of "//itoa(ne)//" is NaN at t ="// &
                      rtoa(stp%t)
                return
            end if
        end do
        ! SciPy's find_active_events with g_old = 0: rising if g_new >= 0, falling if
        ! g_new <= 0; the root is the step's start
        do i = 1, ne
            if (.not. at_start(i)) cycle
            if (.not. leaves_zero(g_new(i), events%direction(i))) cycle
            call add_root(ev_times, ev_ids, nfound, stp%t_old, i)
        end do
        m = sample_count(stp, events)
        if (m > 1) then
            call sampled_crossings(stp, events, m, g_old, g_new, ev_times, ev_ids, nfound, &
                                   info, msg)
            if (info /= CM_SUCCESS) return
        end if
        do i = 1, ne
            if (m > 1 .and. resolved(events, i)) cycle
            if (.not. crossing(g_old(i), g_new(i), events%direction(i))) cycle
            if (g_new(i) == 0.0_dp) then
                te = stp%t
            else
                te = event_root(stp, events, i, g_old(i), g_new(i), 0.0_dp, 1.0_dp, info, &
                                msg)
                if (info /= CM_SUCCESS) return
            end if
            call add_root(ev_times, ev_ids, nfound, te, i)
        end do
        g_old = g_new
        if (nfound == 0) return
        ! order by time in the direction of integration (insertion sort, few events)
        allocate (order(nfound))
        do i = 1, nfound
            order(i) = i
        end do
        do i = 2, nfound
            j = i
            do while (j > 1)
                if ((ev_times(order(j)) - ev_times(order(j - 1)))*posneg >= 0.0_dp) exit
                iev = order(j); order(j) = order(j - 1); order(j - 1) = iev
                j = j - 1
            end do
        end do
        do j = 1, nfound
            i = order(j)
            te = ev_times(i)
            ie = ev_ids(i)
            if (te == stp%t) then
                ye = stp%y
            else if (te == stp%t_old) then
                ye = stp%y_old
            else
                call stp%eval(te, ye, info, msg)
                if (info /= CM_SUCCESS) return
            end if
            if (present(hook)) then
                call hook%at_event(te, ye, info)
                if (info < 0) then
                    msg = "event state: stopped by the step hook"
                    if (allocated(hook%message)) msg = "event state: "//hook%message
                    return
                end if
                info = CM_SUCCESS
            end if
            if (present(res)) call push_event(res, te, ye, ie)
            if (left(ie) > 0) then
                left(ie) = left(ie) - 1
                if (left(ie) == 0) then
                    stop_now = .true.
                    t_stop = te
                    y_stop = ye
                    exit
                end if
            end if
        end do
    end subroutine find_events

    !> A crossing from ga to gb that counts for an event of direction dir (SciPy's rule:
    !! from strictly negative to >= 0 rising, from strictly positive to <= 0 falling).
    pure logical function crossing(ga, gb, dir)
        real(dp), intent(in) :: ga, gb
        integer, intent(in) :: dir
        crossing = (ga < 0.0_dp .and. gb >= 0.0_dp .and. dir >= 0) .or. &
                   (ga > 0.0_dp .and. gb <= 0.0_dp .and. dir <= 0)
    end function crossing

    !> An event zero at a step's start that its end gb moves in its direction dir.
    pure logical function leaves_zero(gb, dir)
        real(dp), intent(in) :: gb
        integer, intent(in) :: dir
        leaves_zero = (gb >= 0.0_dp .and. dir >= 0) .or. (gb <= 0.0_dp .and. dir <= 0)
    end function leaves_zero

    !> Whether event i is sampled inside the steps (a positive resolution).
    pure logical function resolved(events, i)
        class(ode_events), intent(in) :: events
        integer, intent(in) :: i
        resolved = .false.
        if (allocated(events%resolution)) resolved = events%resolution(i) > 0.0_dp
    end function resolved

    !> Number of sub-intervals of the last step: ceiling(|h|/r) for the finest positive
    !! resolution r (1: the step's ends only).
    integer(int64) function sample_count(stp, events) result(m)
        class(ode_stepper), intent(in) :: stp
        class(ode_events), intent(in) :: events
        real(dp) :: r, q
        m = 1
        if (.not. allocated(events%resolution)) return
        r = minval(events%resolution, mask=events%resolution > 0.0_dp)
        if (.not. (r > 0.0_dp .and. r < huge(1.0_dp))) return
        q = abs(stp%h_done)/r
        if (.not. q > 1.0_dp) return
        if (q >= real(M_MAX, dp)) then
            m = M_MAX
        else
            m = ceiling(q, int64)
        end if
    end function sample_count

    !> The crossings of the resolved events between the m + 1 samples x = k/m of the
    !! step's continuous extension (g_old at x = 0, g_new at x = 1), appended to
    !! (ev_times, ev_ids).
    subroutine sampled_crossings(stp, events, m, g_old, g_new, ev_times, ev_ids, nfound, &
                                 info, msg)
        class(ode_stepper), intent(inout) :: stp
        class(ode_events), intent(in) :: events
        integer(int64), intent(in) :: m
        real(dp), intent(in) :: g_old(:), g_new(:)
        real(dp), allocatable, intent(inout) :: ev_times(:)
        integer, allocatable, intent(inout) :: ev_ids(:)
        integer, intent(inout) :: nfound
        integer, intent(out) :: info
        character(len=:), allocatable, intent(inout) :: msg
        real(dp) :: ga(size(g_old)), gb(size(g_old)), ye(stp%n), xa, xb, te
        integer(int64) :: k
        integer :: i
        info = CM_SUCCESS
        ga = g_old
        xa = 0.0_dp
        do k = 1, m
            if (k < m) then
                xb = real(k, dp)/real(m, dp)
                call stp%eval_unit(xb, ye, info, msg)
                if (info /= CM_SUCCESS) return
                call events%eval(stp%t_old + xb*stp%h_done, ye, gb)
            else
                xb = 1.0_dp
                gb = g_new
            end if
            do i = 1, size(g_old)
                if (.not. resolved(events, i)) cycle
                if (.not. crossing(ga(i), gb(i), events%direction(i))) cycle
                if (k == m .and. gb(i) == 0.0_dp) then
                    te = stp%t
                else
                    te = event_root(stp, events, i, ga(i), gb(i), xa, xb, info, msg)
                    if (info /= CM_SUCCESS) return
                end if
                call add_root(ev_times, ev_ids, nfound, te, i)
            end do
            ga = gb
            xa = xb
        end do
    end subroutine sampled_crossings

    !> Append the root (te, i), growing the arrays by doubling.
    pure subroutine add_root(ev_times, ev_ids, nfound, te, i)
        real(dp), allocatable, intent(inout) :: ev_times(:)
        integer, allocatable, intent(inout) :: ev_ids(:)
        integer, intent(inout) :: nfound
        real(dp), intent(in) :: te
        integer, intent(in) :: i
        real(dp), allocatable :: tt(:)
        integer, allocatable :: ii(:)
        if (.not. allocated(ev_times)) allocate (ev_times(4), ev_ids(4))
        if (nfound == size(ev_times)) then
            allocate (tt(2*nfound), ii(2*nfound))
            tt(1:nfound) = ev_times
            ii(1:nfound) = ev_ids
            call move_alloc(tt, ev_times)
            call move_alloc(ii, ev_ids)
        end if
        nfound = nfound + 1
        ev_times(nfound) = te
        ev_ids(nfound) = i
    end subroutine add_root

    !> Root of event ie between x = xa and x = xb of the step's continuous extension
    !! (Brent's method on [xa, xb], ga and gb the event there).
    function event_root(stp, events, ie, ga, gb, xa, xb, info, msg) result(root)
        class(ode_stepper), intent(inout) :: stp
        class(ode_events), intent(in) :: events
        integer, intent(in) :: ie
        real(dp), intent(in) :: ga, gb, xa, xb
        integer, intent(out) :: info
        character(len=:), allocatable, intent(inout) :: msg
        real(dp) :: root
        type(brent_state) :: bs
        logical :: done
        integer :: it
        real(dp) :: gv(size(events%direction)), ye(stp%n), w
        info = CM_SUCCESS
        w = xb - xa
        call brent_init(bs, ga, gb, stp%t_old + xa*stp%h_done, w*stp%h_done)
        do it = 1, 200
            call brent_step(bs, done)
            if (done) exit
            call stp%eval_unit(xa + bs%b*w, ye, info, msg)
            if (info /= CM_SUCCESS) exit
            call events%eval(bs%t + bs%b*bs%h, ye, gv)
            call brent_take(bs, gv(ie))
        end do
        root = bs%t + bs%b*bs%h
    end function event_root

end module conmech_ode_event_locate
