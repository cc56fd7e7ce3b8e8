!> Floquet theory: multipliers, exponents and stability indices of a monodromy matrix, and a
!! solver for Hill's equation N'' + Phi(t) N = 0 with a periodic coefficient.
!!
!! `floquet_analysis`: multipliers as the eigenvalues of a formed monodromy matrix M
!! (LAPACK dgeev); `floquet_from_multipliers`: from the periodic eigenvalues of its factors
!! (conmech_periodic_multipliers, what the orbit solvers use). Floquet exponents are
!! log(mu)/T (principal branch of the complex logarithm).
!!
!! Trivial multipliers. A periodic orbit of an autonomous system has the multiplier 1
!! (eigenvector f(y0)); in a conservative (Hamiltonian) system it is double and forms a
!! Jordan block. An integration error eps in M splits a Jordan block into 1 +- sqrt(eps):
!! the trivial multipliers computed as eigenvalues are only accurate to ~sqrt(eps). Read
!! the stability of a planar conservative orbit (4 x 4 M) from the trace instead:
!! S = (trace M - 2)/2 is the half trace of the non-trivial pair, stable when |S| < 1, and
!! the non-trivial multipliers are S +- sqrt(S^2 - 1), accurate to eps.
module conmech_floquet
    use conmech_kinds, only: dp, pi
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: tolerance_options
    use conmech_ode_solver, only: ode_options, ode_stats, ode_integrate
    use conmech_variational, only: integrate_stm
    use conmech_lapack, only: la_eig
    use conmech_periodic_multipliers, only: multiplier_set, unit_circle_tolerance
    implicit none
    private

    public :: floquet_result, floquet_analysis, planar_stability_index
    public :: floquet_from_multipliers, multipliers_2x2
    public :: hill_coefficient_fun, hill_equation, hill_result, hill_solve, hill_solve_samples
    public :: fourier_coefficients, fourier_eval

    !> Multipliers and derived quantities of a monodromy matrix.
    type :: floquet_result
        integer :: info = CM_BAD_INPUT
        real(dp), allocatable :: mr(:), mi(:)           !! multipliers (real, imaginary parts)
        real(dp), allocatable :: abs_mult(:)            !! |mu|
        complex(dp), allocatable :: exponents(:)        !! log(mu)/T
        real(dp) :: trace = 0.0_dp                      !! trace M
        real(dp) :: det = 0.0_dp                        !! product of the multipliers
        real(dp) :: max_abs = 0.0_dp                    !! spectral radius
        logical :: stable = .false.                     !! all |mu| <= 1 + tol
    end type floquet_result

    abstract interface
        !> Periodic coefficient Phi(t) of Hill's equation.
        function hill_coefficient_fun(t) result(p)
            import :: dp
            real(dp), intent(in) :: t
            real(dp) :: p
        end function hill_coefficient_fun
    end interface

    !> Hill's equation N'' + Phi(t) N = 0 as a first-order system y = [N, N'].
    !! Phi is either a procedure (`phi_fun`) or a real Fourier series (`a0`, `ak`, `bk`,
    !! period `period`) built from equally spaced samples by `fourier_coefficients`.
    type, extends(ode_system) :: hill_equation
        procedure(hill_coefficient_fun), pointer, nopass :: phi_fun => null()
        real(dp) :: period = 2.0_dp*pi
        real(dp) :: a0 = 0.0_dp
        real(dp), allocatable :: ak(:), bk(:)
    contains
        procedure :: rhs => hill_eq_rhs
        procedure :: jacobian => hill_eq_jac
        procedure :: has_jacobian => hill_eq_has_jac
        procedure :: coefficient => hill_eq_coef
    end type hill_equation

    !> Result of `hill_solve`.
    type :: hill_result
        integer :: info = CM_BAD_INPUT
        character(len=:), allocatable :: message
        real(dp) :: monodromy(2, 2) = 0.0_dp  !! [y1 y2] at T, y1 = (1, 0), y2 = (0, 1) at 0
        real(dp) :: half_trace = 0.0_dp       !! (M11 + M22)/2; stable iff |.| < 1
        real(dp) :: det = 0.0_dp              !! det M (1 up to integration error)
        real(dp) :: mr(2) = 0.0_dp, mi(2) = 0.0_dp  !! multipliers
        logical :: stable = .false.           !! |half_trace| < 1
        real(dp) :: rho = 0.0_dp              !! acos(half_trace)/(2 pi) if |.| <= 1, in [0, 1/2]
        integer :: nfev = 0
    end type hill_result

