!> One RATTLE step (Andersen 1983; Hairer-Lubich-Wanner, Geometric Numerical Integration,
!! VII.1) of a mechanical system with holonomic constraints in excessive coordinates,
!! M q'' = Q(t, q, q') + G(t, q)^T lambda, phi(t, q) = 0, and its constraint solves.
!! From (q_n, v_n):
!!
!!     v_{1/2} = v_n + h/2 M_n^{-1} (Q_n + G_n^T lambda)
!!     q_{n+1} = q_n + h v_{1/2},          phi(t_{n+1}, q_{n+1}) = 0
!!     v_{n+1} = v_{1/2} + h/2 M_{n+1}^{-1} (Q_{n+1} + G_{n+1}^T mu),
!!                                         G_{n+1} v_{n+1} + phi_t(t_{n+1}, q_{n+1}) = 0
!!
!! - Position constraints: simplified Newton in the scaled multiplier (h^2/2) lambda with
!!   the matrix G(q~) M_n^{-1} G_n^T (q~ the unconstrained predictor, so the contraction
!!   factor is O(h^2)), factorised once per step (LAPACK dgetf2), iterated until
!!   max|phi| <= proj_tol or the correction is below the round-off of q.
!! - Velocity constraints: one linear solve with G_{n+1} M_{n+1}^{-1} G_{n+1}^T.
!! - Mass matrix: M(q_n) in the first half kick and the position solve, M(q_{n+1}) in
!!   the second (the standard variant). A `diagonal_mass` system costs a division per
!!   coordinate, a `constant_mass` one is inverted once per run; otherwise M is
!!   factorised (Cholesky) and inverted at every grid point. One constraint (n_hol = 1)
!!   needs no factorisation at all (a scalar division). For a constant mass matrix this
!!   is RATTLE exactly; for a configuration-dependent one the method stays symmetric and
!!   of order 2, but is not symplectic.
!! - Velocity-dependent forces: Q_{n+1} = Q(t_{n+1}, q_{n+1}, v_{n+1}) makes the second
!!   kick implicit; it is solved by fixed-point iteration (two force evaluations per step
!!   when Q does not depend on v: the second one confirms the first).
!! A step of any length from a prepared state is also the method's continuous extension
!! (the stepper's continuous extension for off-grid outputs and events: conmech_rattle_stepper).
module conmech_rattle_step
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_lapack, only: dgetrs, dgetf2, dpotri, dgelsd
    use conmech_generalized, only: mass_cholesky
    use conmech_constrained_system, only: constrained_system
    use conmech_state_packer, only: state_packer
    implicit none
    private

    public :: rattle_state, rattle_work, rattle_work_init, rattle_prepare, rattle_step
    public :: rattle_state_transfer

    integer, parameter :: MASS_GENERAL = 0, MASS_DIAGONAL = 1, MASS_CONSTANT = 2
    !> Relative size below which a singular value (or an LU pivot) of the constraint
    !! matrix G M^-1 G^T counts as zero (the explicit methods' KKT solve uses the same).
    real(dp), parameter :: RANK_TOL = 1.0e-11_dp
    !> The coarser truncation of the second attempt of a position solve that failed
    !! (rows nearly dependent: a step that lands close to a singular configuration).
    real(dp), parameter :: COARSE_RANK_TOL = 1.0e-6_dp
    !> A residual that stops decreasing below FLOOR_FACTOR proj_tol is round-off.
    real(dp), parameter :: FLOOR_FACTOR = 100.0_dp

    !> The state at one grid point with what the next step reuses.
    type :: rattle_state
        real(dp) :: t = 0.0_dp
        real(dp), allocatable :: q(:), v(:)
        real(dp), allocatable :: f(:)       !! Q(t, q, v)
        real(dp), allocatable :: mc(:, :)   !! M(t, q)^{-1} (general mass only)
        real(dp), allocatable :: d(:)       !! 1 / diag M(t, q) (diagonal mass only)
        real(dp), allocatable :: x(:, :)    !! M^{-1} G^T (n x n_hol)
        real(dp), allocatable :: g(:, :)    !! G (n_hol x n)
    end type rattle_state

    !> What the steps of one run share: sizes, the kind of mass matrix (and M^{-1} when it
    !! is constant), the position-solve controls, work arrays (allocated once: gfortran
    !! puts automatic arrays on the heap) and the counters of the run.
    type :: rattle_work
        integer :: n = 0                    !! coordinates
        integer :: m = 0                    !! holonomic constraints
        integer :: mkind = MASS_GENERAL
        integer :: proj_max_iter = 1        !! iterations of the position solve
        real(dp) :: proj_tol = 0.0_dp       !! tolerance of max|phi|
        real(dp), allocatable :: minv(:, :) !! M^{-1} (constant mass only)
        real(dp), allocatable :: afree(:), vhalf(:), ph(:), gt(:, :), dq(:), dqsum(:)
        real(dp), allocatable :: w(:), r(:), vprev(:), pt(:, :), sm(:, :), cv(:)
        integer, allocatable :: ipiv(:)
        integer :: nfev = 0                 !! force evaluations
        integer :: nproj = 0                !! position solves
        integer :: proj_iter = 0            !! their total iterations
        integer :: proj_iter_max = 0        !! the most iterations of one solve
        !> position solves that needed the Newton iteration with G at every iterate
        !! (steps landing close to a singular configuration)
        integer :: nfallback = 0
    end type rattle_work

contains

    !> Set up the work of a run of sys from (t0, q0): the mass-matrix kind (M^{-1} once
    !! for a constant mass), the position-solve controls, the work arrays.
    subroutine rattle_work_init(wk, sys, t0, q0, proj_tol, proj_max_iter, info, msg)
        type(rattle_work), intent(out) :: wk
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t0, q0(:)
        real(dp), intent(in) :: proj_tol
        integer, intent(in) :: proj_max_iter
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: n, m, j, lainfo
        n = sys%n
        m = sys%n_hol
        wk%n = n
        wk%m = m
        wk%proj_tol = proj_tol
        wk%proj_max_iter = proj_max_iter
        allocate (wk%afree(n), wk%vhalf(n), wk%ph(m), wk%gt(m, n), wk%dq(n), wk%dqsum(n), &
                  wk%w(n), wk%r(m), wk%vprev(n), wk%pt(m, n), wk%sm(m, m), wk%cv(m), &
                  wk%ipiv(m))
        info = CM_SUCCESS
        wk%mkind = MASS_GENERAL
        if (sys%diagonal_mass) then
            wk%mkind = MASS_DIAGONAL
        else if (sys%constant_mass) then
            ! M^{-1} once, kept for the run
            allocate (wk%minv(n, n))
            call sys%mass(t0, q0, wk%minv)
            call mass_cholesky(wk%minv, info, msg)
            if (info /= CM_SUCCESS) return
            call dpotri('U', n, wk%minv, n, lainfo)
            do j = 1, n - 1
                wk%minv(j + 1:n, j) = wk%minv(j, j + 1:n)
            end do
            wk%mkind = MASS_CONSTANT
        end if
    end subroutine rattle_work_init

    !> Fill a state at (tt, qq, vv): forces, Cholesky of M, G and M^{-1} G^T.
    subroutine rattle_prepare(sys, wk, st, tt, qq, vv, inf, mg)
        class(constrained_system), intent(in) :: sys
        type(rattle_work), intent(inout) :: wk
        type(rattle_state), intent(inout) :: st
        real(dp), intent(in) :: tt, qq(:), vv(:)
        integer, intent(out) :: inf
        character(len=:), allocatable, intent(out) :: mg
        if (.not. allocated(st%f)) call allocate_state(wk, st)
        st%t = tt
        st%q = qq
        st%v = vv
        call sys%forces(tt, qq, vv, st%f)
        wk%nfev = wk%nfev + 1
        call factor_mass(sys, wk, st, inf, mg)
    end subroutine rattle_prepare

    !> One RATTLE step of length hs from st to s2 (s2 prepared for the next step).
    subroutine rattle_step(sys, wk, st, hs, s2, inf, mg)
        class(constrained_system), intent(in) :: sys
        type(rattle_work), intent(inout) :: wk
        type(rattle_state), intent(in) :: st
        real(dp), intent(in) :: hs
        type(rattle_state), intent(inout) :: s2
        integer, intent(out) :: inf
        character(len=:), allocatable, intent(out) :: mg
        real(dp) :: t1, rnorm
        integer :: it, kk, i, m, attempt
        character(len=32) :: b2
        m = wk%m
        t1 = st%t + hs
        if (.not. allocated(s2%f)) call allocate_state(wk, s2)
        ! first half kick without the constraint force, unconstrained predictor
        call minv_times(wk%mkind, wk%minv, st, st%f, wk%afree)
        s2%q = st%q + hs*st%v + (0.5_dp*hs*hs)*wk%afree
        wk%dqsum = 0.0_dp
        if (m > 0) then
            call sys%phi_jac(t1, s2%q, wk%gt)
            wk%w = s2%q
            do attempt = 1, merge(3, 1, m > 1)
                if (attempt == 1) then
                    ! pk = X S^{-1} (n x m) from S^T pk^T = X^T, S = G(q~) X
                    call schur_rows(m, wk%gt, st%x, wk%pt, wk%sm, wk%ipiv, inf)
                else
                    ! near a singular configuration (rows almost dependent) the frozen
                    ! matrix is a poor Newton matrix: again from the predictor, by Newton
                    ! with G at every iterate (minimum-norm rows), then with the nearly
                    ! dependent rows treated as dependent
                    s2%q = wk%w
                    wk%dqsum = 0.0_dp
                    if (attempt == 2) wk%nfallback = wk%nfallback + 1
                    inf = CM_SUCCESS
                end if
                if (inf /= CM_SUCCESS) then
                    mg = "the constraint matrix G M^-1 G^T of the position solve is " &
                         //"zero (rank 0) or not finite"
                    return
                end if
                select case (attempt)
                case (1)
                    call position_newton(sys, wk, t1, s2, st%x, 0.0_dp, it, rnorm, inf)
                case (2)
                    call position_newton(sys, wk, t1, s2, st%x, RANK_TOL, it, rnorm, inf)
                case default
                    call position_newton(sys, wk, t1, s2, st%x, COARSE_RANK_TOL, it, rnorm, &
                                         inf)
                end select
                wk%proj_iter = wk%proj_iter + it
                wk%proj_iter_max = max(wk%proj_iter_max, it)
                wk%nproj = wk%nproj + 1
                if (inf == CM_SUCCESS) exit
            end do
            if (inf /= CM_SUCCESS) then
                write (b2, '(es10.3)') rnorm
                mg = "position constraints not solved: |phi| ="//trim(b2)// &
                     " after proj_max_iter simplified Newton iterations"
                return
            end if
        end if
        ! v_{1/2} = (q_{n+1} - q_n)/h without the cancellation
        wk%vhalf = st%v + (0.5_dp*hs)*wk%afree - wk%dqsum/hs
        ! second half kick at q_{n+1}, velocity constraints
        s2%t = t1
        call factor_mass(sys, wk, s2, inf, mg)
        if (inf /= CM_SUCCESS) return
        if (m > 0) then
            call schur_rows(m, s2%g, s2%x, wk%pt, wk%sm, wk%ipiv, inf)
            if (inf /= CM_SUCCESS) then
                mg = "the constraint matrix G M^-1 G^T of the velocity solve is zero " &
                     //"(rank 0) or not finite"
                return
            end if
        end if
        wk%r = 0.0_dp
        if (m > 0) call sys%phi_t(t1, s2%q, wk%r)
        s2%v = 2.0_dp*wk%vhalf - st%v
        inf = CM_NO_CONVERGENCE
        do kk = 1, 50
            call sys%forces(t1, s2%q, s2%v, s2%f)
            wk%nfev = wk%nfev + 1
            if (.not. all(abs(s2%f) <= huge(1.0_dp))) exit
            call minv_times(wk%mkind, wk%minv, s2, s2%f, wk%w)
            wk%w = wk%vhalf + (0.5_dp*hs)*wk%w
            ! w - (G w + phi_t) S^{-1} G M^{-1} (all rows from the same w)
            do i = 1, m
                wk%cv(i) = dot_product(s2%g(i, :), wk%w) + wk%r(i)
            end do
            do i = 1, m
                wk%w = wk%w - wk%cv(i)*wk%pt(i, :)
            end do
            wk%vprev = s2%v
            s2%v = wk%w
            if (kk > 1 .and. maxval(abs(s2%v - wk%vprev)) <= 4.0_dp*epsilon(1.0_dp)* &
                max(maxval(abs(s2%v)), tiny(1.0_dp))) then
                ! converged: Q(t1, q1, v1) equals s2%f to round-off
                inf = CM_SUCCESS
                exit
            end if
        end do
        if (inf /= CM_SUCCESS) then
            mg = "the velocity-dependent forces of the second half kick did not " &
                 //"converge (or are not finite)"
        end if
    end subroutine rattle_step

    !> The Newton iteration of the position solve from s2%q (the predictor) with the
    !! rows wk%pt (simplified) or rows recomputed at every iterate: q <- q - pt^T phi(q) until max|phi| <= proj_tol, or the
    !! correction is below the round-off of q, or the residual stops decreasing at a
    !! round-off floor (<= FLOOR_FACTOR proj_tol; near dependent rows the round-off of the
    !! corrections is amplified). A residual that grows above the floor is a divergence.
    subroutine position_newton(sys, wk, t1, s2, xx, rcond, it, rnorm, inf)
        class(constrained_system), intent(in) :: sys
        type(rattle_work), intent(inout) :: wk
        real(dp), intent(in) :: t1
        type(rattle_state), intent(inout) :: s2
        !> M_n^-1 G_n^T, the directions of the corrections
        real(dp), intent(in) :: xx(:, :)
        !> 0: the rows wk%pt as given (simplified Newton); > 0: Newton, the rows
        !! recomputed at every iterate, singular values <= rcond sigma_max dropped
        real(dp), intent(in) :: rcond
        integer, intent(out) :: it, inf
        real(dp), intent(out) :: rnorm
        real(dp) :: rprev
        integer :: i, inf2
        inf = CM_NO_CONVERGENCE
        rprev = huge(1.0_dp)
        do it = 1, wk%proj_max_iter + 1
            call sys%phi(t1, s2%q, wk%ph)
            rnorm = maxval(abs(wk%ph))
            if (.not. rnorm < huge(1.0_dp)) exit
            if (rnorm <= wk%proj_tol) then
                inf = CM_SUCCESS
                exit
            end if
            if (rnorm >= rprev) then
                if (rnorm <= FLOOR_FACTOR*wk%proj_tol) inf = CM_SUCCESS
                exit
            end if
            if (rcond > 0.0_dp) then
                call sys%phi_jac(t1, s2%q, wk%gt)
                call min_norm_rows(wk%m, wk%n, wk%gt, xx, wk%pt, rcond, inf2)
                if (inf2 /= CM_SUCCESS) exit
            end if
            if (it > wk%proj_max_iter) exit
            rprev = rnorm
            wk%dq = 0.0_dp
            do i = 1, wk%m
                wk%dq = wk%dq + wk%ph(i)*wk%pt(i, :)
            end do
            wk%dqsum = wk%dqsum + wk%dq
            s2%q = s2%q - wk%dq
            if (maxval(abs(wk%dq)) <= 4.0_dp*epsilon(1.0_dp)*maxval(abs(s2%q))) then
                inf = CM_SUCCESS
                exit
            end if
        end do
        it = min(it, wk%proj_max_iter + 1)
    end subroutine position_newton

    !> Pack or unpack one grid state (conmech_state_packer), allocated for the run of wk.
    subroutine rattle_state_transfer(wk, st, p)
        type(rattle_work), intent(in) :: wk
        type(rattle_state), intent(inout) :: st
        type(state_packer), intent(inout) :: p
        integer :: n, m
        logical :: prepared
        n = wk%n
        m = wk%m
        prepared = allocated(st%f)              ! (the second state before the first step)
        call p%item(prepared)
        if (.not. prepared) return
        call p%item(st%t)
        call p%reals(st%q, n)
        call p%reals(st%v, n)
        call p%reals(st%f, n)
        call p%real_matrix(st%x, n, m)
        call p%real_matrix(st%g, m, n)
        if (wk%mkind == MASS_GENERAL) call p%real_matrix(st%mc, n, n)
        if (wk%mkind == MASS_DIAGONAL) call p%reals(st%d, n)
    end subroutine rattle_state_transfer

    subroutine allocate_state(wk, st)
        type(rattle_work), intent(in) :: wk
        type(rattle_state), intent(inout) :: st
        integer :: n, m
        n = wk%n
        m = wk%m
        allocate (st%q(n), st%v(n), st%f(n), st%x(n, m), st%g(m, n))
        if (wk%mkind == MASS_GENERAL) allocate (st%mc(n, n))
        if (wk%mkind == MASS_DIAGONAL) allocate (st%d(n))
    end subroutine allocate_state

    !> M^{-1} (or 1/diag M) and M^{-1} G^T at st%t, st%q.
    subroutine factor_mass(sys, wk, st, inf, mg)
        class(constrained_system), intent(in) :: sys
        type(rattle_work), intent(in) :: wk
        type(rattle_state), intent(inout) :: st
        integer, intent(out) :: inf
        character(len=:), allocatable, intent(out) :: mg
        integer :: lainfo, jj, n, m
        n = wk%n
        m = wk%m
        inf = CM_SUCCESS
        select case (wk%mkind)
        case (MASS_DIAGONAL)
            call sys%mass_diagonal(st%t, st%q, st%d)
            if (.not. all(st%d > 0.0_dp .and. st%d < huge(1.0_dp))) then
                inf = CM_SINGULAR
                mg = "the diagonal mass matrix has a non-positive or non-finite entry"
                return
            end if
            st%d = 1.0_dp/st%d
        case (MASS_GENERAL)
            call sys%mass(st%t, st%q, st%mc)
            call mass_cholesky(st%mc, inf, mg)
            if (inf /= CM_SUCCESS) return
            ! the explicit inverse (small matrices: one LAPACK call per step instead
            ! of a triangular solve per right-hand side)
            call dpotri('U', n, st%mc, n, lainfo)
            do jj = 1, n - 1
                st%mc(jj + 1:n, jj) = st%mc(jj, jj + 1:n)
            end do
        end select
        if (m > 0) then
            call sys%phi_jac(st%t, st%q, st%g)
            select case (wk%mkind)
            case (MASS_DIAGONAL)
                do jj = 1, m
                    st%x(:, jj) = st%d*st%g(jj, :)
                end do
            case (MASS_CONSTANT)
                st%x = matmul(wk%minv, transpose(st%g))
            case default
                st%x = matmul(st%mc, transpose(st%g))
            end select
        end if
    end subroutine factor_mass

    !> M(st)^{-1} f (minv: M^{-1} of a constant mass, unallocated otherwise).
    subroutine minv_times(mkind, minv, st, f, y)
        integer, intent(in) :: mkind
        real(dp), allocatable, intent(in) :: minv(:, :)
        type(rattle_state), intent(in) :: st
        real(dp), intent(in) :: f(:)
        real(dp), intent(out) :: y(:)
        select case (mkind)
        case (MASS_DIAGONAL)
            y = st%d*f
        case (MASS_CONSTANT)
            y = matmul(minv, f)
        case default
            y = matmul(st%mc, f)
        end select
    end subroutine minv_times

    !> pt = S^{-T} X^T (m x n) for S = gg X (m x m, LU by dgetf2 in sm, ipiv; one
    !! constraint: a division). inf = CM_SINGULAR when S is singular (one constraint
    !! with a vanishing gradient). Dependent constraint rows (redundant constraints, or a
    !! configuration where the rows lose rank) make S singular: the LU's smallest pivot
    !! falls below RANK_TOL times the largest entry of S, and pt becomes the minimum-norm
    !! least-squares rows (S^T)^+ X^T (dgelsd, singular values below RANK_TOL sigma_max
    !! dropped): the Newton corrections act only in the span of the independent rows, and
    !! a consistent set of dependent equations is solved exactly (their residuals are
    !! combinations of the others').
    subroutine schur_rows(m, gg, xx, pt, sm, ipiv, inf)
        integer, intent(in) :: m
        real(dp), intent(in) :: gg(:, :), xx(:, :)
        real(dp), intent(out) :: pt(:, :)
        real(dp), intent(inout) :: sm(m, m)
        integer, intent(inout) :: ipiv(m)
        integer, intent(out) :: inf
        real(dp) :: s1, smax, umin
        integer :: lainfo, i2, j2, n
        inf = CM_SUCCESS
        if (m == 1) then
            s1 = dot_product(gg(1, :), xx(:, 1))
            if (.not. (abs(s1) > 0.0_dp .and. abs(s1) < huge(1.0_dp))) then
                inf = CM_SINGULAR
                return
            end if
            pt(1, :) = xx(:, 1)/s1
            return
        end if
        ! (loops: the library matmul costs more than the product of tiny matrices)
        do j2 = 1, m
            do i2 = 1, m
                sm(i2, j2) = dot_product(gg(i2, :), xx(:, j2))
            end do
        end do
        n = size(gg, 2)
        smax = maxval(abs(sm))
        if (.not. (smax > 0.0_dp .and. smax < huge(1.0_dp))) then
            inf = CM_SINGULAR
            return
        end if
        call dgetf2(m, m, sm, m, ipiv, lainfo)
        umin = huge(1.0_dp)
        do i2 = 1, m
            umin = min(umin, abs(sm(i2, i2)))
        end do
        if (lainfo == 0 .and. umin > RANK_TOL*smax) then
            pt = transpose(xx)
            call dgetrs('T', m, n, sm, m, ipiv, pt, m, lainfo)
            return
        end if
        call min_norm_rows(m, n, gg, xx, pt, RANK_TOL, inf)
    end subroutine schur_rows

    !> pt = (S^T)^+ X^T for S = gg X with dependent rows (dgelsd, singular values
    !! <= rcond sigma_max dropped; see schur_rows).
    subroutine min_norm_rows(m, n, gg, xx, pt, rcond, inf)
        integer, intent(in) :: m, n
        real(dp), intent(in) :: gg(:, :), xx(:, :)
        real(dp), intent(out) :: pt(:, :)
        real(dp), intent(in) :: rcond
        integer, intent(out) :: inf
        real(dp), allocatable :: st(:, :), work(:), sv(:)
        integer, allocatable :: iwork(:)
        real(dp) :: wq(1)
        integer :: iq(1), lwork, lainfo, rank
        allocate (st(m, m), sv(m))
        st = transpose(matmul(gg, xx))
        pt = transpose(xx)
        call dgelsd(m, m, n, st, m, pt, m, sv, rcond, rank, wq, -1, iq, lainfo)
        lwork = max(1, int(wq(1)))
        allocate (work(lwork), iwork(max(1, iq(1))))
        st = transpose(matmul(gg, xx))
        call dgelsd(m, m, n, st, m, pt, m, sv, rcond, rank, work, lwork, iwork, lainfo)
        inf = CM_SUCCESS
        if (lainfo /= 0 .or. rank == 0) inf = CM_SINGULAR
    end subroutine min_norm_rows

end module conmech_rattle_step
