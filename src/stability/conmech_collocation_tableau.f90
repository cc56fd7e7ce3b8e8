!> Gauss-Legendre collocation of degree m on [0, 1]: the nodes c_i (zeros of the shifted
!! Legendre polynomial P_m(2s - 1)), the weights b_i and the integrals
!! a_il = int_0^c_i L_l(s) ds of the Lagrange basis on the nodes, i.e. the m-stage
!! Gauss-Legendre Runge-Kutta method (collocation at Gauss points: the piecewise
!! polynomial of degree m, continuous at the mesh points, superconvergent of order 2m
!! there). The nodes and weights come from the Golub-Welsch eigenproblem of the Jacobi
!! matrix of the Legendre recurrence (LAPACK dsyev); a_il by m-point Gauss quadrature on
!! [0, c_i] (exact: L_l has degree m - 1). Also the Lagrange tools on the nodes
!! (0, c_1, .., c_m) of one interval: values and the m-th derivative of the interpolant.
module conmech_collocation_tableau
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_lapack, only: la_sym_eig
    implicit none
    private

    public :: gauss_tableau, gauss_collocation, lagrange_values, mth_derivative

    !> The m-stage Gauss-Legendre collocation tableau.
    type :: gauss_tableau
        integer :: m = 0
        real(dp), allocatable :: c(:), b(:), a(:, :)
    end type gauss_tableau

contains

    !> The tableau of degree m (1 <= m <= 8); info CM_BAD_INPUT otherwise.
    subroutine gauss_collocation(m, tab, info)
        integer, intent(in) :: m
        type(gauss_tableau), intent(out) :: tab
        integer, intent(out) :: info
        real(dp) :: jm(m, m), v(m, m), w(m), lq(m)
        integer :: i, l, q
        if (m < 1 .or. m > 8) then
            info = CM_BAD_INPUT
            return
        end if
        jm = 0.0_dp
        do i = 1, m - 1
            jm(i, i + 1) = real(i, dp)/sqrt(4.0_dp*i*i - 1.0_dp)
            jm(i + 1, i) = jm(i, i + 1)
        end do
        call la_sym_eig(jm, w, info, v)
        if (info /= CM_SUCCESS) return
        tab%m = m
        tab%c = 0.5_dp*(w + 1.0_dp)
        tab%b = v(1, :)**2
        allocate (tab%a(m, m))
        do i = 1, m
            do l = 1, m
                tab%a(i, l) = 0.0_dp
                do q = 1, m
                    call lagrange_on(tab%c, tab%c(i)*tab%c(q), lq)
                    tab%a(i, l) = tab%a(i, l) + tab%b(q)*lq(l)
                end do
                tab%a(i, l) = tab%c(i)*tab%a(i, l)
            end do
        end do
        info = CM_SUCCESS
    end subroutine gauss_collocation

    !> Lagrange basis values L_j(u) on the nodes x.
    pure subroutine lagrange_on(x, u, lv)
        real(dp), intent(in) :: x(:), u
        real(dp), intent(out) :: lv(:)
        integer :: j, i
        do j = 1, size(x)
            lv(j) = 1.0_dp
            do i = 1, size(x)
                if (i /= j) lv(j) = lv(j)*(u - x(i))/(x(j) - x(i))
            end do
        end do
    end subroutine lagrange_on

    !> Values at u in [0, 1] of the Lagrange basis on the interval's nodes (0, c_1..c_m).
    pure subroutine lagrange_values(tab, u, lv)
        type(gauss_tableau), intent(in) :: tab
        real(dp), intent(in) :: u
        real(dp), intent(out) :: lv(0:)
        call lagrange_on([0.0_dp, tab%c], u, lv)
    end subroutine lagrange_values

    !> The m-th derivative (in the local variable u) of the degree-m interpolant of the
    !! values y(:, 0:m) at (0, c_1..c_m): m! times the leading divided difference.
    pure function mth_derivative(tab, y) result(dm)
        type(gauss_tableau), intent(in) :: tab
        real(dp), intent(in) :: y(:, 0:)
        real(dp) :: dm(size(y, 1))
        real(dp) :: x(0:tab%m), den, fact
        integer :: j, i
        x(0) = 0.0_dp
        x(1:) = tab%c
        fact = 1.0_dp
        do j = 2, tab%m
            fact = fact*j
        end do
        dm = 0.0_dp
        do j = 0, tab%m
            den = 1.0_dp
            do i = 0, tab%m
                if (i /= j) den = den*(x(j) - x(i))
            end do
            dm = dm + y(:, j)/den
        end do
        dm = fact*dm
    end function mth_derivative

end module conmech_collocation_tableau
