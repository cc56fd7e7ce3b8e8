!> Taylor's method for a batch of members at once: the coefficients of `width` members are
!! computed together by a generated routine whose arrays have the members in the fastest
!! dimension (w(width, 0:order, nw): every statement is a short vector operation the
!! compiler turns into SIMD), and each member steps with its own step size, exactly as
!! conmech_taylor_stepper would step it alone (same arithmetic from conmech_taylor_core:
!! bit for bit the same result). A member that has reached tf waits for the others.
!!
!! The lazily compiled batch library of a symbolic system also holds a propagator of its own
!! (conmech.symbolic.taylor_batch: the step control in vector form too, lanes refilled as
!! members end), run here by `taylor_batch_run_members` over OpenMP threads;
!! `taylor_batch_propagate` runs a batch routine given without it.
!!
!! Each round: every member's candidate step is evaluated on its polynomial, the batch is
!! expanded at all candidate points in one call, and each member accepts (its candidate
!! becomes its current point, the new expansion its polynomial) or, if the safety check
!! fails, retries from its current expansion with a shorter step in the next round.
module conmech_taylor_batch
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_taylor_core, only: taylor_order, taylor_decay, taylor_next_rho, taylor_eval_step, &
        taylor_check, taylor_add_time, taylor_shrink, TAYLOR_CHECK_MAX
    implicit none
    private
    public :: taylor_batch_fn, taylor_batch_propagate, taylor_batch_run_fn, &
        taylor_batch_run_members

    abstract interface
        !> The batch coefficients: t(width), w(width, 0:order, nw); on entry w(:, 0, 1:n) =
        !! the members' states, on exit w(:, 0:order, 1:n) their Taylor coefficients.
        subroutine taylor_batch_fn(t, order, w, p) bind(c)
            import :: c_double, c_int
            real(c_double), intent(in) :: t(*)
            integer(c_int), value :: order
            real(c_double), intent(inout) :: w(*)
            real(c_double), intent(in) :: p(*)
        end subroutine taylor_batch_fn
        !> The generated propagator over SIMD lanes (conmech.symbolic.taylor_batch): the
        !! members y(n, m) from span(1) to span(2) in place, each as the scalar stepper
        !! integrates it; tol(n, 2) = [rtol, atol]; order and decay: taylor_order and
        !! taylor_decay of the tolerances (the rule lives here, not in generated code);
        !! per member st (status), te (where it stopped), cnt(:, j) = [expansions,
        !! accepted, rejected].
        subroutine taylor_batch_run_fn(m, y, span, tol, hmax, mxs, order, decay, p, te, st, &
                                       cnt) bind(c)
            import :: c_double, c_int
            integer(c_int), value :: m, mxs, order
            real(c_double), intent(inout) :: y(*)
            real(c_double), intent(in) :: span(2), tol(*), p(*)
            real(c_double), value :: hmax, decay
            real(c_double), intent(out) :: te(*)
            integer(c_int), intent(out) :: st(*), cnt(*)
        end subroutine taylor_batch_run_fn
    end interface

