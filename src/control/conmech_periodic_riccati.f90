!> The stabilising periodic solution of the periodic Riccati differential equation
!!
!!     -P' = A(t)^T P + P A(t) - P B(t) R^-1 B(t)^T P + Q,    P(t + T) = P(t),
!!
!! of a T-periodic linear system x' = A(t) x + B(t) u with weights Q (k x k, symmetric
!! positive semi-definite) and R (m x m, positive definite), and the closed loop
!! x' = (A - B K) x, K = R^-1 B^T P (Bittanti, Laub, Willems: "The periodic Riccati
!! equation", 1991).
!!
!! Method (the choice, and why): the Hamiltonian system z' = H(t) z, H = [A, -S; -Q, -A^T],
!! S = B R^-1 B^T, carries the costate lambda = P x; along the optimal closed loop
!! x' = (A - S P) x, so the graph {[x; P(0) x]} is the invariant subspace of the
!! Hamiltonian monodromy Psi for its multipliers inside the unit circle (k of them, the
!! closed-loop multipliers; the other k are their reciprocals). An ordered real Schur form
!! of Psi (LAPACK dgees, eigenvalues |mu| < 1 first) gives that subspace [X; Y] and
!! P(0) = Y X^-1, with no convergence to wait for however close to the unit circle the
!! closed loop is. But Psi has condition ~ max|mu|/min|mu| (1e11 for a loop that damps
!! fast modes by 1e-6 a period), so this is only the start: the backward pass
!! F: P(T) -> P(0) of the Riccati equation (integrated with Phi = Phi_cl(T, 0), the
!! closed loop's transition matrix, alongside) is then driven to its fixed point by
!! Newton's method, P(T) <- P(T) + D with D - Phi^T D Phi = F(P(T)) - P(T) (a Stein
!! equation, k^2 x k^2), once the closed loop of the pass is stable; plain passes before
!! that (the stabilising solution attracts backward integration from any positive
!! semi-definite start, which is also the start, P(T) = 0, when the Schur form fails).
!! Converged when P(0) returns to P(T) (relative change below `periodic_tol`); the last
!! pass is kept as dense output: P(t) and K(t) at any t.
!!
!! Failures, each with a message: multipliers of Psi on the unit circle (no stabilising
!! periodic solution: (A, B) not stabilisable or (A, Q) not detectable), X singular, a
!! refinement that does not settle, P not positive definite, a closed loop that is not
!! stable.
module conmech_periodic_riccati
    use conmech_kinds, only: dp, nan_dp
    use conmech_status
    use conmech_outcome, only: outcome
    use conmech_lapack, only: dgees, dpotrf, dpotrs, la_eig, la_sym_eig, la_solve, la_finite
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_result, ode_solve, ode_integrate, &
                                  METHOD_DOP853
    use conmech_ode_dense, only: dense_solution
    implicit none
    private
    public :: periodic_lq, riccati_options, riccati_result, periodic_riccati, riccati_gain

    !> A T-periodic linear system x' = A(t) x + B(t) u (k states, m inputs).
    type, abstract :: periodic_lq
        integer :: k = 0
        integer :: m = 0
        real(dp) :: period = 0.0_dp
    contains
        procedure(coef_proc), deferred :: coefficients
    end type periodic_lq

    abstract interface
        !> a = A(t) (k x k), b = B(t) (k x m); info /= 0 on failure.
        subroutine coef_proc(self, t, a, b, info)
            import :: periodic_lq, dp
            class(periodic_lq), intent(in) :: self
            real(dp), intent(in) :: t
            real(dp), intent(out) :: a(:, :), b(:, :)
            integer, intent(out) :: info
        end subroutine coef_proc
    end interface

    !> Options of `periodic_riccati`.
    type :: riccati_options
        real(dp) :: rtol = 1.0e-12_dp        !! tolerances of every integration (DOP853)
        real(dp) :: atol = 1.0e-12_dp
        real(dp) :: periodic_tol = 1.0e-11_dp   !! |P_new(0) - P(0)| <= tol |P(0)|
        integer :: max_passes = 40           !! backward periods of refinement
        real(dp) :: unit_circle_tol = 1.0e-6_dp !! ||mu| - 1| below this: on the circle
        integer :: max_steps = 1000000
    end type riccati_options

    !> The stabilising periodic solution and its closed loop.
    type, extends(outcome) :: riccati_result
        integer :: k = 0, m = 0
        real(dp) :: period = 0.0_dp
        real(dp), allocatable :: p0(:, :)            !! P(0) = P(T)
        real(dp), allocatable :: hmr(:), hmi(:)      !! multipliers of the Hamiltonian
        real(dp), allocatable :: cl_monodromy(:, :)  !! of x' = (A - B K) x
        real(dp), allocatable :: cmr(:), cmi(:)      !! its multipliers
        real(dp) :: periodicity = 0.0_dp  !! |P(0) - P(T)|/|P(0)| of the kept pass
        real(dp) :: min_eig = 0.0_dp      !! smallest eigenvalue of P on 64 points
        integer :: passes = 0             !! backward refinement periods
        real(dp), allocatable :: rinv(:, :)          !! R^-1
        type(dense_solution) :: sol                  !! P(t) (k*k, column-major), t in [0, T]
    end type riccati_result

    !> An ODE built on a periodic LQ problem (internal): the system, R^-1 and, where the
    !! equation has it, the state weight Q.
    type, abstract, extends(ode_system) :: lq_ode
        class(periodic_lq), allocatable :: lq
        real(dp), allocatable :: qw(:, :), rinv(:, :)
    end type lq_ode

    !> The Hamiltonian system Z' = H(t) Z (internal).
    type, extends(lq_ode) :: hamiltonian_ode
    contains
        procedure :: rhs => ham_rhs
    end type hamiltonian_ode

    !> The Riccati equation P' = -(A^T P + P A - P S P + Q) (internal).
    type, extends(lq_ode) :: riccati_ode
    contains
        procedure :: rhs => ric_rhs
    end type riccati_ode

    !> The closed loop x' = (A - S P(t)) x with P from a dense solution (internal).
    type, extends(lq_ode) :: closed_lq_ode
        type(dense_solution) :: psol
    contains
        procedure :: rhs => cl_rhs
    end type closed_lq_ode

