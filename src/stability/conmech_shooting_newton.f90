!> The Newton iteration of single shooting, in the pieces general and symmetric shooting
!! (conmech_shooting) share: the flow and its state transition matrix over [0, t], the
!! Gauss-Newton step in the least-squares sense (LAPACK dgelsd) with its checks, and the
!! stopping test |dx| <= tol max(1, |y|, t) with |residual| <= sqrt(tol). Each piece sets
!! the orbit's status and message (prefixed with the caller's name) when the iteration
!! must stop; the residual vector and the Newton matrix are the caller's.
module conmech_shooting_newton
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options
    use conmech_variational, only: integrate_stm
    use conmech_rank, only: identity
    use conmech_block_chain, only: lstsq_solve
    use conmech_orbit_types, only: shooting_options, periodic_orbit
    implicit none
    private

    public :: ode_opts, shooting_flow, shooting_step, shooting_check

contains

    !> The integrator options of the shooting options.
    function ode_opts(o) result(oo)
        type(shooting_options), intent(in) :: o
        type(ode_options) :: oo
        oo%method = o%method
        oo%rtol = o%rtol
        oo%atol = o%atol
        oo%max_steps = o%max_steps
    end function ode_opts

    !> yt = y(t; y) and phi its state transition matrix from 0; ok false (the orbit's status
    !! set) when the integration fails.
    subroutine shooting_flow(sys, y, t, opt, yt, phi, orbit, who, ok)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: y(:), t
        type(shooting_options), intent(in) :: opt
        real(dp), intent(out) :: yt(:), phi(:, :)
        type(periodic_orbit), intent(inout) :: orbit
        character(len=*), intent(in) :: who
        logical, intent(out) :: ok
        integer :: info
        character(len=:), allocatable :: msg
        yt = y
        phi = identity(size(phi, 1))
        call integrate_stm(sys, 0.0_dp, t, yt, phi, ode_opts(opt), info, msg)
        ok = info >= 0
        if (ok) return
        call orbit%fail(info, who//": integration failed: "//msg)
    end subroutine shooting_flow

    !> The step dx of jac dx = -r (least squares), orbit%residual = max |r|; ok false (the
    !! orbit's status set) for non-finite values or a rank below min_rank (`singular` is
    !! then the message).
    subroutine shooting_step(jac, r, opt, min_rank, dx, orbit, who, singular, ok)
        real(dp), intent(in) :: jac(:, :), r(:)
        type(shooting_options), intent(in) :: opt
        integer, intent(in) :: min_rank
        real(dp), intent(out) :: dx(:)
        type(periodic_orbit), intent(inout) :: orbit
        character(len=*), intent(in) :: who, singular
        logical, intent(out) :: ok
        integer :: rank, info
        orbit%residual = maxval(abs(r))
        ok = .false.
        if (.not. all(abs(jac) <= huge(1.0_dp)) .or. .not. all(abs(r) <= huge(1.0_dp))) then
            call orbit%fail(CM_NO_CONVERGENCE, who//": non-finite values (a bad guess?)")
            return
        end if
        call lstsq_solve(jac, -r, dx, rank, info, opt%rcond)
        if (info /= CM_SUCCESS .or. rank < min_rank) then
            call orbit%fail(CM_SINGULAR, who//": "//singular)
            return
        end if
        ok = .true.
    end subroutine shooting_step

    !> After the update to (y, t) by dx: done with CM_NO_CONVERGENCE when t is no longer
    !! positive (`what` names t in the message), done with success when converged.
    subroutine shooting_check(dx, y, t, opt, orbit, who, what, done)
        real(dp), intent(in) :: dx(:), y(:), t
        type(shooting_options), intent(in) :: opt
        type(periodic_orbit), intent(inout) :: orbit
        character(len=*), intent(in) :: who, what
        logical, intent(out) :: done
        done = .true.
        if (.not. (t > 0.0_dp)) then
            call orbit%fail(CM_NO_CONVERGENCE, who//": "//what//" became non-positive")
            return
        end if
        if (maxval(abs(dx)) <= opt%tol*max(1.0_dp, maxval(abs(y)), t) .and. &
            orbit%residual <= sqrt(opt%tol)) then
            orbit%info = CM_SUCCESS
            orbit%message = "success"
            return
        end if
        done = .false.
    end subroutine shooting_check

end module conmech_shooting_newton
