!> A parameter-continuation wrapper that hides the wrapped Jacobian product (the dense-J
!! path of integrate_stm, as before builtin_param_system forwarded the product).
module continuation_bench_dense
    use conmech, only: builtin_param_system
    implicit none
    private
    public :: param_dense
    type, extends(builtin_param_system) :: param_dense
    contains
        procedure :: has_jacobian_product => no_product
    end type param_dense
contains
    logical function no_product(self)
        class(param_dense), intent(in) :: self
        no_product = .false.
    end function no_product
end module continuation_bench_dense

!> Continuation of a general (non-Hill) family: pseudo-arclength (conmech_continuation)
!! against the natural-parameter continuation (continue_periodic_family) of the same limit
!! cycles of van der Pol's oscillator, mu from 1 to 3, in the same run. Then the Jacobian
!! product forwarded by builtin_param_system: Hill's variation family continued in m
!! (symmetric shooting) on the product path and on the dense-J path (CPU time).
!! Run: fpm run --example continuation_bench --profile release
program continuation_bench
    use conmech
    use continuation_bench_dense, only: param_dense
    implicit none
    type(branch) :: br
    type(cont_options) :: o
    type(builtin_param_system) :: sys
    type(van_der_pol) :: vdp
    type(periodic_orbit), allocatable :: orbs(:)
    type(shooting_options) :: so
    real(dp), allocatable :: ps(:)
    real(dp) :: t_pa, t_nat, res_pa, res_nat
    integer(8) :: c0, c1, rate
    integer :: info, i, n
    character(len=:), allocatable :: msg
    call system_clock(count_rate=rate)
    call make_param_system("vanderpol", [1.0_dp], 1, sys, info, msg)
    o%ds = 0.1_dp
    o%ds_max = 0.3_dp
    o%p_max = 3.0_dp
    o%max_points = 1000
    o%rtol = 1.0e-11_dp
    o%atol = 1.0e-11_dp
    call system_clock(c0)
    call continue_orbits(sys, set_builtin_param, 1.0_dp, [2.0_dp, 0.0_dp], 6.66_dp, br, o)
    call system_clock(c1)
    t_pa = real(c1 - c0, dp)/rate
    res_pa = maxval(br%points(1:br%npoints)%residual)
    ! natural continuation over the same parameter values
    n = br%npoints
    allocate (ps(n), orbs(n))
    ps = br%points(1:n)%p
    so%rtol = 1.0e-11_dp
    so%atol = 1.0e-11_dp
    call system_clock(c0)
    call continue_periodic_family(vdp, set_mu, ps, [2.0_dp, 0.0_dp], 6.66_dp, orbs, &
                                  options=so)
    call system_clock(c1)
    t_nat = real(c1 - c0, dp)/rate
    res_nat = maxval(orbs%residual)
    write (*, '(a)') "# van der Pol limit cycles, mu = 1 .. 3 (same parameter values)"
    write (*, '(a, i0, a, f9.3, a, f9.2, a, es9.2, a, i0)') "pseudo-arclength: ", n, &
        " points in ", t_pa, " s (", 1.0e3_dp*t_pa/n, " ms/point, incl. tangent, "// &
        "multipliers, tests), max residual ", res_pa, ", special points ", br%nspecial
    write (*, '(a, i0, a, f9.3, a, f9.2, a, es9.2, a, i0)') "natural continuation: ", n, &
        " points in ", t_nat, " s (", 1.0e3_dp*t_nat/n, " ms/point, incl. monodromy), "// &
        "max residual ", res_nat, ", failures ", count(orbs%info /= CM_SUCCESS)
    do i = 1, n, max(1, n/5)
        write (*, '(a, f8.4, a, es10.2)') "  mu =", ps(i), "  |T_pa - T_nat| =", &
            abs(br%points(i)%period - orbs(i)%period)
    end do

    call product_vs_dense()

contains

    !> The same branch on both paths, alternating, best of 5 (each timing 10 branches):
    !! CPU time per branch and the largest difference of the points.
    subroutine product_vs_dense()
        type(builtin_param_system) :: ps
        type(param_dense) :: pd
        type(cont_options) :: oh
        type(branch) :: b1, b2
        real(dp) :: t1, t2, best(2), diff
        real(dp), parameter :: y0(4) = [0.8_dp, 0.0_dp, 0.0_dp, 1.0_dp]
        integer :: rep, k
        oh%conservative = .true.
        oh%p_max = 0.25_dp
        oh%max_points = 60
        oh%ds = 0.002_dp
        oh%ds_max = 0.002_dp
        oh%rtol = 1.0e-12_dp
        oh%atol = 1.0e-12_dp
        call make_param_system("hill", [0.15_dp, 1.0_dp], 1, ps, info, msg)
        call make_param_system("hill", [0.15_dp, 1.0_dp], 1, pd%builtin_param_system, info, &
                               msg)
        best = huge(1.0_dp)
        do rep = 1, 5
            call cpu_time(t1)
            do k = 1, 10
                call continue_orbits(ps, set_builtin_param, 0.15_dp, y0, 8*atan(1.0_dp), b1, &
                                     oh, [1, 4], [1, 4], .false., 4.0_dp)
            end do
            call cpu_time(t2)
            best(1) = min(best(1), (t2 - t1)/10)
            call cpu_time(t1)
            do k = 1, 10
                call continue_orbits(pd, set_builtin_param, 0.15_dp, y0, 8*atan(1.0_dp), b2, &
                                     oh, [1, 4], [1, 4], .false., 4.0_dp)
            end do
            call cpu_time(t2)
            best(2) = min(best(2), (t2 - t1)/10)
        end do
        diff = huge(1.0_dp)
        if (b1%npoints == b2%npoints .and. b1%info == CM_SUCCESS) &
            diff = max(maxval(abs(b1%points(1:b1%npoints)%p - b2%points(1:b1%npoints)%p)), &
                       maxval(abs(b1%points(1:b1%npoints)%period - &
                                  b2%points(1:b1%npoints)%period)))
        write (*, '(a)') "# builtin_param_system: Jacobian product forwarded vs dense J"
        write (*, '(a, i0, a, 2f9.4, a, f6.2, a, es9.2)') "hill in m (symmetric shooting, ", &
            b1%npoints, " points), s/branch product, dense:", best, "  dense/product", &
            best(2)/best(1), "  max |diff|", diff
    end subroutine product_vs_dense

    subroutine set_mu(s, p)
        class(ode_system), intent(inout) :: s
        real(dp), intent(in) :: p
        select type (s)
        type is (van_der_pol)
            s%mu = p
        end select
    end subroutine set_mu

end program continuation_bench
