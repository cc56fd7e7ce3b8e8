!> Support of the flat f2py layer for the continuation of equilibria and the Hopf normal
!! form (compiled, not wrapped): `run_eq_continuation` runs `continue_equilibria` from
!! plain arguments and packs the branch into explicit-shape arrays; `run_hopf` evaluates
!! the first Lyapunov coefficient at a given equilibrium.
module conmech_support_families
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS
    use conmech_ode_system, only: ode_system
    use conmech_support_cont, only: set_param_any
    use conmech_equilibrium_continuation, only: eq_options, eq_branch, continue_equilibria
    use conmech_hopf, only: hopf_normal_form, first_lyapunov_coefficient
    implicit none
    private
    public :: run_eq_continuation, run_hopf, EQ_MAX_SPECIAL

    integer, parameter :: EQ_MAX_SPECIAL = 64

contains

    !> Run the continuation and pack the branch. ropt = [ds, ds_min, ds_max, p_min, p_max,
    !! tol, res_tol, locate_tol, test_tol, l1_tol, t]; iopt = [max_points, direction,
    !! max_iter, locate]. Per special point: spi = [kind, index, located, reason,
    !! criticality]; spr = [p, test, bracket, residual, omega, l1, l1_scale, l1_error].
    subroutine run_eq_continuation(sys, n, y0, p0, ropt, iopt, mp, npts, pp, ys, wr, wi, &
                                   psi, nunst, res, iters, nsp, spi, spr, sp_y, sp_wr, &
                                   sp_wi, sp_q, sp_a, info, message)
        class(ode_system), intent(inout) :: sys
        integer(c_int), intent(in) :: n, iopt(4), mp
        real(c_double), intent(in) :: y0(n), p0, ropt(11)
        integer(c_int), intent(out) :: npts, nunst(mp), iters(mp), nsp
        integer(c_int), intent(out) :: spi(5, EQ_MAX_SPECIAL), info
        real(c_double), intent(out) :: pp(mp), ys(n, mp), wr(n, mp), wi(n, mp), psi(3, mp)
        real(c_double), intent(out) :: res(mp), spr(8, EQ_MAX_SPECIAL)
        real(c_double), intent(out) :: sp_y(n, EQ_MAX_SPECIAL), sp_wr(n, EQ_MAX_SPECIAL)
        real(c_double), intent(out) :: sp_wi(n, EQ_MAX_SPECIAL)
        real(c_double), intent(out) :: sp_q(2*n, EQ_MAX_SPECIAL), sp_a(2*n, EQ_MAX_SPECIAL)
        character(len=256), intent(out) :: message
        type(eq_options) :: o
        type(eq_branch) :: br
        integer :: k
        npts = 0
        nsp = 0
        pp = 0.0_dp; ys = 0.0_dp; wr = 0.0_dp; wi = 0.0_dp; psi = 0.0_dp; nunst = 0
        res = 0.0_dp; iters = 0; spi = 0; spr = 0.0_dp; sp_y = 0.0_dp; sp_wr = 0.0_dp
        sp_wi = 0.0_dp; sp_q = 0.0_dp; sp_a = 0.0_dp
        o%ds = ropt(1)
        o%ds_min = ropt(2)
        o%ds_max = ropt(3)
        o%p_min = ropt(4)
        o%p_max = ropt(5)
        o%tol = ropt(6)
        o%res_tol = ropt(7)
        o%locate_tol = ropt(8)
        o%test_tol = ropt(9)
        o%l1_tol = ropt(10)
        o%t = ropt(11)
        o%max_points = min(iopt(1), mp)
        o%direction = iopt(2)
        o%max_iter = iopt(3)
        o%locate = iopt(4) /= 0
        call set_param_any(sys, p0)
        call continue_equilibria(sys, set_param_any, p0, y0, br, o)
        info = br%info
        message = br%message
        npts = br%npoints
        do k = 1, npts
            pp(k) = br%points(k)%p
            ys(:, k) = br%points(k)%y
            wr(:, k) = br%points(k)%wr
            wi(:, k) = br%points(k)%wi
            psi(:, k) = br%points(k)%psi
            nunst(k) = br%points(k)%n_unstable
            res(k) = br%points(k)%residual
            iters(k) = br%points(k)%iterations
        end do
        nsp = min(br%nspecial, EQ_MAX_SPECIAL)
        do k = 1, nsp
            associate (s => br%special(k))
                spi(:, k) = [s%kind, s%index, merge(1, 0, s%located), s%reason, s%criticality]
                spr(:, k) = [s%point%p, s%test, s%bracket, s%point%residual, s%omega, s%l1, &
                             s%l1_scale, s%l1_error]
                sp_y(:, k) = s%point%y
                if (allocated(s%point%wr)) then
                    sp_wr(:, k) = s%point%wr
                    sp_wi(:, k) = s%point%wi
                end if
                if (allocated(s%q)) then
                    sp_q(1:n, k) = real(s%q, dp)
                    sp_q(n + 1:, k) = aimag(s%q)
                    sp_a(1:n, k) = real(s%adj, dp)
                    sp_a(n + 1:, k) = aimag(s%adj)
                end if
            end associate
        end do
    end subroutine run_eq_continuation

    !> The first Lyapunov coefficient at the equilibrium y of sys (parameter already set):
    !! out = [omega, re_lambda, l1, scale, l1_error, criticality, exact Jacobian (0/1)],
    !! q and the adjoint vector as [real; imaginary] parts.
    subroutine run_hopf(sys, n, t, y, l1_tol, out, q, adj, info, message)
        class(ode_system), intent(inout) :: sys
        integer(c_int), intent(in) :: n
        real(c_double), intent(in) :: t, y(n), l1_tol
        real(c_double), intent(out) :: out(7), q(2*n), adj(2*n)
        integer(c_int), intent(out) :: info
        character(len=256), intent(out) :: message
        type(hopf_normal_form) :: hf
        character(len=:), allocatable :: msg
        out = 0.0_dp
        q = 0.0_dp
        adj = 0.0_dp
        call first_lyapunov_coefficient(sys, t, y, hf, info, msg, l1_tol)
        message = msg
        if (info /= CM_SUCCESS) return
        out = [hf%omega, hf%re_lambda, hf%l1, hf%scale, hf%l1_error, &
               real(hf%criticality, dp), merge(1.0_dp, 0.0_dp, hf%exact_jacobian)]
        q(1:n) = real(hf%q, dp)
        q(n + 1:) = aimag(hf%q)
        adj(1:n) = real(hf%p, dp)
        adj(n + 1:) = aimag(hf%p)
    end subroutine run_hopf

end module conmech_support_families
