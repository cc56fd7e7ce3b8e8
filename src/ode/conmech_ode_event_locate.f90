!> Event location on the last step of a stepper: sign changes of the event functions
!! between the step's ends, each root found by Brent's method on the step's continuous
!! extension (to near machine precision), reported in the order of time.
module conmech_ode_event_locate
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_events
    use conmech_ode_dense, only: interp
    use conmech_ode_result, only: ode_result, push_event
    use conmech_rk_stepper, only: rk_stepper
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
        real(dp) :: a, b, c, fa, fb, fcc, d, e, tol, m, p, q, r, s
        integer :: it
        real(dp) :: gv(size(events%direction)), ye(stp%n), t, h
        t = stp%t_old
        h = stp%h_done
        a = 0.0_dp; b = 1.0_dp; fa = ga; fb = gb
        c = a; fcc = fa; d = b - a; e = d
        do it = 1, 200
            if (abs(fcc) < abs(fb)) then
                a = b; b = c; c = a
                fa = fb; fb = fcc; fcc = fa
            end if
            tol = 2.0_dp*epsilon(1.0_dp)*abs(t + b*h)/abs(h) + 0.5_dp*tiny(1.0_dp)
            tol = max(tol, 2.0_dp*epsilon(1.0_dp))
            m = 0.5_dp*(c - b)
            if (abs(m) <= tol .or. fb == 0.0_dp) exit
            if (abs(e) < tol .or. abs(fa) <= abs(fb)) then
                d = m; e = m
            else
                s = fb/fa
                if (a == c) then
                    p = 2.0_dp*m*s
                    q = 1.0_dp - s
                else
                    q = fa/fcc
                    r = fb/fcc
                    p = s*(2.0_dp*m*q*(q - r) - (b - a)*(r - 1.0_dp))
                    q = (q - 1.0_dp)*(r - 1.0_dp)*(s - 1.0_dp)
                end if
                if (p > 0.0_dp) then
                    q = -q
                else
                    p = -p
                end if
                if (2.0_dp*p < min(3.0_dp*m*q - abs(tol*q), abs(e*q))) then
                    e = d
                    d = p/q
                else
                    d = m; e = m
                end if
            end if
            a = b; fa = fb
            if (abs(d) > tol) then
                b = b + d
            else
                b = b + sign(tol, m)
            end if
            call interp(stp%fc, stp%form, b, ye)
            call events%eval(t + b*h, ye, gv)
            fb = gv(ie)
            if ((fb > 0.0_dp .and. fcc > 0.0_dp) .or. (fb < 0.0_dp .and. fcc < 0.0_dp)) then
                c = a; fcc = fa; d = b - a; e = d
            end if
        end do
        root = t + b*h
    end function event_root

end module conmech_ode_event_locate
