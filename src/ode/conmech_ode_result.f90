!> The result of `ode_solve` (solution points, events, dense output, counters, status) and
!! its growable output buffers.
module conmech_ode_result
    use conmech_kinds, only: dp
    use conmech_status, only: CM_BAD_INPUT
    use conmech_ode_options, only: ode_stats
    use conmech_ode_dense, only: dense_solution
    implicit none
    private

    public :: ode_result, push_point, push_event, shrink_result, start_outputs

    !> points the outputs hold first (the end points of a run)
    integer, parameter :: FIRST_ROOM = 16
    !> numbers (times and states) the outputs' second growth makes room for (8 kB)
    integer, parameter :: ROOM = 1024

    !> Result of `ode_solve`.
    type :: ode_result
        integer :: status = CM_BAD_INPUT
        character(len=:), allocatable :: message
        logical :: success = .false.
        type(ode_stats) :: stats
        integer :: nt = 0                          !! number of output points
        real(dp), allocatable :: t(:)              !! (nt)
        real(dp), allocatable :: y(:, :)           !! (n, nt)
        integer :: nev = 0                         !! number of events found
        real(dp), allocatable :: ev_t(:)           !! (nev) event times
        real(dp), allocatable :: ev_y(:, :)        !! (n, nev) states at the events
        integer, allocatable :: ev_id(:)           !! (nev) which event function
        type(dense_solution) :: sol                !! if options%dense_output
    end type ode_result

contains

    !> Empty outputs for states of size n: room for FIRST_ROOM points already (the first
    !! growth of `push_point`, without the allocation of empty arrays before it), none
    !! for events.
    subroutine start_outputs(res, n)
        type(ode_result), intent(inout) :: res
        integer, intent(in) :: n
        allocate (res%t(FIRST_ROOM), res%y(n, FIRST_ROOM), res%ev_t(0), res%ev_y(n, 0), &
                  res%ev_id(0))
    end subroutine start_outputs

    !> Append the point (t, y) to the outputs: room for FIRST_ROOM points first (the end
    !! points of a run), then at once for ROOM numbers (times and states), so that a run
    !! of a small system stores its steps without growing again (each growth allocates and
    !! copies both arrays), then twice the room each time.
    subroutine push_point(res, t, y)
        type(ode_result), intent(inout) :: res
        real(dp), intent(in) :: t, y(:)
        integer :: cap
        if (res%nt >= size(res%t)) then
            cap = FIRST_ROOM
            if (size(res%t) > 0) cap = max(2*size(res%t), ROOM/(size(y) + 1))
            call resize(res%t, res%y, res%nt, cap)
        end if
        res%nt = res%nt + 1
        res%t(res%nt) = t
        res%y(:, res%nt) = y
    end subroutine push_point

    !> Append the event (t, y) of event function id.
    subroutine push_event(res, t, y, id)
        type(ode_result), intent(inout) :: res
        real(dp), intent(in) :: t, y(:)
        integer, intent(in) :: id
        integer, allocatable :: ii(:)
        integer :: cap
        cap = size(res%ev_t)
        if (res%nev >= cap) then
            cap = max(8, 2*cap)
            call resize(res%ev_t, res%ev_y, res%nev, cap)
            allocate (ii(cap))
            ii(1:res%nev) = res%ev_id(1:res%nev)
            call move_alloc(ii, res%ev_id)
        end if
        res%nev = res%nev + 1
        res%ev_t(res%nev) = t
        res%ev_y(:, res%nev) = y
        res%ev_id(res%nev) = id
    end subroutine push_event

    !> The output and event arrays cut to their counts.
    subroutine shrink_result(res)
        type(ode_result), intent(inout) :: res
        integer, allocatable :: ii(:)
        if (size(res%t) /= res%nt) call resize(res%t, res%y, res%nt, res%nt)
        if (size(res%ev_t) /= res%nev) then
            call resize(res%ev_t, res%ev_y, res%nev, res%nev)
            ii = res%ev_id(1:res%nev)
            call move_alloc(ii, res%ev_id)
        end if
    end subroutine shrink_result

    !> Times t and states y (columns) to capacity cap, keeping the first nkeep.
    subroutine resize(t, y, nkeep, cap)
        real(dp), allocatable, intent(inout) :: t(:), y(:, :)
        integer, intent(in) :: nkeep, cap
        real(dp), allocatable :: tt(:), yy(:, :)
        allocate (tt(cap), yy(size(y, 1), cap))
        tt(1:nkeep) = t(1:nkeep)
        yy(:, 1:nkeep) = y(:, 1:nkeep)
        call move_alloc(tt, t)
        call move_alloc(yy, y)
    end subroutine resize

end module conmech_ode_result
