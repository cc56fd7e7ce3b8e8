!> Orthogonal collocation of a periodic (or symmetric) orbit at Gauss points, as in AUTO
!! (Doedel) and MATCONT: on each mesh interval [s_k, s_(k+1)] of [0, 1] (time t = S s) the
!! orbit is a polynomial of degree m, continuous at the mesh points, satisfying the ODE at
!! the m Gauss points. In the stage form of the Gauss-Legendre Runge-Kutta method
!! (conmech_collocation_tableau), with h_k = (s_(k+1) - s_k) S:
!!
!!     R_i = Y_i - z_k - h_k sum_l a_il f(t_l, Y_l) = 0            (i = 1..m)
!!     G_k = z_k + h_k sum_i b_i f(t_i, Y_i) - z_(k+1) = 0
!!
!! Newton's linearisation of interval k is condensed (AUTO's "condensation of
!! parameters"): W = I - h_k [a_il J_l] (n m x n m, LU by LAPACK dgetrf) eliminates the
!! stage corrections, dY = W^-1 (-R) + W^-1 E dz_k - W^-1 dR/dw dw (E = [I; ..; I]), and
!! leaves the chain block A_k = I + V W^-1 E, B_k = -I, C_k = dG/dw - V W^-1 dR/dw,
!! d_k = -G - V W^-1 (-R) with V = h_k [b_1 J_1 .. b_m J_m], solved by
!! conmech_block_chain. A_k is the interval's discrete transfer matrix: their product is
!! the collocation's monodromy, whose periodic eigenvalues are the multipliers. The span
!! S is an unknown only for autonomous systems (its derivative then needs no df/dt).
module conmech_collocation
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_lapack, only: dgetrf, dgetrs
    use conmech_orbit_types, only: set_parameter_proc
    use conmech_orbit_bvp, only: orbit_bvp, bvp_z, bvp_begin
    use conmech_block_chain, only: chain_factor
    use conmech_multiple_shooting, only: guess_states
    implicit none
    private

    public :: co_evaluate, co_guess, co_stage

