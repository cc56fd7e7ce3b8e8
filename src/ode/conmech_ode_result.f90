!> The result of `ode_solve` (solution points, events, dense output, counters, status) and
!! its growable output buffers.
module conmech_ode_result
    use conmech_kinds, only: dp
    use conmech_status, only: CM_BAD_INPUT
    use conmech_ode_options, only: ode_stats
    use conmech_ode_dense, only: dense_solution
    implicit none
    private

    public :: ode_result, push_point, push_event, shrink_result

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

    subroutine push_point(res, t, y)
        type(ode_result), intent(inout) :: res
        real(dp), intent(in) :: t, y(:)
        real(dp), allocatable :: tt(:), yy(:, :)
        integer :: cap
        cap = size(res%t)
        if (res%nt >= cap) then
            cap = max(16, 2*cap)
            allocate (tt(cap), yy(size(y), cap))
            tt(1:res%nt) = res%t(1:res%nt)
            yy(:, 1:res%nt) = res%y(:, 1:res%nt)
            call move_alloc(tt, res%t)
            call move_alloc(yy, res%y)
        end if
        res%nt = res%nt + 1
        res%t(res%nt) = t
        res%y(:, res%nt) = y
    end subroutine push_point

    subroutine push_event(res, t, y, id)
        type(ode_result), intent(inout) :: res
        real(dp), intent(in) :: t, y(:)
        integer, intent(in) :: id
        real(dp), allocatable :: tt(:), yy(:, :)
        integer, allocatable :: ii(:)
        integer :: cap
        cap = size(res%ev_t)
        if (res%nev >= cap) then
            cap = max(8, 2*cap)
            allocate (tt(cap), yy(size(y), cap), ii(cap))
            tt(1:res%nev) = res%ev_t(1:res%nev)
            yy(:, 1:res%nev) = res%ev_y(:, 1:res%nev)
            ii(1:res%nev) = res%ev_id(1:res%nev)
            call move_alloc(tt, res%ev_t)
            call move_alloc(yy, res%ev_y)
            call move_alloc(ii, res%ev_id)
        end if
        res%nev = res%nev + 1
        res%ev_t(res%nev) = t
        res%ev_y(:, res%nev) = y
        res%ev_id(res%nev) = id
    end subroutine push_event

    subroutine shrink_result(res)
        type(ode_result), intent(inout) :: res
        real(dp), allocatable :: tt(:), yy(:, :)
        integer, allocatable :: ii(:)
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
    end subroutine shrink_result

end module conmech_ode_result
