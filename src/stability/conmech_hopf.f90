!> The first Lyapunov coefficient of an equilibrium at a Hopf point (Kuznetsov, Elements of
!! Applied Bifurcation Theory, 3rd ed. 2004, sec. 3.5, eq. (3.20)):
!!
!!     l1 = Re[ <p, C(q, q, conj q)> - 2 <p, B(q, A^-1 B(q, conj q))>
!!              + <p, B(conj q, (2 i omega I - A)^-1 B(q, q))> ] / (2 omega),
!!
!! with A = df/dy at the equilibrium, A q = i omega q, A^T p = -i omega p, <q, q> = 1,
!! <p, q> = 1 (<u, v> = conj(u)^T v), and B, C the second and third derivatives of f as
!! multilinear forms. l1 < 0: supercritical (a stable cycle is born on the side where
!! the equilibrium is unstable), l1 > 0: subcritical; l1 = 0: a degenerate (Bautin)
!! point, where the normal form to this order does not decide.
!!
!! The forms come from central differences: of the Jacobian when the system's Jacobian is
!! analytic (B(u, v) = [J(y + h u) - J(y - h u)] v / 2h; the third derivative from the
!! second difference of J), else of f alone (four evaluations per B, eight per C). The
!! complex arguments are split into real and imaginary parts by multilinearity. l1 is
!! computed with steps h, 2 h and 4 h and extrapolated (Richardson; the differences' errors
!! are O(h^2)), the steps chosen for the extrapolated value (h = eps^(1/5), eps^(1/6)
!! relative for the first and second differences of J, eps^(1/6) and eps^(1/7) for the
!! second and third of f); `l1_error` = |R(h) - R(2 h)|/15 + 1e3 eps scale estimates the
!! error of the extrapolated R(h) = l1. The linear solves run in real
!! arithmetic (LAPACK through `la_solve`, the complex one as a real system of size 2n).
!! `scale` = (|t1| + |t2| + |t3|)/(2 omega), the size of the three terms. The point is
!! reported degenerate when |l1| <= max(l1_tol scale, l1_error) (l1_tol default 1e-6):
!! l1 is then not distinguishable from 0.
module conmech_hopf
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_lapack, only: la_eig, la_solve
    implicit none
    private

    integer, parameter, public :: HOPF_SUPERCRITICAL = 1   !! l1 < 0
    integer, parameter, public :: HOPF_SUBCRITICAL = 2     !! l1 > 0
    integer, parameter, public :: HOPF_DEGENERATE = 3      !! |l1| within its accuracy of 0

    public :: hopf_normal_form, first_lyapunov_coefficient

    !> The normal-form data of a Hopf point.
    type :: hopf_normal_form
        real(dp) :: omega = 0.0_dp            !! the pair +-i omega
        real(dp) :: re_lambda = 0.0_dp        !! the real part of that pair (~0 at the point)
        real(dp) :: l1 = 0.0_dp               !! first Lyapunov coefficient
        real(dp) :: scale = 0.0_dp            !! size of the terms of l1 (see the module notes)
        real(dp) :: l1_error = 0.0_dp         !! estimate of the differences' error in l1
        integer :: criticality = 0            !! HOPF_SUPERCRITICAL, _SUBCRITICAL, _DEGENERATE
        logical :: exact_jacobian = .false.   !! forms from differences of the exact J
        complex(dp), allocatable :: q(:)      !! A q = i omega q, <q, q> = 1
        complex(dp), allocatable :: p(:)      !! A^T p = -i omega p, <p, q> = 1
    end type hopf_normal_form

    !> Where the forms are evaluated (internal).
    type :: form_point
        real(dp) :: t = 0.0_dp
        real(dp), allocatable :: y(:)
        real(dp) :: s = 1.0_dp                !! max(1, |y|): the scale of the steps
        real(dp) :: hfac = 1.0_dp             !! the steps are hfac times the base ones
        logical :: exact = .false.
    end type form_point

