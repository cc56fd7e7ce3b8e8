!> Output machinery shared by the implicit integrators (Radau IIA, Gauss-Legendre): the
!! solution points (every step, or t_eval interpolated on the collocation polynomial),
!! the dense output, and event location, for one accepted step at a time.
!!
!! A step [t, t + h] is described by its collocation polynomial in the power basis,
!! u(t + x h) = fc(:, 0) + x fc(:, 1) + ... + x^nf fc(:, nf) (dense_solution%form = 2, the
!! power form of conmech_ode_solver). Event zeros are located on it by Brent's method.
!! Everything lives in the caller's `step_output` object: thread-safe.
module conmech_radau_common
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_events
    use conmech_ode_solver, only: ode_options, ode_result, dense_solution
    use conmech_ode_result, only: push_point, push_event
    use conmech_ode_dense, only: dense_push, power_basis_matrix
    use conmech_brent, only: brent_state, brent_init, brent_step, brent_take
    implicit none
    private

    integer, parameter, public :: FORM_POWER_BASIS = 2  !! dense_solution%form of the power basis

    public :: step_output, out_init, out_step, out_finish, poly_eval, check_t_eval
    public :: power_basis_matrix
    public :: tolerance_vectors

    !> State of the outputs during one integration.
    type :: step_output
        integer :: n = 0, nf = 0
        integer :: n_eval = 0, i_eval = 1, ne = 0
        logical :: has_events = .false., store_steps = .false., dense = .false.
        real(dp) :: posneg = 1.0_dp
        real(dp), allocatable :: g_old(:), g_new(:), ye(:)
    end type step_output

