!> Error estimate and step-size control of Radau IIA (RADAU5's, Hairer & Wanner, Solving
!! ODEs II, section IV.8): the initial step (SciPy's select_initial_step heuristic for an
!! estimator of order 3), the embedded error estimate (estrad), the proposal
!! h / max(facr, min(facl, err^(1/4)/fac)) with Gustafsson's predictive correction, and
!! the choice after an accepted step (refresh the Jacobian? keep h and the LU?).
module conmech_radau_control
    use conmech_kinds, only: dp
    use conmech_lapack, only: dgetrs
    use conmech_ode_system, only: ode_system
    use conmech_radau_coefficients, only: DD1, DD2, DD3, NIT, THET, QUOT1, QUOT2
    use conmech_radau_newton, only: radau_rhs
    use conmech_radau_stepper, only: radau_stepper
    implicit none
    private

    public :: radau_initial_step, radau_estimate_error, radau_propose_step
    public :: radau_predictive_step, radau_next_step

contains

    !> Initial step of SciPy's select_initial_step (error estimator order 3), signed.
    function radau_initial_step(s, sys) result(hh)
        type(radau_stepper), intent(inout) :: s
        class(ode_system), intent(in) :: sys
        real(dp) :: hh, d0, d1, d2, h1
        d0 = sqrt(sum((s%y/s%scal)**2)/s%n)
        d1 = sqrt(sum((s%f0/s%scal)**2)/s%n)
        if (d0 < 1.0e-5_dp .or. d1 < 1.0e-5_dp) then
            hh = 1.0e-6_dp
        else
            hh = 0.01_dp*d0/d1
        end if
        hh = min(hh, s%hmax)
        s%a1 = s%y + hh*s%posneg*s%f0
        call radau_rhs(sys, s%st, s%t + hh*s%posneg, s%a1, s%a2)
        d2 = sqrt(sum(((s%a2 - s%f0)/s%scal)**2)/s%n)/hh
        if (.not. (abs(d2) <= huge(1.0_dp))) d2 = huge(1.0_dp)
        if (d1 <= 1.0e-15_dp .and. d2 <= 1.0e-15_dp) then
            h1 = max(1.0e-6_dp, hh*1.0e-3_dp)
        else
            h1 = (0.01_dp/max(d1, d2))**0.25_dp
        end if
        hh = min(100.0_dp*hh, h1, s%hmax)*s%posneg
    end function radau_initial_step

    !> RADAU5's error estimate (estrad) into s%err: (I - h gamma0 J)^{-1}(f0 + (e1 z1 +
    !! e2 z2 + e3 z3)/h), refined by one more solve at the first step or after a rejection.
    subroutine radau_estimate_error(s, sys)
        type(radau_stepper), intent(inout) :: s
        class(ode_system), intent(in) :: sys
        real(dp) :: hee1, hee2, hee3
        integer :: linfo, n
        n = s%n
        hee1 = DD1/s%h
        hee2 = DD2/s%h
        hee3 = DD3/s%h
        s%a2 = hee1*s%z1 + hee2*s%z2 + hee3*s%z3
        if (allocated(s%mass)) s%a2 = matmul(s%mass, s%a2)
        s%cont = s%a2 + s%f0
        call solve_and_measure()
        if (s%err < 1.0_dp) return
        if (s%first .or. s%reject) then
            s%a1 = s%y + s%cont
            call radau_rhs(sys, s%st, s%t, s%a1, s%a3)
            s%cont = s%a3 + s%a2
            call solve_and_measure()
        end if
        if (.not. (abs(s%err) <= huge(1.0_dp))) s%err = 1.0e10_dp
    contains
        !> cont <- (I - h gamma0 J)^{-1} cont by the real LU (sparse or dense) and its
        !! scaled RMS norm (at least 1e-10) into err.
        subroutine solve_and_measure()
            if (s%sparse) then
                call s%slu%solve_real(s%cont)
            else
                call dgetrs('N', n, 1, s%e1, n, s%ip1, s%cont, n, linfo)
            end if
            s%err = max(sqrt(sum((s%cont/s%scal)**2)/real(n, dp)), 1.0e-10_dp)
        end subroutine solve_and_measure
    end subroutine radau_estimate_error

    !> The proposed step s%hnew = h/quot, quot = max(facr, min(facl, err^(1/4)/fac)),
    !! fac = min(safe, safe (1 + 2 NIT)/(newt + 2 NIT)); returns quot.
    function radau_propose_step(s) result(quot)
        type(radau_stepper), intent(inout) :: s
        real(dp) :: quot, fac
        fac = min(s%safe, s%cfac/real(s%newt + 2*NIT, dp))
        quot = max(s%facr, min(s%facl, s%err**0.25_dp/fac))
        s%hnew = s%h/quot
    end function radau_propose_step

    !> After an accepted step (the naccept-th): Gustafsson's predictive controller (from
    !! the second accepted step on) may shrink s%hnew; then it remembers h and err.
    subroutine radau_predictive_step(s, quot, naccept)
        type(radau_stepper), intent(inout) :: s
        real(dp), intent(in) :: quot
        integer, intent(in) :: naccept
        real(dp) :: facgus, q
        if (naccept > 1) then
            facgus = (s%hacc/s%h)*(s%err**2/s%erracc)**0.25_dp/s%safe
            facgus = max(s%facr, min(s%facl, facgus))
            q = max(quot, facgus)
            s%hnew = s%h/q
        end if
        s%hacc = s%h
        s%erracc = max(1.0e-2_dp, s%err)
    end subroutine radau_predictive_step

    !> The next step after an accepted one (s%t, s%y already advanced): bounded by hmax
    !! (and by the last step after a rejection), cut at tf; the Jacobian is refreshed
    !! after a slow Newton iteration; otherwise h and the LU are kept when
    !! QUOT1 <= hnew/h <= QUOT2.
    subroutine radau_next_step(s)
        type(radau_stepper), intent(inout) :: s
        s%h_capped = abs(s%hnew) > s%hmax
        s%hnew = s%posneg*min(abs(s%hnew), s%hmax)
        if (s%reject) s%hnew = s%posneg*min(abs(s%hnew), abs(s%h))
        s%reject = .false.
        ! a constant Jacobian is never re-evaluated (SciPy keeps the LU then as well)
        s%need_jac = s%newt > 2 .and. s%theta > THET .and. .not. s%jstruct%constant
        if ((s%t + s%hnew - s%tf)*s%posneg >= 0.0_dp) then
            s%h = s%tf - s%t
            s%final_step = .true.
            s%need_lu = .true.
        else
            ! (h is kept only within hmax: a step raised to the smallest one may exceed it)
            if (.not. s%need_jac .and. s%hnew/s%h >= QUOT1 .and. s%hnew/s%h <= QUOT2 .and. &
                abs(s%h) <= s%hmax) then
                s%need_lu = .false.
            else
                s%h = s%hnew
                s%need_lu = .true.
            end if
        end if
    end subroutine radau_next_step

end module conmech_radau_control
