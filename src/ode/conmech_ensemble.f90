!> Ensembles, i.e. many initial states and/or parameter sets of one system, integrated in
!! parallel (OpenMP threads when compiled with OpenMP; serially otherwise).
!!
!! Each member is one `ode_solve` of its own: member i of an ensemble is bit for bit the
!! single solve of the same system, initial state, options and t_eval, whatever the number
!! of threads. Two ways to name the members' systems:
!! - one system for every member (`class(ode_system)`): the members differ in y0 only;
!! - an `ensemble_members` object whose `system(i, ...)` allocates member i's system (e.g.
!!   the i-th column of a parameter table); it must be safe to call from several threads.
!!
!! Results (`ensemble_result`) are arrays: states at the common `t_eval` (n, nt, m),
!! final times and states, per-member status and counters, and the first `max_events`
!! events of each member (time, state, which event function). Events are an `ode_events`
!! object shared by all members (`crossing_events` is the built-in kind: a component
!! crossing a value, with a direction); `terminal` stops a member at its `max_events`-th
!! event, which is then its final state.
!!
!! A `progress` object, if given, is called by the calling thread between chunks of
!! members (`chunk` members each), never from inside the parallel region; it may cancel
!! the rest (members not run get status ENSEMBLE_NOT_RUN).
!!
!! Nothing is saved between calls: every routine is thread-safe.
module conmech_ensemble
    use conmech_kinds, only: dp, nan_dp
    use conmech_status
    use conmech_text, only: itoa
    use conmech_ode_system, only: ode_system, ode_events, ode_step_hook
    use conmech_ode_solver, only: ode_options, ode_result, ode_solve
    !$ use omp_lib, only: omp_get_max_threads
    implicit none
    private

    public :: ode_ensemble, ensemble_members, ensemble_options, ensemble_result
    public :: ensemble_progress, crossing_events

    integer, parameter, public :: ENSEMBLE_NOT_RUN = -99  !! member status: not integrated

    !> Settings of an ensemble run (the integrator's options are an `ode_options`).
    type :: ensemble_options
        integer :: threads = 0          !! OpenMP threads; 0: the OpenMP default
        integer :: chunk = 0            !! members between progress calls; 0: automatic
        integer :: max_events = 1       !! events kept per member (the first ones)
        logical :: terminal = .false.   !! stop each member at its max_events-th event
    end type ensemble_options

    !> The systems of the members: member i's system, allocated by `system`.
    type, abstract :: ensemble_members
    contains
        procedure(members_count), deferred :: count
        procedure(members_system), deferred :: system
    end type ensemble_members

    abstract interface
        !> Number of members.
        integer function members_count(self)
            import :: ensemble_members
            class(ensemble_members), intent(in) :: self
        end function members_count
        !> Allocate the system of member i (1 <= i <= count); info /= 0 with a message if
        !! it cannot be built. Called from several threads at once.
        subroutine members_system(self, i, sys, info, msg)
            import :: ensemble_members, ode_system
            class(ensemble_members), intent(in) :: self
            integer, intent(in) :: i
            class(ode_system), allocatable, intent(out) :: sys
            integer, intent(out) :: info
            character(len=:), allocatable, intent(out) :: msg
        end subroutine members_system
    end interface

    !> Progress report, called by the calling thread between chunks of members.
    type, abstract :: ensemble_progress
    contains
        procedure(progress_report), deferred :: report
    end type ensemble_progress

    abstract interface
        !> `done` of `total` members are finished; set `cancel` to skip the rest.
        subroutine progress_report(self, done, total, cancel)
            import :: ensemble_progress
            class(ensemble_progress), intent(inout) :: self
            integer, intent(in) :: done, total
            logical, intent(out) :: cancel
        end subroutine progress_report
    end interface

    !> Built-in event kind: g_j = y(component(j)) - value(j), j = 1..size(component);
    !! `direction` (+1 rising, -1 falling, 0 both) as in every `ode_events`.
    type, extends(ode_events) :: crossing_events
        integer, allocatable :: component(:)
        real(dp), allocatable :: value(:)
    contains
        procedure :: eval => crossing_eval
    end type crossing_events

    !> Results of an ensemble of m members of dimension n, nt output times, k events kept.
    !! Entries a member did not reach (after a failure, a terminal event or a cancel) are
    !! NaN (states and times) and 0 (event ids).
    type :: ensemble_result
        integer :: status = CM_BAD_INPUT   !! CM_SUCCESS, or the first failure (see message)
        character(len=:), allocatable :: message
        integer :: n = 0, m = 0, nt = 0, k = 0
        integer :: done = 0                        !! members integrated
        real(dp), allocatable :: y(:, :, :)        !! (n, nt, m) states at t_eval
        real(dp), allocatable :: t_final(:)        !! (m) where each member ended
        real(dp), allocatable :: y_final(:, :)     !! (n, m) its state there
        integer, allocatable :: member_status(:)   !! (m) status of each member
        integer, allocatable :: nfev(:), naccept(:), nreject(:)   !! (m)
        integer, allocatable :: nev(:)             !! (m) events kept (<= k)
        real(dp), allocatable :: ev_t(:, :)        !! (k, m) event times
        real(dp), allocatable :: ev_y(:, :, :)     !! (n, k, m) states at the events
        integer, allocatable :: ev_id(:, :)        !! (k, m) which event function (1-based)
    end type ensemble_result

    !> Step hook of one member: keeps the last state and, for terminal ensembles, counts
    !! the crossings with the integrator's own rule and stops after the step of the k-th.
    type, extends(ode_step_hook) :: member_hook
        real(dp) :: t_last = 0.0_dp
        real(dp), allocatable :: y_last(:)
        class(ode_events), allocatable :: ev
        real(dp), allocatable :: g_old(:), g_new(:)
        integer :: count = 0
        integer :: k = 0
        logical :: count_events = .false.
    contains
        procedure :: after_step => member_after_step
    end type member_hook

    !> Integrate every member; see the module documentation.
    interface ode_ensemble
        module procedure ensemble_one_system
        module procedure ensemble_of_members
    end interface ode_ensemble

contains

    subroutine crossing_eval(self, t, y, g)
        class(crossing_events), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: g(:)
        g = y(self%component) - self%value
    end subroutine crossing_eval

    subroutine member_after_step(self, t, y, changed, info)
        class(member_hook), intent(inout) :: self
        real(dp), intent(in) :: t
        real(dp), intent(inout) :: y(:)
        logical, intent(out) :: changed
        integer, intent(out) :: info
        integer :: i
        changed = .false.
        info = 0
        self%t_last = t
        self%y_last = y
        if (.not. self%count_events) return
        call self%ev%eval(t, y, self%g_new)
        do i = 1, size(self%g_new)
            if (self%g_old(i) < 0.0_dp .and. self%g_new(i) >= 0.0_dp .and. &
                self%ev%direction(i) >= 0) self%count = self%count + 1
            if (self%g_old(i) > 0.0_dp .and. self%g_new(i) <= 0.0_dp .and. &
                self%ev%direction(i) <= 0) self%count = self%count + 1
        end do
        self%g_old = self%g_new
        if (self%count >= self%k) info = 1
    end subroutine member_after_step

    !> Members differing in their initial state: y0(:, i) for member i (m = size(y0, 2)).
    subroutine ensemble_one_system(sys, t_span, y0, options, res, t_eval, events, ens_options, &
                                   progress)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: y0(:, :)
        type(ode_options), intent(in) :: options
        type(ensemble_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        type(ensemble_options), intent(in), optional :: ens_options
        class(ensemble_progress), intent(inout), optional :: progress
        call run_ensemble(size(y0, 2), t_span, y0, options, res, t_eval, events, &
                          ens_options, progress, sys=sys)
    end subroutine ensemble_one_system

    !> Members with their own systems (members%count() of them); y0 has one column (shared
    !! by all) or one per member.
    subroutine ensemble_of_members(members, t_span, y0, options, res, t_eval, events, &
                                   ens_options, progress)
        class(ensemble_members), intent(in) :: members
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: y0(:, :)
        type(ode_options), intent(in) :: options
        type(ensemble_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        type(ensemble_options), intent(in), optional :: ens_options
        class(ensemble_progress), intent(inout), optional :: progress
        call run_ensemble(members%count(), t_span, y0, options, res, t_eval, events, &
                          ens_options, progress, members=members)
    end subroutine ensemble_of_members

    subroutine run_ensemble(m, t_span, y0, options, res, t_eval, events, ens_options, &
                            progress, sys, members)
        integer, intent(in) :: m
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: y0(:, :)
        type(ode_options), intent(in) :: options
        type(ensemble_result), intent(out) :: res
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        type(ensemble_options), intent(in), optional :: ens_options
        class(ensemble_progress), intent(inout), optional :: progress
        class(ode_system), intent(in), optional :: sys
        class(ensemble_members), intent(in), optional :: members

        type(ensemble_options) :: eo
        type(ode_options) :: opt
        integer :: n, nt, k, ne, nthr, chunk, i, i0, i1, first_bad
        logical :: cancel
        real(dp) :: nan
        character(len=160), allocatable :: msgs(:)
        character(len=24) :: buf

        if (present(ens_options)) eo = ens_options
        n = size(y0, 1)
        nt = 0
        if (present(t_eval)) nt = size(t_eval)
        ne = 0
        if (present(events)) ne = events%n_events()
        k = 0
        if (ne > 0) k = eo%max_events
        res%n = n
        res%m = m
        res%nt = nt
        res%k = k
        res%done = 0
        res%status = CM_BAD_INPUT
        nan = nan_dp

        ! ---------------------------------------------------------------- validation
        if (m < 1) then
            res%message = "bad input: the ensemble has no members"
        else if (n < 1) then
            res%message = "bad input: y0 is empty"
        else if (size(y0, 2) /= 1 .and. size(y0, 2) /= m) then
            res%message = "bad input: y0 must have one column or one per member ("// &
                          itoa(m)//")"
        else if (eo%threads < 0) then
            res%message = "bad input: threads must be non-negative"
        else if (eo%chunk < 0) then
            res%message = "bad input: chunk must be non-negative"
        else if (ne > 0 .and. eo%max_events < 1) then
            res%message = "bad input: max_events must be positive"
        else if (eo%terminal .and. ne == 0) then
            res%message = "bad input: a terminal ensemble needs events"
        else
            res%message = ""
        end if
        if (len(res%message) == 0 .and. ne > 0) then
            if (size(events%direction) /= ne .or. .not. allocated(events%terminal)) then
                res%message = "bad input: events need direction and terminal for each function"
            end if
            select type (events)
            type is (crossing_events)
                if (.not. allocated(events%component) .or. .not. allocated(events%value)) then
                    res%message = "bad input: crossing events need component and value"
                else if (size(events%component) /= ne .or. size(events%value) /= ne) then
                    res%message = "bad input: crossing events need one component and one " &
                                  //"value per event"
                else if (any(events%component < 1 .or. events%component > n)) then
                    res%message = "bad input: an event component is outside 1..n"
                end if
            end select
        end if
        if (len(res%message) > 0) then
            call allocate_outputs()
            return
        end if

        call allocate_outputs()
        res%member_status = ENSEMBLE_NOT_RUN
        opt = options
        opt%dense_output = .false.
        opt%save_steps = .false.

        nthr = 1
        !$ nthr = omp_get_max_threads()
        if (eo%threads > 0) nthr = eo%threads
        chunk = m
        if (present(progress)) then
            chunk = eo%chunk
            if (chunk == 0) chunk = max(16*nthr, (m + 99)/100)
        end if
        allocate (msgs(m))

        cancel = .false.
        i0 = 1
        do while (i0 <= m)
            i1 = min(m, i0 + chunk - 1)
            !$omp parallel do num_threads(nthr) schedule(dynamic, 1) default(shared) private(i)
            do i = i0, i1
                call one_member(i)
            end do
            !$omp end parallel do
            res%done = i1
            if (present(progress)) call progress%report(i1, m, cancel)
            if (cancel) exit
            i0 = i1 + 1
        end do

        first_bad = 0
        do i = 1, res%done
            if (res%member_status(i) < 0) then
                first_bad = i
                exit
            end if
        end do
        if (first_bad > 0) then
            res%status = res%member_status(first_bad)
            res%message = "member "//itoa(first_bad)//": "//trim(msgs(first_bad))
        else if (cancel .and. res%done < m) then
            res%status = CM_USER_ERROR
            write (buf, '(i0," of ",i0)') res%done, m
            res%message = "cancelled by the progress report after "//trim(buf)//" members"
        else
            res%status = CM_SUCCESS
            res%message = "success"
        end if

    contains

        subroutine allocate_outputs()
            allocate (res%y(n, nt, m), res%t_final(m), res%y_final(n, m))
            allocate (res%member_status(m), res%nfev(m), res%naccept(m), res%nreject(m))
            allocate (res%nev(m), res%ev_t(k, m), res%ev_y(n, k, m), res%ev_id(k, m))
            res%y = nan
            res%t_final = nan
            res%y_final = nan
            res%member_status = CM_BAD_INPUT
            res%nfev = 0
            res%naccept = 0
            res%nreject = 0
            res%nev = 0
            res%ev_t = nan
            res%ev_y = nan
            res%ev_id = 0
        end subroutine allocate_outputs

        !> Integrate member i into its columns of res (called from the threads).
        subroutine one_member(i)
            integer, intent(in) :: i
            class(ode_system), allocatable :: own
            integer :: info
            character(len=:), allocatable :: msg
            if (present(members)) then
                call members%system(i, own, info, msg)
                if (info /= CM_SUCCESS) then
                    res%member_status(i) = info
                    msgs(i) = msg
                    return
                end if
                call solve_member(own, t_span, y0(:, min(i, size(y0, 2))), opt, nt, t_eval, &
                                  events, k, eo%terminal, res%y(:, :, i), res%t_final(i), &
                                  res%y_final(:, i), res%member_status(i), res%nfev(i), &
                                  res%naccept(i), res%nreject(i), res%nev(i), res%ev_t(:, i), &
                                  res%ev_y(:, :, i), res%ev_id(:, i), msgs(i))
            else
                call solve_member(sys, t_span, y0(:, min(i, size(y0, 2))), opt, nt, t_eval, &
                                  events, k, eo%terminal, res%y(:, :, i), res%t_final(i), &
                                  res%y_final(:, i), res%member_status(i), res%nfev(i), &
                                  res%naccept(i), res%nreject(i), res%nev(i), res%ev_t(:, i), &
                                  res%ev_y(:, :, i), res%ev_id(:, i), msgs(i))
            end if
        end subroutine one_member

    end subroutine run_ensemble

    !> One member: ode_solve, then its outputs copied into the ensemble's arrays.
    subroutine solve_member(sys, t_span, y0, opt, nt, t_eval, events, k, terminal, y_out, &
                            t_fin, y_fin, status, nfev, naccept, nreject, nev, ev_t, ev_y, &
                            ev_id, msg)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t_span(2)
        real(dp), intent(in) :: y0(:)
        type(ode_options), intent(in) :: opt
        integer, intent(in) :: nt
        real(dp), intent(in), optional :: t_eval(:)
        class(ode_events), intent(in), optional :: events
        integer, intent(in) :: k
        logical, intent(in) :: terminal
        real(dp), intent(inout) :: y_out(:, :), t_fin, y_fin(:)
        integer, intent(out) :: status, nfev, naccept, nreject, nev
        real(dp), intent(inout) :: ev_t(:), ev_y(:, :)
        integer, intent(inout) :: ev_id(:)
        character(len=*), intent(out) :: msg

        type(ode_result) :: r
        type(member_hook) :: hook
        class(ode_events), allocatable :: ev
        logical :: use_hook
        real(dp) :: t_stop, posneg
        integer :: j

        use_hook = nt > 0 .or. terminal
        if (use_hook) then
            hook%t_last = t_span(1)
            hook%y_last = y0
        end if
        if (k > 0) then
            ! the members' events never stop the integrator themselves: a terminal ensemble
            ! stops through the hook after the step of the k-th event
            allocate (ev, source=events)
            ev%terminal = .false.
            if (terminal) then
                allocate (hook%ev, source=ev)
                allocate (hook%g_old(ev%n_events()), hook%g_new(ev%n_events()))
                call ev%eval(t_span(1), y0, hook%g_old)
                hook%k = k
                hook%count_events = .true.
            end if
        end if

        if (nt > 0 .and. k > 0) then
            call ode_solve(sys, t_span, y0, opt, r, t_eval=t_eval, events=ev, hook=hook)
        else if (nt > 0) then
            call ode_solve(sys, t_span, y0, opt, r, t_eval=t_eval, hook=hook)
        else if (k > 0 .and. terminal) then
            call ode_solve(sys, t_span, y0, opt, r, events=ev, hook=hook)
        else if (k > 0) then
            call ode_solve(sys, t_span, y0, opt, r, events=ev)
        else
            call ode_solve(sys, t_span, y0, opt, r)
        end if

        status = r%status
        msg = r%message
        nfev = r%stats%nfev
        naccept = r%stats%naccept
        nreject = r%stats%nreject
        nev = min(r%nev, k)
        do j = 1, nev
            ev_t(j) = r%ev_t(j)
            ev_y(:, j) = r%ev_y(:, j)
            ev_id(j) = r%ev_id(j)
        end do
        do j = 1, r%nt
            if (j > nt) exit
            y_out(:, j) = r%y(:, j)
        end do
        if (use_hook) then
            t_fin = hook%t_last
            y_fin = hook%y_last
        else if (r%nt > 0) then
            t_fin = r%t(r%nt)
            y_fin = r%y(:, r%nt)
        end if
        if (terminal .and. status == CM_EVENT_STOP .and. r%nev >= k) then
            ! stopped after the step holding the k-th event: the member ends at that event,
            ! and outputs beyond it are not part of its solution
            t_stop = r%ev_t(k)
            t_fin = t_stop
            y_fin = r%ev_y(:, k)
            msg = "a termination event occurred"
            posneg = sign(1.0_dp, t_span(2) - t_span(1))
            do j = 1, min(r%nt, nt)
                if ((t_eval(j) - t_stop)*posneg > 0.0_dp) &
                    y_out(:, j) = nan_dp
            end do
        end if
    end subroutine solve_member

end module conmech_ensemble
