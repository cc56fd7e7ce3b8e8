!> The stage system of a Radau IIA step, solved by RADAU5's simplified Newton iteration
!! (Hairer & Wanner, Solving ODEs II, section IV.8): counted right-hand side evaluations,
!! the Jacobian (analytic, or forward differences with Hairer's steps), the real LU of
!! gamma/h M - J and the complex LU of (alpha + i beta)/h M - J (LAPACK dgetrf/zgetrf, or
!! sparse ones on the sparse path: conmech_radau_sparse),
!! and the iteration on the transformed stage increments with the contraction control.
module conmech_radau_newton
    use conmech_kinds, only: dp
    use conmech_lapack, only: dgetrf, dgetrs, zgetrf, zgetrs
    use conmech_ode_options, only: ode_stats
    use conmech_ode_system, only: ode_system
    use conmech_radau_coefficients
    use conmech_radau_collocation, only: radau_extrapolate
    use conmech_radau_stepper, only: radau_stepper
    use conmech_sparse_jacobian_system, only: sparse_jacobian_system
    implicit none
    private

    public :: radau_rhs, radau_jacobian, radau_decompose, radau_newton

contains

    !> ff = f(tt, yy), counted in stats%nfev.
    subroutine radau_rhs(sys, stats, tt, yy, ff)
        class(ode_system), intent(in) :: sys
        type(ode_stats), intent(inout) :: stats
        real(dp), intent(in) :: tt, yy(:)
        real(dp), intent(out) :: ff(:)
        call sys%rhs(tt, yy, ff)
        stats%nfev = stats%nfev + 1
    end subroutine radau_rhs

    !> s%jac = df/dy at (s%t, s%y): the system's `jacobian` if it has one (a constant one,
    !! s%jstruct%constant, is read and not counted in njev: SciPy's count; on the sparse
    !! path a sparse_jacobian_system with the same pattern gives its values on it), else
    !! forward differences with steps sqrt(eps max(1e-5, |y_j|)) (n evaluations, or one
    !! per group of columns with a sparsity pattern; s%f0 = f(t, y)).
    subroutine radau_jacobian(s, sys)
        type(radau_stepper), intent(inout) :: s
        class(ode_system), intent(in) :: sys
        real(dp) :: delt, ysafe
        real(dp), allocatable :: jfull(:, :)
        integer :: jj
        if (sys%has_jacobian()) then
            if (.not. s%jstruct%constant) s%st%njev = s%st%njev + 1
            if (s%sparse) then
                ! a system that gives J on the same pattern: its values, never densified
                select type (sys)
                class is (sparse_jacobian_system)
                    if (sys%same_pattern(s%jstruct%col_ptr, s%jstruct%row_idx)) then
                        call sys%jacobian_values(s%t, s%y, s%jval)
                        return
                    end if
                end select
                ! the system gives J dense: its entries on the pattern
                allocate (jfull(s%n, s%n))
                call sys%jacobian(s%t, s%y, jfull)
                call s%jstruct%gather(jfull, s%jval)
            else
                call sys%jacobian(s%t, s%y, s%jac)
            end if
            return
        end if
        s%st%njev = s%st%njev + 1
        if (s%sparse) then
            call s%jstruct%fd_values(sys, s%t, s%y, s%f0, s%uround, s%jval, s%a2, s%a1, &
                                     s%st%nfev)
            return
        end if
        if (s%jstruct%grouped()) then
            call s%jstruct%fd_jacobian(sys, s%t, s%y, s%f0, s%uround, s%jac, s%a2, s%a1, &
                                       s%st%nfev)
            return
        end if
        do jj = 1, s%n
            ysafe = s%y(jj)
            delt = sqrt(s%uround*max(1.0e-5_dp, abs(ysafe)))
            s%y(jj) = ysafe + delt
            call radau_rhs(sys, s%st, s%t, s%y, s%a1)
            s%y(jj) = ysafe
            s%jac(:, jj) = (s%a1 - s%f0)/delt
        end do
    end subroutine radau_jacobian

    !> LU of gamma/h M - J (real, s%e1) and (alpha + i beta)/h M - J (complex, s%e2);
    !! M = I unless s%mass is allocated. linfo: LAPACK's info (/= 0: singular).
    subroutine radau_decompose(s, linfo)
        type(radau_stepper), intent(inout) :: s
        integer, intent(out) :: linfo
        real(dp) :: fac1
        complex(dp) :: sig
        integer :: ii, n, info2
        n = s%n
        fac1 = GAM0/s%h
        sig = cmplx(ALPH/s%h, BETA/s%h, kind=dp)
        if (s%sparse) then
            call s%slu%decompose(s%jval, fac1, sig, linfo, info2)
            s%st%nlu = s%st%nlu + 1
            if (linfo /= 0) return
            s%st%nlu = s%st%nlu + 1
            linfo = info2
            return
        end if
        if (allocated(s%mass)) then
            s%e1 = fac1*s%mass - s%jac
            s%e2 = sig*s%mass - s%jac
        else
            s%e1 = -s%jac
            s%e2 = cmplx(-s%jac, 0.0_dp, kind=dp)
            do ii = 1, n
                s%e1(ii, ii) = s%e1(ii, ii) + fac1
                s%e2(ii, ii) = s%e2(ii, ii) + sig
            end do
        end if
        call dgetrf(n, n, s%e1, n, s%ip1, linfo)
        s%st%nlu = s%st%nlu + 1
        if (linfo /= 0) return
        call zgetrf(n, n, s%e2, n, s%ip2, linfo)
        s%st%nlu = s%st%nlu + 1
    end subroutine radau_decompose

    !> Simplified Newton iteration for the stage increments z1..z3 (RADAU5's control):
    !! s%converged, s%newt; a slow contraction shrinks s%h (not converged), a failure
    !! (divergence, NIT iterations, non-finite values) halves it and sets s%newton_failed.
    subroutine radau_newton(s, sys)
        type(radau_stepper), intent(inout) :: s
        class(ode_system), intent(in) :: sys
        real(dp) :: fac1, alphn, betan, s2, s3, dyno, dynold, thq, thqold, dyth, qnewt
        real(dp) :: hhfac
        integer :: linfo, i, n
        n = s%n
        s%converged = .false.
        fac1 = GAM0/s%h
        alphn = ALPH/s%h
        betan = BETA/s%h
        ! starting values: the previous collocation polynomial, extrapolated
        if (s%first .or. .not. s%have_cont) then
            s%z1 = 0.0_dp; s%z2 = 0.0_dp; s%z3 = 0.0_dp
            s%w1 = 0.0_dp; s%w2 = 0.0_dp; s%w3 = 0.0_dp
        else
            call radau_extrapolate(s%fc, s%cvec, s%h/s%h_done, s%z1, s%z2, s%z3)
            s%w1 = TI11*s%z1 + TI12*s%z2 + TI13*s%z3
            s%w2 = TI21*s%z1 + TI22*s%z2 + TI23*s%z3
            s%w3 = TI31*s%z1 + TI32*s%z2 + TI33*s%z3
        end if
        s%newt = 0
        s%faccon = max(s%faccon, s%uround)**0.8_dp
        s%theta = abs(THET)
        dynold = 0.0_dp
        thqold = 0.0_dp
        do
            if (s%newt >= NIT) exit
            call radau_rhs(sys, s%st, s%t + C1*s%h, s%y + s%z1, s%a1)
            call radau_rhs(sys, s%st, s%t + C2*s%h, s%y + s%z2, s%a2)
            call radau_rhs(sys, s%st, s%t + s%h, s%y + s%z3, s%a3)
            if (.not. (all(abs(s%a1) <= huge(1.0_dp)) .and. all(abs(s%a2) <= huge(1.0_dp)) .and. &
                       all(abs(s%a3) <= huge(1.0_dp)))) exit
            if (allocated(s%mass)) then
                s%b1 = matmul(s%mass, s%w1)
                s%b2 = matmul(s%mass, s%w2)
                s%b3 = matmul(s%mass, s%w3)
            else
                s%b1 = s%w1
                s%b2 = s%w2
                s%b3 = s%w3
            end if
            s%z1 = TI11*s%a1 + TI12*s%a2 + TI13*s%a3 - fac1*s%b1
            do i = 1, n
                s2 = TI21*s%a1(i) + TI22*s%a2(i) + TI23*s%a3(i)
                s3 = TI31*s%a1(i) + TI32*s%a2(i) + TI33*s%a3(i)
                s%zc(i) = cmplx(s2 - alphn*s%b2(i) + betan*s%b3(i), &
                                s3 - alphn*s%b3(i) - betan*s%b2(i), kind=dp)
            end do
            if (s%sparse) then
                call s%slu%solve_real(s%z1)
                call s%slu%solve_complex(s%zc)
            else
                call dgetrs('N', n, 1, s%e1, n, s%ip1, s%z1, n, linfo)
                call zgetrs('N', n, 1, s%e2, n, s%ip2, s%zc, n, linfo)
            end if
            s%z2 = real(s%zc, dp)
            s%z3 = aimag(s%zc)
            s%newt = s%newt + 1
            dyno = sqrt(sum((s%z1/s%scal)**2 + (s%z2/s%scal)**2 + (s%z3/s%scal)**2) &
                        /real(3*n, dp))
            if (.not. (abs(dyno) <= huge(1.0_dp))) exit
            if (s%newt > 1 .and. s%newt < NIT) then
                thq = dyno/dynold
                if (s%newt == 2) then
                    s%theta = thq
                else
                    s%theta = sqrt(thq*thqold)
                end if
                thqold = thq
                if (s%theta < 0.99_dp) then
                    s%faccon = s%theta/(1.0_dp - s%theta)
                    dyth = s%faccon*dyno*s%theta**(NIT - 1 - s%newt)/s%fnewt
                    if (dyth >= 1.0_dp) then
                        ! slow convergence: a smaller step
                        qnewt = max(1.0e-4_dp, min(20.0_dp, dyth))
                        hhfac = 0.8_dp*qnewt**(-1.0_dp/real(4 + NIT - 1 - s%newt, dp))
                        s%h = hhfac*s%h
                        return
                    end if
                else
                    exit
                end if
            end if
            dynold = max(dyno, s%uround)
            s%w1 = s%w1 + s%z1
            s%w2 = s%w2 + s%z2
            s%w3 = s%w3 + s%z3
            s%z1 = T11*s%w1 + T12*s%w2 + T13*s%w3
            s%z2 = T21*s%w1 + T22*s%w2 + T23*s%w3
            s%z3 = T31*s%w1 + s%w2
            if (s%faccon*dyno <= s%fnewt) then
                s%converged = .true.
                return
            end if
        end do
        ! divergence, too many iterations or non-finite values: halve the step
        s%newton_failed = .true.
        s%h = 0.5_dp*s%h
    end subroutine radau_newton

end module conmech_radau_newton
