!> Transverse linearisation of a periodic orbit of any autonomous system x' = f(x)
!! (x in R^N): moving transverse coordinates along the orbit, reduced by the invariants.
!!
!! Along the orbit x*(t) (period T) the sections are the hyperplanes normal to the flow,
!! z(t) = f(x*(t)) (moving Poincare sections). Coordinates x = x*(tau) + Q(tau) xi with
!! f^T Q = 0 give, to first order, d xi/dtau = Q^T (A Q - Q') xi, A = df/dx (the general
!! formula A_perp = P^+ (I - f z^T/(z^T f)) (A P - P') for z = f and orthonormal P = Q).
!! Invariants remove further coordinates: Q spans
!!
!!     S(t) = { dx : f^T dx = 0, C dx = 0, grad H^T dx = 0 },   k = N - 1 - n_C - [H],
!!
!! where the rows of C(x) are normals of an invariant manifold (excessive coordinates:
!! the holonomic constraints phi and their derivatives G v, the Pfaffian constraints) and H
!! a conserved energy. The dynamics of the removed coordinates (constraint violation,
!! energy change) do not depend on xi, so the k x k system of xi carries the non-trivial
!! multipliers of the orbit; the N - k trivial ones (flow direction, energy, constraints)
!! are 1.
!!
!! The invariant covectors (the rows of C and grad H) are evaluated once, at x*(0), and
!! carried along by the adjoint equation y' = -y A: then y dx is conserved by the
!! variational flow exactly as the invariants are, consistently with the A integrated
!! (grad H evaluated at every point instead would differ from the transported one by its
!! own round-off, and that difference, fed through the coupling of the energy direction,
!! costs two digits). The frame is transported without rotation inside S: with W = [y^T, f]
!! (its columns span the complement of S), Q' = -W (W^T W)^-1 (W'^T Q), W'^T Q =
!! [-y A Q; (A f)^T Q], which keeps Q orthonormal and in S; the integrated Q drifts off S
!! by the integration error, so every evaluation first projects it onto S. Then
!! Q^T Q' = 0 and A_red = Q^T A Q. After one period Q(T) = Q(0) R with R a rotation (the
!! holonomy); the periodic frame Qp(t) = Q(t) R^(-t/T) gives the periodic coefficient
!! matrix
!!
!!     A_perp(t) = E^T A_red E + log(R)/T,   E = R^(-t/T),
!!
!! and B_perp(t) = E^T Q^T B(t) for a system with an input matrix B = dF/du. The transverse
!! monodromy in the periodic frame is R Phi_red(T).
!!
!! A system without an analytic Jacobian gets sixth-order central differences here: the
!! identities the construction rests on (f' = A f, the adjoint of the same A) make the
!! transverse and the full multipliers differ by the Jacobian's error.
!!
!! `transverse_build` integrates the orbit, the covectors, the frame, Phi_red (and
!! optionally the full N x N monodromy, and with inputs the controllability Gramian) in
!! one run with dense output (Verner 9(8) by default: on the double pendulum ten times
!! more accurate than DOP853 at the same tolerance, with fewer evaluations);
!! `transverse_eval` then gives x*, Qp, A_perp, B_perp at any t from the dense output,
!! and `transverse_hill` the coefficients of the normal deviation's equation
!! N'' + psi N' + Phi N = 0 of a two-degree-of-freedom system.
module conmech_transverse_general
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_lapack, only: dgesvd, la_eig, la_finite, la_solve
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_result, ode_solve
    use conmech_rotation_log, only: rotation_log_init, nearest_rotation
    use conmech_transverse_model, only: transverse_model
    use conmech_transverse_frame, only: transverse_options, transverse_frame, frame_derivative, &
        transverse_jacobian, ENERGY_NONE, ENERGY_AUTO, ENERGY_REQUIRED
    implicit none
    private

    public :: transverse_options, transverse_frame, transverse_build, transverse_eval
    public :: transverse_hill, transverse_jacobian, ENERGY_NONE, ENERGY_AUTO, ENERGY_REQUIRED

contains

    !> Build the transverse linearisation of the orbit through y0 with period `period` of
    !! `sys` (invariants and inputs described by `model`). On success fr%info = CM_SUCCESS;
    !! CM_BAD_INPUT with a message for an orbit that does not close, a vector field that
    !! vanishes on it, dependent normals, or an energy that is required but not conserved.
    subroutine transverse_build(sys, model, y0, period, opt, fr)
        class(ode_system), intent(in) :: sys
        class(transverse_model), intent(in) :: model
        real(dp), intent(in) :: y0(:), period
        type(transverse_options), intent(in) :: opt
        type(transverse_frame), intent(out) :: fr
        type(ode_options) :: oo
        type(ode_result) :: res
        real(dp), allocatable :: z0(:), w(:, :), u(:, :), s(:), vt(:, :), work(:), c(:, :)
        real(dp), allocatable :: q0(:, :), qt(:, :), r(:, :), mred(:, :), g(:), f(:)
        real(dp), allocatable :: y0c(:, :)
        real(dp) :: wq(1), tol, defect, dsgn
        integer :: n, k, nc, ny, p, o, lainfo, info, j
        character(len=:), allocatable :: msg
        character(len=24) :: b1, b2

        n = size(y0)
        fr%n = n
        fr%period = period
        fr%y0 = y0
        nc = model%n_normals()
        fr%nc = nc
        fr%m = model%n_inputs
        if (.not. (period > 0.0_dp .and. period <= huge(1.0_dp)) .or. .not. la_finite(y0)) then
            call fr%fail(CM_BAD_INPUT, "transverse: the period must be positive and y0 finite")
            return
        end if
        if (.not. (opt%rtol > 0.0_dp .and. opt%rtol < 1.0_dp .and. opt%atol > 0.0_dp)) then
            call fr%fail(CM_BAD_INPUT, "transverse: rtol must be in (0, 1) and atol > 0")
            return
        end if
        oo%method = opt%method
        oo%rtol = opt%rtol
        oo%atol = opt%atol
        oo%max_steps = opt%max_steps

        if (opt%energy == ENERGY_REQUIRED .and. .not. model%has_energy()) then
            call fr%fail(CM_BAD_INPUT, "transverse: the system has no energy to reduce by")
            return
        end if
        ! ---- on the invariant manifold; the orbit alone: closure, the vector field,
        !      conservation of the energy
        if (nc > 0) then
            defect = model%manifold_residual(0.0_dp, y0)
            tol = max(1.0e-10_dp, 1.0e2_dp*opt%atol)*max(1.0_dp, maxval(abs(y0)))
            if (.not. defect <= tol) then
                write (b1, '(es10.3)') defect
                call fr%fail(CM_BAD_INPUT, "transverse: y0 is not on the constraints "// &
                             "(max |phi|, |C v| = "//trim(adjustl(b1))//")")
                return
            end if
        end if
        call check_orbit(info)
        if (info /= CM_SUCCESS) return
        k = n - 1 - nc
        if (fr%reduced) k = k - 1
        if (k < 1) then
            call fr%fail(CM_BAD_INPUT, "transverse: no transverse coordinate is left (N - 1 "// &
                         "minus the invariants is < 1)")
            return
        end if
        fr%k = k

        ! ---- the invariant covectors at t = 0 (manifold normals, energy gradient), made
        !      orthogonal to f(0) (exact ones are), and the initial frame: the orthogonal
        !      complement of [Y^T, f] (SVD)
        ny = nc
        if (fr%reduced) ny = ny + 1
        p = ny + 1
        allocate (w(n, p), u(n, n), s(p), vt(1, 1), f(n), g(n), c(max(nc, 1), n), q0(n, k))
        allocate (y0c(max(ny, 1), n))
        call sys%rhs(0.0_dp, y0, f)
        if (nc > 0) then
            call model%normals(0.0_dp, y0, c)
            y0c(1:nc, :) = c(1:nc, :)
        end if
        if (fr%reduced) then
            call model%energy_gradient(0.0_dp, y0, g)
            y0c(ny, :) = g
        end if
        do j = 1, ny
            y0c(j, :) = y0c(j, :) - dot_product(y0c(j, :), f)/dot_product(f, f)*f
            y0c(j, :) = y0c(j, :)/max(norm2(y0c(j, :)), tiny(1.0_dp))
            w(:, j) = y0c(j, :)
        end do
        w(:, p) = f/norm2(f)
        call dgesvd('A', 'N', n, p, w, n, s, u, n, vt, 1, wq, -1, lainfo)
        allocate (work(max(1, int(wq(1)))))
        call dgesvd('A', 'N', n, p, w, n, s, u, n, vt, 1, work, size(work), lainfo)
        if (lainfo /= 0 .or. .not. (s(p) > 1.0e-8_dp*s(1))) then
            call fr%fail(CM_BAD_INPUT, "transverse: the vector field, the constraint normals "// &
                         "and the energy gradient are dependent at y0 (is y0 on the constraints?)")
            return
        end if
        q0 = u(:, p + 1:n)

        ! ---- one run: orbit, covectors, frame, Phi_red, Gramian, full monodromy
        fr%ode%n = n
        fr%ode%k = k
        fr%ode%ny = ny
        fr%ode%m = fr%m
        fr%ode%full = opt%full_monodromy
        allocate (fr%ode%sys, source=sys)
        allocate (fr%ode%model, source=model)
        allocate (z0(n + ny*n + n*k + k*k + merge(k*k, 0, fr%m > 0) + &
                     merge(n*n, 0, fr%ode%full)))
        z0 = 0.0_dp
        z0(1:n) = y0
        o = n
        if (ny > 0) z0(o + 1:o + ny*n) = reshape(y0c(1:ny, :), [ny*n])
        o = o + ny*n
        z0(o + 1:o + n*k) = reshape(q0, [n*k])
        o = o + n*k
        do j = 1, k
            z0(o + (j - 1)*k + j) = 1.0_dp
        end do
        o = o + k*k
        if (fr%m > 0) o = o + k*k
        if (fr%ode%full) then
            do j = 1, n
                z0(o + (j - 1)*n + j) = 1.0_dp
            end do
        end if
        oo%dense_output = .true.
        oo%save_steps = .false.
        call ode_solve(fr%ode, [0.0_dp, period], z0, oo, res)
        fr%nfev = res%stats%nfev
        if (res%status /= CM_SUCCESS) then
            call fr%fail_with_cause(res%status, "transverse: the integration along the orbit "// &
                                    "failed", res%message)
            return
        end if
        z0 = res%y(:, res%nt)
        call move_alloc(res%sol%ts, fr%sol%ts)
        call move_alloc(res%sol%hs, fr%sol%hs)
        call move_alloc(res%sol%coef, fr%sol%coef)
        fr%sol%n = res%sol%n
        fr%sol%nseg = res%sol%nseg
        fr%sol%nf = res%sol%nf
        fr%sol%form = res%sol%form
        fr%sol%t_first = res%sol%t_first
        fr%sol%t_last = res%sol%t_last

        ! ---- holonomy R = Q(0)^T Q(T), the monodromies
        allocate (qt(n, k), r(k, k), mred(k, k))
        qt = reshape(z0(n + ny*n + 1:n + ny*n + n*k), [n, k])
        block
            real(dp) :: fx(n), ax(n, n), qs(n, k), dq(n, k), bx(n, max(model%n_inputs, 1))
            real(dp) :: cv(max(ny, 1), n), dcv(max(ny, 1), n)
            if (ny > 0) cv(1:ny, :) = reshape(z0(n + 1:n + ny*n), [ny, n])
            call frame_derivative(fr%ode, period, z0(1:n), cv(1:ny, :), qt, fx, ax, qs, dq, &
                                  dcv(1:ny, :), bx, info)
            qt = qs
        end block
        call nearest_rotation(matmul(transpose(q0), qt), r, defect, dsgn, info)
        fr%frame_defect = defect
        if (info /= CM_SUCCESS .or. dsgn < 0.0_dp .or. defect > 1.0e-6_dp) then
            write (b1, '(es10.3)') defect
            call fr%fail(CM_NO_CONVERGENCE, "transverse: the frame did not return to the "// &
                         "transverse space after one period (defect "//trim(b1)//")")
            return
        end if
        fr%holonomy = r
        call rotation_log_init(r, fr%hlog, info, msg)
        if (info /= CM_SUCCESS) then
            call fr%fail(info, "transverse: "//msg)
            return
        end if
        o = n + ny*n + n*k
        mred = reshape(z0(o + 1:o + k*k), [k, k])
        fr%monodromy = matmul(r, mred)
        call monodromy_eig(fr%monodromy, fr%mr, fr%mi, "transverse")
        if (info /= CM_SUCCESS) return
        o = o + k*k
        if (fr%m > 0) then
            fr%gramian = matmul(r, matmul(reshape(z0(o + 1:o + k*k), [k, k]), transpose(r)))
            o = o + k*k
        end if
        if (fr%ode%full) then
            fr%full_monodromy = reshape(z0(o + 1:o + n*n), [n, n])
            call monodromy_eig(fr%full_monodromy, fr%fr, fr%fi, "full")
            if (info /= CM_SUCCESS) return
        end if
        write (b1, '(es10.3)') fr%closure
        write (b2, '(es10.3)') fr%frame_defect
        fr%info = CM_SUCCESS
        fr%message = "success (closure "//trim(adjustl(b1))//", frame defect "// &
                     trim(adjustl(b2))//")"

    contains

        !> Integrate the orbit alone, sampled at 64 points: closure, f /= 0, and whether
        !! the model's energy is conserved (sets fr%reduced).
        subroutine check_orbit(info)
            integer, intent(out) :: info
            type(ode_result) :: ro
            type(ode_options) :: o1
            real(dp) :: ts(64), fx(n), gx(n), fmin, fmax, drift
            integer :: i
            character(len=24) :: c1, c2
            do i = 1, 64
                ts(i) = period*real(i - 1, dp)/63.0_dp
            end do
            o1 = oo
            call ode_solve(sys, [0.0_dp, period], y0, o1, ro, t_eval=ts)
            if (ro%status /= CM_SUCCESS .or. ro%nt /= 64) then
                info = CM_BAD_INPUT
                call fr%fail_with_cause(info, "transverse: the orbit could not be integrated "// &
                                        "over one period", ro%message)
                return
            end if
            fr%closure = maxval(abs(ro%y(:, 64) - y0))
            tol = opt%closure_tol
            if (.not. tol > 0.0_dp) tol = max(1.0e-8_dp, 1.0e3_dp*max(opt%rtol, opt%atol))* &
                                          max(1.0_dp, maxval(abs(y0)))
            if (.not. fr%closure <= tol) then
                write (c1, '(es10.3)') fr%closure
                write (c2, '(es10.3)') tol
                info = CM_BAD_INPUT
                call fr%fail(info, "transverse: the orbit is not periodic: |x(T) - x(0)| = "// &
                             trim(adjustl(c1))//" > "//trim(adjustl(c2)))
                return
            end if
            fmin = huge(1.0_dp)
            fmax = 0.0_dp
            drift = 0.0_dp
            do i = 1, 64
                call sys%rhs(ts(i), ro%y(:, i), fx)
                fmin = min(fmin, norm2(fx))
                fmax = max(fmax, norm2(fx))
                if (opt%energy /= ENERGY_NONE .and. model%has_energy()) then
                    call model%energy_gradient(ts(i), ro%y(:, i), gx)
                    if (.not. norm2(gx) > 0.0_dp) then
                        drift = huge(1.0_dp)
                    else
                        drift = max(drift, abs(dot_product(gx, fx))/(norm2(gx)*norm2(fx)))
                    end if
                end if
            end do
            if (.not. (fmin > 1.0e-10_dp*fmax .and. fmax > 0.0_dp)) then
                info = CM_BAD_INPUT
                call fr%fail(info, "transverse: the vector field vanishes on the orbit (an "// &
                             "equilibrium is not a periodic orbit)")
                return
            end if
            fr%energy_drift = drift
            fr%reduced = .false.
            if (opt%energy /= ENERGY_NONE .and. model%has_energy()) &
                fr%reduced = drift <= opt%conservation_tol
            if (opt%energy == ENERGY_REQUIRED .and. .not. fr%reduced) then
                info = CM_BAD_INPUT
                if (.not. model%has_energy()) then
                    call fr%fail(info, "transverse: the system has no energy to reduce by")
                else
                    write (c1, '(es10.3)') drift
                    call fr%fail(info, "transverse: the energy is not conserved along the "// &
                                 "orbit (|grad H . f|/(|grad H| |f|) up to "// &
                                 trim(adjustl(c1))//")")
                end if
                return
            end if
            info = CM_SUCCESS
        end subroutine check_orbit

        !> The eigenvalues (wr, wi) of a monodromy matrix a (info; on failure fr fails,
        !! naming `which` monodromy).
        subroutine monodromy_eig(a, wr, wi, which)
            real(dp), intent(in) :: a(:, :)
            real(dp), allocatable, intent(out) :: wr(:), wi(:)
            character(len=*), intent(in) :: which
            allocate (wr(size(a, 1)), wi(size(a, 1)))
            call la_eig(a, wr, wi, info)
            if (info /= CM_SUCCESS) call fr%fail(info, "transverse: eigenvalues of the "// &
                                                 which//" monodromy failed")
        end subroutine monodromy_eig

    end subroutine transverse_build

    !> The orbit point x, the periodic frame qp (N x k), A_perp (k x k) and, with inputs,
    !! B_perp (k x m) at time t (taken modulo the period); optionally dqp = qp'.
    subroutine transverse_eval(fr, t, x, qp, ap, bp, info, dqp)
        type(transverse_frame), intent(in) :: fr
        real(dp), intent(in) :: t
        real(dp), intent(out) :: x(:), qp(:, :), ap(:, :), bp(:, :)
        integer, intent(out) :: info
        real(dp), intent(out), optional :: dqp(:, :)
        real(dp) :: z(fr%sol%n), q(fr%n, fr%k), f(fr%n), a(fr%n, fr%n), dq(fr%n, fr%k)
        real(dp) :: bx(fr%n, max(fr%m, 1)), e(fr%k, fr%k), l(fr%k, fr%k), tt
        real(dp) :: cv(max(fr%ode%ny, 1), fr%n), dcv(max(fr%ode%ny, 1), fr%n), qs(fr%n, fr%k)
        integer :: n, k, ny
        n = fr%n
        k = fr%k
        if (fr%info /= CM_SUCCESS) then
            info = CM_BAD_INPUT
            return
        end if
        tt = modulo(t, fr%period)
        ny = fr%ode%ny
        call fr%sol%eval(tt, z)
        x = z(1:n)
        if (ny > 0) cv(1:ny, :) = reshape(z(n + 1:n + ny*n), [ny, n])
        q = reshape(z(n + ny*n + 1:n + ny*n + n*k), [n, k])
        call frame_derivative(fr%ode, tt, x, cv(1:ny, :), q, f, a, qs, dq, dcv(1:ny, :), bx, &
                              info)
        if (info /= CM_SUCCESS) return
        call fr%hlog%power(-tt/fr%period, e)
        call fr%hlog%generator(l)
        qp = matmul(qs, e)
        ap = matmul(transpose(e), matmul(matmul(transpose(qs), matmul(a, qs) - dq), e)) + &
             l/fr%period
        if (fr%m > 0) bp(:, 1:fr%m) = matmul(transpose(e), matmul(transpose(qs), bx(:, 1:fr%m)))
        if (present(dqp)) dqp = matmul(dq, e) - matmul(qs, matmul(l, e))/fr%period
    end subroutine transverse_eval

    !> For a two-degree-of-freedom system in second-order form x = [q, v] (v = dq/dt) with
    !! the energy removed (N = 4, k = 2): the normal deviation N = n . dq (n the unit normal
    !! to v in the configuration plane, turned +90 degrees) of isoenergetic perturbations
    !! obeys N'' + psi(t) N' + phi(t) N = 0. With r0 = [n; 0], r1 = [dn; n] and
    !! r2 = [ddn + a_q^T n; 2 dn + a_v^T n] (A = [0 I; a_q a_v], dn and ddn the first and
    !! second time derivatives of n), the i-th derivative of N is r_i . dx along the
    !! variational flow; on the isoenergetic section {f . dx = 0, grad H . dx = 0}
    !! r2 = -phi r0 - psi r1, i.e. r2 + phi r0 + psi r1 = alpha f + beta grad H (a 4 x 4
    !! solve at the orbit point with the model's grad H: no frame enters). For
    !! dv/dt = -grad V + 2 omega J v (identity mass) psi = 0 and phi is Hill's coefficient
    !! n^T V'' n + 3 (turn - omega)^2 + omega^2.
    subroutine transverse_hill(fr, t, phi, psi, info)
        type(transverse_frame), intent(in) :: fr
        real(dp), intent(in) :: t
        real(dp), intent(out) :: phi, psi
        integer, intent(out) :: info
        real(dp) :: z(fr%sol%n), x(4), f(4), a(4, 4), af(4), g(4)
        real(dp) :: v1(2), v2(2), v3(2), nn(2), n1(2), n2(2)
        real(dp) :: s, s1, s2, r0(4), r1(4), r2(4), mat(4, 4), rhs(4, 1), sol(4, 1), tt
        phi = 0.0_dp
        psi = 0.0_dp
        if (fr%info /= CM_SUCCESS .or. fr%n /= 4 .or. fr%k /= 2 .or. .not. fr%reduced) then
            info = CM_BAD_INPUT
            return
        end if
        tt = modulo(t, fr%period)
        call fr%sol%eval(tt, z)
        x = z(1:4)
        call transverse_jacobian(fr%ode%sys, tt, x, f, a)
        if (maxval(abs(f(1:2) - x(3:4))) > 1.0e-10_dp*max(1.0_dp, maxval(abs(x(3:4))))) then
            info = CM_BAD_INPUT    ! not in second-order form x = [q, v]
            return
        end if
        call fr%ode%model%energy_gradient(tt, x, g)
        af = matmul(a, f)
        v1 = x(3:4)         ! velocity
        v2 = f(3:4)         ! acceleration
        v3 = af(3:4)        ! its time derivative
        s = norm2(v1)
        if (.not. s > 0.0_dp) then
            info = CM_SINGULAR   ! v = 0: no normal
            return
        end if
        s1 = dot_product(v1, v2)/s
        s2 = (dot_product(v2, v2) + dot_product(v1, v3))/s - s1**2/s
        nn = rot90(v1)/s
        n1 = rot90(v2/s - v1*s1/s**2)
        n2 = rot90(v3/s - 2.0_dp*v2*s1/s**2 - v1*s2/s**2 + 2.0_dp*v1*s1**2/s**3)
        r0 = [nn, 0.0_dp, 0.0_dp]
        r1 = [n1, nn]
        r2 = [n2 + matmul(nn, a(3:4, 1:2)), 2.0_dp*n1 + matmul(nn, a(3:4, 3:4))]
        mat(:, 1) = r0
        mat(:, 2) = r1
        mat(:, 3) = -f/norm2(f)
        mat(:, 4) = -g/norm2(g)
        rhs(:, 1) = -r2
        call la_solve(mat, rhs, sol, info)
        if (info /= CM_SUCCESS) return
        phi = sol(1, 1)
        psi = sol(2, 1)

    contains

        pure function rot90(v) result(w)
            real(dp), intent(in) :: v(2)
            real(dp) :: w(2)
            w = [-v(2), v(1)]
        end function rot90

    end subroutine transverse_hill

end module conmech_transverse_general
