!> Multiple shooting of a periodic (or symmetric) orbit: the span [0, S] cut into K
!! segments, one integration of the state and its STM per segment (the variational
!! equations of `integrate_stm`, analytic Jacobians or J x products where the system has
!! them). Segment k gives the residual y(t_(k+1); z_k) - z_(k+1) and the chain block
!! (A_k, B_k, C_k) = (Phi_k, -I, [d y_end/dS, d y_end/dp]) of conmech_orbit_bvp; the
!! derivative in S is mesh_(k+1) f(t_(k+1), y_end) - mesh_k Phi_k f(t_k, z_k), the one in
!! the parameter a central difference of two state integrations (all segments at p + h,
!! then at p - h: two parameter changes per evaluation).
!!
!! The segments keep the Newton problem well conditioned where single shooting is not:
!! each STM grows only by its segment's factor, and the structured elimination of
!! conmech_block_chain never multiplies them together.
module conmech_multiple_shooting
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_integrate
    use conmech_variational, only: integrate_stm
    use conmech_orbit_types, only: set_parameter_proc
    use conmech_orbit_bvp, only: orbit_bvp, bvp_z, bvp_span, bvp_begin
    use conmech_block_chain, only: chain_factor
    implicit none
    private

    public :: ms_evaluate, ms_guess, guess_states, segment_closure, bvp_ode_options

