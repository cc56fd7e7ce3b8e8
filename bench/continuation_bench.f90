!> Continuation of a general (non-Hill) family: pseudo-arclength (conmech_continuation)
!! against the natural-parameter continuation (continue_periodic_family) of the same limit
!! cycles of van der Pol's oscillator, mu from 1 to 3, in the same run.
!! Run: fpm run --example continuation_bench --profile release
program continuation_bench
    use conmech
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

contains

    subroutine set_mu(s, p)
        class(ode_system), intent(inout) :: s
        real(dp), intent(in) :: p
        select type (s)
        type is (van_der_pol)
            s%mu = p
        end select
    end subroutine set_mu

end program continuation_bench
