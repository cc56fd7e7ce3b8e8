!> Logarithm and real powers of a rotation (an orthogonal matrix with determinant +1).
!!
!! A rotation R in SO(k) is normal, so its real Schur form (LAPACK dgees) is block
!! diagonal: 2 x 2 blocks cos(theta) I + sin(theta) K with K = +-[0 -1; 1 0], 1 x 1 blocks
!! +1, and an even number of 1 x 1 blocks -1, paired into rotations by pi in the plane of
!! their Schur vectors. With Z the Schur vectors and Z_j the two columns of plane j,
!!
!!     log R = sum_j theta_j Z_j K_j Z_j^T          (real, skew-symmetric)
!!     R^s   = I + sum_j Z_j ((cos(s theta_j) - 1) I + sin(s theta_j) K_j) Z_j^T
!!
!! for any real s. The transverse construction uses R^(-t/T) to turn a frame transported
!! along a periodic orbit, which returns rotated by R after one period, into a periodic one.
module conmech_rotation_log
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_lapack, only: dgees, dgesvd, la_finite
    implicit none
    private
    public :: rotation_log, rotation_log_init, nearest_rotation

    !> The planes and angles of a rotation (see the module notes).
    type :: rotation_log
        integer :: k = 0                        !! order of the rotation
        integer :: nplane = 0                   !! number of rotation planes
        real(dp), allocatable :: z(:, :)        !! (k, k) orthonormal Schur vectors
        integer, allocatable :: plane(:, :)     !! (2, nplane) columns of z spanning plane j
        real(dp), allocatable :: sgn(:)         !! (nplane) K_j = sgn_j [0 -1; 1 0]
        real(dp), allocatable :: angle(:)       !! (nplane) theta_j in (0, pi]
    contains
        procedure :: power => rl_power
        procedure :: generator => rl_generator
    end type rotation_log

