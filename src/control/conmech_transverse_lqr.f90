!> Orbital stabilisation by transverse LQR: the feedback
!!
!!     u = u_nom(x) + K(tau(x)) xi(x),   xi = Qp(tau)^T (x - x*(tau)),   K = -R^-1 B_perp^T P,
!!
!! around a periodic orbit x*(t) of the closed loop x' = F(x, u_nom(x)) (u_nom: e.g. the
!! virtual-constraint feedback), with P the stabilising periodic solution of the Riccati
!! equation of the transverse linearisation (A_perp, B_perp) (Shiriaev, Perram,
!! Canudas-de-Wit 2005; Manchester 2011, moving Poincare sections).
!!
!! The phase tau(x) is the orbit point whose section (normal to the flow, the sections of
!! the transverse construction) contains x: f*(tau) . (x - x*(tau)) = 0, the stationarity
!! condition of |x - x*(tau)|^2. It is found from the nearest node of a table over one
!! period, then by Newton's method safeguarded by bisection on the bracket of the two
!! neighbouring nodes. The table holds ng + 1 nodes (the last = the first): x*, f* and
!! f*' (cubic Hermite interpolation, error ~ h^4), the periodic frame Qp and Qp' (cubic
!! Hermite) and K with the second derivatives of its periodic cubic spline (C2: a gain
!! interpolated linearly would put a kink into the closed-loop vector field at every
!! node, and the integrators' step control would stop at each). At x on the orbit xi = 0
!! and u = u_nom: the orbit stays a solution of the nonlinear closed loop (up to the
!! interpolation error of x*).
module conmech_transverse_lqr
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_lapack, only: la_solve
    use conmech_control_system, only: feedback_law
    use conmech_periodic_riccati, only: periodic_lq
    use conmech_transverse_general, only: transverse_frame, transverse_eval
    implicit none
    private
    public :: transverse_lq, transverse_lqr_law, periodic_spline

    !> The transverse linearisation as a periodic linear system (A_perp, B_perp).
    type, extends(periodic_lq) :: transverse_lq
        type(transverse_frame) :: fr
    contains
        procedure :: coefficients => tlq_coefficients
    end type transverse_lq

    !> The orbital stabilising law (see the module notes).
    type, extends(feedback_law) :: transverse_lqr_law
        class(feedback_law), allocatable :: nominal   !! u_nom (absent: zero)
        logical :: has_nominal = .false.
        integer :: n = 0, k = 0, ng = 0
        real(dp) :: period = 0.0_dp
        real(dp), allocatable :: xs(:, :), fs(:, :), as(:, :)   !! (n, ng + 1)
        real(dp), allocatable :: qs(:, :, :), qd(:, :, :)       !! (n, k, ng + 1)
        real(dp), allocatable :: ks(:, :, :)                    !! (m, k, ng + 1)
        real(dp), allocatable :: km(:, :, :)                    !! K'' of the spline
    contains
        procedure :: eval => lqr_eval
        procedure :: project => lqr_project
    end type transverse_lqr_law

contains

    subroutine tlq_coefficients(self, t, a, b, info)
        class(transverse_lq), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(out) :: a(:, :), b(:, :)
        integer, intent(out) :: info
        real(dp) :: x(self%fr%n), qp(self%fr%n, self%fr%k)
        call transverse_eval(self%fr, t, x, qp, a, b, info)
    end subroutine tlq_coefficients

    !> Cubic Hermite basis at s in [0, 1] (values h and derivatives dh, per unit s).
    pure subroutine hermite(s, h, dh)
        real(dp), intent(in) :: s
        real(dp), intent(out) :: h(4), dh(4)
        h = [2*s**3 - 3*s**2 + 1, s**3 - 2*s**2 + s, -2*s**3 + 3*s**2, s**3 - s**2]
        dh = [6*s**2 - 6*s, 3*s**2 - 4*s + 1, -6*s**2 + 6*s, 3*s**2 - 2*s]
    end subroutine hermite

    !> x*(tau), f*(tau), f*'(tau) from the table (tau in [0, T)).
    pure subroutine orbit_at(self, tau, x, f, df)
        class(transverse_lqr_law), intent(in) :: self
        real(dp), intent(in) :: tau
        real(dp), intent(out) :: x(:), f(:), df(:)
        real(dp) :: hseg, s, h(4), dh(4)
        integer :: j
        hseg = self%period/self%ng
        j = min(int(tau/hseg), self%ng - 1) + 1
        s = (tau - (j - 1)*hseg)/hseg
        call hermite(s, h, dh)
        x = h(1)*self%xs(:, j) + h(2)*hseg*self%fs(:, j) + h(3)*self%xs(:, j + 1) + &
            h(4)*hseg*self%fs(:, j + 1)
        f = h(1)*self%fs(:, j) + h(2)*hseg*self%as(:, j) + h(3)*self%fs(:, j + 1) + &
            h(4)*hseg*self%as(:, j + 1)
        df = (dh(1)*self%fs(:, j) + dh(2)*hseg*self%as(:, j) + dh(3)*self%fs(:, j + 1) + &
              dh(4)*hseg*self%as(:, j + 1))/hseg
    end subroutine orbit_at

    !> The phase tau of x, its transverse coordinates xi = Qp^T (x - x*(tau)), the
    !! distance |x - x*(tau)|; info = CM_NO_CONVERGENCE if the section equation has no
    !! root between the neighbours of the nearest node (x far from the orbit: tau is then
    !! the nearest node's).
    subroutine lqr_project(self, x, tau, xi, dist, info)
        class(transverse_lqr_law), intent(in) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: tau, xi(:), dist
        integer, intent(out) :: info
        real(dp) :: xo(self%n), fo(self%n), dfo(self%n), d2, best, lo, hi, g, dg, glo, hseg
        real(dp) :: step, qq(self%n, self%k), h(4), dh(4), s
        integer :: j, jb, it
        hseg = self%period/self%ng
        best = huge(1.0_dp)
        jb = 1
        do j = 1, self%ng
            d2 = sum((x - self%xs(:, j))**2)
            if (d2 < best) then
                best = d2
                jb = j
            end if
        end do
        lo = (jb - 2)*hseg
        hi = jb*hseg
        tau = (jb - 1)*hseg
        glo = section(lo)
        info = CM_SUCCESS
        if (glo*section(hi) > 0.0_dp) then
            info = CM_NO_CONVERGENCE
        else
            do it = 1, 60
                call orbit_at(self, modulo(tau, self%period), xo, fo, dfo)
                g = dot_product(fo, x - xo)
                dg = dot_product(dfo, x - xo) - dot_product(fo, fo)
                if (g*glo > 0.0_dp) then
                    lo = tau
                    glo = g
                else
                    hi = tau
                end if
                step = -g/dg
                if (dg /= 0.0_dp .and. tau + step > lo .and. tau + step < hi) then
                    tau = tau + step
                else
                    step = 0.5_dp*(lo + hi) - tau
                    tau = 0.5_dp*(lo + hi)
                end if
                if (abs(step) <= 1.0e-15_dp*self%period .or. hi - lo <= 1.0e-15_dp*self%period) exit
            end do
        end if
        tau = modulo(tau, self%period)
        call orbit_at(self, tau, xo, fo, dfo)
        dist = norm2(x - xo)
        j = min(int(tau/hseg), self%ng - 1) + 1
        s = (tau - (j - 1)*hseg)/hseg
        call hermite(s, h, dh)
        qq = h(1)*self%qs(:, :, j) + h(2)*hseg*self%qd(:, :, j) + h(3)*self%qs(:, :, j + 1) + &
             h(4)*hseg*self%qd(:, :, j + 1)
        xi = matmul(x - xo, qq)

    contains

        real(dp) function section(tt)
            real(dp), intent(in) :: tt
            real(dp) :: xa(self%n), fa(self%n), da(self%n)
            call orbit_at(self, modulo(tt, self%period), xa, fa, da)
            section = dot_product(fa, x - xa)
        end function section

    end subroutine lqr_project

    !> Second derivatives ym (.., ng + 1) of the periodic cubic spline through the values
    !! y (.., ng + 1) (y(:, ng + 1) = y(:, 1)) on a uniform grid of step h:
    !! ym(j-1) + 4 ym(j) + ym(j+1) = 6 (y(j+1) - 2 y(j) + y(j-1))/h^2, cyclic (dense LU).
    subroutine periodic_spline(y, h, ym, info)
        real(dp), intent(in) :: y(:, :), h
        real(dp), intent(out) :: ym(:, :)
        integer, intent(out) :: info
        real(dp), allocatable :: a(:, :), r(:, :), x(:, :)
        integer :: ng, j, jm, jp
        ng = size(y, 2) - 1
        allocate (a(ng, ng), r(ng, size(y, 1)), x(ng, size(y, 1)))
        a = 0.0_dp
        do j = 1, ng
            jm = modulo(j - 2, ng) + 1
            jp = modulo(j, ng) + 1
            a(j, j) = 4.0_dp
            a(j, jm) = a(j, jm) + 1.0_dp
            a(j, jp) = a(j, jp) + 1.0_dp
            r(j, :) = 6.0_dp*(y(:, jp) - 2.0_dp*y(:, j) + y(:, jm))/h**2
        end do
        call la_solve(a, r, x, info)
        if (info /= CM_SUCCESS) return
        ym(:, 1:ng) = transpose(x)
        ym(:, ng + 1) = ym(:, 1)
    end subroutine periodic_spline

    subroutine lqr_eval(self, t, x, u)
        class(transverse_lqr_law), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: u(:)
        real(dp) :: tau, xi(self%k), dist, hseg, s
        integer :: info, j
        call self%project(x, tau, xi, dist, info)
        hseg = self%period/self%ng
        j = min(int(tau/hseg), self%ng - 1) + 1
        s = (tau - (j - 1)*hseg)/hseg
        u = matmul((1.0_dp - s)*self%ks(:, :, j) + s*self%ks(:, :, j + 1) + &
                   hseg**2/6.0_dp*(((1.0_dp - s)**3 - (1.0_dp - s))*self%km(:, :, j) + &
                                   (s**3 - s)*self%km(:, :, j + 1)), xi)
        if (self%has_nominal) then
            block
                real(dp) :: un(size(u))
                call self%nominal%eval(t, x, un)
                u = u + un
            end block
        end if
    end subroutine lqr_eval

end module conmech_transverse_lqr
