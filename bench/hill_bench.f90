!> Benchmark of Hill's variation orbit + monodromy (fast symmetric path against the generic
!! DOP853 shooting of the library, measured in the same run), and family throughput.
!! Run: fpm run --example hill_bench --profile release [--flag -fopenmp] -- [n_family]
program hill_bench
    use conmech
    !$ use omp_lib, only: omp_set_num_threads, omp_get_max_threads
    implicit none
    real(dp), parameter :: m_hill = 0.080848933808312_dp, c_hill = 1.0715832774160_dp
    type(hill_orbit) :: orb
    type(hill_orbit), allocatable :: fam(:)
    type(hill_orbit_options) :: opt
    type(hill_problem) :: hp
    type(periodic_orbit) :: po
    type(shooting_options) :: so
    real(dp), allocatable :: ms(:)
    real(dp) :: t0, t1, tcold, twarm, tgen, guess(2), s, cerr
    integer(8) :: c0, c1, rate
    integer :: i, nrep, nfam, nthr, k, nfail, ns
    character(len=32) :: arg

    nfam = 10000
    if (command_argument_count() >= 1) then
        call get_command_argument(1, arg)
        read (arg, *) nfam
    end if
    call system_clock(count_rate=rate)

    write (*, '(a)') "# Hill variation orbit + 4x4 monodromy, m = 0.080848933808312"
    write (*, '(a)') "nsteps/quarter  |c err|     us/orbit(cold)  us/orbit(warm)  nfev(warm)"
    do ns = 12, 32, 4
        opt%nsteps = ns
        opt%eigenvalues = .true.
        call hill_variation_orbit(m_hill, 1.0_dp, orb, opt)
        cerr = abs(orb%c - c_hill)
        guess = [orb%y0(1), orb%y0(4)]
        nrep = 2000
        call system_clock(c0)
        do i = 1, nrep
            call hill_variation_orbit(m_hill, 1.0_dp, orb, opt)
        end do
        call system_clock(c1)
        tcold = real(c1 - c0, dp)/rate/nrep
        ! warm start: the neighbour's solution (as in continuation), perturbed by 1e-8
        call system_clock(c0)
        do i = 1, nrep
            call hill_variation_orbit(m_hill, 1.0_dp, orb, opt, guess=guess*(1.0_dp + 1.0e-8_dp))
        end do
        call system_clock(c1)
        twarm = real(c1 - c0, dp)/rate/nrep
        write (*, '(i8, es14.2, 2f14.2, i10)') ns, cerr, 1.0e6_dp*tcold, 1.0e6_dp*twarm, orb%nfev
    end do

    ! peer in the same run: the library's generic path (adaptive DOP853 on the 20-dim
    ! variational system, generic symmetric shooting, monodromy over the full period)
    hp%m = m_hill
    so%rtol = 1.0e-13_dp
    so%atol = 1.0e-13_dp
    nrep = 50
    call system_clock(c0)
    do i = 1, nrep
        call find_symmetric_orbit(hp, [0.95_dp, 0.0_dp, 0.0_dp, 0.95_dp], [1, 4], 0.5_dp*pi, &
                                  [1, 4], po, so, period_factor=4.0_dp)
    end do
    call system_clock(c1)
    tgen = real(c1 - c0, dp)/rate/nrep
    s = 0.5_dp*(po%floquet%trace - 2.0_dp)
    write (*, '(a, f10.1, a, es9.2)') "generic shooting (adaptive DOP853, rtol 1e-13): us/orbit", &
        1.0e6_dp*tgen, "  |c err|", abs(hill_perigee_c(s) - c_hill)
    so%method = METHOD_VERNER98
    call system_clock(c0)
    do i = 1, nrep
        call find_symmetric_orbit(hp, [0.95_dp, 0.0_dp, 0.0_dp, 0.95_dp], [1, 4], 0.5_dp*pi, &
                                  [1, 4], po, so, period_factor=4.0_dp)
    end do
    call system_clock(c1)
    s = 0.5_dp*(po%floquet%trace - 2.0_dp)
    write (*, '(a, f8.1, a, es9.2)') &
        "generic shooting (adaptive Verner 9(8), rtol 1e-13): us/orbit", &
        1.0e6_dp*real(c1 - c0, dp)/rate/nrep, "  |c err|", abs(hill_perigee_c(s) - c_hill)

    opt = hill_orbit_options()
    call hill_variation_orbit(m_hill, 1.0_dp, orb, opt)
    call system_clock(c0)
    do i = 1, 2000
        call hill_variation_orbit(m_hill, 1.0_dp, orb, opt)
    end do
    call system_clock(c1)
    tcold = real(c1 - c0, dp)/rate/2000
    write (*, '(a, f8.1)') "speed-up of the default fast path (cold start) over generic:", &
        tgen/tcold

    ! family throughput
    allocate (ms(nfam), fam(nfam))
    do i = 1, nfam
        ms(i) = 0.01_dp + 0.14_dp*real(i - 1, dp)/real(max(nfam - 1, 1), dp)
    end do
    write (*, '(a, i0, a)') "# family of ", nfam, " orbits, m in [0.01, 0.15] (S and c, "// &
        "multipliers not computed)"
    opt%eigenvalues = .false.
    nthr = 1
    !$ nthr = omp_get_max_threads()
    ! best of 3 (the machine is shared), threads alternating
    do k = 1, max(1, min(2, nthr))
        t1 = huge(1.0_dp)
        do i = 1, 3
            !$ call omp_set_num_threads(k)
            call system_clock(c0)
            call hill_family(ms, 1.0_dp, fam, opt)
            call system_clock(c1)
            t1 = min(t1, real(c1 - c0, dp)/rate)
        end do
        nfail = count(fam%info /= CM_SUCCESS)
        write (*, '(a, i0, a, f12.0, a, f8.2, a, i0)') "threads ", k, ": orbits/s ", &
            nfam/t1, "  us/orbit ", 1.0e6_dp*t1/nfam, "  failures ", nfail
    end do
    write (*, '(a, es9.2)') "max true closure error (residual) over the family:", &
        maxval(fam%residual)
    ! the same with the multipliers by dgeev for every orbit (one thread; as measured
    ! before the multipliers were left out of the family)
    opt%eigenvalues = .true.
    !$ call omp_set_num_threads(1)
    t1 = huge(1.0_dp)
    do i = 1, 3
        call system_clock(c0)
        call hill_family(ms, 1.0_dp, fam, opt)
        call system_clock(c1)
        t1 = min(t1, real(c1 - c0, dp)/rate)
    end do
    write (*, '(a, f12.0, a, f8.2)') "threads 1, with dgeev multipliers: orbits/s", &
        nfam/t1, "  us/orbit ", 1.0e6_dp*t1/nfam
    t0 = 0.0_dp
end program hill_bench
