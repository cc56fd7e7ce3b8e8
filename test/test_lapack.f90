!> The LAPACK layer: illegal arguments and NaN input give a status, never a stop.
program test_lapack
    use conmech
    use conmech_lapack, only: dgesv
    use conmech_rank, only: min_norm_solve, singular_values
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    real(dp) :: a(2, 2), b(2, 1), x(2, 1), wr(2), wi(2), nan, s(2), xs(2), w(3)
    integer :: ipiv(2), info, rank

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
    call la_eig(a, wr(1:1), wi, info)
    call ts%check(info == CM_BAD_INPUT, "la_eig with a short wr: CM_BAD_INPUT")
    call la_sym_eig(a, w, info)
    call ts%check(info == CM_BAD_INPUT, "la_sym_eig with a long w: CM_BAD_INPUT")
    b(2, 1) = nan
    call la_solve(a, b, x, info)
    call ts%check(info == CM_NONFINITE, "la_solve with a NaN right-hand side: CM_NONFINITE")
    call min_norm_solve(a, b(:, 1), xs, 1.0e-12_dp, rank, info)
    call ts%check(info == CM_NONFINITE, "min_norm_solve with a NaN b: CM_NONFINITE")
    call min_norm_solve(a, b(1:1, 1), xs, 1.0e-12_dp, rank, info)
    call ts%check(info == CM_BAD_INPUT, "min_norm_solve with a short b: CM_BAD_INPUT")
    call singular_values(a, s(1:1), info)
    call ts%check(info == CM_BAD_INPUT, "singular_values with a short s: CM_BAD_INPUT")
    a(2, 2) = nan
    call singular_values(a, s, info)
    call ts%check(info == CM_NONFINITE, "singular_values with a NaN entry: CM_NONFINITE")
    call ts%finish()
end program test_lapack