contains

    !> The first Lyapunov coefficient of the equilibrium y of `sys` (at time t) whose
    !! Jacobian has the pair nearest the imaginary axis +-i omega (its real part is
    !! returned in hf%re_lambda; the caller locates the Hopf point first). info CM_BAD_INPUT
    !! if the Jacobian has no complex pair, CM_SINGULAR if A or 2 i omega - A is singular
    !! (a zero eigenvalue or a 1:2 resonance at the point).
    subroutine first_lyapunov_coefficient(sys, t, y, hf, info, msg, l1_tol)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        type(hopf_normal_form), intent(out) :: hf
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        real(dp), intent(in), optional :: l1_tol
        integer :: k
        real(dp) :: a(size(y), size(y)), wr(size(y)), wi(size(y)), vr(size(y), size(y))
        real(dp) :: tol, l1h(3), sc(3), r2
        complex(dp) :: pq
        type(form_point) :: fp
        tol = 1.0e-6_dp
        if (present(l1_tol)) tol = l1_tol
        msg = "success"
        call sys%jacobian(t, y, a)
        call la_eig(a, wr, wi, info, vr)
        if (info /= CM_SUCCESS) then
            msg = "first Lyapunov coefficient: the eigenvalues of the Jacobian failed"
            return
        end if
        k = critical_pair(wr, wi)
        if (k == 0) then
            info = CM_BAD_INPUT
            msg = "first Lyapunov coefficient: the Jacobian has no complex eigenvalue pair "// &
                  "(not a Hopf point)"
            return
        end if
        hf%omega = wi(k)
        hf%re_lambda = wr(k)
        hf%q = cmplx(vr(:, k), vr(:, k + 1), dp)
        hf%q = hf%q/sqrt(sum(abs(hf%q)**2))
        ! the adjoint eigenvector: A^T v = (wr + i omega) v, so p = conj(v)
        call la_eig(transpose(a), wr, wi, info, vr)
        if (info /= CM_SUCCESS) then
            msg = "first Lyapunov coefficient: the eigenvalues of the Jacobian failed"
            return
        end if
        k = nearest_pair(wr, wi, hf%re_lambda, hf%omega)
        hf%p = conjg(cmplx(vr(:, k), vr(:, k + 1), dp))
        pq = sum(conjg(hf%p)*hf%q)
        if (.not. (abs(pq) > 0.0_dp)) then
            info = CM_SINGULAR
            msg = "first Lyapunov coefficient: <p, q> = 0 (a Jordan block at i omega)"
            return
        end if
        hf%p = hf%p/conjg(pq)
        fp%t = t
        fp%y = y
        fp%s = max(1.0_dp, maxval(abs(y)))
        fp%exact = sys%has_jacobian()
        hf%exact_jacobian = fp%exact
        ! l1 with the difference steps h, 2 h and 4 h, extrapolated (Richardson: the forms'
        ! errors are O(h^2)); the two extrapolated values differ by ~15 times the error
        do k = 1, 3
            fp%hfac = real(2**(k - 1), dp)
            call l1_terms(sys, fp, a, hf%q, hf%p, hf%omega, l1h(k), sc(k), info, msg)
            if (info /= CM_SUCCESS) return
        end do
        hf%l1 = (4.0_dp*l1h(1) - l1h(2))/3.0_dp
        r2 = (4.0_dp*l1h(2) - l1h(3))/3.0_dp
        hf%l1_error = abs(hf%l1 - r2)/15.0_dp + 1.0e3_dp*epsilon(1.0_dp)*sc(1)
        hf%scale = sc(1)
        if (.not. (abs(hf%l1) > max(tol*hf%scale, hf%l1_error))) then
            hf%criticality = HOPF_DEGENERATE
        else if (hf%l1 < 0.0_dp) then
            hf%criticality = HOPF_SUPERCRITICAL
        else
            hf%criticality = HOPF_SUBCRITICAL
        end if
        info = CM_SUCCESS
    end subroutine first_lyapunov_coefficient

    !> l1 (and the size of its terms, `scale`) from the forms by differences with the steps
    !! of fp (see the module notes).
    subroutine l1_terms(sys, fp, a, q, p, omega, l1, scale, info, msg)
        class(ode_system), intent(in) :: sys
        type(form_point), intent(in) :: fp
        real(dp), intent(in) :: a(:, :), omega
        complex(dp), intent(in) :: q(:), p(:)
        real(dp), intent(out) :: l1, scale
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: n, k
        real(dp) :: r(size(q)), s(size(q)), w(size(q)), dj_r(size(q), size(q))
        real(dp) :: dj_s(size(q), size(q)), big(2*size(q), 2*size(q)), rhs(2*size(q), 1)
        real(dp) :: sol(2*size(q), 1), x1(size(q), 1), bqc(size(q)), br(size(q))
        real(dp) :: bi(size(q))
        complex(dp) :: bqq(size(q)), c3(size(q)), bq_a(size(q)), bqb(size(q))
        complex(dp) :: t1, t2, t3
        n = size(q)
        l1 = 0.0_dp
        scale = 0.0_dp
        r = real(q, dp)
        s = aimag(q)
        ! B(q, conj q) = B(r, r) + B(s, s), w = A^-1 B(q, conj q) (real)
        if (fp%exact) then
            call jac_difference(sys, fp, r, dj_r)
            call jac_difference(sys, fp, s, dj_s)
            bqc = matmul(dj_r, r) + matmul(dj_s, s)
        else
            bqc = form2(sys, fp, r, r) + form2(sys, fp, s, s)
        end if
        call la_solve(a, reshape(bqc, [n, 1]), x1, info)
        if (info /= CM_SUCCESS) then
            info = CM_SINGULAR
            msg = "first Lyapunov coefficient: the Jacobian is singular (a zero eigenvalue "// &
                  "at the Hopf point: a Bogdanov-Takens or fold-Hopf point)"
            return
        end if
        w = x1(:, 1)
        ! B(q, q) = B(r, r) - B(s, s) + 2 i B(r, s); b = (2 i omega - A)^-1 B(q, q)
        if (fp%exact) then
            bqq = cmplx(matmul(dj_r, r) - matmul(dj_s, s), 2.0_dp*matmul(dj_r, s), dp)
        else
            bqq = cmplx(form2(sys, fp, r, r) - form2(sys, fp, s, s), &
                        2.0_dp*form2(sys, fp, r, s), dp)
        end if
        big = 0.0_dp
        big(1:n, 1:n) = -a
        big(n + 1:, n + 1:) = -a
        do k = 1, n
            big(k, n + k) = -2.0_dp*omega
            big(n + k, k) = 2.0_dp*omega
        end do
        rhs(1:n, 1) = real(bqq, dp)
        rhs(n + 1:, 1) = aimag(bqq)
        call la_solve(big, rhs, sol, info)
        if (info /= CM_SUCCESS) then
            info = CM_SINGULAR
            msg = "first Lyapunov coefficient: 2 i omega is an eigenvalue (1:2 resonance)"
            return
        end if
        br = sol(1:n, 1)
        bi = sol(n + 1:, 1)
        ! B(q, w), B(conj q, b); C(q, q, conj q) = C(r,r,r) + C(r,s,s) + i (C(r,r,s)
        ! + C(s,s,s))
        if (fp%exact) then
            bq_a = cmplx(matmul(dj_r, w), matmul(dj_s, w), dp)
            bqb = cmplx(matmul(dj_r, br) + matmul(dj_s, bi), &
                        matmul(dj_r, bi) - matmul(dj_s, br), dp)
            call jac_second_difference(sys, fp, r, dj_r)
            call jac_second_difference(sys, fp, s, dj_s)
            c3 = cmplx(matmul(dj_r, r) + matmul(dj_s, r), matmul(dj_r, s) + matmul(dj_s, s), &
                       dp)
        else
            bq_a = cmplx(form2(sys, fp, r, w), form2(sys, fp, s, w), dp)
            bqb = cmplx(form2(sys, fp, r, br) + form2(sys, fp, s, bi), &
                        form2(sys, fp, r, bi) - form2(sys, fp, s, br), dp)
            c3 = cmplx(form3(sys, fp, r, r, r) + form3(sys, fp, r, s, s), &
                       form3(sys, fp, r, r, s) + form3(sys, fp, s, s, s), dp)
        end if
        t1 = sum(conjg(p)*c3)
        t2 = -2.0_dp*sum(conjg(p)*bq_a)
        t3 = sum(conjg(p)*bqb)
        l1 = real(t1 + t2 + t3, dp)/(2.0_dp*omega)
        scale = (abs(t1) + abs(t2) + abs(t3))/(2.0_dp*omega)
        info = CM_SUCCESS
        msg = "success"
    end subroutine l1_terms

    !> The index of the eigenvalue with positive imaginary part nearest the imaginary axis
    !! (in |Re|/|lambda|), 0 if none (dgeev stores a pair as j, j + 1 with wi(j) > 0).
    pure integer function critical_pair(wr, wi) result(k)
        real(dp), intent(in) :: wr(:), wi(:)
        k = pair_argmin(wi, abs(wr)/hypot(wr, merge(wi, 1.0_dp, wi > 0.0_dp)), 0)
    end function critical_pair

    !> The eigenvalue with wi > 0 nearest (re, im).
    pure integer function nearest_pair(wr, wi, re, im) result(k)
        real(dp), intent(in) :: wr(:), wi(:), re, im
        k = pair_argmin(wi, hypot(wr - re, wi - im), 1)
    end function nearest_pair

    !> The first j < size(wi) with wi(j) > 0 and the smallest d(j) (`none` if no such j).
    pure integer function pair_argmin(wi, d, none) result(k)
        real(dp), intent(in) :: wi(:), d(:)
        integer, intent(in) :: none
        real(dp) :: best
        integer :: j
        k = none
        best = huge(1.0_dp)
        do j = 1, size(wi) - 1
            if (.not. (wi(j) > 0.0_dp)) cycle
            if (d(j) < best) then
                best = d(j)
                k = j
            end if
        end do
    end function pair_argmin

    !> dj = [J(y + h u) - J(y - h u)]/(2 h), the derivative of J along u (h = hfac
    !! eps^(1/5) s/|u|).
    subroutine jac_difference(sys, fp, u, dj)
        class(ode_system), intent(in) :: sys
        type(form_point), intent(in) :: fp
        real(dp), intent(in) :: u(:)
        real(dp), intent(out) :: dj(:, :)
        real(dp) :: jp(size(u), size(u)), jm(size(u), size(u)), h, un
        un = maxval(abs(u))
        dj = 0.0_dp
        if (.not. (un > 0.0_dp)) return
        h = fp%hfac*epsilon(1.0_dp)**0.2_dp*fp%s/un
        call sys%jacobian(fp%t, fp%y + h*u, jp)
        call sys%jacobian(fp%t, fp%y - h*u, jm)
        dj = (jp - jm)/(2.0_dp*h)
    end subroutine jac_difference

    !> dj = [J(y + h u) - 2 J(y) + J(y - h u)]/h^2, the second derivative of J along u
    !! (h = hfac eps^(1/6) s/|u|).
    subroutine jac_second_difference(sys, fp, u, dj)
        class(ode_system), intent(in) :: sys
        type(form_point), intent(in) :: fp
        real(dp), intent(in) :: u(:)
        real(dp), intent(out) :: dj(:, :)
        real(dp) :: jp(size(u), size(u)), jm(size(u), size(u)), j0(size(u), size(u))
        real(dp) :: h, un
        un = maxval(abs(u))
        dj = 0.0_dp
        if (.not. (un > 0.0_dp)) return
        h = fp%hfac*epsilon(1.0_dp)**(1.0_dp/6.0_dp)*fp%s/un
        call sys%jacobian(fp%t, fp%y + h*u, jp)
        call sys%jacobian(fp%t, fp%y, j0)
        call sys%jacobian(fp%t, fp%y - h*u, jm)
        dj = (jp - 2.0_dp*j0 + jm)/(h*h)
    end subroutine jac_second_difference

    !> B(u, v) from four evaluations of f (h = hfac eps^(1/6) s along the unit directions).
    function form2(sys, fp, u, v) result(b)
        class(ode_system), intent(in) :: sys
        type(form_point), intent(in) :: fp
        real(dp), intent(in) :: u(:), v(:)
        real(dp) :: b(size(u))
        real(dp) :: f1(size(u)), f2(size(u)), f3(size(u)), f4(size(u)), h, nu, nv
        nu = maxval(abs(u))
        nv = maxval(abs(v))
        b = 0.0_dp
        if (.not. (nu > 0.0_dp .and. nv > 0.0_dp)) return
        h = fp%hfac*epsilon(1.0_dp)**(1.0_dp/6.0_dp)*fp%s
        call sys%rhs(fp%t, fp%y + h*(u/nu + v/nv), f1)
        call sys%rhs(fp%t, fp%y + h*(u/nu - v/nv), f2)
        call sys%rhs(fp%t, fp%y - h*(u/nu - v/nv), f3)
        call sys%rhs(fp%t, fp%y - h*(u/nu + v/nv), f4)
        b = (f1 - f2 - f3 + f4)/(4.0_dp*h*h)*nu*nv
    end function form2

    !> C(u, v, w) from eight evaluations of f (h = hfac eps^(1/7) s along the unit
    !! directions).
    function form3(sys, fp, u, v, w) result(c)
        class(ode_system), intent(in) :: sys
        type(form_point), intent(in) :: fp
        real(dp), intent(in) :: u(:), v(:), w(:)
        real(dp) :: c(size(u))
        real(dp) :: f(size(u)), h, nu, nv, nw, sg
        integer :: i, j, k
        nu = maxval(abs(u))
        nv = maxval(abs(v))
        nw = maxval(abs(w))
        c = 0.0_dp
        if (.not. (nu > 0.0_dp .and. nv > 0.0_dp .and. nw > 0.0_dp)) return
        h = fp%hfac*epsilon(1.0_dp)**(1.0_dp/7.0_dp)*fp%s
        do i = -1, 1, 2
            do j = -1, 1, 2
                do k = -1, 1, 2
                    call sys%rhs(fp%t, fp%y + h*(i*u/nu + j*v/nv + k*w/nw), f)
                    sg = real(i*j*k, dp)
                    c = c + sg*f
                end do
            end do
        end do
        c = c/(8.0_dp*h**3)*nu*nv*nw
    end function form3

end module conmech_hopf
