!> The family of Hill's variation orbits over m (natural continuation in m, OpenMP chunks,
!! deterministic whatever the number of threads) and the location of its stability
!! changes (S = +1 or -1), on top of `hill_variation_orbit` (conmech_hill_orbit).
module conmech_hill_family
    use conmech_kinds, only: dp
    use conmech_illinois, only: illinois_bracket
    use conmech_status
    use conmech_hill_orbit, only: hill_orbit, hill_orbit_options, hill_variation_orbit
    implicit none
    private
    public :: hill_family, hill_locate_index

contains

    !> The family over ms (any order; continuation works best for sorted, close values).
    !! The index range is cut into chunks of `chunk_size` consecutive orbits (default 256;
    !! `nchunks` instead gives the number of chunks). First, serially, the first orbit of
    !! every chunk is computed by continuation with a stride of chunk_size/8 points
    !! (quadratic extrapolation; point by point where a stride fails; a cold start,
    !! `hill_orbit_guess`, for the first one). Then the chunks run in parallel with OpenMP,
    !! each orbit starting Newton from the cubic extrapolation of the previous four of its chunk
    !! and with the step count its predecessor needed (the error control may raise it).
    !! Nothing depends on the number of threads, so neither do the results (bit for bit).
    !! Every orbit meets the same Newton and closure tolerances as a single orbit.
    subroutine hill_family(ms, kappa, orbs, options, nchunks, chunk_size)
        real(dp), intent(in) :: ms(:)
        real(dp), intent(in) :: kappa
        type(hill_orbit), intent(out) :: orbs(:)
        type(hill_orbit_options), intent(in), optional :: options
        integer, intent(in), optional :: nchunks, chunk_size
        type(hill_orbit_options) :: opt, opti, opt0
        integer :: nc, ic, i, i0, i1, n, nprev, j, cs, ilast, np0
        real(dp) :: u(2), mm(4), uu(2, 4), mm0(4), uu0(2, 4)
        if (present(options)) opt = options
        n = size(ms)
        if (n < 1) return
        cs = 256
        if (present(chunk_size)) cs = max(1, chunk_size)
        if (present(nchunks)) cs = (n + max(1, nchunks) - 1)/max(1, nchunks)
        nc = (n + cs - 1)/cs
        ! serial pass: walk to every chunk start with a stride of cs/8 points (point by
        ! point where a stride fails), keeping the chunk starts
        nprev = 0
        opti = opt
        ilast = 0
        do ic = 1, nc
            i1 = (ic - 1)*cs + 1
            do while (ilast < i1)
                i = min(i1, ilast + max(1, cs/8))
                if (ilast == 0) i = 1
                mm0 = mm
                uu0 = uu
                np0 = nprev
                opt0 = opti
                call serial_orbit(ms(i), kappa, orbs(i), opti, opt, mm, uu, nprev)
                if (orbs(i)%info /= CM_SUCCESS .and. i > ilast + 1 .and. np0 > 0) then
                    mm = mm0
                    uu = uu0
                    nprev = np0
                    opti = opt0
                    do j = ilast + 1, i
                        call serial_orbit(ms(j), kappa, orbs(j), opti, opt, mm, uu, nprev)
                    end do
                end if
                ilast = i
            end do
        end do
        !$omp parallel do schedule(dynamic, 1) default(shared) &
        !$omp private(ic, i, i0, i1, nprev, u, mm, uu, opti)
        do ic = 1, nc
            i0 = (ic - 1)*cs + 1
            i1 = min(n, ic*cs)
            nprev = 0
            opti = opt
            call push_orbit(orbs(i0), mm, uu, nprev, opti, opt)
            do i = i0 + 1, i1
                if (nprev == 0) then
                    opti%nsteps = opt%nsteps
                    call hill_variation_orbit(ms(i), kappa, orbs(i), opti)
                else
                    call extrapolate_u(ms(i), mm, uu, min(nprev, 4), u)
                    call hill_variation_orbit(ms(i), kappa, orbs(i), opti, guess=u)
                end if
                call push_orbit(orbs(i), mm, uu, nprev, opti, opt)
            end do
        end do
        !$omp end parallel do
    end subroutine hill_family

    !> One orbit of the serial pass: from the extrapolation of the history (quadratic),
    !! else cold; pushed into the history.
    subroutine serial_orbit(m, kappa, orb, opti, opt, mm, uu, nprev)
        real(dp), intent(in) :: m, kappa
        type(hill_orbit), intent(inout) :: orb
        type(hill_orbit_options), intent(inout) :: opti
        type(hill_orbit_options), intent(in) :: opt
        real(dp), intent(inout) :: mm(4), uu(2, 4)
        integer, intent(inout) :: nprev
        real(dp) :: u(2)
        if (nprev > 0) then
            call extrapolate_u(m, mm, uu, min(nprev, 3), u)
            call hill_variation_orbit(m, kappa, orb, opti, guess=u)
        end if
        if (nprev == 0 .or. orb%info /= CM_SUCCESS) then
            opti%nsteps = opt%nsteps
            call hill_variation_orbit(m, kappa, orb, opti)
        end if
        call push_orbit(orb, mm, uu, nprev, opti, opt)
    end subroutine serial_orbit

    !> Lagrange extrapolation of (x0, v0) to m through the last np orbits.
    pure subroutine extrapolate_u(m, mm, uu, np, u)
        real(dp), intent(in) :: m, mm(4), uu(2, 4)
        integer, intent(in) :: np
        real(dp), intent(out) :: u(2)
        integer :: j
        u = 0.0_dp
        do j = 1, np
            u = u + lagrange_weight(m, mm, np, j)*uu(:, j)
        end do
    end subroutine extrapolate_u

    !> Record a converged orbit in the extrapolation history (reset it on failure); the
    !! next orbit starts from this one's error-controlled step count.
    pure subroutine push_orbit(orb, mm, uu, nprev, opti, opt)
        type(hill_orbit), intent(in) :: orb
        real(dp), intent(inout) :: mm(4), uu(2, 4)
        integer, intent(inout) :: nprev
        type(hill_orbit_options), intent(inout) :: opti
        type(hill_orbit_options), intent(in) :: opt
        if (orb%info == CM_SUCCESS) then
            opti%nsteps = max(opt%nsteps, orb%nsteps)
            mm(2:4) = mm(1:3)
            uu(:, 2:4) = uu(:, 1:3)
            mm(1) = orb%m
            uu(:, 1) = [orb%y0(1), orb%y0(4)]
            nprev = nprev + 1
        else
            nprev = 0
            mm = 0.0_dp
            uu = 0.0_dp
        end if
    end subroutine push_orbit

    !> Locate the m where the stability index S crosses `target` (+1: a multiplier pair
    !! through +1, the loss of stability of the variation family near m = 0.195; -1:
    !! through -1) between two orbits `oa`, `ob` of the family whose S - target differ in
    !! sign. Illinois (modified regula falsi) on S(m) - target; each orbit is warm-started
    !! from the linear interpolation of the bracket's orbits. Converged when the bracket
    !! is below `mtol` (default 1e-13 max(1, m)) or S - target vanishes; `orb` is the orbit
    !! at the located m (its info and message say whether the location succeeded).
    subroutine hill_locate_index(oa, ob, target, orb, options, mtol)
        type(hill_orbit), intent(in) :: oa, ob
        real(dp), intent(in) :: target
        type(hill_orbit), intent(out) :: orb
        type(hill_orbit_options), intent(in), optional :: options
        real(dp), intent(in), optional :: mtol
        type(hill_orbit_options) :: opt
        type(illinois_bracket) :: br
        real(dp) :: ua(2), ub(2), mc, fc, tl, w
        integer :: it
        logical :: moved
        if (present(options)) opt = options
        tl = 1.0e-13_dp
        if (present(mtol)) tl = mtol
        br%a = oa%m
        br%b = ob%m
        br%fa = oa%stability_index - target
        br%fb = ob%stability_index - target
        if (oa%info /= CM_SUCCESS .or. ob%info /= CM_SUCCESS .or. &
            .not. (br%fa*br%fb <= 0.0_dp) .or. oa%kappa /= ob%kappa .or. br%a == br%b) then
            call orb%fail(CM_BAD_INPUT, "hill_locate_index: need two converged orbits (same "// &
                                        "kappa) with S - target of opposite signs")
            return
        end if
        ua = [oa%y0(1), oa%y0(4)]
        ub = [ob%y0(1), ob%y0(4)]
        do it = 1, 100
            mc = br%trial()
            w = (mc - br%a)/(br%b - br%a)
            call hill_variation_orbit(mc, oa%kappa, orb, opt, guess=(1.0_dp - w)*ua + w*ub)
            if (orb%info /= CM_SUCCESS) return
            fc = orb%stability_index - target
            if (fc == 0.0_dp .or. abs(br%b - br%a) <= tl*max(1.0_dp, abs(mc))) return
            call br%update(mc, fc, moved)
            if (moved) ua = ub
            ub = [orb%y0(1), orb%y0(4)]
        end do
        call orb%fail(CM_NO_CONVERGENCE, "hill_locate_index: no convergence in 100 iterations")
    end subroutine hill_locate_index

    pure real(dp) function lagrange_weight(x, xs, np, j) result(w)
        real(dp), intent(in) :: x, xs(:)
        integer, intent(in) :: np, j
        integer :: k
        w = 1.0_dp
        do k = 1, np
            if (k /= j) w = w*(x - xs(k))/(xs(j) - xs(k))
        end do
    end function lagrange_weight

end module conmech_hill_family
