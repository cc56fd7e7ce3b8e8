!> Event location on the last step of a stepper: sign changes of the event functions
!! between the step's ends, each root found by Brent's method on the step's continuous
!! extension (to near machine precision), reported in the order of time.
module conmech_ode_event_locate
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_events
    use conmech_ode_dense, only: interp
    use conmech_ode_result, only: ode_result, push_event
    use conmech_rk_stepper, only: rk_stepper
    use conmech_brent, only: brent_state, brent_init, brent_step, brent_take
    implicit none
    private
    public :: find_events

contains

    !> Locate the zero crossings of the event functions in the accepted step.
    subroutine find_events(stp, events, g_old, stop_now, t_stop, res)
        type(rk_stepper), intent(in) :: stp
        class(ode_events), intent(in) :: events
        real(dp), intent(inout) :: g_old(:)
        logical, intent(inout) :: stop_now
        real(dp), intent(inout) :: t_stop
        type(ode_result), intent(inout), optional :: res
        real(dp) :: g_new(size(g_old)), ev_times(size(g_old)), ye(stp%n), t, h, posneg, te
        integer :: ev_ids(size(g_old)), ne, ie, iev
        integer :: i, j, nfound, order(size(g_old))
        real(dp) :: tmin
        logical :: cross
        ne = size(g_old)
        t = stp%t_old
        h = stp%h_done
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
                    ev_times(nfound) = t + h
                else
                    ev_times(nfound) = event_root(stp, events, i, g_old(i), g_new(i))
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
        tmin = t + h
        do j = 1, nfound
            i = order(j)
            te = ev_times(i)
            ie = ev_ids(i)
            if (stop_now .and. (te - tmin)*posneg > 0.0_dp) exit
            if (te == t + h) then
                ye = stp%y
            else
                call stp%eval(te, ye)
            end if
            if (present(res)) call push_event(res, te, ye, ie)
            if (events%terminal(ie) .and. .not. stop_now) then
                stop_now = .true.
                tmin = te
                t_stop = te
            end if
        end do
    end subroutine find_events

    !> Root of event ie on the dense output of the current step (Brent's method).
    function event_root(stp, events, ie, ga, gb) result(root)
        type(rk_stepper), intent(in) :: stp
        class(ode_events), intent(in) :: events
        integer, intent(in) :: ie
        real(dp), intent(in) :: ga, gb
        real(dp) :: root
        type(brent_state) :: bs
        logical :: done
        integer :: it
        real(dp) :: gv(size(events%direction)), ye(stp%n)
        call brent_init(bs, ga, gb, stp%t_old, stp%h_done)
        do it = 1, 200
            call brent_step(bs, done)
            if (done) exit
            call interp(stp%fc, stp%form, bs%b, ye)
            call events%eval(bs%t + bs%b*bs%h, ye, gv)
            call brent_take(bs, gv(ie))
        end do
        root = bs%t + bs%b*bs%h
    end function event_root

end module conmech_ode_event_locate
