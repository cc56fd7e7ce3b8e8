!> Periodic orbits by multiple shooting and orthogonal collocation against single
!! shooting, the collocation's order of convergence, multipliers of a very unstable orbit
!! and the failures that must be reported.
program test_orbit_bvp
    use conmech_kinds, only: dp, pi
    use conmech_status
    use conmech_testing, only: test_suite
    use conmech_ode_system, only: ode_system
    use conmech_systems, only: make_system
    use conmech_shooting
    implicit none
    type(test_suite) :: suite
    !> Van der Pol's limit cycle at mu = 1 (Hairer, Norsett and Wanner; REFERENCE.md)
    real(dp), parameter :: T_VDP = 6.663286859323130_dp
    suite%name = "test_orbit_bvp"
    call three_methods_agree()
    call collocation_order()
    call unstable_three_laps()
    call symmetric_by_all_methods()
    call reported_failures()
    call suite%finish()

contains

    subroutine vdp(sys)
        class(ode_system), allocatable, intent(out) :: sys
        integer :: info
        character(len=:), allocatable :: msg
        call make_system("vanderpol", [1.0_dp], sys, info, msg)
    end subroutine vdp

    !> Single shooting, multiple shooting (8 segments) and collocation (40 intervals of
    !! degree 4, adapted mesh) find the same limit cycle and multipliers: the shooting
    !! methods to 1e-9 (the integrator's tolerance 1e-12 amplified by the Newton problem),
    !! collocation to its discretisation error (8e-10 in the period at this mesh).
    subroutine three_methods_agree()
        class(ode_system), allocatable :: sys
        type(periodic_orbit) :: o(3)
        type(shooting_options) :: so
        real(dp) :: tl
        integer :: i
        call vdp(sys)
        do i = 1, 3
            so%discretisation = i
            call find_periodic_orbit(sys, [2.0_dp, 0.0_dp], 6.5_dp, o(i), options=so)
            call suite%check(o(i)%info == CM_SUCCESS, orbit_method_name(i)// &
                             " converges: "//o(i)%message)
            if (o(i)%info /= CM_SUCCESS) return
            tl = merge(1.0e-8_dp, 1.0e-9_dp, i == ORBIT_COLLOCATION)
            call suite%check_close(o(i)%period, T_VDP, tl, orbit_method_name(i)// &
                                   ": the published period")
            call suite%check_close(minval(o(i)%floquet%abs_mult), &
                                   minval(o(1)%floquet%abs_mult), tl, &
                                   orbit_method_name(i)//": the contracting multiplier")
            call suite%check_close(maxval(o(i)%floquet%abs_mult), 1.0_dp, 0.1_dp*tl + 1.0e-9_dp, &
                                   orbit_method_name(i)//": the trivial multiplier")
        end do
        call suite%check(size(o(3)%nodes, 2) == 41 .and. o(3)%degree == 4, &
                         "collocation: 41 mesh nodes of degree 4")
        call suite%check_less(maxval(abs(o(2)%y0 - o(1)%y0)), 1.0e-9_dp, &
                              "multiple = single shooting (initial state)")
    end subroutine three_methods_agree

    !> The period of Gauss collocation with m points per interval converges at order 2m
    !! (superconvergence at the mesh points) on a uniform mesh: the observed order from
    !! N = 32, 64 intervals is within 0.3 of 2m for m = 2, 3, 4 (errors 1e-4 .. 3e-11).
    subroutine collocation_order()
        class(ode_system), allocatable :: sys
        type(periodic_orbit) :: o
        type(shooting_options) :: so
        real(dp) :: e(2), order
        integer :: m, i
        character(len=80) :: buf
        call vdp(sys)
        so%discretisation = ORBIT_COLLOCATION
        so%adapt = 0
        so%rtol = 1.0e-6_dp     ! the closure check's tolerance (coarse meshes on purpose)
        so%atol = 1.0e-6_dp
        do m = 2, 4
            so%degree = m
            do i = 1, 2
                so%intervals = 32*2**(i - 1)
                call find_periodic_orbit(sys, [2.0_dp, 0.0_dp], 6.5_dp, o, options=so)
                call suite%check(o%info == CM_SUCCESS, "collocation converges: "//o%message)
                e(i) = abs(o%period - T_VDP)
            end do
            order = log(e(1)/e(2))/log(2.0_dp)
            write (buf, '(a,i0,a,f6.2,a,2es9.2)') "collocation degree ", m, &
                ": observed order ", order, " errors ", e
            call suite%check(abs(order - 2*m) < 0.3_dp, trim(buf))
        end do
    end subroutine collocation_order

    !> Henon's family a (Hill's problem in Henon's units): an orbit about L1 with
    !! S ~ 780, traversed three times (mu_max ~ 4e9). Multiple shooting over 24 segments
    !! keeps |mu_min mu_max - 1| and the trivial pair to 1e-8; the multipliers of the
    !! three laps are the cubes of one lap's.
    subroutine unstable_three_laps()
        class(ode_system), allocatable :: sys
        type(periodic_orbit) :: one, three
        type(shooting_options) :: so
        real(dp) :: a(4), w, x0, vy, mu1, y0(4)
        integer :: info
        character(len=:), allocatable :: msg
        character(len=80) :: buf
        call make_system("hill", [1.0_dp, 1.0_dp], sys, info, msg)
        w = sqrt(2.0_dp*sqrt(7.0_dp) - 1.0_dp)
        x0 = 3.0_dp**(-1.0_dp/3.0_dp) + 0.1_dp
        vy = -(9.0_dp + w*w)*0.1_dp/2.0_dp
        call find_symmetric_orbit(sys, [x0, 0.0_dp, 0.0_dp, vy], [4], pi/w, [2, 3], one, &
                                  free_time=.true.)
        call suite%check(one%info == CM_SUCCESS, "the Lyapunov orbit about L1")
        if (one%info /= CM_SUCCESS) return
        mu1 = maxval(one%floquet%abs_mult)
        so%discretisation = ORBIT_MULTIPLE
        so%segments = 24
        y0 = one%y0
        call find_periodic_orbit(sys, y0, 3.0_dp*one%period, three, PO_FIXED_PERIOD, so)
        call suite%check(three%info == CM_SUCCESS, "three laps by multiple shooting: "// &
                         three%message)
        if (three%info /= CM_SUCCESS) return
        a = sort4(three%floquet%abs_mult)
        write (buf, '(a,es10.3)') "three laps: mu_max ", a(4)
        call suite%check(a(4) > 1.0e9_dp, trim(buf))
        call suite%check_less(abs(a(1)*a(4) - 1.0_dp), 1.0e-8_dp, "|mu_min mu_max - 1|")
        call suite%check_less(max(abs(a(2) - 1.0_dp), abs(a(3) - 1.0_dp)), 1.0e-8_dp, &
                              "the trivial pair")
        call suite%check_less(abs(a(4)/mu1**3 - 1.0_dp), 1.0e-7_dp, "mu_max = (one lap)^3")
        call suite%check_less(three%multipliers%accuracy, 1.0e-6_dp, &
                              "the reported accuracy is small")
    end subroutine unstable_three_laps

    pure function sort4(v) result(s)
        real(dp), intent(in) :: v(4)
        real(dp) :: s(4), t
        integer :: i, j
        s = v
        do i = 1, 3
            do j = i + 1, 4
                if (s(j) < s(i)) then
                    t = s(i)
                    s(i) = s(j)
                    s(j) = t
                end if
            end do
        end do
    end function sort4

    !> Hill's variation orbit (two symmetry lines, quarter period) by symmetric single
    !! shooting, multiple shooting and collocation: same initial state and multipliers.
    subroutine symmetric_by_all_methods()
        class(ode_system), allocatable :: sys
        type(periodic_orbit) :: o(3)
        type(shooting_options) :: so
        integer :: i, info
        character(len=:), allocatable :: msg
        call make_system("hill", [0.0808_dp, 1.0_dp], sys, info, msg)
        do i = 1, 3
            so%discretisation = i
            so%segments = 4
            so%intervals = 24
            call find_symmetric_orbit(sys, [0.95_dp, 0.0_dp, 0.0_dp, 0.95_dp], [1, 4], &
                                      0.5_dp*pi, [1, 4], o(i), so, period_factor=4.0_dp)
            call suite%check(o(i)%info == CM_SUCCESS, "symmetric "//orbit_method_name(i)// &
                             ": "//o(i)%message)
            if (o(i)%info /= CM_SUCCESS) return
            call suite%check_less(maxval(abs(o(i)%y0 - o(1)%y0)), 1.0e-9_dp, &
                                  "symmetric "//orbit_method_name(i)//" = single")
            call suite%check_close(0.5_dp*(sum(o(i)%floquet%mr) - 2.0_dp), &
                                   0.5_dp*(sum(o(1)%floquet%mr) - 2.0_dp), 1.0e-8_dp, &
                                   "symmetric "//orbit_method_name(i)//": the same S")
        end do
    end subroutine symmetric_by_all_methods

    subroutine reported_failures()
        class(ode_system), allocatable :: sys
        type(periodic_orbit) :: o
        type(shooting_options) :: so
        integer :: info
        character(len=:), allocatable :: msg
        call vdp(sys)
        ! a start at the equilibrium
        call find_periodic_orbit(sys, [0.0_dp, 0.0_dp], 6.5_dp, o)
        call suite%check(o%info == CM_BAD_INPUT .and. index(o%message, "equilibrium") > 0, &
                         "an equilibrium start is named: "//o%message)
        ! a mesh that cannot resolve the orbit: 4 intervals of degree 1 (the midpoint rule)
        so%discretisation = ORBIT_COLLOCATION
        so%intervals = 4
        so%degree = 1
        so%adapt = 0
        call find_periodic_orbit(sys, [2.0_dp, 0.0_dp], 6.5_dp, o, options=so)
        call suite%check(o%info /= CM_SUCCESS .and. index(o%message, "collocation") > 0, &
                         "a coarse collocation mesh is reported: "//o%message)
        ! free/target counts
        call make_system("hill", [0.0808_dp, 1.0_dp], sys, info, msg)
        call find_symmetric_orbit(sys, [0.95_dp, 0.0_dp, 0.0_dp, 0.95_dp], [1, 2, 4], &
                                  0.5_dp*pi, [1, 2, 3, 4], o, period_factor=4.0_dp)
        call suite%check(o%info == CM_BAD_INPUT .and. index(o%message, "3 unknowns") > 0 &
                         .and. index(o%message, "4 targets") > 0, &
                         "counts named: "//o%message)
    end subroutine reported_failures

end program test_orbit_bvp
