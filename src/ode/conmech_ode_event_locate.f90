!> Event location on the last step of any stepper: sign changes of the event functions
!! between the step's ends (with each event's direction), each root found by Brent's method
!! on the step's continuous extension (`eval_unit`, to near machine precision in t),
!! reported in the order of time up to the first terminal one.
module conmech_ode_event_locate
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS
    use conmech_ode_system, only: ode_events, ode_step_hook
    use conmech_ode_result, only: ode_result, push_event
    use conmech_ode_stepper, only: ode_stepper
    use conmech_brent, only: brent_state, brent_init, brent_step, brent_take
    implicit none
    private
    public :: find_events

contains

    !> Locate the zero crossings of the event functions in the accepted step of stp
    !! (g_old: the functions at its start, updated to its end). Each event state is passed
    !! to hook%at_event (if present) and stored in res (if present). At a terminal event:
    !! stop_now, its time t_stop and state y_stop; later events of the step are dropped.
    !! info /= CM_SUCCESS (with msg) when the extension or the hook fails.
    subroutine find_events(stp, events, g_old, stop_now, t_stop, y_stop, info, msg, res, &
                           hook)
        class(ode_stepper), intent(inout) :: stp
        class(ode_events), intent(in) :: events
        real(dp), intent(inout) :: g_old(:)
        logical, intent(inout) :: stop_now
        real(dp), intent(inout) :: t_stop
        real(dp), intent(inout) :: y_stop(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(inout) :: msg
        type(ode_result), intent(inout), optional :: res
        class(ode_step_hook), intent(inout), optional :: hook
        real(dp) :: g_new(size(g_old)), ev_times(size(g_old)), ye(stp%n), posneg, te
        integer :: ev_ids(size(g_old)), ne, ie, iev
        integer :: i, j, nfound, order(size(g_old))
        real(dp) :: tmin
        logical :: cross
        info = CM_SUCCESS
        ne = size(g_old)
        posneg = stp%posneg
        call events%eval(stp%t, stp%y, g_new)
        nfound = 0
        do i = 1, ne
            cross = .false.
            if (g_old(i) < 0.0_dp .and. g_new(i) >= 0.0_dp .and. &
                events%direction(i) >= 0) cross = .true.
            if (g_old(i) > 0.0_dp .and. g_new(i) <= 0.0_dp .and. &
                events%direction(i) <= 0) cross = .true.
            if (cross) then
                nfound = nfound + 1
                ev_ids(nfound) = i
                if (g_new(i) == 0.0_dp) then
                    ev_times(nfound) = stp%t
                else
                    ev_times(nfound) = event_root(stp, events, i, g_old(i), g_new(i), info, &
                                                  msg)
                    if (info /= CM_SUCCESS) return
                end if
            end if
        end do
        g_old = g_new
        if (nfound == 0) return
        ! order by time in the direction of integration (insertion sort, few events)
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
        tmin = stp%t
        do j = 1, nfound
            i = order(j)
            te = ev_times(i)
            ie = ev_ids(i)
            if (stop_now .and. (te - tmin)*posneg > 0.0_dp) exit
            if (te == stp%t) then
                ye = stp%y
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
            if (events%terminal(ie) .and. .not. stop_now) then
                stop_now = .true.
                tmin = te
                t_stop = te
                y_stop = ye
            end if
        end do
    end subroutine find_events

    !> Root of event ie on the continuous extension of the step (Brent's method in
    !! x = (s - t_old)/h_done).
    function event_root(stp, events, ie, ga, gb, info, msg) result(root)
        class(ode_stepper), intent(inout) :: stp
        class(ode_events), intent(in) :: events
        integer, intent(in) :: ie
        real(dp), intent(in) :: ga, gb
        integer, intent(out) :: info
        character(len=:), allocatable, intent(inout) :: msg
        real(dp) :: root
        type(brent_state) :: bs
        logical :: done
        integer :: it
        real(dp) :: gv(size(events%direction)), ye(stp%n)
        info = CM_SUCCESS
        call brent_init(bs, ga, gb, stp%t_old, stp%h_done)
        do it = 1, 200
            call brent_step(bs, done)
            if (done) exit
            call stp%eval_unit(bs%b, ye, info, msg)
            if (info /= CM_SUCCESS) exit
            call events%eval(bs%t + bs%b*bs%h, ye, gv)
            call brent_take(bs, gv(ie))
        end do
        root = bs%t + bs%b*bs%h
    end function event_root

end module conmech_ode_event_locate
