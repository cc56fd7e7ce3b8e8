!> Virtual holonomic constraints of an underactuated mechanical system with one passive
!! degree of freedom (n coordinates, m = n - 1 inputs, M q'' = Q + B u), their reduced
!! dynamics and the feedback that keeps them (Shiriaev, Perram, Canudas-de-Wit, IEEE TAC
!! 50(8), 2005).
!!
!! The constraint: one coordinate is the phase, theta = q_ip; the others follow
!! q_o(i) = Phi_i(theta), i = 1..n-1, with Phi_i a polynomial in theta, a Chebyshev series
!! on [a, b], or a trigonometric polynomial a_0 + sum_j (a_j cos j theta + b_j sin j theta).
!! Phibar(theta) is the full vector (theta at ip).
!!
!! Reduced dynamics: with B_perp a row annihilating B (B_perp B = 0; the generalized
!! cross product of B's columns, normalised, sign fixed at a reference point so that its
!! largest entry is positive: for B = the columns e_i of the actuated coordinates it is
!! e_passive), along the constraint
!!
!!     alpha(theta) theta'' + beta(theta) theta'^2 + gamma(theta) = 0,
!!     alpha = B_perp M Phibar',  beta = B_perp (M Phibar'' - (Q(Phibar, Phibar') - Q0)),
!!     gamma = -B_perp Q0,  Q0 = Q(Phibar, 0),
!!
!! which needs Q - Q0 quadratic in the velocities (no damping or gyroscopic terms; checked).
!! E = theta'^2 as a function of theta obeys the linear equation
!! dE/dtheta = -2 (beta E + gamma)/alpha: the integral of the reduced dynamics
!! I = theta'^2 - E(theta; theta_0, theta_0'^2) is E's solution through (theta_0, theta_0').
!!
!! The feedback (partial feedback linearisation, computed torque on the actuated side):
!! the outputs y = q_o - Phi(theta) obey y'' = L M^-1 (Q + B u) - Phi'' theta'^2,
!! L = [I_(n-1) on o, -Phi' on ip]; u = D^-1 (v - L M^-1 Q + Phi'' theta'^2) with the
!! decoupling matrix D = L M^-1 B makes y'' = v = -kp y - kd y' (+ the law's extra input).
!! D is invertible where the constraint is regular (alpha /= 0).
module conmech_vhc
    use conmech_kinds, only: dp, nan_dp
    use conmech_status
    use conmech_lapack, only: la_solve, la_det, dpotrs
    use conmech_ode_system, only: ode_system
    use conmech_generalized, only: mass_cholesky
    use conmech_control_system, only: feedback_law
    use conmech_mech_plant, only: mech_plant
    implicit none
    private
    public :: vhc, vhc_eval, vhc_coefficients, vhc_reduced, vhc_energy, vhc_law
    public :: vhc_annihilator, VHC_POLY, VHC_CHEBYSHEV, VHC_FOURIER

    integer, parameter :: VHC_POLY = 1        !! sum_j c_j theta^j, j = 0..ncoef-1
    integer, parameter :: VHC_CHEBYSHEV = 2   !! sum_j c_j T_j(s), s = (2 theta - a - b)/(b - a)
    integer, parameter :: VHC_FOURIER = 3     !! c_1 + sum_j c_2j cos j theta + c_2j+1 sin j theta

    !> A virtual holonomic constraint (see the module notes).
    type :: vhc
        integer :: n = 0                  !! coordinates
        integer :: ip = 1                 !! the phase coordinate
        integer :: kind = VHC_POLY
        integer :: ncoef = 0
        real(dp) :: a = -1.0_dp, b = 1.0_dp   !! Chebyshev interval
        real(dp), allocatable :: c(:, :)  !! (n - 1, ncoef) coefficients
        real(dp) :: sgn = 1.0_dp          !! sign of B_perp (fixed at a reference point)
    end type vhc

    !> The reduced dynamics as a first-order system y = [theta, theta'].
    type, extends(ode_system) :: vhc_reduced
        type(mech_plant) :: plant
        type(vhc) :: con
    contains
        procedure :: rhs => red_rhs
    end type vhc_reduced

    !> dE/dtheta = -2 (beta E + gamma)/alpha, with theta as the independent variable.
    type, extends(ode_system) :: vhc_energy
        type(mech_plant) :: plant
        type(vhc) :: con
    contains
        procedure :: rhs => en_rhs
    end type vhc_energy

    !> The constraint-keeping feedback (partial feedback linearisation).
    type, extends(feedback_law) :: vhc_law
        type(mech_plant) :: plant
        type(vhc) :: con
        real(dp), allocatable :: kp(:), kd(:)   !! (n - 1) output gains
    contains
        procedure :: eval => law_eval
    end type vhc_law

contains

    !> Phibar, Phibar', Phibar'' (n-vectors) at theta.
    pure subroutine vhc_eval(con, theta, phi, dphi, ddphi)
        type(vhc), intent(in) :: con
        real(dp), intent(in) :: theta
        real(dp), intent(out) :: phi(:), dphi(:), ddphi(:)
        real(dp) :: v(con%ncoef), d1(con%ncoef), d2(con%ncoef), s, ds
        integer :: j, i, o, k
        select case (con%kind)
        case (VHC_POLY)
            do j = 1, con%ncoef
                k = j - 1
                v(j) = theta**k
                d1(j) = 0.0_dp
                d2(j) = 0.0_dp
                if (k >= 1) d1(j) = k*theta**(k - 1)
                if (k >= 2) d2(j) = k*(k - 1)*theta**(k - 2)
            end do
        case (VHC_CHEBYSHEV)
            ds = 2.0_dp/(con%b - con%a)
            s = (2.0_dp*theta - con%a - con%b)/(con%b - con%a)
            v(1) = 1.0_dp
            d1(1) = 0.0_dp
            d2(1) = 0.0_dp
            if (con%ncoef >= 2) then
                v(2) = s
                d1(2) = 1.0_dp
                d2(2) = 0.0_dp
            end if
            do j = 3, con%ncoef
                v(j) = 2.0_dp*s*v(j - 1) - v(j - 2)
                d1(j) = 2.0_dp*v(j - 1) + 2.0_dp*s*d1(j - 1) - d1(j - 2)
                d2(j) = 4.0_dp*d1(j - 1) + 2.0_dp*s*d2(j - 1) - d2(j - 2)
            end do
            d1 = d1*ds
            d2 = d2*ds**2
        case default   ! VHC_FOURIER
            v(1) = 1.0_dp
            d1(1) = 0.0_dp
            d2(1) = 0.0_dp
            do j = 1, (con%ncoef - 1)/2
                v(2*j) = cos(j*theta)
                v(2*j + 1) = sin(j*theta)
                d1(2*j) = -j*v(2*j + 1)
                d1(2*j + 1) = j*v(2*j)
                d2(2*j) = -j*j*v(2*j)
                d2(2*j + 1) = -j*j*v(2*j + 1)
            end do
        end select
        phi(con%ip) = theta
        dphi(con%ip) = 1.0_dp
        ddphi(con%ip) = 0.0_dp
        o = 0
        do i = 1, con%n
            if (i == con%ip) cycle
            o = o + 1
            phi(i) = dot_product(con%c(o, :), v)
            dphi(i) = dot_product(con%c(o, :), d1)
            ddphi(i) = dot_product(con%c(o, :), d2)
        end do
    end subroutine vhc_eval

    !> The unit row annihilating bq (n x (n-1)): the generalized cross product of its
    !! columns (cofactors), continuous in bq, times `sgn`.
    subroutine vhc_annihilator(bq, sgn, bp)
        real(dp), intent(in) :: bq(:, :), sgn
        real(dp), intent(out) :: bp(:)
        real(dp) :: minor(size(bq, 1) - 1, size(bq, 1) - 1)
        integer :: n, i
        n = size(bq, 1)
        if (n == 1) then
            bp = 1.0_dp
            return
        end if
        do i = 1, n
            minor(1:i - 1, :) = bq(1:i - 1, :)
            minor(i:n - 1, :) = bq(i + 1:n, :)
            bp(i) = la_det(minor)*merge(1.0_dp, -1.0_dp, mod(i, 2) == 1)
        end do
        bp = sgn*bp/max(norm2(bp), tiny(1.0_dp))
    end subroutine vhc_annihilator

    !> alpha, beta, gamma at theta. info = CM_BAD_INPUT if Q - Q0 is not quadratic in
    !! the velocities (relative defect above 1e-8), CM_SINGULAR for a mass matrix that is
    !! not positive definite.
    subroutine vhc_coefficients(plant, con, theta, alpha, beta, gamma, info)
        type(mech_plant), intent(in) :: plant
        type(vhc), intent(in) :: con
        real(dp), intent(in) :: theta
        real(dp), intent(out) :: alpha, beta, gamma
        integer, intent(out) :: info
        real(dp) :: q(con%n), dq(con%n), ddq(con%n), mm(con%n, con%n), q0(con%n)
        real(dp) :: q1(con%n), q2(con%n), zero(con%n), bq(con%n, plant%n_inputs), bp(con%n)
        real(dp) :: scale
        call vhc_eval(con, theta, q, dq, ddq)
        zero = 0.0_dp
        call plant%mech%mass(0.0_dp, q, mm)
        call plant%mech%forces(0.0_dp, q, zero, q0)
        call plant%mech%forces(0.0_dp, q, dq, q1)
        call plant%mech%forces(0.0_dp, q, 2.0_dp*dq, q2)
        call plant%inputs(0.0_dp, q, bq)
        call vhc_annihilator(bq, con%sgn, bp)
        alpha = dot_product(bp, matmul(mm, dq))
        beta = dot_product(bp, matmul(mm, ddq) - (q1 - q0))
        gamma = -dot_product(bp, q0)
        scale = max(maxval(abs(q2 - q0)), maxval(abs(q0)), 1.0e-300_dp)
        info = CM_SUCCESS
        if (maxval(abs((q2 - q0) - 4.0_dp*(q1 - q0))) > 1.0e-8_dp*scale) info = CM_BAD_INPUT
    end subroutine vhc_coefficients

    subroutine red_rhs(self, t, y, dydt)
        class(vhc_reduced), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: al, be, ga
        integer :: info
        call vhc_coefficients(self%plant, self%con, y(1), al, be, ga, info)
        dydt(1) = y(2)
        dydt(2) = -(be*y(2)**2 + ga)/al
    end subroutine red_rhs

    subroutine en_rhs(self, t, y, dydt)
        class(vhc_energy), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: al, be, ga
        integer :: info
        call vhc_coefficients(self%plant, self%con, t, al, be, ga, info)
        dydt(1) = -2.0_dp*(be*y(1) + ga)/al
    end subroutine en_rhs

    !> u = D^-1 (v - L M^-1 Q + Phi'' theta'^2), v = -kp y - kd y' (see the module notes).
    subroutine law_eval(self, t, x, u)
        class(vhc_law), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: u(:)
        real(dp) :: phi(self%con%n), dphi(self%con%n), ddphi(self%con%n)
        real(dp) :: mm(self%con%n, self%con%n), z(self%con%n, 1 + self%n_inputs)
        real(dp) :: lz(self%con%n - 1, 1 + self%n_inputs), rhs(self%con%n - 1, 1)
        real(dp) :: sol(self%con%n - 1, 1), y, yd, th, thd
        integer :: n, nd, i, o, info
        n = self%con%n
        nd = n
        th = x(self%con%ip)
        thd = x(nd + self%con%ip)
        call vhc_eval(self%con, th, phi, dphi, ddphi)
        call self%plant%mech%mass_forces(t, x(1:nd), x(nd + 1:2*nd), mm, z(:, 1))
        call self%plant%inputs(t, x(1:nd), z(:, 2:))
        call mass_cholesky(mm, info)
        if (info /= CM_SUCCESS) then
            u = nan_dp
            return
        end if
        call dpotrs('U', nd, 1 + self%n_inputs, mm, nd, z, nd, info)
        o = 0
        do i = 1, n
            if (i == self%con%ip) cycle
            o = o + 1
            lz(o, :) = z(i, :) - dphi(i)*z(self%con%ip, :)
            y = x(i) - phi(i)
            yd = x(nd + i) - dphi(i)*thd
            rhs(o, 1) = -self%kp(o)*y - self%kd(o)*yd - lz(o, 1) + ddphi(i)*thd**2
        end do
        call la_solve(lz(:, 2:), rhs, sol, info, rcond_min=1.0e-13_dp)
        if (info /= CM_SUCCESS) then
            u = nan_dp
            return
        end if
        u = sol(:, 1)
    end subroutine law_eval

end module conmech_vhc