contains

    !> Stage i of interval j in X.
    pure function co_stage(bvp, x, j, i) result(y)
        type(orbit_bvp), intent(in) :: bvp
        real(dp), intent(in) :: x(:)
        integer, intent(in) :: j, i
        real(dp) :: y(bvp%n)
        integer :: o
        o = bvp%n*(bvp%k + 1) + ((j - 1)*bvp%m + (i - 1))*bvp%n
        y = x(o + 1:o + bvp%n)
    end function co_stage

    !> Residuals, condensed chain blocks, stage updates and the factorisation at X.
    subroutine co_evaluate(bvp, sys, set_param, x, info, msg)
        type(orbit_bvp), intent(inout) :: bvp
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        real(dp), intent(in) :: x(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        real(dp), allocatable :: fp(:, :, :), f(:, :), jac(:, :, :), w(:, :), rhs(:, :)
        real(dp), allocatable :: v(:, :), dsw(:, :), drw(:, :), y(:, :)
        integer, allocatable :: ipiv(:)
        real(dp) :: span, p, hk, hs, h, zk(bvp%n), zk1(bvp%n), gk(bvp%n)
        integer :: n, m, k, nm, nw, j, i, l, jw, nrhs, r0, c0
        n = bvp%n
        m = bvp%m
        k = bvp%k
        nm = n*m
        nw = bvp%nw
        call bvp_begin(bvp, x, .true., span, p, info, msg)
        if (info /= CM_SUCCESS) return
        allocate (f(n, m), jac(n, n, m), w(nm, nm), rhs(nm, 1 + n + nw), v(n, nm), &
                  dsw(n, max(nw, 1)), drw(nm, max(nw, 1)), y(n, m), ipiv(nm))
        if (bvp%pfree) then
            ! df/dp at every stage by central differences (two parameter changes)
            allocate (fp(n, m, k))
            h = bvp%fd_step*max(1.0_dp, abs(p))
            call set_param(sys, p + h)
            call stage_f(fp, 1.0_dp)
            call set_param(sys, p - h)
            call stage_f(fp, -1.0_dp)
            call set_param(sys, p)
            fp = fp/(2.0_dp*h)
        end if
        nrhs = 1 + n + nw
        do j = 1, k
            hk = bvp%mesh(j + 1) - bvp%mesh(j)
            hs = hk*span
            zk = bvp_z(bvp, x, j)
            zk1 = bvp_z(bvp, x, j + 1)
            do i = 1, m
                y(:, i) = co_stage(bvp, x, j, i)
                call sys%rhs_jacobian((bvp%mesh(j) + bvp%tab%c(i)*hk)*span, y(:, i), f(:, i), &
                                      jac(:, :, i))
            end do
            ! stage residuals R and the mesh residual G
            do i = 1, m
                gk = y(:, i) - zk - hs*matmul(f, bvp%tab%a(i, :))
                bvp%sres((i - 1)*n + 1:i*n, j) = gk
            end do
            gk = zk + hs*matmul(f, bvp%tab%b) - zk1
            bvp%gres(:, j) = gk
            ! W = I - hs [a_il J_l]
            w = 0.0_dp
            do l = 1, m
                c0 = (l - 1)*n
                do i = 1, m
                    r0 = (i - 1)*n
                    w(r0 + 1:r0 + n, c0 + 1:c0 + n) = -hs*bvp%tab%a(i, l)*jac(:, :, l)
                end do
            end do
            do i = 1, nm
                w(i, i) = w(i, i) + 1.0_dp
            end do
            ! right-hand sides: -R | E | dR/dw
            rhs = 0.0_dp
            rhs(:, 1) = -bvp%sres(:, j)
            do i = 1, m
                do l = 1, n
                    rhs((i - 1)*n + l, 1 + l) = 1.0_dp
                end do
            end do
            jw = 0
            if (bvp%tfree) then
                jw = 1
                do i = 1, m
                    drw((i - 1)*n + 1:i*n, 1) = -hk*matmul(f, bvp%tab%a(i, :))
                end do
                dsw(:, 1) = hk*matmul(f, bvp%tab%b)
            end if
            if (bvp%pfree) then
                do i = 1, m
                    drw((i - 1)*n + 1:i*n, jw + 1) = -hs*matmul(fp(:, :, j), bvp%tab%a(i, :))
                end do
                dsw(:, jw + 1) = hs*matmul(fp(:, :, j), bvp%tab%b)
            end if
            if (nw > 0) rhs(:, 2 + n:) = drw(:, 1:nw)
            call dgetrf(nm, nm, w, nm, ipiv, info)
            if (info /= 0) then
                info = CM_SINGULAR
                msg = "a collocation interval's stage matrix is singular (refine the mesh)"
                return
            end if
            call dgetrs('N', nm, nrhs, w, nm, ipiv, rhs, nm, info)
            bvp%ws(:, j) = rhs(:, 1)
            bvp%wz(:, :, j) = rhs(:, 2:1 + n)
            if (nw > 0) bvp%ww(:, :, j) = rhs(:, 2 + n:)
            do i = 1, m
                v(:, (i - 1)*n + 1:i*n) = hs*bvp%tab%b(i)*jac(:, :, i)
            end do
            bvp%a(:, :, j) = matmul(v, bvp%wz(:, :, j))
            bvp%b(:, :, j) = 0.0_dp
            do i = 1, n
                bvp%a(i, i, j) = bvp%a(i, i, j) + 1.0_dp
                bvp%b(i, i, j) = -1.0_dp
            end do
            if (nw > 0) bvp%c(:, :, j) = dsw(:, 1:nw) - matmul(v, bvp%ww(:, :, j))
            bvp%d(:, j) = -gk - matmul(v, bvp%ws(:, j))
            call sys%rhs(bvp%mesh(j)*span, zk, bvp%fstart(:, j))
            call sys%rhs(bvp%mesh(j + 1)*span, zk1, bvp%fend(:, j))
        end do
        call chain_factor(bvp%chain, bvp%a, bvp%b, bvp%c, info)
        msg = "success"
        if (info == CM_SINGULAR) msg = "a collocation transfer matrix is singular"
        if (info == CM_NONFINITE) msg = "non-finite values in the collocation equations"
    contains
        subroutine stage_f(acc, sgn)
            real(dp), intent(inout) :: acc(:, :, :)
            real(dp), intent(in) :: sgn
            real(dp) :: fv(n)
            integer :: jj, ii
            do jj = 1, k
                do ii = 1, m
                    call sys%rhs((bvp%mesh(jj) + bvp%tab%c(ii)*(bvp%mesh(jj + 1) - &
                                  bvp%mesh(jj)))*span, co_stage(bvp, x, jj, ii), fv)
                    if (sgn > 0.0_dp) then
                        acc(:, ii, jj) = fv
                    else
                        acc(:, ii, jj) = acc(:, ii, jj) - fv
                    end if
                end do
            end do
        end subroutine stage_f
    end subroutine co_evaluate

    !> Nodes and stages of the orbit integrated from y0 over [0, span] (the initial
    !! guess), into x (border unknowns untouched).
    subroutine co_guess(bvp, sys, y0, span, x, info, msg)
        type(orbit_bvp), intent(in) :: bvp
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: y0(:), span
        real(dp), intent(inout) :: x(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        real(dp) :: times(1 + bvp%k*(bvp%m + 1)), ys(bvp%n, 1 + bvp%k*(bvp%m + 1))
        integer :: j, i, n, o, c
        n = bvp%n
        ! per interval its m stages, then its end node
        times(1) = 0.0_dp
        do j = 1, bvp%k
            do i = 1, bvp%m + 1
                c = 1 + (j - 1)*(bvp%m + 1) + i
                if (i <= bvp%m) then
                    times(c) = (bvp%mesh(j) + bvp%tab%c(i)*(bvp%mesh(j + 1) - bvp%mesh(j)))*span
                else
                    times(c) = bvp%mesh(j + 1)*span
                end if
            end do
        end do
        call guess_states(bvp, sys, y0, times, ys, info, msg)
        if (info < 0) return
        x(1:n) = y0
        do j = 1, bvp%k
            do i = 1, bvp%m + 1
                c = 1 + (j - 1)*(bvp%m + 1) + i
                if (i <= bvp%m) then
                    o = n*(bvp%k + 1) + ((j - 1)*bvp%m + (i - 1))*n
                    x(o + 1:o + n) = ys(:, c)
                else
                    x(j*n + 1:(j + 1)*n) = ys(:, c)
                end if
            end do
        end do
    end subroutine co_guess

end module conmech_collocation