contains

    logical function inside_unit(wr, wi)
        real(dp), intent(in) :: wr, wi
        inside_unit = wr**2 + wi**2 < 1.0_dp
    end function inside_unit

    !> A(t) and B(t) for an rhs; false, with dydt NaN (the integrator then stops on a
    !! non-finite value), when the system cannot give them.
    logical function lq_coefficients(self, t, a, b, dydt) result(ok)
        class(lq_ode), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(out) :: a(:, :), b(:, :), dydt(:)
        integer :: info
        call self%lq%coefficients(t, a, b, info)
        ok = info == CM_SUCCESS
        if (.not. ok) dydt = nan_dp
    end function lq_coefficients

    subroutine ham_rhs(self, t, y, dydt)
        class(hamiltonian_ode), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: a(self%lq%k, self%lq%k), b(self%lq%k, max(self%lq%m, 1))
        real(dp) :: z(2*self%lq%k, 2*self%lq%k), h(2*self%lq%k, 2*self%lq%k)
        integer :: k
        k = self%lq%k
        if (.not. lq_coefficients(self, t, a, b, dydt)) return
        h(1:k, 1:k) = a
        h(1:k, k + 1:2*k) = -matmul(b, matmul(self%rinv, transpose(b)))
        h(k + 1:2*k, 1:k) = -self%qw
        h(k + 1:2*k, k + 1:2*k) = -transpose(a)
        z = reshape(y, [2*k, 2*k])
        dydt = reshape(matmul(h, z), [4*k*k])
    end subroutine ham_rhs

    subroutine ric_rhs(self, t, y, dydt)
        class(riccati_ode), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: a(self%lq%k, self%lq%k), b(self%lq%k, max(self%lq%m, 1))
        real(dp) :: p(self%lq%k, self%lq%k), pb(self%lq%k, max(self%lq%m, 1))
        real(dp) :: d(self%lq%k, self%lq%k)
        integer :: k
        k = self%lq%k
        if (.not. lq_coefficients(self, t, a, b, dydt)) return
        p = reshape(y(1:k*k), [k, k])
        p = 0.5_dp*(p + transpose(p))
        pb = matmul(p, b)
        d = matmul(transpose(a), p)
        d = d + transpose(d) - matmul(pb, matmul(self%rinv, transpose(pb))) + self%qw
        dydt(1:k*k) = -reshape(d, [k*k])
        if (size(y) > k*k) then
            ! Psi(t) = Phi_cl(T, t): dPsi/dt = -Psi (A - S P)
            d = a - matmul(b, matmul(self%rinv, transpose(pb)))
            dydt(k*k + 1:2*k*k) = -reshape(matmul(reshape(y(k*k + 1:2*k*k), [k, k]), d), &
                                           [k*k])
        end if
    end subroutine ric_rhs

    subroutine cl_rhs(self, t, y, dydt)
        class(closed_lq_ode), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: a(self%lq%k, self%lq%k), b(self%lq%k, max(self%lq%m, 1))
        real(dp) :: p(self%lq%k*self%lq%k), x(self%lq%k, self%lq%k)
        integer :: k
        k = self%lq%k
        if (.not. lq_coefficients(self, t, a, b, dydt)) return
        call self%psol%eval(t, p)
        a = a - matmul(b, matmul(self%rinv, matmul(transpose(b), reshape(p, [k, k]))))
        x = reshape(y, [k, k])
        dydt = reshape(matmul(a, x), [k*k])
    end subroutine cl_rhs

    !> K(t) = R^-1 B(t)^T P(t) (m x k) and P(t) from a solved result.
    subroutine riccati_gain(res, lq, t, kg, p, info)
        type(riccati_result), intent(in) :: res
        class(periodic_lq), intent(in) :: lq
        real(dp), intent(in) :: t
        real(dp), intent(out) :: kg(:, :), p(:, :)
        integer, intent(out) :: info
        real(dp) :: a(lq%k, lq%k), b(lq%k, max(lq%m, 1)), pv(lq%k*lq%k), tt
        tt = modulo(t, res%period)
        call lq%coefficients(tt, a, b, info)
        if (info /= CM_SUCCESS) return
        call res%sol%eval(tt, pv)
        p = reshape(pv, [lq%k, lq%k])
        p = 0.5_dp*(p + transpose(p))
        kg = matmul(res%rinv, matmul(transpose(b(:, 1:lq%m)), p))
    end subroutine riccati_gain

    !> Solve for the stabilising periodic P (see the module notes).
    subroutine periodic_riccati(lq, qw, rw, opt, res)
        class(periodic_lq), intent(in) :: lq
        real(dp), intent(in) :: qw(:, :), rw(:, :)
        type(riccati_options), intent(in) :: opt
        type(riccati_result), intent(out) :: res
        type(hamiltonian_ode) :: hs
        type(riccati_ode) :: rs
        type(closed_lq_ode) :: cs
        type(ode_options) :: oo
        type(ode_result) :: rr
        real(dp), allocatable :: z(:), psi(:, :), vs(:, :), wr(:), wi(:), work(:), p(:, :)
        real(dp), allocatable :: pnew(:, :), xt(:, :), yt(:, :), ev(:), rc(:, :), xi(:)
        real(dp), allocatable :: phi(:, :), stein(:, :), rhs(:, :), dvec(:, :), z0(:)
        real(dp) :: ev2r(lq%k), ev2i(lq%k)
        logical, allocatable :: bwork(:)
        real(dp) :: wq(1), dist, t, change
        integer :: k, m, sdim, lainfo, info, j, i, pass
        character(len=:), allocatable :: msg
        character(len=24) :: b1, b2

        k = lq%k
        m = lq%m
        res%k = k
        res%m = m
        res%period = lq%period
        if (k < 1 .or. m < 1 .or. .not. (lq%period > 0.0_dp) .or. size(qw, 1) /= k .or. &
            size(qw, 2) /= k .or. size(rw, 1) /= m .or. size(rw, 2) /= m) then
            call res%fail(CM_BAD_INPUT, "riccati: need k, m >= 1, a positive period, Q k x k "// &
                      "and R m x m")
            return
        end if
        if (.not. (la_finite(qw) .and. la_finite(rw))) then
            call res%fail(CM_BAD_INPUT, "riccati: Q and R must be finite")
            return
        end if
        allocate (rc(m, m), ev(max(k, m)))
        rc = rw
        call dpotrf('U', m, rc, m, lainfo)
        if (lainfo /= 0 .or. maxval(abs(rw - transpose(rw))) > 1.0e-12_dp*maxval(abs(rw))) then
            call res%fail(CM_BAD_INPUT, "riccati: R must be symmetric positive definite")
            return
        end if
        call la_sym_eig(0.5_dp*(qw + transpose(qw)), ev(1:k), info)
        if (info /= CM_SUCCESS .or. ev(1) < -1.0e-12_dp*max(abs(ev(k)), 1.0_dp) .or. &
            maxval(abs(qw - transpose(qw))) > 1.0e-12_dp*max(maxval(abs(qw)), 1.0_dp)) then
            call res%fail(CM_BAD_INPUT, "riccati: Q must be symmetric positive semi-definite")
            return
        end if
        allocate (res%rinv(m, m))
        res%rinv = 0.0_dp
        do j = 1, m
            res%rinv(j, j) = 1.0_dp
        end do
        call dpotrs('U', m, m, rc, m, res%rinv, m, lainfo)
        oo%method = METHOD_DOP853
        oo%rtol = opt%rtol
        oo%atol = opt%atol
        oo%max_steps = opt%max_steps

        ! ---- the Hamiltonian monodromy and its stable subspace
        allocate (hs%lq, source=lq)
        hs%qw = 0.5_dp*(qw + transpose(qw))
        hs%rinv = res%rinv
        allocate (z(4*k*k), psi(2*k, 2*k))
        psi = 0.0_dp
        do j = 1, 2*k
            psi(j, j) = 1.0_dp
        end do
        z = reshape(psi, [4*k*k])
        call ode_integrate(hs, 0.0_dp, lq%period, z, oo, info, message=msg)
        if (info < 0) then
            call res%fail(info, "riccati: the Hamiltonian system could not be integrated: "//msg)
            return
        end if
        psi = reshape(z, [2*k, 2*k])
        allocate (vs(2*k, 2*k), wr(2*k), wi(2*k), bwork(2*k))
        call dgees('V', 'S', inside_unit, 2*k, psi, 2*k, sdim, wr, wi, vs, 2*k, wq, -1, &
                   bwork, lainfo)
        allocate (work(max(1, int(wq(1)))))
        call dgees('V', 'S', inside_unit, 2*k, psi, 2*k, sdim, wr, wi, vs, 2*k, work, &
                   size(work), bwork, lainfo)
        res%hmr = wr
        res%hmi = wi
        if (lainfo /= 0 .and. lainfo /= 2*k + 2) sdim = -1   ! no usable start from it
        allocate (z0(2*k*k))
        dist = minval(abs(sqrt(wr**2 + wi**2) - 1.0_dp))
        if (dist < opt%unit_circle_tol .and. maxval(wr**2 + wi**2) < 1.0e16_dp) then
            write (b1, '(es10.3)') dist
            call res%fail(CM_NO_CONVERGENCE, "riccati: no stabilising periodic solution: the "// &
                      "Hamiltonian monodromy has multipliers on the unit circle "// &
                      "(min ||mu| - 1| = "//trim(adjustl(b1))//"): the system is not "// &
                      "stabilisable, or not detectable through Q")
            return
        end if
        allocate (xt(k, k), yt(k, k), p(k, k), pnew(k, k))
        p = 0.0_dp
        if (sdim == k) then
            xt = transpose(vs(1:k, 1:k))
            yt = transpose(vs(k + 1:2*k, 1:k))
            call la_solve(xt, yt, pnew, info, rcond_min=1.0e-13_dp)
            if (info == CM_SUCCESS) then
                p = transpose(pnew)
                p = 0.5_dp*(p + transpose(p))
            else if (maxval(wr**2 + wi**2) < 1.0e16_dp) then
                ! a well-conditioned monodromy whose stable subspace is not a graph over x
                call res%fail(CM_NO_CONVERGENCE, "riccati: no stabilising periodic solution: "// &
                          "the stable subspace of the Hamiltonian monodromy is not a graph "// &
                          "(X singular): the system is not stabilisable")
                return
            end if
        end if

        ! ---- backward passes driven to the fixed point (Newton on the Stein equation)
        allocate (rs%lq, source=lq)
        rs%qw = hs%qw
        rs%rinv = res%rinv
        oo%dense_output = .true.
        oo%save_steps = .false.
        change = huge(1.0_dp)
        allocate (phi(k, k), stein(k*k, k*k), rhs(k*k, 1), dvec(k*k, 1))
        do pass = 1, opt%max_passes
            z0 = 0.0_dp
            z0(1:k*k) = reshape(p, [k*k])
            do j = 1, k
                z0(k*k + (j - 1)*k + j) = 1.0_dp
            end do
            call ode_solve(rs, [lq%period, 0.0_dp], z0, oo, rr)
            if (rr%status /= CM_SUCCESS) then
                call res%fail_with_cause(rr%status, "riccati: the backward integration failed", &
                                         rr%message)
                return
            end if
            pnew = reshape(rr%y(1:k*k, rr%nt), [k, k])
            pnew = 0.5_dp*(pnew + transpose(pnew))
            phi = reshape(rr%y(k*k + 1:2*k*k, rr%nt), [k, k])
            change = maxval(abs(pnew - p))/max(maxval(abs(pnew)), tiny(1.0_dp))
            res%passes = pass
            if (change <= opt%periodic_tol) exit
            call la_eig(phi, ev2r, ev2i, info)
            if (info == CM_SUCCESS .and. maxval(ev2r**2 + ev2i**2) < 1.0_dp .and. &
                change < 1.0e-1_dp) then
                ! Newton: D - Phi^T D Phi = F(P) - P, vec(Phi^T D Phi) = (Phi^T x Phi^T) vec D
                do j = 1, k
                    do i = 1, k
                        stein((j - 1)*k + 1:j*k, (i - 1)*k + 1:i*k) = -phi(i, j)*transpose(phi)
                    end do
                end do
                do j = 1, k*k
                    stein(j, j) = stein(j, j) + 1.0_dp
                end do
                rhs(:, 1) = reshape(pnew - p, [k*k])
                call la_solve(stein, rhs, dvec, info)
                if (info == CM_SUCCESS) then
                    p = p + reshape(dvec(:, 1), [k, k])
                    p = 0.5_dp*(p + transpose(p))
                    cycle
                end if
            end if
            p = pnew
        end do
        res%periodicity = change
        if (.not. change <= opt%periodic_tol) then
            write (b1, '(es10.3)') change
            call res%fail(CM_NO_CONVERGENCE, "riccati: the backward passes did not return "// &
                      "to P(0) (relative change "//trim(adjustl(b1))//"): no stabilising "// &
                      "periodic solution")
            return
        end if
        res%p0 = pnew
        call move_alloc(rr%sol%ts, res%sol%ts)
        call move_alloc(rr%sol%hs, res%sol%hs)
        res%sol%n = k*k
        res%sol%nseg = rr%sol%nseg
        res%sol%nf = rr%sol%nf
        res%sol%form = rr%sol%form
        res%sol%t_first = rr%sol%t_first
        res%sol%t_last = rr%sol%t_last
        res%sol%coef = rr%sol%coef(1:k*k, :, 1:rr%sol%nseg)

        ! ---- P positive definite along the period
        res%min_eig = huge(1.0_dp)
        allocate (xi(k*k))
        do j = 0, 63
            t = lq%period*real(j, dp)/64.0_dp
            call res%sol%eval(t, xi)
            p = reshape(xi, [k, k])
            call la_sym_eig(0.5_dp*(p + transpose(p)), ev(1:k), info)
            res%min_eig = min(res%min_eig, ev(1))
        end do
        if (.not. res%min_eig > 0.0_dp) then
            write (b1, '(es10.3)') res%min_eig
            call res%fail(CM_NO_CONVERGENCE, "riccati: the periodic solution is not positive "// &
                      "definite (smallest eigenvalue "//trim(adjustl(b1))//")")
            return
        end if

        ! ---- the closed loop x' = (A - B K) x
        allocate (cs%lq, source=lq)
        cs%rinv = res%rinv
        cs%psol = res%sol
        oo%dense_output = .false.
        deallocate (z)
        allocate (z(k*k), res%cmr(k), res%cmi(k))
        xt = 0.0_dp
        do j = 1, k
            xt(j, j) = 1.0_dp
        end do
        z = reshape(xt, [k*k])
        call ode_integrate(cs, 0.0_dp, lq%period, z, oo, info, message=msg)
        if (info < 0) then
            call res%fail(info, "riccati: the closed loop could not be integrated: "//msg)
            return
        end if
        res%cl_monodromy = reshape(z, [k, k])
        call la_eig(res%cl_monodromy, res%cmr, res%cmi, info)
        if (info /= CM_SUCCESS) then
            call res%fail(info, "riccati: eigenvalues of the closed-loop monodromy failed")
            return
        end if
        dist = maxval(sqrt(res%cmr**2 + res%cmi**2))
        write (b1, '(es10.3)') dist
        write (b2, '(es10.3)') res%periodicity
        if (.not. dist < 1.0_dp) then
            call res%fail(CM_NO_CONVERGENCE, "riccati: the closed loop is not stable (largest "// &
                      "multiplier modulus "//trim(adjustl(b1))//")")
            return
        end if
        res%info = CM_SUCCESS
        res%message = "success (largest closed-loop multiplier "//trim(adjustl(b1))// &
                      ", periodicity "//trim(adjustl(b2))//")"

    end subroutine periodic_riccati

end module conmech_periodic_riccati