contains

    !> The members y(:, 1:m) (n states each) from t0 to tf in place by the generated lane
    !! propagator `run` (parameters p shared), in chunks of consecutive members spread
    !! over `threads` OpenMP threads (0: the default number); each member's result does not
    !! depend on the chunks or threads. info(j), tend(j), nexp(j), nacc(j), nrej(j): see
    !! taylor_batch_run_fn.
    subroutine taylor_batch_run_members(run, p, n, m, y, t0, tf, rtol, atol, hmax, max_steps, &
                                        threads, tend, info, nexp, nacc, nrej)
        !$ use omp_lib, only: omp_get_max_threads
        procedure(taylor_batch_run_fn) :: run
        integer, intent(in) :: n, m, max_steps, threads
        real(dp), intent(in) :: p(:), t0, tf, rtol(n), atol(n), hmax
        real(dp), intent(inout) :: y(n, m)
        real(dp), intent(out) :: tend(m)
        integer(c_int), intent(out) :: info(m), nexp(m), nacc(m), nrej(m)
        integer(c_int), allocatable :: cnt(:, :)
        real(dp) :: tol(n, 2), eps, decay
        integer :: nthr, chunk, nc, b, j0, nm, ord
        nthr = 1
        !$ nthr = omp_get_max_threads()
        if (threads > 0) nthr = threads
        ! chunks small enough for the threads to share the work evenly, large enough that
        ! a chunk's last members (when lanes fall idle) are a small part of it
        chunk = max(16, min(512, (m + 8*nthr - 1)/(8*nthr)))
        nc = (m + chunk - 1)/chunk
        tol(:, 1) = rtol
        tol(:, 2) = atol
        ! the scalar stepper's order and step factor (taylor_propagate's tolerance eps)
        eps = max(minval(max(rtol, epsilon(1.0_dp))), minval(atol))
        ord = taylor_order(eps)
        decay = taylor_decay(eps)
        allocate (cnt(3, m))
        !$omp parallel do num_threads(nthr) schedule(dynamic, 1) default(shared) &
        !$omp private(b, j0, nm)
        do b = 1, nc
            j0 = (b - 1)*chunk + 1
            nm = min(chunk, m - j0 + 1)
            call run(int(nm, c_int), y(:, j0:j0 + nm - 1), [t0, tf], tol, hmax, &
                     int(max_steps, c_int), int(ord, c_int), decay, p, tend(j0:j0 + nm - 1), &
                     info(j0:j0 + nm - 1), cnt(:, j0:j0 + nm - 1))
        end do
        !$omp end parallel do
        nexp = cnt(1, :)
        nacc = cnt(2, :)
        nrej = cnt(3, :)
    end subroutine taylor_batch_run_members

    !> Advance the members y(:, 1:nm) (nm <= width) from t0 to tf in place by Taylor's
    !! method with the batch routine `fn` (width members, nw work columns, parameters p),
    !! tolerances rtol, atol (per component), at most max_steps attempted steps and steps of
    !! at most hmax per member. info(j): CM_SUCCESS, CM_TOO_MANY_STEPS, CM_STEP_TOO_SMALL or
    !! CM_NONFINITE (y(:, j) where member j stopped, at time tend(j)); nfev counts the
    !! batch expansions, naccept/nreject each member's steps.
    subroutine taylor_batch_propagate(fn, width, nw, p, n, nm, t0, tf, y, rtol, atol, hmax, &
                                      max_steps, info, tend, nfev, naccept, nreject)
        procedure(taylor_batch_fn) :: fn
        integer, intent(in) :: width, nw, n, nm, max_steps
        real(dp), intent(in) :: p(:), t0, tf, rtol(n), atol(n), hmax
        real(dp), intent(inout) :: y(n, nm)
        integer, intent(out) :: info(nm), nfev, naccept(nm), nreject(nm)
        real(dp), intent(out) :: tend(nm)
        real(dp), allocatable :: w(:, :, :), cur(:, :, :)
        real(dp) :: t(width), tlo(width), h(width), tc(width), e(n, width), hcand(width)
        real(dp) :: ynew(n), dy(n), f1(n), eps, decay, posneg, hm, err, rt(n), rho
        integer :: ord, j, k, nsteps(width)
        logical :: active(width), hit(width)
        info = CM_SUCCESS
        nfev = 0
        naccept = 0
        nreject = 0
        tend = t0
        if (nm < 1 .or. tf == t0) return
        rt = max(rtol, epsilon(1.0_dp))
        eps = max(minval(rt), minval(atol))
        ord = taylor_order(eps)
        decay = taylor_decay(eps)
        posneg = sign(1.0_dp, tf - t0)
        hm = min(abs(hmax), abs(tf - t0))
        allocate (w(width, 0:ord, nw), cur(0:ord, n, width))
        w = 0.0_dp
        t = t0
        tlo = 0.0_dp
        nsteps = 0
        active = .false.
        active(1:nm) = .true.
        ! the expansions at t0 (idle lanes repeat the last member)
        do j = 1, width
            w(j, 0, 1:n) = y(:, min(j, nm))
        end do
        call fn(t, int(ord, c_int), w, p)
        nfev = nfev + 1
        do j = 1, nm
            cur(:, :, j) = w(j, :, 1:n)
            if (.not. all(abs(cur(1, :, j)) <= huge(1.0_dp))) then
                info(j) = CM_NONFINITE
                active(j) = .false.
                cycle
            end if
            call taylor_next_rho(n, n, ord, cur(:, :, j), rt, atol, eps, decay, e(:, j), rho)
            h(j) = min(rho, hm)*posneg
        end do
        do while (any(active))
            ! candidate points of the active members
            do j = 1, width
                tc(j) = t(min(j, nm))
                hcand(j) = 0.0_dp
                hit(j) = .false.
                if (j > nm) then
                    w(j, 0, 1:n) = y(:, nm)
                    cycle
                end if
                if (.not. active(j)) then
                    w(j, 0, 1:n) = y(:, j)
                    cycle
                end if
                if (nsteps(j) >= max_steps) then
                    info(j) = CM_TOO_MANY_STEPS
                    active(j) = .false.
                    w(j, 0, 1:n) = y(:, j)
                    cycle
                end if
                if (.not. (0.1_dp*abs(h(j)) > abs(t(j))*epsilon(1.0_dp))) then
                    info(j) = CM_STEP_TOO_SMALL
                    active(j) = .false.
                    w(j, 0, 1:n) = y(:, j)
                    cycle
                end if
                hcand(j) = h(j)
                if ((t(j) + hcand(j) - tf)*posneg >= 0.0_dp) then
                    hcand(j) = (tf - t(j)) - tlo(j)
                    hit(j) = .true.
                end if
                nsteps(j) = nsteps(j) + 1
                call taylor_eval_step(n, ord, cur(:, :, j), hcand(j), ynew, dy)
                w(j, 0, 1:n) = ynew
                tc(j) = t(j) + hcand(j)
            end do
            if (.not. any(active)) exit
            call fn(tc, int(ord, c_int), w, p)
            nfev = nfev + 1
            do j = 1, nm
                if (.not. active(j) .or. hcand(j) == 0.0_dp) cycle
                call taylor_eval_step(n, ord, cur(:, :, j), hcand(j), ynew, dy)
                f1 = w(j, 1, 1:n)
                err = taylor_check(n, ord, hcand(j), ynew, dy, f1, e(:, j))
                if (.not. (err <= TAYLOR_CHECK_MAX)) then
                    nreject(j) = nreject(j) + 1
                    h(j) = taylor_shrink(hcand(j), err, ord)
                    cycle
                end if
                naccept(j) = naccept(j) + 1
                y(:, j) = ynew
                cur(:, :, j) = w(j, :, 1:n)
                if (hit(j)) then
                    t(j) = tf
                    tlo(j) = 0.0_dp
                    active(j) = .false.
                else
                    call taylor_add_time(t(j), tlo(j), hcand(j))
                end if
                if (.not. all(abs(cur(1, :, j)) <= huge(1.0_dp))) then
                    info(j) = CM_NONFINITE
                    active(j) = .false.
                    cycle
                end if
                call taylor_next_rho(n, n, ord, cur(:, :, j), rt, atol, eps, decay, e(:, j), &
                                     rho)
                h(j) = min(rho, hm)*posneg
            end do
        end do
        do k = 1, nm
            tend(k) = t(k)
        end do
    end subroutine taylor_batch_propagate

end module conmech_taylor_batch
