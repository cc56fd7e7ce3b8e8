!> Branch switching at a period-doubling point: from the located point (p*, y*, T*) of a
!! branch, onto the branch of orbits of period 2 T* that bifurcates there.
!!
!! At the point, the monodromy M has the multiplier -1 with eigenvector v (found by inverse
!! iteration on M + I, LAPACK dgesv). For the doubled period the shooting Jacobian has the
!! two-dimensional kernel {old tangent, (v, 0, 0)}: the continuation of the problem with
!! period 2 T* starts at (y*, 2 T*, p*) with the tangent (v, 0, 0), so its first
!! pseudo-arclength step leaves the old branch (which the hyperplane t . (X - X*) = ds
!! excludes) for the new one; `direction` (+1/-1) picks the sign of v.
module conmech_branch_switch
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options
    use conmech_variational, only: integrate_stm
    use conmech_lapack, only: dgesv
    use conmech_shooting, only: set_parameter_proc
    use conmech_continuation, only: cont_options, branch, special_point, continue_orbits, &
                                    SP_PD
    implicit none
    private
    public :: switch_period_doubling

contains

    !> The doubled-period branch from the period-doubling point `sp` (general shooting of an
    !! autonomous system, period free). `options` as for continue_orbits (its `direction`
    !! chooses the side of v).
    subroutine switch_period_doubling(sys, set_param, sp, br, options)
        class(ode_system), intent(inout) :: sys
        procedure(set_parameter_proc) :: set_param
        type(special_point), intent(in) :: sp
        type(branch), intent(out) :: br
        type(cont_options), intent(in), optional :: options
        type(cont_options) :: o
        type(ode_options) :: oo
        real(dp), allocatable :: y(:), phi(:, :), a(:, :), v(:, :), t0(:)
        integer, allocatable :: ipiv(:)
        integer :: n, j, it, info
        character(len=:), allocatable :: msg
        if (present(options)) o = options
        if (sp%kind /= SP_PD .or. .not. allocated(sp%point%y0)) then
            br%info = CM_BAD_INPUT
            br%message = "switch_period_doubling: not a located period-doubling point"
            return
        end if
        n = size(sp%point%y0)
        allocate (y(n), phi(n, n), a(n, n), v(n, 1), ipiv(n), t0(n + 2))
        oo%rtol = o%rtol
        oo%atol = o%atol
        call set_param(sys, sp%point%p)
        y = sp%point%y0
        phi = 0.0_dp
        do j = 1, n
            phi(j, j) = 1.0_dp
        end do
        call integrate_stm(sys, 0.0_dp, sp%point%period, y, phi, oo, info, msg)
        if (info < 0) then
            br%info = info
            br%message = "switch_period_doubling: "//msg
            return
        end if
        ! inverse iteration on M + I for the eigenvector of the multiplier -1
        v(:, 1) = 1.0_dp/sqrt(real(n, dp))
        do it = 1, 3
            a = phi
            do j = 1, n
                a(j, j) = a(j, j) + 1.0_dp
            end do
            call dgesv(n, 1, a, n, ipiv, v, n, info)
            if (info < 0 .or. .not. (norm2(v(:, 1)) > 0.0_dp)) then
                br%info = CM_SINGULAR
                br%message = "switch_period_doubling: no eigenvector for the multiplier -1"
                return
            end if
            v(:, 1) = v(:, 1)/norm2(v(:, 1))
        end do
        t0 = 0.0_dp
        t0(1:n) = real(sign(1, o%direction), dp)*v(:, 1)
        call continue_orbits(sys, set_param, sp%point%p, sp%point%y0, 2.0_dp*sp%point%period, &
                             br, o, tangent0=t0)
    end subroutine switch_period_doubling

end module conmech_branch_switch
