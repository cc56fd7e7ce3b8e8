!> The problem a continuation of periodic orbits follows (see conmech_continuation and
!! conmech_cont_problem): its set-up from the user's options, the unknowns X of single
!! shooting (general or symmetric) or of a boundary-value discretisation (conmech_orbit_bvp)
!! and their packing, the phase condition's reference, and the reduced norm.
!!
!! The reduced unknowns: single shooting, all of X; multiple shooting and collocation,
!! the first node z_1 and the border unknowns (S, p) only. Tangents are normalised and the
!! pseudo-arclength equation written in them, so that a step `ds` means the same for every
!! discretisation.
module conmech_cont_setup
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_text, only: itoa
    use conmech_ode_system, only: ode_system
    use conmech_orbit_types, only: set_parameter_proc, ORBIT_SINGLE, ORBIT_COLLOCATION
    use conmech_orbit_bvp
    use conmech_multiple_shooting, only: ms_guess
    use conmech_collocation, only: co_guess
    use conmech_branch_types
    implicit none
    private

    public :: cproblem, cconstraint, branch_energy, CON_LINEAR, CON_ENERGY
    public :: cp_setup, cp_pack_start, cp_unpack, cp_set_reference, cp_rdot, cp_rnorm, is_bvp

    integer, parameter :: CON_LINEAR = 1  !! a . X = b
    integer, parameter :: CON_ENERGY = 2  !! E(y0(X), p(X)) = b

    !> The continued problem.
    type :: cproblem
        integer :: n = 0, nx = 0, neq = 0
        logical :: sym = .false., tfree = .true.
        integer, allocatable :: free(:), targets(:)
        real(dp) :: pf = 2.0_dp, tfix = 0.0_dp
        real(dp), allocatable :: ybase(:), yref(:), fref(:)
        type(cont_options) :: o
        integer :: ntriv = 0
        type(orbit_bvp) :: bvp                    !! multiple shooting / collocation
        ! the last single-shooting evaluation
        real(dp), allocatable :: g(:), dg(:, :), phi(:, :)
    end type cproblem

    !> The extra row of the corrector.
    type :: cconstraint
        integer :: kind = CON_LINEAR
        real(dp), allocatable :: a(:)
        real(dp) :: b = 0.0_dp
    end type cconstraint

    !> An energy (first integral) E(y, p) along a branch: extend it and implement `value`.
    type, abstract :: branch_energy
    contains
        procedure(energy_value), deferred :: value
    end type branch_energy

    abstract interface
        function energy_value(self, y, p) result(e)
            import :: dp, branch_energy
            class(branch_energy), intent(in) :: self
            real(dp), intent(in) :: y(:), p
            real(dp) :: e
        end function energy_value
    end interface

