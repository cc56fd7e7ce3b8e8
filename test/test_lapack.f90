!> The LAPACK layer: illegal arguments and NaN input give a status, never a stop.
program test_lapack
    use conmech
    use conmech_lapack, only: dgesv
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    real(dp) :: a(2, 2), b(2, 1), x(2, 1), wr(2), wi(2), nan
    integer :: ipiv(2), info

    ts%name = "test_lapack"
    ! an illegal argument (n = -1): LAPACK calls XERBLA, which must return, not STOP
    a = reshape([2.0_dp, 1.0_dp, 1.0_dp, 3.0_dp], [2, 2])
    b(:, 1) = [1.0_dp, 2.0_dp]
    call dgesv(-1, 1, a, 2, ipiv, b, 2, info)
    call ts%check(info == -1, "dgesv with n = -1 returns info = -1 and the program goes on")
    nan = 0.0_dp
    nan = nan/nan
    a(1, 2) = nan
    call la_solve(a, b, x, info)
    call ts%check(info == CM_NONFINITE, "la_solve with a NaN entry: CM_NONFINITE")
    call la_eig(a, wr, wi, info)
    call ts%check(info == CM_NONFINITE, "la_eig with a NaN entry: CM_NONFINITE")
    a(1, 2) = 1.0_dp
    call la_solve(a, b, x, info)
    call ts%check(info == CM_SUCCESS .and. abs(2.0_dp*x(1, 1) + x(2, 1) - 1.0_dp) < 1.0e-14_dp &
                  .and. abs(x(1, 1) + 3.0_dp*x(2, 1) - 2.0_dp) < 1.0e-14_dp, &
                  "la_solve solves a regular system")
    call ts%finish()
end program test_lapack