contains

    !> Any eigenvalue selection (dgees needs one even without sorting).
    logical function select_none(wr, wi)
        real(dp), intent(in) :: wr, wi
        select_none = .false.
    end function select_none

    !> The orthogonal matrix nearest to a (Frobenius norm): U V^T from the SVD a = U S V^T.
    !! `defect` = max |S - 1| (how far a was from orthogonal), `det_sign` = sign of det a.
    subroutine nearest_rotation(a, r, defect, det_sign, info)
        real(dp), intent(in) :: a(:, :)
        real(dp), intent(out) :: r(:, :)
        real(dp), intent(out) :: defect, det_sign
        integer, intent(out) :: info
        real(dp), allocatable :: w(:, :), u(:, :), vt(:, :), s(:), work(:)
        real(dp) :: wq(1), du, dv
        integer :: k, lwork, lainfo
        k = size(a, 1)
        defect = huge(1.0_dp)
        det_sign = 0.0_dp
        if (.not. la_finite(a)) then
            info = CM_NONFINITE
            return
        end if
        allocate (w(k, k), u(k, k), vt(k, k), s(k))
        w = a
        call dgesvd('A', 'A', k, k, w, k, s, u, k, vt, k, wq, -1, lainfo)
        lwork = max(1, int(wq(1)))
        allocate (work(lwork))
        call dgesvd('A', 'A', k, k, w, k, s, u, k, vt, k, work, lwork, lainfo)
        if (lainfo /= 0) then
            info = CM_NO_CONVERGENCE
            return
        end if
        r = matmul(u, vt)
        defect = maxval(abs(s - 1.0_dp))
        du = det_orthogonal(u)
        dv = det_orthogonal(vt)
        det_sign = sign(1.0_dp, du*dv)
        info = CM_SUCCESS
    end subroutine nearest_rotation

    !> Determinant (+-1) of an orthogonal matrix, from its real Schur form.
    real(dp) function det_orthogonal(q) result(d)
        real(dp), intent(in) :: q(:, :)
        real(dp), allocatable :: a(:, :), z(:, :), wr(:), wi(:), work(:)
        logical, allocatable :: bwork(:)
        real(dp) :: wq(1)
        integer :: k, sdim, lwork, lainfo, i
        k = size(q, 1)
        allocate (a(k, k), z(1, 1), wr(k), wi(k), bwork(k))
        a = q
        call dgees('N', 'N', select_none, k, a, k, sdim, wr, wi, z, 1, wq, -1, bwork, lainfo)
        lwork = max(1, int(wq(1)))
        allocate (work(lwork))
        call dgees('N', 'N', select_none, k, a, k, sdim, wr, wi, z, 1, work, lwork, bwork, &
                   lainfo)
        d = 1.0_dp
        do i = 1, k
            if (wi(i) == 0.0_dp .and. wr(i) < 0.0_dp) d = -d
        end do
    end function det_orthogonal

    !> The planes and angles of the rotation r (orthogonal to round-off, det +1).
    !! CM_BAD_INPUT if r has determinant -1 (an odd number of eigenvalues -1).
    subroutine rotation_log_init(r, rl, info, message)
        real(dp), intent(in) :: r(:, :)
        type(rotation_log), intent(out) :: rl
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: message
        real(dp), allocatable :: a(:, :), wr(:), wi(:), work(:)
        logical, allocatable :: bwork(:)
        integer, allocatable :: neg(:)
        real(dp) :: wq(1), av, om
        integer :: k, sdim, lwork, lainfo, i, nneg
        k = size(r, 1)
        rl%k = k
        allocate (a(k, k), wr(k), wi(k), bwork(k), neg(k), rl%z(k, k))
        allocate (rl%plane(2, k/2 + 1), rl%sgn(k/2 + 1), rl%angle(k/2 + 1))
        rl%nplane = 0
        if (k == 0) then
            info = CM_SUCCESS
            message = "success"
            return
        end if
        if (.not. la_finite(r)) then
            info = CM_NONFINITE
            message = "rotation_log: non-finite entries"
            return
        end if
        a = r
        call dgees('V', 'N', select_none, k, a, k, sdim, wr, wi, rl%z, k, wq, -1, bwork, &
                   lainfo)
        lwork = max(1, int(wq(1)))
        allocate (work(lwork))
        call dgees('V', 'N', select_none, k, a, k, sdim, wr, wi, rl%z, k, work, lwork, &
                   bwork, lainfo)
        if (lainfo /= 0) then
            info = CM_NO_CONVERGENCE
            message = "rotation_log: the Schur form of the rotation did not converge"
            return
        end if
        nneg = 0
        i = 1
        do while (i <= k)
            if (i < k) then
                if (a(i + 1, i) /= 0.0_dp) then
                    ! a 2 x 2 block [av b; c av] with b c < 0: cos(theta) I + sin(theta) K
                    av = 0.5_dp*(a(i, i) + a(i + 1, i + 1))
                    om = sqrt(max(-a(i, i + 1)*a(i + 1, i), 0.0_dp))
                    rl%nplane = rl%nplane + 1
                    rl%plane(:, rl%nplane) = [i, i + 1]
                    rl%sgn(rl%nplane) = sign(1.0_dp, a(i + 1, i))
                    rl%angle(rl%nplane) = atan2(om, av)
                    i = i + 2
                    cycle
                end if
            end if
            if (a(i, i) < 0.0_dp) then
                nneg = nneg + 1
                neg(nneg) = i
            end if
            i = i + 1
        end do
        if (mod(nneg, 2) /= 0) then
            info = CM_BAD_INPUT
            message = "rotation_log: the matrix has determinant -1 (not a rotation)"
            return
        end if
        do i = 1, nneg, 2
            rl%nplane = rl%nplane + 1
            rl%plane(:, rl%nplane) = [neg(i), neg(i + 1)]
            rl%sgn(rl%nplane) = 1.0_dp
            rl%angle(rl%nplane) = acos(-1.0_dp)
        end do
        info = CM_SUCCESS
        message = "success"
    end subroutine rotation_log_init

    !> e = R^s = exp(s log R).
    subroutine rl_power(self, s, e)
        class(rotation_log), intent(in) :: self
        real(dp), intent(in) :: s
        real(dp), intent(out) :: e(:, :)
        real(dp) :: c, sn, d(2, 2)
        integer :: j, i
        e = 0.0_dp
        do i = 1, self%k
            e(i, i) = 1.0_dp
        end do
        do j = 1, self%nplane
            c = cos(s*self%angle(j)) - 1.0_dp
            sn = sin(s*self%angle(j))*self%sgn(j)
            d = reshape([c, sn, -sn, c], [2, 2])
            e = e + matmul(self%z(:, self%plane(:, j)), &
                           matmul(d, transpose(self%z(:, self%plane(:, j)))))
        end do
    end subroutine rl_power

    !> l = log R (skew-symmetric).
    subroutine rl_generator(self, l)
        class(rotation_log), intent(in) :: self
        real(dp), intent(out) :: l(:, :)
        real(dp) :: d(2, 2)
        integer :: j
        l = 0.0_dp
        do j = 1, self%nplane
            d = reshape([0.0_dp, 1.0_dp, -1.0_dp, 0.0_dp], [2, 2])*self%sgn(j)*self%angle(j)
            l = l + matmul(self%z(:, self%plane(:, j)), &
                           matmul(d, transpose(self%z(:, self%plane(:, j)))))
        end do
    end subroutine rl_generator

end module conmech_rotation_log
