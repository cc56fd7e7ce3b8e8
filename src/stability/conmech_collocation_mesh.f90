!> Mesh adaptation of a collocation solution by equidistribution, as in AUTO (Russell and
!! Christiansen 1978; Doedel's ADAPT): the error of degree-m collocation on an interval of
!! length h is ~ h^(m+1) |u^(m+1)|. The m-th derivative of the collocation polynomial is
!! constant on each interval; differences of it between neighbouring intervals estimate
!! u^(m+1) (over the mean of their lengths), and the new mesh equidistributes the integral
!! of |u^(m+1)|^(1/(m+1)) (the monitor, piecewise constant, with a floor of 1/20 of its
!! mean so that no interval grows without bound where the orbit is straight). The
!! solution is carried to the new mesh by evaluating the old collocation polynomials at the
!! new nodes and stages.
module conmech_collocation_mesh
    use conmech_kinds, only: dp
    use conmech_orbit_bvp, only: orbit_bvp, bvp_z
    use conmech_collocation, only: co_stage
    use conmech_collocation_tableau, only: gauss_tableau, lagrange_values, mth_derivative
    implicit none
    private

    public :: co_adapt, co_evaluate_polynomial, co_new_mesh, co_remesh

contains

    !> The collocation polynomial of X at s in [0, 1] (the interval containing s).
    pure function co_evaluate_polynomial(bvp, tab, x, s) result(y)
        type(orbit_bvp), intent(in) :: bvp
        type(gauss_tableau), intent(in) :: tab
        real(dp), intent(in) :: x(:), s
        real(dp) :: y(bvp%n)
        real(dp) :: lv(0:bvp%m), u
        integer :: j, i
        j = 1
        do while (j < bvp%k .and. s > bvp%mesh(j + 1))
            j = j + 1
        end do
        u = (s - bvp%mesh(j))/(bvp%mesh(j + 1) - bvp%mesh(j))
        call lagrange_values(tab, u, lv)
        y = lv(0)*bvp_z(bvp, x, j)
        do i = 1, bvp%m
            y = y + lv(i)*co_stage(bvp, x, j, i)
        end do
    end function co_evaluate_polynomial

    !> A new mesh equidistributing the error monitor of X (same number of intervals), and
    !! X carried over to it (bvp%mesh is replaced; xn has X's layout). `ratio`: the largest
    !! over the smallest monitor integral of an old interval (1 for an equidistributed
    !! mesh).
    subroutine co_adapt(bvp, tab, x, xn, ratio)
        type(orbit_bvp), intent(inout) :: bvp
        type(gauss_tableau), intent(in) :: tab
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: xn(:)
        real(dp), intent(out) :: ratio
        real(dp) :: newmesh(bvp%k + 1)
        call co_new_mesh(bvp, tab, x, newmesh, ratio)
        call co_remesh(bvp, tab, newmesh, x, xn)
        bvp%mesh = newmesh
    end subroutine co_adapt

    !> The mesh equidistributing the error monitor of X (see the module notes).
    subroutine co_new_mesh(bvp, tab, x, newmesh, ratio)
        type(orbit_bvp), intent(in) :: bvp
        type(gauss_tableau), intent(in) :: tab
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: newmesh(:)
        real(dp), intent(out) :: ratio
        real(dp) :: dm(bvp%n, bvp%k), del(bvp%k), phi(bvp%k), cum(0:bvp%k), yv(bvp%n, 0:bvp%m)
        real(dp) :: h(bvp%k), target, mean
        integer :: m, k, j, i, q
        m = bvp%m
        k = bvp%k
        newmesh = bvp%mesh
        ratio = 1.0_dp
        if (k < 3) return
        h = bvp%mesh(2:) - bvp%mesh(:k)
        do j = 1, k
            yv(:, 0) = bvp_z(bvp, x, j)
            do i = 1, m
                yv(:, i) = co_stage(bvp, x, j, i)
            end do
            dm(:, j) = mth_derivative(tab, yv)/h(j)**m
        end do
        ! del(j): the (m+1)-th derivative between intervals j and j+1 (cyclic if periodic)
        do j = 1, k - 1
            del(j) = 2.0_dp*maxval(abs(dm(:, j + 1) - dm(:, j)))/(h(j) + h(j + 1))
        end do
        del(k) = 2.0_dp*maxval(abs(dm(:, 1) - dm(:, k)))/(h(k) + h(1))
        do j = 1, k
            if (bvp%periodic) then
                phi(j) = 0.5_dp*(del(j) + del(merge(k, j - 1, j == 1)))
            else if (j == 1) then
                phi(j) = del(1)
            else if (j == k) then
                phi(j) = del(k - 1)
            else
                phi(j) = 0.5_dp*(del(j) + del(max(1, j - 1)))
            end if
        end do
        phi = phi**(1.0_dp/(m + 1))
        mean = sum(phi*h)
        if (.not. (mean > 0.0_dp)) return
        phi = max(phi, 0.05_dp*mean)
        cum(0) = 0.0_dp
        do j = 1, k
            cum(j) = cum(j - 1) + phi(j)*h(j)
        end do
        ratio = maxval(phi*h)/minval(phi*h)
        newmesh(1) = 0.0_dp
        newmesh(k + 1) = 1.0_dp
        j = 1
        do q = 1, k - 1
            target = cum(k)*real(q, dp)/k
            do while (cum(j) < target .and. j < k)
                j = j + 1
            end do
            newmesh(q + 1) = bvp%mesh(j) + (target - cum(j - 1))/phi(j)
        end do
    end subroutine co_new_mesh

    !> v (nodes, stages and border values of X's layout on bvp%mesh) carried to newmesh
    !! by evaluating its collocation polynomials (linear in v: solutions and tangents
    !! alike); the border values are copied.
    subroutine co_remesh(bvp, tab, newmesh, v, vn)
        type(orbit_bvp), intent(in) :: bvp
        type(gauss_tableau), intent(in) :: tab
        real(dp), intent(in) :: newmesh(:), v(:)
        real(dp), intent(out) :: vn(:)
        real(dp) :: s
        integer :: n, m, k, j, i, o
        n = bvp%n
        m = bvp%m
        k = bvp%k
        vn = v
        do j = 1, k
            o = (j - 1)*n
            vn(o + 1:o + n) = co_evaluate_polynomial(bvp, tab, v, newmesh(j))
            do i = 1, m
                s = newmesh(j) + tab%c(i)*(newmesh(j + 1) - newmesh(j))
                o = n*(k + 1) + ((j - 1)*m + (i - 1))*n
                vn(o + 1:o + n) = co_evaluate_polynomial(bvp, tab, v, s)
            end do
        end do
        vn(k*n + 1:(k + 1)*n) = bvp_z(bvp, v, k + 1)
    end subroutine co_remesh

end module conmech_collocation_mesh