contains

    !> Multipliers (dgeev), exponents, trace, determinant and stability of a monodromy
    !! matrix m over the period t_period; `tol` (default 1e-6) for |mu| <= 1 + tol.
    subroutine floquet_analysis(m, t_period, res, tol)
        real(dp), intent(in) :: m(:, :)
        real(dp), intent(in) :: t_period
        type(floquet_result), intent(out) :: res
        real(dp), intent(in), optional :: tol
        integer :: n, i
        real(dp) :: tl
        tl = 1.0e-6_dp
        if (present(tol)) tl = tol
        n = size(m, 1)
        if (size(m, 2) /= n .or. n < 1 .or. .not. t_period > 0.0_dp) then
            res%info = CM_BAD_INPUT
            return
        end if
        allocate (res%mr(n), res%mi(n), res%abs_mult(n), res%exponents(n))
        call la_eig(m, res%mr, res%mi, res%info)
        if (res%info /= CM_SUCCESS) return
        res%trace = 0.0_dp
        do i = 1, n
            res%trace = res%trace + m(i, i)
        end do
        res%abs_mult = sqrt(res%mr**2 + res%mi**2)
        res%det = 1.0_dp
        call exponents_and_det(res, t_period, tl)
    end subroutine floquet_analysis

    !> The floquet_result of multipliers computed from the factors of the monodromy
    !! (conmech_periodic_multipliers): exponents, det (their product), trace (of the
    !! formed monodromy m) and stability with the tolerance max(1e-6, ten times the
    !! error estimate of the multipliers near the unit circle).
    subroutine floquet_from_multipliers(ms, m, t_period, res)
        type(multiplier_set), intent(in) :: ms
        real(dp), intent(in) :: m(:, :)
        real(dp), intent(in) :: t_period
        type(floquet_result), intent(out) :: res
        integer :: n, i
        res%info = ms%info
        if (ms%info /= CM_SUCCESS .or. .not. allocated(ms%mr)) return
        n = size(ms%mr)
        res%mr = ms%mr
        res%mi = ms%mi
        res%abs_mult = sqrt(res%mr**2 + res%mi**2)
        allocate (res%exponents(n))
        res%trace = 0.0_dp
        do i = 1, min(n, size(m, 1), size(m, 2))
            res%trace = res%trace + m(i, i)
        end do
        call exponents_and_det(res, t_period, unit_circle_tolerance(ms, 1.0e-6_dp))
    end subroutine floquet_from_multipliers

    !> From the multipliers mr + i mi (and |mu|, already in res) of a period t_period: the
    !! Floquet exponents log(mu)/T (-huge for mu = 0 or T <= 0), det M as their product,
    !! max |mu| and stability (max |mu| <= 1 + tol).
    subroutine exponents_and_det(res, t_period, tol)
        type(floquet_result), intent(inout) :: res
        real(dp), intent(in) :: t_period, tol
        complex(dp) :: mu
        integer :: i
        mu = (1.0_dp, 0.0_dp)
        do i = 1, size(res%mr)
            mu = mu*cmplx(res%mr(i), res%mi(i), dp)
            if (res%abs_mult(i) > 0.0_dp .and. t_period > 0.0_dp) then
                res%exponents(i) = log(cmplx(res%mr(i), res%mi(i), dp))/t_period
            else
                res%exponents(i) = cmplx(-huge(1.0_dp), 0.0_dp, dp)
            end if
        end do
        res%det = real(mu, dp)
        res%max_abs = maxval(res%abs_mult)
        res%stable = res%max_abs <= 1.0_dp + tol
    end subroutine exponents_and_det

    !> Trace-based stability index of a planar conservative periodic orbit (4 x 4 monodromy):
    !! S = (trace M - 2)/2; linearly stable iff |S| < 1.
    pure real(dp) function planar_stability_index(m) result(s)
        real(dp), intent(in) :: m(4, 4)
        s = 0.5_dp*(m(1, 1) + m(2, 2) + m(3, 3) + m(4, 4) - 2.0_dp)
    end function planar_stability_index

    ! ------------------------------------------------------------------- Hill's equation

    real(dp) function hill_eq_coef(self, t) result(p)
        class(hill_equation), intent(in) :: self
        real(dp), intent(in) :: t
        if (associated(self%phi_fun)) then
            p = self%phi_fun(t)
        else
            p = fourier_eval(self%a0, self%ak, self%bk, self%period, t)
        end if
    end function hill_eq_coef

    subroutine hill_eq_rhs(self, t, y, dydt)
        class(hill_equation), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        dydt(1) = y(2)
        dydt(2) = -self%coefficient(t)*y(1)
    end subroutine hill_eq_rhs

    subroutine hill_eq_jac(self, t, y, dfdy)
        class(hill_equation), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        dfdy(1, 1) = 0.0_dp
        dfdy(1, 2) = 1.0_dp
        dfdy(2, 1) = -self%coefficient(t)
        dfdy(2, 2) = 0.0_dp
    end subroutine hill_eq_jac

    logical function hill_eq_has_jac(self)
        class(hill_equation), intent(in) :: self
        hill_eq_has_jac = .true.
    end function hill_eq_has_jac

    !> Real Fourier coefficients of equally spaced samples p(j) = Phi(j T/ns), j = 0..ns-1:
    !! Phi(t) ~ a0 + sum_k ak cos(k w t) + bk sin(k w t), w = 2 pi/T, k = 1..ns/2 (the Nyquist
    !! term of an even ns is halved). Trigonometric interpolation: spectrally accurate
    !! for a smooth periodic coefficient.
    subroutine fourier_coefficients(p, a0, ak, bk)
        real(dp), intent(in) :: p(:)
        real(dp), intent(out) :: a0
        real(dp), allocatable, intent(out) :: ak(:), bk(:)
        integer :: ns, nk, k, j
        real(dp) :: th
        ns = size(p)
        nk = ns/2
        allocate (ak(nk), bk(nk))
        a0 = sum(p)/ns
        do k = 1, nk
            ak(k) = 0.0_dp
            bk(k) = 0.0_dp
            do j = 0, ns - 1
                th = 2.0_dp*pi*real(mod(k*j, ns), dp)/ns
                ak(k) = ak(k) + p(j + 1)*cos(th)
                bk(k) = bk(k) + p(j + 1)*sin(th)
            end do
            ak(k) = 2.0_dp*ak(k)/ns
            bk(k) = 2.0_dp*bk(k)/ns
            if (2*k == ns) then
                ak(k) = 0.5_dp*ak(k)
                bk(k) = 0.0_dp
            end if
        end do
    end subroutine fourier_coefficients

    !> Value at t of the Fourier series a0 + sum ak cos(k w t) + bk sin(k w t), w = 2 pi/T.
    pure real(dp) function fourier_eval(a0, ak, bk, period, t) result(p)
        real(dp), intent(in) :: a0, ak(:), bk(:), period, t
        real(dp) :: c1, s1, ck, sk, tmp
        integer :: k
        c1 = cos(2.0_dp*pi*t/period)
        s1 = sin(2.0_dp*pi*t/period)
        ck = 1.0_dp
        sk = 0.0_dp
        p = a0
        do k = 1, size(ak)
            tmp = ck*c1 - sk*s1
            sk = sk*c1 + ck*s1
            ck = tmp
            p = p + ak(k)*ck + bk(k)*sk
        end do
    end function fourier_eval

    !> Monodromy of Hill's equation N'' + Phi(t) N = 0 over one period T of Phi (a function).
    !! `rtol` (default 1e-12) is the integrator's tolerance (DOP853, atol = rtol).
    subroutine hill_solve(phi, period, res, rtol)
        procedure(hill_coefficient_fun) :: phi
        real(dp), intent(in) :: period
        type(hill_result), intent(out) :: res
        real(dp), intent(in), optional :: rtol
        type(hill_equation) :: eq
        eq%phi_fun => phi
        eq%period = period
        call hill_monodromy(eq, res, rtol)
    end subroutine hill_solve

    !> As `hill_solve` with Phi given by ns >= 3 equally spaced samples over one period
    !! (p(j) = Phi((j - 1) T/ns)), trigonometrically interpolated.
    subroutine hill_solve_samples(p, period, res, rtol)
        real(dp), intent(in) :: p(:)
        real(dp), intent(in) :: period
        type(hill_result), intent(out) :: res
        real(dp), intent(in), optional :: rtol
        type(hill_equation) :: eq
        if (size(p) < 3) then
            res%info = CM_BAD_INPUT
            res%message = "hill_solve_samples: need at least 3 samples"
            return
        end if
        eq%period = period
        call fourier_coefficients(p, eq%a0, eq%ak, eq%bk)
        call hill_monodromy(eq, res, rtol)
    end subroutine hill_solve_samples

    subroutine hill_monodromy(eq, res, rtol)
        type(hill_equation), intent(in) :: eq
        type(hill_result), intent(out) :: res
        real(dp), intent(in), optional :: rtol
        type(ode_options) :: opt
        type(ode_stats) :: st
        real(dp) :: y(2), phi(2, 2)
        character(len=:), allocatable :: msg
        if (.not. (eq%period > 0.0_dp)) then
            res%info = CM_BAD_INPUT
            res%message = "hill_solve: the period must be positive"
            return
        end if
        opt = tolerance_options(1.0e-12_dp, rtol)
        y = 0.0_dp
        phi = reshape([1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2])
        ! the state y = 0 is a solution: the STM alone is integrated (y stays 0)
        call integrate_stm(eq, 0.0_dp, eq%period, y, phi, opt, res%info, msg, st)
        res%message = msg
        res%nfev = st%nfev
        if (res%info < 0) return
        res%monodromy = phi
        res%half_trace = 0.5_dp*(phi(1, 1) + phi(2, 2))
        res%det = phi(1, 1)*phi(2, 2) - phi(1, 2)*phi(2, 1)
        res%stable = abs(res%half_trace) < 1.0_dp
        call multipliers_2x2(res%half_trace, res%det, res%mr, res%mi)
        res%rho = acos(max(-1.0_dp, min(1.0_dp, res%half_trace)))/(2.0_dp*pi)
        res%info = CM_SUCCESS
        res%message = "success"
    end subroutine hill_monodromy

    !> The two multipliers of a 2 x 2 monodromy from its half trace a and determinant d:
    !! the roots a +- sqrt(a^2 - d) of mu^2 - 2 a mu + d, real or a complex pair.
    pure subroutine multipliers_2x2(half_trace, det, mr, mi)
        real(dp), intent(in) :: half_trace, det
        real(dp), intent(out) :: mr(2), mi(2)
        real(dp) :: disc
        disc = half_trace**2 - det
        if (disc >= 0.0_dp) then
            mr = [half_trace + sqrt(disc), half_trace - sqrt(disc)]
            mi = 0.0_dp
        else
            mr = half_trace
            mi = [sqrt(-disc), -sqrt(-disc)]
        end if
    end subroutine multipliers_2x2

end module conmech_floquet
