!> Dense output of the integrators: the continuous extension of one step (`interp`,
!! Hairer's form or the power basis), the piecewise polynomial of a whole integration
!! (`dense_solution`, one polynomial per accepted step), and the power-basis coefficients
!! of a collocation polynomial from its values at the nodes (`power_basis_matrix`).
module conmech_ode_dense
    use conmech_kinds, only: dp
    implicit none
    private

    integer, parameter, public :: FORM_HAIRER = 1   !! y0 + x (F1 + (1-x)(F2 + x (F3 + ...)))
    integer, parameter, public :: FORM_POWER = 2    !! y0 + x F1 + x^2 F2 + ... + x^nf F_nf

    public :: dense_solution, interp, dense_init, dense_push, power_basis_matrix

    !> Piecewise polynomial dense output, Hairer's form on each step [t0, t0 + h]:
    !! y(t0 + x h) = y0 + x (F1 + (1-x)(F2 + x (F3 + (1-x)(F4 + ...)))).
    type :: dense_solution
        integer :: n = 0            !! dimension
        integer :: nseg = 0         !! number of steps stored
        integer :: nf = 0           !! number of F coefficients (3 RK4, 4 DOPRI5, 7 DOP853,
                                    !! 8 VERNER98)
        integer :: form = FORM_HAIRER   !! polynomial form of the coefficients
        real(dp) :: t_first = 0.0_dp, t_last = 0.0_dp
        real(dp), allocatable :: ts(:), hs(:)      !! step start and signed length
        real(dp), allocatable :: coef(:, :, :)     !! (n, 0:nf, nseg); coef(:,0,:) = y0
    contains
        procedure :: eval => dense_eval
        procedure :: eval_many => dense_eval_many
    end type dense_solution

contains

    !> Matrix P (s x s) of the interpolation in the power basis through the origin: the
    !! polynomial u with u(0) = 0 and u(c_i) = z_i is u(x) = sum_j x^j sum_i P(j, i) z_i
    !! (expanded Lagrange basis x/c_i prod_{k /= i} (x - c_k)/(c_i - c_k); nodes distinct
    !! and non-zero).
    pure function power_basis_matrix(c) result(p)
        real(dp), intent(in) :: c(:)
        real(dp) :: p(size(c), size(c))
        real(dp) :: poly(0:size(c)), den
        integer :: i, k, j, s
        s = size(c)
        do i = 1, s
            ! poly = x * prod_{k /= i} (x - c_k), coefficients of x^0..x^s
            poly = 0.0_dp
            poly(1) = 1.0_dp
            den = c(i)
            do k = 1, s
                if (k == i) cycle
                do j = s, 1, -1
                    poly(j) = poly(j - 1) - c(k)*poly(j)
                end do
                poly(0) = -c(k)*poly(0)
                den = den*(c(i) - c(k))
            end do
            p(:, i) = poly(1:s)/den
        end do
    end function power_basis_matrix

    !> Continuous extension at x = (t - t0)/h: Hairer's form
    !! y0 + x (F1 + (1-x)(F2 + x (F3 + ...))) or the power form y0 + sum_j x^j F_j.
    pure subroutine interp(fc, form, x, yout)
        real(dp), intent(in) :: fc(:, 0:)
        integer, intent(in) :: form
        real(dp), intent(in) :: x
        real(dp), intent(out) :: yout(:)
        integer :: j, nf
        real(dp) :: x1
        nf = ubound(fc, 2)
        if (form == FORM_POWER) then
            yout = fc(:, nf)
            do j = nf - 1, 1, -1
                yout = fc(:, j) + x*yout
            end do
            yout = fc(:, 0) + x*yout
            return
        end if
        x1 = 1.0_dp - x
        yout = fc(:, nf)
        do j = nf - 1, 1, -1
            if (mod(j, 2) == 1) then
                yout = fc(:, j) + x1*yout
            else
                yout = fc(:, j) + x*yout
            end if
        end do
        yout = fc(:, 0) + x*yout
    end subroutine interp

    subroutine dense_init(sol, n, nf, form, t0)
        type(dense_solution), intent(out) :: sol
        integer, intent(in) :: n, nf, form
        real(dp), intent(in) :: t0
        sol%n = n
        sol%nf = nf
        sol%form = form
        sol%nseg = 0
        sol%t_first = t0
        sol%t_last = t0
        allocate (sol%ts(16), sol%hs(16), sol%coef(n, 0:nf, 16))
    end subroutine dense_init

    subroutine dense_push(sol, t, h, fc, t_end)
        type(dense_solution), intent(inout) :: sol
        real(dp), intent(in) :: t, h, fc(:, 0:), t_end
        real(dp), allocatable :: ts(:), hs(:), cc(:, :, :)
        integer :: cap
        cap = size(sol%ts)
        if (sol%nseg >= cap) then
            cap = 2*cap
            allocate (ts(cap), hs(cap), cc(sol%n, 0:sol%nf, cap))
            ts(1:sol%nseg) = sol%ts(1:sol%nseg)
            hs(1:sol%nseg) = sol%hs(1:sol%nseg)
            cc(:, :, 1:sol%nseg) = sol%coef(:, :, 1:sol%nseg)
            call move_alloc(ts, sol%ts)
            call move_alloc(hs, sol%hs)
            call move_alloc(cc, sol%coef)
        end if
        sol%nseg = sol%nseg + 1
        sol%ts(sol%nseg) = t
        sol%hs(sol%nseg) = h
        sol%coef(:, :, sol%nseg) = fc
        sol%t_last = t_end
    end subroutine dense_push

    !> Evaluate the dense output at t (extrapolates from the end steps outside the range).
    subroutine dense_eval(self, t, y)
        class(dense_solution), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(out) :: y(:)
        integer :: lo, hi, mid
        real(dp) :: dir
        if (self%nseg == 0) then
            y = 0.0_dp
            return
        end if
        dir = sign(1.0_dp, self%hs(1))
        lo = 1
        hi = self%nseg
        ! last segment whose start is <= t (in the direction of integration)
        do while (lo < hi)
            mid = (lo + hi + 1)/2
            if ((t - self%ts(mid))*dir >= 0.0_dp) then
                lo = mid
            else
                hi = mid - 1
            end if
        end do
        call interp(self%coef(:, :, lo), self%form, (t - self%ts(lo))/self%hs(lo), y)
    end subroutine dense_eval

    !> Evaluate the dense output at many times: y(:, i) at t(i).
    subroutine dense_eval_many(self, t, y)
        class(dense_solution), intent(in) :: self
        real(dp), intent(in) :: t(:)
        real(dp), intent(out) :: y(:, :)
        integer :: i
        do i = 1, size(t)
            call self%eval(t(i), y(:, i))
        end do
    end subroutine dense_eval_many

end module conmech_ode_dense
