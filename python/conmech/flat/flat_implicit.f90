!> Flat f2py layer of the implicit integrators (Radau IIA, Gauss-Legendre); conventions:
!! see flat_ode.f90. counts = [nfev, njev, nlu, naccept, nreject].

!> Solve y' = fun(t, y) with an implicit method (5 RADAU5, 6 GAUSS4, 7 GAUSS6) for a Python
!! right-hand side and, if has_jac /= 0, a Python Jacobian jac(t, y) -> (n, n) (else
!! forward differences). Other arguments as flat_solve_callback.
subroutine flat_solve_implicit_callback(fun, jac, events, store, n, t_span, y0, method, &
                                        has_jac, rtol, atol, first_step, max_step, &
                                        max_steps, dense, neval, t_eval, ne, ev_dir, &
                                        ev_term, counts, dense_form, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_flat_ode_support, only: callback_jac_system
    use conmech_flat_implicit_support, only: run_implicit
    implicit none
    integer(c_int), intent(in) :: n
    real(c_double), intent(in) :: t_span(2)
    real(c_double), intent(in) :: y0(n)
    integer(c_int), intent(in) :: method, has_jac
    real(c_double), intent(in) :: rtol(n), atol(n)
    real(c_double), intent(in) :: first_step, max_step
    integer(c_int), intent(in) :: max_steps, dense, neval
    real(c_double), intent(in) :: t_eval(max(neval, 1))
    integer(c_int), intent(in) :: ne
    integer(c_int), intent(in) :: ev_dir(max(ne, 1)), ev_term(max(ne, 1))
    integer(c_int), intent(out) :: counts(5), dense_form, info
    character(len=256), intent(out) :: message
!f2py external fun, jac, events, store
    interface
        subroutine fun(t, y, dydt, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dydt(n)
        end subroutine fun
        subroutine jac(t, y, dfdy, n)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: dfdy(n, n)
        end subroutine jac
        subroutine events(t, y, g, n, ne)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n, ne
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: g(ne)
        end subroutine events
        subroutine store(t, y, ev_t, ev_y, ev_id, ts, hs, coef, n, nt, nev, nseg, nf1)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n, nt, nev, nseg, nf1
            real(c_double), intent(in) :: t(nt)
            real(c_double), intent(in) :: y(n, nt)
            real(c_double), intent(in) :: ev_t(nev)
            real(c_double), intent(in) :: ev_y(n, nev)
            integer(c_int), intent(in) :: ev_id(nev)
            real(c_double), intent(in) :: ts(nseg)
            real(c_double), intent(in) :: hs(nseg)
            real(c_double), intent(in) :: coef(n, nf1, nseg)
        end subroutine store
    end interface
    type(callback_jac_system) :: sys

    sys%f => fun
    sys%n = n
    if (has_jac /= 0) sys%jac => jac
    call run_implicit(sys, n, t_span, y0, method, rtol, atol, first_step, max_step, &
                      max_steps, dense, neval, t_eval, ne, ev_dir, ev_term, events, store, &
                      counts, dense_form, info, message)
end subroutine flat_solve_implicit_callback

!> The built-in system `name` (parameters as flat_solve_builtin) with an implicit method;
!! its analytic Jacobian if it has one, else forward differences.
subroutine flat_solve_implicit_builtin(name, np, params, nspec, spec, events, store, n, &
                                       t_span, y0, &
                                       method, rtol, atol, first_step, max_step, max_steps, &
                                       dense, neval, t_eval, ne, ev_dir, ev_term, counts, &
                                       dense_form, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_flat_spec, only: spec_system, spec_dimension
    use conmech_flat_ode_support, only: copy_message
    use conmech_flat_implicit_support, only: run_implicit
    implicit none
    character(len=*), intent(in) :: name
    integer(c_int), intent(in) :: np
    real(c_double), intent(in) :: params(max(np, 1))
    integer(c_int), intent(in) :: nspec
    integer(8), intent(in) :: spec(max(nspec, 1))  ! c_int64_t (f2py: long_long)
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
    integer(c_int), intent(out) :: counts(5), dense_form, info
    character(len=256), intent(out) :: message
!f2py external events, store
    interface
        subroutine events(t, y, g, n, ne)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n, ne
            real(c_double), intent(in) :: t
            real(c_double), intent(in) :: y(n)
            real(c_double), intent(out) :: g(ne)
        end subroutine events
        subroutine store(t, y, ev_t, ev_y, ev_id, ts, hs, coef, n, nt, nev, nseg, nf1)
            use, intrinsic :: iso_c_binding, only: c_double, c_int
            integer(c_int), intent(in) :: n, nt, nev, nseg, nf1
            real(c_double), intent(in) :: t(nt)
            real(c_double), intent(in) :: y(n, nt)
            real(c_double), intent(in) :: ev_t(nev)
            real(c_double), intent(in) :: ev_y(n, nev)
            integer(c_int), intent(in) :: ev_id(nev)
            real(c_double), intent(in) :: ts(nseg)
            real(c_double), intent(in) :: hs(nseg)
            real(c_double), intent(in) :: coef(n, nf1, nseg)
        end subroutine store
    end interface
    class(ode_system), allocatable :: sys
    character(len=:), allocatable :: msg
    character(len=24) :: buf

    counts = 0
    dense_form = 0
    call spec_system(name, real(params(1:np), dp), nspec, spec, sys, info, msg)
    if (info /= CM_SUCCESS) then
        call copy_message(msg, message)
        return
    end if
    if (spec_dimension(name, nspec, spec) /= n) then
        info = CM_BAD_INPUT
        write (buf, '(i0)') spec_dimension(name, nspec, spec)
        call copy_message("bad input: y0 must have size "//trim(buf)//" for the system '" &
                          //trim(name)//"'", message)
        return
    end if
    call run_implicit(sys, n, t_span, y0, method, rtol, atol, first_step, max_step, &
                      max_steps, dense, neval, t_eval, ne, ev_dir, ev_term, events, store, &
                      counts, dense_form, info, message)
end subroutine flat_solve_implicit_builtin