contains

    !> True for multiple shooting and collocation.
    logical function is_bvp(pb)
        type(cproblem), intent(in) :: pb
        is_bvp = pb%o%discretisation /= ORBIT_SINGLE
    end function is_bvp

    !> Set up the problem (see continue_orbits); a message names what is wrong.
    subroutine cp_setup(pb, y0, period, p0, free, targets, free_time, period_factor, info, &
                        msg)
        type(cproblem), intent(inout) :: pb
        real(dp), intent(in) :: y0(:), period, p0
        integer, intent(in), optional :: free(:), targets(:)
        logical, intent(in), optional :: free_time
        real(dp), intent(in), optional :: period_factor
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: nf, ntg, k
        character(len=64) :: b1
        pb%n = size(y0)
        info = CM_BAD_INPUT
        if (pb%n < 1 .or. .not. all(abs(y0) <= huge(1.0_dp)) .or. .not. (period > 0.0_dp) .or. &
            .not. (abs(p0) <= huge(1.0_dp)) .or. pb%o%max_points < 1 .or. &
            .not. (pb%o%ds > 0.0_dp) .or. .not. (pb%o%ds_min > 0.0_dp)) then
            msg = "continuation: bad input (empty or non-finite y0 or p0, period <= 0, "// &
                  "max_points < 1, ds <= 0)"
            return
        end if
        if (pb%o%discretisation < 1 .or. pb%o%discretisation > 3) then
            msg = "continuation: unknown discretisation"
            return
        end if
        pb%sym = present(free)
        if (pb%o%in_period .and. .not. pb%o%autonomous) then
            msg = "continuation: in_period is for autonomous systems"
            return
        end if
        if (pb%sym .neqv. present(targets)) then
            msg = "continuation: symmetric shooting needs both free and targets"
            return
        end if
        pb%ybase = y0
        if (present(period_factor)) pb%pf = period_factor
        if (pb%sym) then
            nf = size(free)
            ntg = size(targets)
            if (nf < 1 .or. ntg < 1 .or. any(free < 1) .or. &
                any(free > pb%n) .or. any(targets < 1) .or. any(targets > pb%n)) then
                msg = "continuation: free and targets must be state indices"
                return
            end if
            pb%free = free
            pb%targets = targets
            pb%tfree = .false.
            if (present(free_time)) pb%tfree = free_time
            if (pb%o%in_period .and. pb%tfree) then
                msg = "continuation: in_period continues in the time itself (free_time "// &
                    "must be false)"
                return
            end if
            if (.not. (pb%pf > 0.0_dp)) then
                msg = "continuation: period_factor must be positive"
                return
            end if
            if (nf + merge(1, 0, pb%tfree) /= ntg) then
                write (b1, '(i0,a,i0,a)') nf + merge(1, 0, pb%tfree), " unknowns (", nf, &
                    " free components"
                if (pb%tfree) b1 = trim(b1)//" + the time"
                msg = "continuation: "//trim(b1)//") for "// &
                      itoa(ntg)//" targets: symmetric shooting needs as "// &
                      "many unknowns (free components, and the time if free) as targets "// &
                      "(the parameter is the one extra unknown of the branch)"
                return
            end if
            pb%tfix = period/pb%pf
            pb%nx = nf + 1
            if (pb%tfree) pb%nx = pb%nx + 1
            pb%neq = ntg
        else
            pb%pf = 1.0_dp
            pb%tfree = pb%o%autonomous .and. .not. pb%o%fixed_period .and. &
                       .not. pb%o%in_period
            pb%tfix = period
            pb%nx = pb%n + 1
            if (pb%tfree) pb%nx = pb%nx + 1
            pb%neq = pb%n
            if (pb%o%autonomous) pb%neq = pb%n + 1
        end if
        pb%ntriv = 0
        if (pb%o%autonomous) pb%ntriv = 1
        if (pb%o%conservative) pb%ntriv = pb%ntriv + 1
        allocate (pb%yref(pb%n), pb%fref(pb%n))
        pb%yref = y0
        pb%fref = 0.0_dp
        if (is_bvp(pb)) then
            k = pb%o%segments
            if (pb%o%discretisation == ORBIT_COLLOCATION) k = pb%o%intervals
            ! X = [nodes, stages, S (if free or continued), p (unless in_period)]
            if (pb%sym) then
                call bvp_setup(pb%bvp, pb%o%discretisation, pb%n, k, pb%o%degree, .false., &
                               pb%tfree .or. pb%o%in_period, .not. pb%o%in_period, &
                               pb%tfix, p0, info, msg, free, targets, y0)
            else
                call bvp_setup(pb%bvp, pb%o%discretisation, pb%n, k, pb%o%degree, .true., &
                               pb%tfree .or. pb%o%in_period, .not. pb%o%in_period, &
                               pb%tfix, p0, info, msg)
            end if
            if (info /= CM_SUCCESS) then
                msg = "continuation: "//msg
                return
            end if
            pb%bvp%autonomous = pb%o%autonomous
            pb%bvp%rtol = pb%o%rtol
            pb%bvp%atol = pb%o%atol
            pb%bvp%integrator = pb%o%integrator
            pb%bvp%fd_step = pb%o%fd_step
            pb%nx = pb%bvp%nx
        end if
        info = CM_SUCCESS
        msg = "success"
    end subroutine cp_setup

    !> X of the start (y0, period, p0); multiple shooting and collocation integrate y0
    !! over the period for the other nodes (info from that integration).
    subroutine cp_pack_start(sys, pb, y0, period, p0, x, info, msg)
        class(ode_system), intent(in) :: sys
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: y0(:), period, p0
        real(dp), intent(out) :: x(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: nf
        info = CM_SUCCESS
        msg = "success"
        x = 0.0_dp
        if (is_bvp(pb)) then
            if (pb%bvp%tfree) x(bvp_index_w(pb%bvp, 1)) = period/pb%pf
            if (pb%bvp%pfree) x(pb%nx) = p0
            if (pb%bvp%method == ORBIT_COLLOCATION) then
                call co_guess(pb%bvp, sys, y0, period/pb%pf, x, info, msg)
            else
                call ms_guess(pb%bvp, sys, y0, period/pb%pf, x, info, msg)
            end if
            return
        end if
        if (pb%sym) then
            nf = size(pb%free)
            x(1:nf) = y0(pb%free)
            if (pb%tfree) x(nf + 1) = period/pb%pf
        else
            x(1:pb%n) = y0
            if (pb%tfree) x(pb%n + 1) = period
        end if
        x(pb%nx) = p0
        if (pb%o%in_period) x(pb%nx) = period/pb%pf
    end subroutine cp_pack_start

    !> (full initial state, integration time, period, parameter) of X. With in_period
    !! the parameter is the period.
    pure subroutine cp_unpack(pb, x, y, tend, per, p)
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: y(:), tend, per, p
        integer :: nf
        if (pb%o%discretisation /= ORBIT_SINGLE) then
            y = bvp_z(pb%bvp, x, 1)
            tend = bvp_span(pb%bvp, x)
            per = pb%pf*tend
            p = bvp_param(pb%bvp, x)
            if (pb%o%in_period) p = per
            return
        end if
        if (pb%sym) then
            nf = size(pb%free)
            y = pb%ybase
            y(pb%free) = x(1:nf)
            tend = pb%tfix
            if (pb%tfree) tend = x(nf + 1)
        else
            y = x(1:pb%n)
            tend = pb%tfix
            if (pb%tfree) tend = x(pb%n + 1)
        end if
        if (pb%o%in_period) tend = x(pb%nx)
        per = pb%pf*tend
        p = x(pb%nx)
        if (pb%o%in_period) p = per
    end subroutine cp_unpack

    !> The phase condition's reference: the current point and its vector field.
    subroutine cp_set_reference(sys, set_param, pb, x)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(cproblem), intent(inout) :: pb
        real(dp), intent(in) :: x(:)
        real(dp) :: tend, per, p
        if (pb%sym .or. .not. pb%o%autonomous) return
        call cp_unpack(pb, x, pb%yref, tend, per, p)
        if (.not. pb%o%in_period) call set_param(sys, p)
        call sys%rhs(0.0_dp, pb%yref, pb%fref)
        if (is_bvp(pb)) then
            pb%bvp%yref = pb%yref
            pb%bvp%fref = pb%fref
        end if
    end subroutine cp_set_reference

    !> Dot product and norm over the reduced unknowns.
    pure real(dp) function cp_rdot(pb, a, b) result(d)
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: a(:), b(:)
        integer :: nw
        if (pb%o%discretisation == ORBIT_SINGLE) then
            d = dot_product(a, b)
        else
            nw = pb%bvp%nw
            d = dot_product(a(1:pb%n), b(1:pb%n)) + &
                dot_product(a(pb%nx - nw + 1:), b(pb%nx - nw + 1:))
        end if
    end function cp_rdot

    pure real(dp) function cp_rnorm(pb, a) result(r)
        type(cproblem), intent(in) :: pb
        real(dp), intent(in) :: a(:)
        r = sqrt(max(cp_rdot(pb, a, a), 0.0_dp))
    end function cp_rnorm

end module conmech_cont_setup