contains

    !> The integrator options of the problem (DOP853 unless changed).
    pure function bvp_ode_options(bvp) result(oo)
        type(orbit_bvp), intent(in) :: bvp
        type(ode_options) :: oo
        oo%rtol = bvp%rtol
        oo%atol = bvp%atol
        oo%max_steps = bvp%max_steps
        oo%method = bvp%integrator
    end function bvp_ode_options

    !> Residuals, chain blocks and their factorisation at X.
    subroutine ms_evaluate(bvp, sys, set_param, x, info, msg)
        type(orbit_bvp), intent(inout) :: bvp
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        real(dp), intent(in) :: x(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(ode_options) :: oo
        real(dp) :: y(bvp%n), phi(bvp%n, bvp%n), f0(bvp%n), f1(bvp%n), z(bvp%n)
        real(dp), allocatable :: yp(:, :), ym(:, :)
        real(dp) :: span, p, t0, t1, h
        integer :: n, k, j, i, jw
        character(len=16) :: buf
        n = bvp%n
        k = bvp%k
        oo = bvp_ode_options(bvp)
        call bvp_begin(bvp, x, .false., span, p, info, msg)
        if (info /= CM_SUCCESS) return
        if (bvp%pfree) then
            ! the parameter derivative of every segment end: all at p + h, then p - h
            allocate (yp(n, k), ym(n, k))
            h = bvp%fd_step*max(1.0_dp, abs(p))
            call set_param(sys, p + h)
            call ends(yp, info, msg)
            if (info < 0) return
            call set_param(sys, p - h)
            call ends(ym, info, msg)
            if (info < 0) return
            call set_param(sys, p)
        end if
        do j = 1, k
            t0 = bvp%mesh(j)*span
            t1 = bvp%mesh(j + 1)*span
            z = bvp_z(bvp, x, j)
            y = z
            phi = 0.0_dp
            do i = 1, n
                phi(i, i) = 1.0_dp
            end do
            call integrate_stm(sys, t0, t1, y, phi, oo, info, msg)
            if (info < 0) then
                write (buf, '(i0)') j
                msg = "segment "//trim(buf)//": "//msg
                return
            end if
            call sys%rhs(t0, z, f0)
            call sys%rhs(t1, y, f1)
            bvp%gres(:, j) = y - bvp_z(bvp, x, j + 1)
            bvp%d(:, j) = -bvp%gres(:, j)
            bvp%a(:, :, j) = phi
            bvp%b(:, :, j) = 0.0_dp
            do i = 1, n
                bvp%b(i, i, j) = -1.0_dp
            end do
            jw = 0
            if (bvp%tfree) then
                jw = 1
                bvp%c(:, 1, j) = bvp%mesh(j + 1)*f1 - bvp%mesh(j)*matmul(phi, f0)
            end if
            if (bvp%pfree) bvp%c(:, jw + 1, j) = (yp(:, j) - ym(:, j))/(2.0_dp*h)
            bvp%fstart(:, j) = f0
            bvp%fend(:, j) = f1
        end do
        call chain_factor(bvp%chain, bvp%a, bvp%b, bvp%c, info)
        msg = "success"
        if (info == CM_SINGULAR) msg = "a segment STM is singular"
        if (info == CM_NONFINITE) msg = "non-finite values in the segment STMs"
    contains
        subroutine ends(ye, inf, m)
            real(dp), intent(out) :: ye(:, :)
            integer, intent(out) :: inf
            character(len=:), allocatable, intent(out) :: m
            integer :: jj
            inf = CM_SUCCESS
            do jj = 1, k
                ye(:, jj) = bvp_z(bvp, x, jj)
                call ode_integrate(sys, bvp%mesh(jj)*span, bvp%mesh(jj + 1)*span, ye(:, jj), &
                                   oo, inf, message=m)
                if (inf < 0) return
            end do
        end subroutine ends
    end subroutine ms_evaluate

    !> The nodes z_j = y(mesh_j S) of the orbit integrated from y0 (the initial guess of
    !! the segments), into x (stages and border unknowns untouched).
    subroutine ms_guess(bvp, sys, y0, span, x, info, msg)
        type(orbit_bvp), intent(in) :: bvp
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: y0(:), span
        real(dp), intent(inout) :: x(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        real(dp) :: ys(bvp%n, bvp%k + 1)
        call guess_states(bvp, sys, y0, bvp%mesh(1:bvp%k + 1)*span, ys, info, msg)
        if (info < 0) return
        x(1:(bvp%k + 1)*bvp%n) = reshape(ys, [(bvp%k + 1)*bvp%n])
    end subroutine ms_guess

    !> The orbit integrated from y0 at times(1) through the increasing times: ys(:, i) is
    !! its state at times(i) (ys(:, 1) = y0), one integration from each time to the next
    !! (the initial guess of a discretisation). info and msg of the last integration, or
    !! of the one that failed (info < 0).
    subroutine guess_states(bvp, sys, y0, times, ys, info, msg)
        type(orbit_bvp), intent(in) :: bvp
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: y0(:), times(:)
        real(dp), intent(out) :: ys(:, :)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(ode_options) :: oo
        real(dp) :: y(bvp%n)
        integer :: i
        oo = bvp_ode_options(bvp)
        y = y0
        ys(:, 1) = y
        info = CM_SUCCESS
        msg = "success"
        do i = 2, size(times)
            call ode_integrate(sys, times(i - 1), times(i), y, oo, info, message=msg)
            if (info < 0) then
                msg = "integrating the initial guess: "//msg
                return
            end if
            ys(:, i) = y
        end do
    end subroutine guess_states

    !> The closure of the nodes by independent integrations (the state alone, not the
    !! variational equations): max over j of |y(t_(j+1); z_j) - z_(j+1)|.
    subroutine segment_closure(bvp, sys, x, closure, info, msg)
        type(orbit_bvp), intent(in) :: bvp
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: closure
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(ode_options) :: oo
        real(dp) :: y(bvp%n), span
        integer :: j
        oo = bvp_ode_options(bvp)
        span = bvp_span(bvp, x)
        closure = 0.0_dp
        info = CM_SUCCESS
        msg = "success"
        do j = 1, bvp%k
            y = bvp_z(bvp, x, j)
            call ode_integrate(sys, bvp%mesh(j)*span, bvp%mesh(j + 1)*span, y, oo, info, &
                               message=msg)
            if (info < 0) return
            closure = max(closure, maxval(abs(y - bvp_z(bvp, x, j + 1))))
        end do
    end subroutine segment_closure

end module conmech_multiple_shooting