contains

    !> Check t_eval (finite, inside t_span, sorted in the direction of integration).
    subroutine check_t_eval(t_span, t_eval, info, msg)
        real(dp), intent(in) :: t_span(2), t_eval(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: i
        info = CM_BAD_INPUT
        if (.not. all(ieee_is_finite(t_eval))) then
            msg = "bad input: t_eval contains non-finite values"
            return
        end if
        do i = 1, size(t_eval)
            if ((t_eval(i) - t_span(1))*(t_span(2) - t_eval(i)) < 0.0_dp) then
                msg = "bad input: t_eval values must lie in t_span"
                return
            end if
            ! max(i - 1, 1): at i = 1 the difference is 0 (nothing to compare)
            if ((t_eval(i) - t_eval(max(i - 1, 1)))*(t_span(2) - t_span(1)) < 0.0_dp) then
                msg = "bad input: t_eval must be sorted in the direction of integration"
                return
            end if
        end do
        info = CM_SUCCESS
        msg = "success"
    end subroutine check_t_eval

    !> Per-component tolerances from the options (rtol raised to 100 eps, as SciPy).
    subroutine tolerance_vectors(opt, n, rtolv, atolv, info, msg)
        type(ode_options), intent(in) :: opt
        integer, intent(in) :: n
        real(dp), allocatable, intent(out) :: rtolv(:), atolv(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        allocate (rtolv(n), atolv(n))
        info = CM_BAD_INPUT
        if (allocated(opt%rtol_vec)) then
            if (size(opt%rtol_vec) /= n) then
                msg = "bad input: rtol must be a scalar or have the size of y0"
                return
            end if
            rtolv = opt%rtol_vec
        else
            rtolv = opt%rtol
        end if
        if (allocated(opt%atol_vec)) then
            if (size(opt%atol_vec) /= n) then
                msg = "bad input: atol must be a scalar or have the size of y0"
                return
            end if
            atolv = opt%atol_vec
        else
            atolv = opt%atol
        end if
        if (.not. (all(rtolv >= 0.0_dp) .and. all(atolv >= 0.0_dp))) then
            msg = "bad input: rtol and atol must be non-negative"
            return
        end if
        rtolv = max(rtolv, 100.0_dp*epsilon(1.0_dp))
        info = CM_SUCCESS
        msg = "success"
    end subroutine tolerance_vectors

    !> u(x) = fc(:, 0) + x fc(:, 1) + ... + x^nf fc(:, nf) (Horner).
    pure subroutine poly_eval(fc, x, u)
        real(dp), intent(in) :: fc(:, 0:)
        real(dp), intent(in) :: x
        real(dp), intent(out) :: u(:)
        integer :: j, nf
        nf = ubound(fc, 2)
        u = fc(:, nf)
        do j = nf - 1, 0, -1
            u = fc(:, j) + x*u
        end do
    end subroutine poly_eval

    !> Start the outputs at (t0, y0): allocate the result arrays, store the first point.
    subroutine out_init(o, res, opt, t0, tf, y0, nf, t_eval, events)
        type(step_output), intent(out) :: o
        type(ode_result), intent(inout) :: res
        type(ode_options), intent(in) :: opt
        real(dp), intent(in) :: t0, tf, y0(:)
        integer, intent(in) :: nf
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        integer :: n
        n = size(y0)
        o%n = n
        o%nf = nf
        o%posneg = sign(1.0_dp, tf - t0)
        if (present(t_eval)) o%n_eval = size(t_eval)
        if (present(events)) o%has_events = events%n_events() > 0
        o%store_steps = o%n_eval == 0 .and. opt%save_steps
        o%dense = opt%dense_output
        if (.not. allocated(res%t)) allocate (res%t(0), res%y(n, 0))
        if (.not. allocated(res%ev_t)) allocate (res%ev_t(0), res%ev_y(n, 0), res%ev_id(0))
        res%nt = 0
        res%nev = 0
        if (o%n_eval == 0) call push_point(res, t0, y0)
        o%i_eval = 1
        do while (o%i_eval <= o%n_eval)
            if (t_eval(o%i_eval) /= t0) exit
            call push_point(res, t0, y0)
            o%i_eval = o%i_eval + 1
        end do
        if (o%dense) then
            res%sol%n = n
            res%sol%nf = nf
            res%sol%form = FORM_POWER_BASIS
            res%sol%nseg = 0
            res%sol%t_first = t0
            res%sol%t_last = t0
            allocate (res%sol%ts(16), res%sol%hs(16), res%sol%coef(n, 0:nf, 16))
        end if
        if (o%has_events) then
            o%ne = events%n_events()
            allocate (o%g_old(o%ne), o%g_new(o%ne), o%ye(n))
            call events%eval(t0, y0, o%g_old)
        end if
    end subroutine out_init

    !> Outputs of the accepted step [t, t + h] (polynomial fc, end state ynew): events,
    !! t_eval points, the step end, the dense output. If a terminal event occurs, stop_now
    !! is set and (t_stop, y_stop) is the event point, the last output.
    subroutine out_step(o, res, t, h, fc, ynew, stop_now, t_stop, y_stop, t_eval, events)
        type(step_output), intent(inout) :: o
        type(ode_result), intent(inout) :: res
        real(dp), intent(in) :: t, h, fc(:, 0:), ynew(:)
        logical, intent(out) :: stop_now
        real(dp), intent(out) :: t_stop, y_stop(:)
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        real(dp) :: t_new, u(o%n)
        t_new = t + h
        stop_now = .false.
        t_stop = t_new
        y_stop = ynew
        if (o%has_events) call find_events()
        do while (o%i_eval <= o%n_eval)
            if (stop_now) then
                if ((t_eval(o%i_eval) - t_stop)*o%posneg > 0.0_dp) exit
            else
                if ((t_eval(o%i_eval) - t_new)*o%posneg > 0.0_dp) exit
            end if
            if (t_eval(o%i_eval) == t_new .and. .not. stop_now) then
                call push_point(res, t_new, ynew)
            else
                call poly_eval(fc, (t_eval(o%i_eval) - t)/h, u)
                call push_point(res, t_eval(o%i_eval), u)
            end if
            o%i_eval = o%i_eval + 1
        end do
        if (o%store_steps) call push_point(res, t_stop, y_stop)
        if (o%dense) call dense_push(res%sol, t, h, fc, t_stop)

    contains

        subroutine find_events()
            integer :: i, j, nfound, ids(o%ne), order(o%ne), tmp
            real(dp) :: times(o%ne), tmin, te
            logical :: cross
            call events%eval(t_new, ynew, o%g_new)
            nfound = 0
            do i = 1, o%ne
                cross = .false.
                if (o%g_old(i) < 0.0_dp .and. o%g_new(i) >= 0.0_dp .and. &
                    events%direction(i) >= 0) cross = .true.
                if (o%g_old(i) > 0.0_dp .and. o%g_new(i) <= 0.0_dp .and. &
                    events%direction(i) <= 0) cross = .true.
                if (cross) then
                    nfound = nfound + 1
                    ids(nfound) = i
                    if (o%g_new(i) == 0.0_dp) then
                        times(nfound) = t_new
                    else
                        times(nfound) = event_root(i, o%g_old(i), o%g_new(i))
                    end if
                end if
            end do
            o%g_old = o%g_new
            if (nfound == 0) return
            do i = 1, nfound
                order(i) = i
            end do
            do i = 2, nfound
                j = i
                do while (j > 1)
                    if ((times(order(j)) - times(order(j - 1)))*o%posneg >= 0.0_dp) exit
                    tmp = order(j); order(j) = order(j - 1); order(j - 1) = tmp
                    j = j - 1
                end do
            end do
            tmin = t_new
            do j = 1, nfound
                i = order(j)
                te = times(i)
                if (stop_now .and. (te - tmin)*o%posneg > 0.0_dp) exit
                if (te == t_new) then
                    o%ye = ynew
                else
                    call poly_eval(fc, (te - t)/h, o%ye)
                end if
                call push_event(res, te, o%ye, ids(i))
                if (events%terminal(ids(i)) .and. .not. stop_now) then
                    stop_now = .true.
                    tmin = te
                    t_stop = te
                    y_stop = o%ye
                end if
            end do
        end subroutine find_events

        !> Zero of event ie on the polynomial of the step (Brent's method in x in [0, 1]).
        function event_root(ie, ga, gb) result(root)
            integer, intent(in) :: ie
            real(dp), intent(in) :: ga, gb
            real(dp) :: root, gv(o%ne)
            type(brent_state) :: bs
            logical :: done
            integer :: it
            call brent_init(bs, ga, gb, t, h)
            do it = 1, 200
                call brent_step(bs, done)
                if (done) exit
                call poly_eval(fc, bs%b, o%ye)
                call events%eval(t + bs%b*h, o%ye, gv)
                call brent_take(bs, gv(ie))
            end do
            root = t + bs%b*h
        end function event_root

    end subroutine out_step

    !> End of the run: the last point when only the end points are kept, sizes trimmed.
    subroutine out_finish(o, res, t, y)
        type(step_output), intent(in) :: o
        type(ode_result), intent(inout) :: res
        real(dp), intent(in) :: t, y(:)
        real(dp), allocatable :: tt(:), yy(:, :)
        integer, allocatable :: ii(:)
        if (o%n_eval == 0 .and. .not. o%store_steps) then
            if (res%nt == 0) then
                call push_point(res, t, y)
            else if (res%t(res%nt) /= t) then
                call push_point(res, t, y)
            end if
        end if
        if (size(res%t) /= res%nt) then
            tt = res%t(1:res%nt)
            yy = res%y(:, 1:res%nt)
            call move_alloc(tt, res%t)
            call move_alloc(yy, res%y)
        end if
        if (size(res%ev_t) /= res%nev) then
            tt = res%ev_t(1:res%nev)
            yy = res%ev_y(:, 1:res%nev)
            ii = res%ev_id(1:res%nev)
            call move_alloc(tt, res%ev_t)
            call move_alloc(yy, res%ev_y)
            call move_alloc(ii, res%ev_id)
        end if
        if (o%dense) res%sol%t_last = t
    end subroutine out_finish

end module conmech_radau_common
