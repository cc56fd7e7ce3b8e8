!> Driver for instruction counts and timings of the Hill family (bench/hill_callgrind.sh):
!! the 10,000-point variation-orbit family over m in [0.01, 0.15] (as in hill_bench), run
!! `reps` times; prints the best wall time per orbit, failures and max true closure.
!! Multipliers (dgeev) off, as in the hill_family program and conmech.hill.family; a third
!! argument 1 turns them on. Usage: hill_family_ir [n] [reps] [eig]
program hill_family_ir
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS
    use conmech_hill_orbit, only: hill_orbit, hill_orbit_options
    use conmech_hill_family, only: hill_family
    implicit none
    type(hill_orbit), allocatable :: fam(:)
    type(hill_orbit_options) :: opt
    real(dp), allocatable :: ms(:)
    real(dp) :: best
    integer(8) :: c0, c1, rate
    integer :: n, reps, i, k
    character(len=32) :: arg
    n = 10000
    reps = 1
    if (command_argument_count() >= 1) then
        call get_command_argument(1, arg)
        read (arg, *) n
    end if
    if (command_argument_count() >= 2) then
        call get_command_argument(2, arg)
        read (arg, *) reps
    end if
    opt%eigenvalues = .false.
    if (command_argument_count() >= 3) then
        call get_command_argument(3, arg)
        opt%eigenvalues = trim(arg) == "1"
    end if
    allocate (ms(n), fam(n))
    do i = 1, n
        ms(i) = 0.01_dp + 0.14_dp*real(i - 1, dp)/real(max(n - 1, 1), dp)
    end do
    call system_clock(count_rate=rate)
    best = huge(1.0_dp)
    do k = 1, reps
        call system_clock(c0)
        call hill_family(ms, 1.0_dp, fam, opt)
        call system_clock(c1)
        best = min(best, real(c1 - c0, dp)/rate)
    end do
    write (*, '(a, f10.3, a, i0, a, es9.2)') "us/orbit ", 1.0e6_dp*best/n, "  failures ", &
        count(fam%info /= CM_SUCCESS), "  max residual ", maxval(fam%residual)
end program hill_family_ir
