!> Taylor's method in quadruple precision (real128, gfortran's IEEE binary128: 113-bit
!! significand, unit round-off 9.6e-35) for reference solutions: the generated routine
!! conmech_taylor_qp expands the solution in real128 (C pointers to real128 values), and
!! the step follows Jorba and Zou (order ceil(-ln(tol)/2 + 1): 36 at 1e-30; rho from the
!! last two coefficients; the step's safety check from the next expansion; the time summed
!! in double length). The double-precision stepper raises that order (taylor_order of
!! conmech_taylor_core), because its step is bound by the latency of a chain of fast
!! operations; real128 arithmetic is done in software, each operation costs far more than
!! a pipeline's latency, and the work counted in products, which Jorba and Zou's order
!! minimises, is what a step costs.
module conmech_taylor_quad
    use, intrinsic :: iso_c_binding, only: c_int, c_ptr, c_loc
    use, intrinsic :: iso_fortran_env, only: qp => real128
    use conmech_status
    implicit none
    private
    public :: qp, taylor_qp_fn, taylor_propagate_qp

    abstract interface
        !> Quadruple-precision coefficients: t, w(0:order, nw), p as real128 behind C
        !! pointers (on entry w(0, 1:n) = y, on exit w(0:order, 1:n) its coefficients).
        subroutine taylor_qp_fn(t, order, w, p) bind(c)
            import :: c_int, c_ptr
            type(c_ptr), value :: t, w, p
            integer(c_int), value :: order
        end subroutine taylor_qp_fn
    end interface

contains

    !> Advance y (real128) from t0 to tf in place with the tolerance tol (absolute below
    !! |y| = 1, relative above, as Jorba and Zou); at most max_steps steps. info: CM_SUCCESS,
    !! CM_TOO_MANY_STEPS, CM_STEP_TOO_SMALL or CM_NONFINITE; nsteps accepted steps, order p.
    subroutine taylor_propagate_qp(fn, n, nw, p, t0, tf, y, tol, max_steps, info, nsteps, &
                                   order)
        procedure(taylor_qp_fn) :: fn
        integer, intent(in) :: n, nw, max_steps
        real(qp), intent(in), target :: p(:)
        real(qp), intent(in) :: t0, tf, tol
        real(qp), intent(inout) :: y(n)
        integer, intent(out) :: info, nsteps, order
        real(qp), allocatable, target :: jet(:, :), nxt(:, :)
        real(qp), target :: tt
        real(qp) :: t, tlo, h, posneg, e, rho, s1, s2, decay, err, d, ynew(n), dy(n), s, bb
        real(qp) :: lo
        integer :: k, i, attempts
        logical :: hit
        info = CM_SUCCESS
        nsteps = 0
        order = max(2, ceiling(-0.5_qp*log(max(tol, tiny(1.0_qp))) + 1.0_qp))
        if (tf == t0) return
        if (.not. (tol > 0.0_qp) .or. n < 1 .or. nw < n) then
            info = CM_BAD_INPUT
            return
        end if
        decay = exp(-2.0_qp - 0.7_qp/real(order - 1, qp))
        posneg = sign(1.0_qp, tf - t0)
        allocate (jet(0:order, nw), nxt(0:order, nw))
        jet = 0.0_qp
        nxt = 0.0_qp
        t = t0
        tlo = 0.0_qp
        jet(0, 1:n) = y
        tt = t
        call fn(c_loc(tt), int(order, c_int), c_loc(jet), c_loc(p))
        attempts = 0
        do
            ! Jorba and Zou's step from the current expansion
            e = max(tol, tol*maxval(abs(y)))
            s1 = maxval(abs(jet(order - 1, 1:n)))/e*tol
            s2 = maxval(abs(jet(order, 1:n)))/e*tol
            rho = huge(1.0_qp)
            if (s1 > 0.0_qp) rho = exp(-log(s1)/real(order - 1, qp))
            if (s2 > 0.0_qp) rho = min(rho, exp(-log(s2)/real(order, qp)))
            if (rho < huge(1.0_qp)) rho = rho*decay
            h = min(rho, abs(tf - t0))*posneg
            do
                attempts = attempts + 1
                if (attempts > max_steps) then
                    info = CM_TOO_MANY_STEPS
                    return
                end if
                if (.not. (0.1_qp*abs(h) > abs(t)*epsilon(1.0_qp))) then
                    info = CM_STEP_TOO_SMALL
                    return
                end if
                hit = (t + h - tf)*posneg >= 0.0_qp
                if (hit) h = (tf - t) - tlo
                do i = 1, n
                    ynew(i) = jet(order, i)
                    dy(i) = real(order, qp)*jet(order, i)
                    do k = order - 1, 1, -1
                        ynew(i) = jet(k, i) + h*ynew(i)
                        dy(i) = real(k, qp)*jet(k, i) + h*dy(i)
                    end do
                    ynew(i) = jet(0, i) + h*ynew(i)
                end do
                nxt(0, 1:n) = ynew
                tt = t + h
                call fn(c_loc(tt), int(order, c_int), c_loc(nxt), c_loc(p))
                err = 0.0_qp
                do i = 1, n
                    d = abs(h*(dy(i) - nxt(1, i)))
                    err = max(err, d/(e + 16.0_qp*epsilon(1.0_qp)*(abs(ynew(i)) + &
                                                                   abs(h*dy(i)))))
                end do
                err = err/real(order + 1, qp)
                if (err <= 10.0_qp) exit
                if (.not. (err == err)) then
                    info = CM_NONFINITE
                    return
                end if
                h = 0.5_qp*h
            end do
            jet = nxt
            y = ynew
            nsteps = nsteps + 1
            if (hit) exit
            s = t + h                       ! (t, tlo) += h in double length
            bb = s - t
            lo = (t - (s - bb)) + (h - bb) + tlo
            t = s + lo
            tlo = lo - (t - s)
        end do
    end subroutine taylor_propagate_qp

end module conmech_taylor_quad
