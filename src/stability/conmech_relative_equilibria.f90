!> Linearisation of an equilibrium relative to first integrals and to a family of
!! equilibria (the reduced linearisation, without deriving the reduced system).
!!
!! At an equilibrium y of y' = f(y) with first integrals I_1 .. I_k, the gradients
!! D = [dI_i(y)] satisfy D A = 0 (A = df/dy): the linear flow keeps each dI_i . dy fixed, so
!! V = ker D is invariant under A. A family of equilibria through y (a cyclic coordinate's
!! translation, a symmetry orbit) with tangent K (A K = 0, K in V) is neutral. The
!! linearisation relative to the integrals is the map A induces on V / span K: with W an
!! orthonormal basis of V orthogonal to K (the null space of [D; K^T], LAPACK's SVD),
!!
!!     A_r = W^T A W     (dimension n - rank [D; K^T]).
!!
!! For a Lagrangian system with a cyclic coordinate and its momentum as the integral this
!! is the linearisation of the Routh-reduced dynamics at the same point: the cart of the
!! lecture notes at theta = pi gives z'' + 2 g z = 0, a centre, while the full linearisation
!! has the Jordan block of the cart's drift.
module conmech_relative_equilibria
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_rank, only: null_space
    implicit none
    private

    public :: relative_linearization

contains

    !> A_r = W^T A W on the tangent of the integrals' level set modulo the family (see the
    !! module notes). grads(k, n): the integrals' gradients at y (rows; a zero row, e.g. the
    !! energy's at an equilibrium, adds nothing); family(n, d): the family's tangent. Each
    !! nonzero gradient row must satisfy |dI A| <= check_tol |dI| max(1, |A|), else
    !! CM_BAD_INPUT (that function is not conserved by the linearisation). Returns
    !! ar(1:m, 1:m) and the basis w(:, 1:m) (ar, w: at least n x n).
    subroutine relative_linearization(a, grads, family, ar, w, m, info, message, check_tol)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(in) :: grads(:, :)
        real(dp), intent(in) :: family(:, :)
        real(dp), intent(out) :: ar(:, :)
        real(dp), intent(out) :: w(:, :)
        integer, intent(out) :: m
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: message
        real(dp), intent(in), optional :: check_tol   !! default 1e-6
        real(dp), allocatable :: c(:, :), basis(:, :)
        real(dp) :: ct, gmax, g, amax, res
        integer :: n, k, d, i, nr
        character(len=64) :: buf
        n = size(a, 1)
        k = size(grads, 1)
        d = size(family, 2)
        m = 0
        ar = 0.0_dp
        w = 0.0_dp
        ct = 1.0e-6_dp
        if (present(check_tol)) ct = check_tol
        if (size(a, 2) /= n .or. size(grads, 2) /= n .or. size(family, 1) /= n .or. &
            size(ar, 1) < n .or. size(ar, 2) < n .or. size(w, 1) /= n .or. &
            size(w, 2) < n) then
            info = CM_BAD_INPUT
            message = "relative_linearization: inconsistent dimensions"
            return
        end if
        amax = max(1.0_dp, maxval(abs(a)))
        gmax = 0.0_dp
        do i = 1, k
            gmax = max(gmax, norm2(grads(i, :)))
        end do
        allocate (c(k + d, n), basis(n, n))
        nr = 0
        do i = 1, k
            g = norm2(grads(i, :))
            if (g <= 1.0e-12_dp*max(1.0_dp, gmax)) cycle
            res = maxval(abs(matmul(grads(i, :), a)))
            if (res > ct*g*amax) then
                write (buf, "(i0, a, es10.3)") i, ": |dI A|/(|dI| |A|) = ", res/(g*amax)
                info = CM_BAD_INPUT
                message = "relative_linearization: the linearisation does not conserve "// &
                          "integral "//trim(buf)
                return
            end if
            nr = nr + 1
            c(nr, :) = grads(i, :)/g
        end do
        do i = 1, d
            nr = nr + 1
            c(nr, :) = family(:, i)/max(norm2(family(:, i)), tiny(1.0_dp))
        end do
        if (nr == 0) then
            m = n
            ar(1:n, 1:n) = a
            do i = 1, n
                w(i, i) = 1.0_dp
            end do
            info = CM_SUCCESS
            message = "success"
            return
        end if
        call null_space(c(1:nr, :), 1.0e-8_dp, basis, m, info)
        if (info /= CM_SUCCESS) then
            message = "relative_linearization: SVD failed"
            return
        end if
        w(:, 1:m) = basis(:, 1:m)
        ar(1:m, 1:m) = matmul(transpose(basis(:, 1:m)), matmul(a, basis(:, 1:m)))
        message = "success"
    end subroutine relative_linearization

end module conmech_relative_equilibria
