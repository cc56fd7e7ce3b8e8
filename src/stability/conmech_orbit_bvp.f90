!> A periodic orbit (or the half/quarter of a symmetric one) as a discretised two-point
!! boundary-value problem: the unknowns, the boundary rows and the structured Newton solve,
!! shared by multiple shooting (conmech_multiple_shooting) and orthogonal collocation
!! (conmech_collocation), by the orbit solvers (conmech_orbit_newton) and the
!! continuation.
!!
!! The time span [0, S] (S the period T of a periodic orbit, or tau = T/period_factor of a
!! symmetric one) is cut at mesh(1) = 0 < ... < mesh(K+1) = 1 (times mesh S) into K
!! segments (multiple shooting) or collocation intervals. Unknowns
!!
!!     X = [z_1 .. z_(K+1) (the states at the nodes), Y (collocation stages, n m K),
!!          S (if the span is free), p (if the parameter is free: continuation)]
!!
!! Each segment/interval k gives n equations "end of segment k from z_k" - z_(k+1) = 0
!! (after the condensation of the collocation stages), linearised as the chain
!! A_k dz_k + B_k dz_(k+1) + C_k dw = d_k of conmech_block_chain. Boundary rows:
!! - periodic: z_1 - z_(K+1) = 0, the phase condition f(y_ref) . (z_1 - y_ref) = 0
!!   (autonomous systems; y_ref the guess or the previous orbit of a branch) and,
!!   optionally, the energy E(z_1) = E_given (its gradient by central differences);
!! - symmetric: the components of z_1 not in `free` keep their given values, the
!!   components `targets` of z_(K+1) vanish.
!! A continuation adds its pseudo-arclength row on (z_1, w).
module conmech_orbit_bvp
    use conmech_kinds, only: dp
    use conmech_central_step, only: central_step
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: METHOD_DOP853
    use conmech_orbit_types, only: ORBIT_MULTIPLE, ORBIT_COLLOCATION, energy_fun
    use conmech_block_chain, only: block_chain, chain_factor, chain_solve
    use conmech_collocation_tableau, only: gauss_tableau, gauss_collocation
    implicit none
    private

    public :: orbit_bvp, bvp_setup, bvp_pack, bvp_z, bvp_span, bvp_param, bvp_index_w
    public :: bvp_boundary, bvp_solve, bvp_residual, bvp_state_scale, bvp_begin

    !> The discretised problem and its last linearisation.
    type :: orbit_bvp
        integer :: method = ORBIT_MULTIPLE
        integer :: n = 0, k = 0, m = 0    !! state dimension, segments, collocation degree
        integer :: nx = 0, nw = 0         !! unknowns in X, border unknowns (span, p)
        logical :: periodic = .true.      !! periodic (else symmetric two-point)
        logical :: tfree = .true.         !! the span S is an unknown
        logical :: pfree = .false.        !! the parameter is an unknown
        logical :: autonomous = .true.    !! phase condition (periodic)
        logical :: energy_row = .false.   !! E(z_1) = energy_value (periodic)
        real(dp) :: energy_value = 0.0_dp
        real(dp) :: span = 0.0_dp         !! S when fixed
        real(dp) :: p = 0.0_dp            !! parameter when fixed
        real(dp) :: fd_step = 1.0e-5_dp   !! relative step of the parameter derivative
        real(dp) :: rtol = 1.0e-12_dp, atol = 1.0e-12_dp  !! integrator tolerances
        integer :: max_steps = 100000
        integer :: integrator = METHOD_DOP853   !! of the segments and their STMs
        integer, allocatable :: free(:), targets(:)
        real(dp), allocatable :: ybase(:)        !! symmetric: the fixed components' values
        real(dp), allocatable :: mesh(:)         !! K + 1 nodes in [0, 1]
        real(dp), allocatable :: yref(:), fref(:)  !! phase condition
        ! the last linearisation (filled by the method's evaluate)
        real(dp), allocatable :: a(:, :, :), b(:, :, :), c(:, :, :), d(:, :)
        real(dp), allocatable :: gres(:, :)      !! chain residuals (n, K)
        real(dp), allocatable :: sres(:, :)      !! collocation stage residuals (n m, K)
        real(dp), allocatable :: fstart(:, :), fend(:, :)  !! f at the segment ends
        real(dp), allocatable :: ws(:, :), wz(:, :, :), ww(:, :, :)  !! stage updates
        real(dp), allocatable :: bz1(:, :), bzk(:, :), bw(:, :), bres(:)  !! boundary rows
        type(block_chain) :: chain
        type(gauss_tableau) :: tab               !! collocation: the Gauss tableau
    end type orbit_bvp

contains

    !> Set up the problem: n, K segments (or intervals with `degree` m stages), periodic
    !! or symmetric (free, targets), which border unknowns are free, the fixed span/p.
    subroutine bvp_setup(bvp, method, n, k, m, periodic, tfree, pfree, span, p, info, msg, &
                         free, targets, ybase)
        type(orbit_bvp), intent(inout) :: bvp
        integer, intent(in) :: method, n, k, m
        logical, intent(in) :: periodic, tfree, pfree
        real(dp), intent(in) :: span, p
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer, intent(in), optional :: free(:), targets(:)
        real(dp), intent(in), optional :: ybase(:)
        integer :: j
        info = CM_BAD_INPUT
        if (n < 1 .or. k < 1 .or. k > 100000) then
            msg = "the number of segments/intervals must be in 1..100000"
            return
        end if
        if (method == ORBIT_COLLOCATION .and. (m < 1 .or. m > 8)) then
            msg = "the collocation degree must be in 1..8"
            return
        end if
        if (.not. (span > 0.0_dp)) then
            msg = "the period must be positive"
            return
        end if
        bvp%method = method
        bvp%n = n
        bvp%k = k
        bvp%m = merge(m, 0, method == ORBIT_COLLOCATION)
        bvp%periodic = periodic
        bvp%tfree = tfree
        bvp%pfree = pfree
        bvp%span = span
        bvp%p = p
        bvp%nw = merge(1, 0, tfree) + merge(1, 0, pfree)
        bvp%nx = n*(k + 1) + n*bvp%m*k + bvp%nw
        if (.not. periodic) then
            if (.not. (present(free) .and. present(targets) .and. present(ybase))) then
                msg = "a symmetric orbit needs free, targets and the base state"
                return
            end if
            bvp%free = free
            bvp%targets = targets
            bvp%ybase = ybase
        end if
        if (method == ORBIT_COLLOCATION) then
            call gauss_collocation(m, bvp%tab, info)
            if (info /= CM_SUCCESS) then
                msg = "the Gauss collocation tableau could not be computed"
                return
            end if
        end if
        bvp%mesh = [(real(j, dp)/k, j = 0, k)]
        allocate (bvp%yref(n), bvp%fref(n))
        bvp%yref = 0.0_dp
        bvp%fref = 0.0_dp
        info = CM_SUCCESS
        msg = "success"
    end subroutine bvp_setup

    !> The index in X of the span (which = 1) or of the parameter (which = 2); 0 if fixed.
    pure integer function bvp_index_w(bvp, which) result(i)
        type(orbit_bvp), intent(in) :: bvp
        integer, intent(in) :: which
        i = 0
        if (which == 1 .and. bvp%tfree) i = bvp%nx - bvp%nw + 1
        if (which == 2 .and. bvp%pfree) i = bvp%nx
    end function bvp_index_w

    !> X from the nodes z(n, K+1), the stages (collocation) and the border values.
    pure subroutine bvp_pack(bvp, z, stages, span, p, x)
        type(orbit_bvp), intent(in) :: bvp
        real(dp), intent(in) :: z(:, :), stages(:, :), span, p
        real(dp), intent(out) :: x(:)
        integer :: nz
        nz = bvp%n*(bvp%k + 1)
        x(1:nz) = reshape(z, [nz])
        if (bvp%m > 0) x(nz + 1:nz + size(stages)) = reshape(stages, [size(stages)])
        if (bvp%tfree) x(bvp_index_w(bvp, 1)) = span
        if (bvp%pfree) x(bvp%nx) = p
    end subroutine bvp_pack

    !> Node j of X.
    pure function bvp_z(bvp, x, j) result(z)
        type(orbit_bvp), intent(in) :: bvp
        real(dp), intent(in) :: x(:)
        integer, intent(in) :: j
        real(dp) :: z(bvp%n)
        z = x((j - 1)*bvp%n + 1:j*bvp%n)
    end function bvp_z

    pure real(dp) function bvp_span(bvp, x) result(s)
        type(orbit_bvp), intent(in) :: bvp
        real(dp), intent(in) :: x(:)
        s = bvp%span
        if (bvp%tfree) s = x(bvp_index_w(bvp, 1))
    end function bvp_span

    pure real(dp) function bvp_param(bvp, x) result(p)
        type(orbit_bvp), intent(in) :: bvp
        real(dp), intent(in) :: x(:)
        p = bvp%p
        if (bvp%pfree) p = x(bvp%nx)
    end function bvp_param

    !> The start of an evaluation at X, the same for multiple shooting and collocation:
    !! the time span S and the parameter p of X (CM_NO_CONVERGENCE when S <= 0, the Newton
    !! iterate having left the problem), and the chain blocks A, B, C, d with the chain
    !! residuals and segment-end values allocated for K segments (kept when their sizes
    !! still hold; C zeroed); `stages` (collocation) also the stage blocks of m stages.
    subroutine bvp_begin(bvp, x, stages, span, p, info, msg)
        type(orbit_bvp), intent(inout) :: bvp
        real(dp), intent(in) :: x(:)
        logical, intent(in) :: stages
        real(dp), intent(out) :: span, p
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: n, k, nm, nw
        logical :: keep
        span = bvp_span(bvp, x)
        p = bvp_param(bvp, x)
        if (.not. (span > 0.0_dp)) then
            info = CM_NO_CONVERGENCE
            msg = "the period became non-positive"
            return
        end if
        info = CM_SUCCESS
        n = bvp%n
        k = bvp%k
        nm = n*bvp%m
        nw = bvp%nw
        if (allocated(bvp%a)) then
            keep = size(bvp%a, 3) == k .and. size(bvp%c, 2) == nw
            if (keep .and. stages) then
                keep = allocated(bvp%ws)
                if (keep) keep = size(bvp%ws, 1) == nm
            end if
            if (keep) return
            deallocate (bvp%a, bvp%b, bvp%c, bvp%d, bvp%gres, bvp%fstart, bvp%fend)
        end if
        allocate (bvp%a(n, n, k), bvp%b(n, n, k), bvp%c(n, nw, k), bvp%d(n, k), &
                  bvp%gres(n, k), bvp%fstart(n, k), bvp%fend(n, k))
        if (stages) then
            if (allocated(bvp%ws)) deallocate (bvp%ws, bvp%wz, bvp%ww, bvp%sres)
            allocate (bvp%ws(nm, k), bvp%wz(nm, n, k), bvp%ww(nm, nw, k), bvp%sres(nm, k))
        end if
        bvp%c = 0.0_dp
    end subroutine bvp_begin

    !> max(1, |z|) over the nodes: the scale of the closure tolerances.
    pure real(dp) function bvp_state_scale(bvp, x) result(s)
        type(orbit_bvp), intent(in) :: bvp
        real(dp), intent(in) :: x(:)
        s = max(1.0_dp, maxval(abs(x(1:bvp%n*(bvp%k + 1)))))
    end function bvp_state_scale

    !> The boundary rows at X and their residuals (energy: gradient by central differences).
    subroutine bvp_boundary(bvp, x, energy)
        type(orbit_bvp), intent(inout) :: bvp
        real(dp), intent(in) :: x(:)
        procedure(energy_fun), optional :: energy
        real(dp) :: z1(bvp%n), zk(bvp%n), yp(bvp%n), h
        integer :: n, nb, i, r, j
        n = bvp%n
        z1 = bvp_z(bvp, x, 1)
        zk = bvp_z(bvp, x, bvp%k + 1)
        if (bvp%periodic) then
            nb = n + merge(1, 0, bvp%autonomous) + merge(1, 0, bvp%energy_row)
        else
            nb = n - size(bvp%free) + size(bvp%targets)
        end if
        if (allocated(bvp%bz1)) deallocate (bvp%bz1, bvp%bzk, bvp%bw, bvp%bres)
        allocate (bvp%bz1(nb, n), bvp%bzk(nb, n), bvp%bw(nb, bvp%nw), bvp%bres(nb))
        bvp%bz1 = 0.0_dp
        bvp%bzk = 0.0_dp
        bvp%bw = 0.0_dp
        if (bvp%periodic) then
            do i = 1, n
                bvp%bz1(i, i) = 1.0_dp
                bvp%bzk(i, i) = -1.0_dp
            end do
            bvp%bres(1:n) = z1 - zk
            r = n
            if (bvp%autonomous) then
                r = r + 1
                bvp%bz1(r, :) = bvp%fref
                bvp%bres(r) = dot_product(bvp%fref, z1 - bvp%yref)
            end if
            if (bvp%energy_row .and. present(energy)) then
                r = r + 1
                bvp%bres(r) = energy(z1) - bvp%energy_value
                do j = 1, n
                    h = central_step(z1(j))
                    yp = z1
                    yp(j) = z1(j) + h
                    bvp%bz1(r, j) = energy(yp)
                    yp(j) = z1(j) - h
                    bvp%bz1(r, j) = (bvp%bz1(r, j) - energy(yp))/(2.0_dp*h)
                end do
            end if
        else
            r = 0
            do i = 1, n
                if (any(bvp%free == i)) cycle
                r = r + 1
                bvp%bz1(r, i) = 1.0_dp
                bvp%bres(r) = z1(i) - bvp%ybase(i)
            end do
            do j = 1, size(bvp%targets)
                r = r + 1
                bvp%bzk(r, bvp%targets(j)) = 1.0_dp
                bvp%bres(r) = zk(bvp%targets(j))
            end do
        end if
    end subroutine bvp_boundary

    !> max |residual| of the last evaluation: chain, stages and boundary rows.
    pure real(dp) function bvp_residual(bvp) result(r)
        type(orbit_bvp), intent(in) :: bvp
        r = maxval(abs(bvp%gres))
        if (allocated(bvp%sres)) then
            if (size(bvp%sres) > 0) r = max(r, maxval(abs(bvp%sres)))
        end if
        if (allocated(bvp%bres)) then
            if (size(bvp%bres) > 0) r = max(r, maxval(abs(bvp%bres)))
        end if
    end function bvp_residual

    !> The Newton step dx of the last linearisation (factorised chain), with `ne` extra
    !! rows ez1 . dz_1 + ew . dw = erhs (e.g. the pseudo-arclength row). `rhs_scale` 1
    !! for a Newton step (right-hand side -G), 0 for a homogeneous solve (the tangent: only
    !! the extra rows' right-hand side). rank: the rank of the final system; full rank is
    !! 2n + nw.
    subroutine bvp_solve(bvp, ez1, ew, erhs, rhs_scale, dx, rank, info, rcond)
        type(orbit_bvp), intent(in) :: bvp
        real(dp), intent(in) :: ez1(:, :), ew(:, :), erhs(:), rhs_scale, rcond
        real(dp), intent(out) :: dx(:)
        integer, intent(out) :: rank, info
        real(dp), allocatable :: bz1(:, :), bzk(:, :), bw(:, :), br(:), z(:, :), w(:), dy(:)
        integer :: n, k, nb, ne, nz, j, nm
        n = bvp%n
        k = bvp%k
        nb = size(bvp%bres)
        ne = size(erhs)
        allocate (bz1(nb + ne, n), bzk(nb + ne, n), bw(nb + ne, bvp%nw), br(nb + ne))
        bz1(1:nb, :) = bvp%bz1
        bzk(1:nb, :) = bvp%bzk
        bw(1:nb, :) = bvp%bw
        br(1:nb) = -rhs_scale*bvp%bres
        if (ne > 0) then
            bz1(nb + 1:, :) = ez1
            bzk(nb + 1:, :) = 0.0_dp
            bw(nb + 1:, :) = ew
            br(nb + 1:) = erhs
        end if
        allocate (z(n, k + 1), w(bvp%nw))
        call chain_solve(bvp%chain, rhs_scale*bvp%d, bz1, bzk, bw, br, z, w, rank, info, &
                         rcond)
        if (info /= CM_SUCCESS) return
        nz = n*(k + 1)
        dx = 0.0_dp
        dx(1:nz) = reshape(z, [nz])
        if (bvp%m > 0) then
            ! stages: dY_k = W^-1 (-R) + W^-1 E dz_k - W^-1 (dR/dw) dw
            nm = n*bvp%m
            allocate (dy(nm))
            do j = 1, k
                dy = rhs_scale*bvp%ws(:, j) + matmul(bvp%wz(:, :, j), z(:, j))
                if (bvp%nw > 0) dy = dy - matmul(bvp%ww(:, :, j), w)
                dx(nz + (j - 1)*nm + 1:nz + j*nm) = dy
            end do
        end if
        if (bvp%nw > 0) dx(bvp%nx - bvp%nw + 1:) = w
        if (.not. all(abs(dx) <= huge(1.0_dp))) info = CM_NONFINITE
    end subroutine bvp_solve

end module conmech_orbit_bvp
