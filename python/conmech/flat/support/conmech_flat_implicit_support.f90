!> Support of the flat f2py layer for the implicit integrators (Radau IIA, Gauss): a
!! `run_implicit`, which runs
!! `ode_solve` with an implicit method and hands the result, with the Jacobian and LU
!! counts, to a `store` procedure (conventions of conmech_flat_ode_support).
!!
!!     fun(t, y, dydt, n)         real(c_double) t, y(n), dydt(n)
!!     jac(t, y, dfdy, n)         real(c_double) t, y(n), dfdy(n, n)   (if associated)
!! (the systems are conmech_flat_ode_support's callback_system / callback_jac_system)
module conmech_flat_implicit_support
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_status, only: CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_ode_solver, only: ode_options, ode_result, ode_solve, METHOD_RADAU5, &
        METHOD_GAUSS6
    use conmech_flat_ode_support, only: callback_events, copy_message
    implicit none
    private
    public :: run_implicit

contains

    !> Run `ode_solve` with an implicit method from plain arguments (see run_solve of
    !! conmech_flat_ode_support); counts(1:5) = [nfev, njev, nlu, naccept, nreject].
    subroutine run_implicit(sys, n, t_span, y0, method, rtol, atol, first_step, max_step, &
                            max_steps, dense, neval, t_eval, ne, ev_dir, ev_term, events, &
                            store, counts, dense_form, info, message)
        class(ode_system), intent(in) :: sys
        integer(c_int), intent(in) :: n
        real(c_double), intent(in) :: t_span(2)
        real(c_double), intent(in) :: y0(n)
        integer(c_int), intent(in) :: method
        real(c_double), intent(in) :: rtol(n), atol(n)
        real(c_double), intent(in) :: first_step, max_step
        integer(c_int), intent(in) :: max_steps, dense, neval
        real(c_double), intent(in) :: t_eval(max(neval, 1))
        integer(c_int), intent(in) :: ne
        integer(c_int), intent(in) :: ev_dir(max(ne, 1)), ev_term(max(ne, 1))
        external :: events, store
        integer(c_int), intent(out) :: counts(5), dense_form, info
        character(len=*), intent(out) :: message
        type(ode_options) :: opt
        type(ode_result) :: res
        type(callback_events) :: ev
        real(c_double) :: empty1(0), empty3(n, 1, 0)
        integer :: nseg, nf1

        counts = 0
        dense_form = 0
        if (n < 1 .or. neval < 0 .or. ne < 0) then
            info = CM_BAD_INPUT
            call copy_message("bad input: array sizes must be positive", message)
            return
        end if
        if (method < METHOD_RADAU5 .or. method > METHOD_GAUSS6) then
            info = CM_BAD_INPUT
            call copy_message("bad input: not an implicit method", message)
            return
        end if
        opt%method = method
        opt%rtol_vec = rtol
        opt%atol_vec = atol
        opt%first_step = first_step
        opt%max_step = max_step
        opt%max_steps = max_steps
        opt%dense_output = dense /= 0
        if (ne > 0) then
            ev%g => events
            ev%n = n
            ev%ne = ne
            ev%direction = ev_dir(1:ne)
            ev%terminal = ev_term(1:ne) /= 0
            if (neval > 0) then
                call ode_solve(sys, t_span, y0, opt, res, t_eval=t_eval(1:neval), events=ev)
            else
                call ode_solve(sys, t_span, y0, opt, res, events=ev)
            end if
        else
            if (neval > 0) then
                call ode_solve(sys, t_span, y0, opt, res, t_eval=t_eval(1:neval))
            else
                call ode_solve(sys, t_span, y0, opt, res)
            end if
        end if
        counts = [res%stats%nfev, res%stats%njev, res%stats%nlu, res%stats%naccept, &
                  res%stats%nreject]
        info = res%status
        call copy_message(res%message, message)
        nseg = 0
        nf1 = 1
        if (opt%dense_output .and. allocated(res%sol%ts)) then
            nseg = res%sol%nseg
            nf1 = res%sol%nf + 1
            dense_form = res%sol%form
        end if
        if (.not. allocated(res%t)) return
        if (nseg > 0) then
            call store(res%t(1:res%nt), res%y(:, 1:res%nt), res%ev_t(1:res%nev), &
                       res%ev_y(:, 1:res%nev), res%ev_id(1:res%nev), res%sol%ts(1:nseg), &
                       res%sol%hs(1:nseg), res%sol%coef(:, :, 1:nseg), &
                       n, res%nt, res%nev, nseg, nf1)
        else
            call store(res%t(1:res%nt), res%y(:, 1:res%nt), res%ev_t(1:res%nev), &
                       res%ev_y(:, 1:res%nev), res%ev_id(1:res%nev), empty1, empty1, &
                       empty3, n, res%nt, res%nev, 0, 1)
        end if
    end subroutine run_implicit

end module conmech_flat_implicit_support
