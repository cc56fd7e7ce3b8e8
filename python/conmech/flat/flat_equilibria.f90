!> Flat f2py layer of the equilibrium structure: the full analysis of an equilibrium
!! (eigenvalues, Jordan structure on the imaginary axis, family of equilibria, drift,
!! classification), the classification of a plain matrix, the linearisation relative to
!! first integrals, and the degrees of freedom of a constrained system. Plain subroutines,
!! c_double/c_int explicit-shape arrays, an `info` code and a message. Nothing is saved
!! between calls; nothing stops or prints.
!!
!! Callback conventions (as in flat_ode.f90): fun(t, y, dydt, n), jfun(t, y, dfdy, n).

!> Full equilibrium analysis at y of the system given by the one flat argument set
!! (conmech_flat_system).
subroutine flat_equilibrium_structure(name, np, params, nspec, spec, fun, jfun, source, n, y, &
                                      t, tol, jac, wr, wi, kind, saddle, residual, analytic, &
                                      zero_mult, largest_block, secular_freq, family_dim, &
                                      family, ndrift, drift, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_ode_system, only: ode_system
    use conmech_flat_system, only: flat_system
    use conmech_equilibria, only: equilibrium_result, analyze_equilibrium
    use conmech_support_equilibria, only: unpack_structure
    implicit none
    integer(c_int), intent(in) :: n
    real(c_double), intent(in) :: y(n), t, tol
    real(c_double), intent(out) :: jac(n, n), wr(n), wi(n), residual, secular_freq
    real(c_double), intent(out) :: family(n, n), drift(n, n)
    integer(c_int), intent(out) :: kind, saddle, analytic, zero_mult, largest_block
    integer(c_int), intent(out) :: family_dim, ndrift, info
    character(len=256), intent(out) :: message
    include "flat_system_args.inc"
    class(ode_system), allocatable :: sys
    type(equilibrium_result) :: e
    call flat_system(name, params(1:np), nspec, spec, fun, jfun, source, n, sys, info, message)
    if (info /= 0) return
    call analyze_equilibrium(sys, y, e, t, tol)
    call unpack_structure(e, n, jac, wr, wi, kind, saddle, residual, analytic, zero_mult, &
                          largest_block, secular_freq, family_dim, family, ndrift, drift, &
                          info, message)
end subroutine flat_equilibrium_structure

!> Eigenvalues, Jordan structure and classification of a plain n x n matrix (no family).
subroutine flat_classify_matrix(n, a, tol, wr, wi, kind, saddle, zero_mult, largest_block, &
                                secular_freq, ndrift, drift, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_equilibria, only: equilibrium_result, classify_matrix
    use conmech_support_equilibria, only: unpack_structure
    implicit none
    integer(c_int), intent(in) :: n
    real(c_double), intent(in) :: a(n, n), tol
    real(c_double), intent(out) :: wr(n), wi(n), secular_freq, drift(n, n)
    integer(c_int), intent(out) :: kind, saddle, zero_mult, largest_block, ndrift, info
    character(len=256), intent(out) :: message
    type(equilibrium_result) :: e
    real(c_double) :: jac(n, n), residual, family(n, n)
    integer(c_int) :: analytic, family_dim
    call classify_matrix(a, e, tol)
    call unpack_structure(e, n, jac, wr, wi, kind, saddle, residual, analytic, zero_mult, &
                          largest_block, secular_freq, family_dim, family, ndrift, drift, &
                          info, message)
end subroutine flat_classify_matrix

!> Linearisation relative to first integrals (gradient rows grads(k, n)) and a family
!! (tangent family(n, d)): ar(1:m, 1:m) = W^T A W, W = w(:, 1:m)
!! (conmech_relative_equilibria).
subroutine flat_relative_linearization(n, k, d, a, grads, family, ar, w, m, info, message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_relative_equilibria, only: relative_linearization
    use conmech_flat_ode_support, only: copy_message
    implicit none
    integer(c_int), intent(in) :: n, k, d
    real(c_double), intent(in) :: a(n, n), grads(max(k, 1), n), family(n, max(d, 1))
    real(c_double), intent(out) :: ar(n, n), w(n, n)
    integer(c_int), intent(out) :: m, info
    character(len=256), intent(out) :: message
    character(len=:), allocatable :: msg
    call relative_linearization(a, grads(1:k, :), family(:, 1:d), ar, w, m, info, msg)
    call copy_message(msg, message)
end subroutine flat_relative_linearization

!> Degrees of freedom of a built-in or compiled constrained system at (t, q) (projected
!! onto the constraint manifold first when project /= 0); see conmech_degrees_of_freedom.
subroutine flat_degrees_of_freedom(name, np, params, nspec, spec, n, t, q, project, rank_tol, &
                                   qout, residual, rank_h, rank_nh, dof, velocity_dof, info, &
                                   message)
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_constrained_system, only: constrained_system
    use conmech_flat_spec, only: spec_constrained
    use conmech_degrees_of_freedom, only: dof_result, degrees_of_freedom
    use conmech_flat_ode_support, only: copy_message
    implicit none
    include "flat_spec_args.inc"
    integer(c_int), intent(in) :: n, project
    real(c_double), intent(in) :: t, q(n), rank_tol
    real(c_double), intent(out) :: qout(n), residual
    integer(c_int), intent(out) :: rank_h, rank_nh, dof, velocity_dof, info
    character(len=256), intent(out) :: message
    class(constrained_system), allocatable :: cs
    type(dof_result) :: r
    character(len=:), allocatable :: msg
    qout = q
    residual = 0.0_c_double
    rank_h = 0
    rank_nh = 0
    dof = 0
    velocity_dof = 0
    call spec_constrained(name, real(params(1:np), dp), nspec, spec, cs, info, msg)
    if (info == CM_SUCCESS .and. cs%n /= n) then
        info = CM_BAD_INPUT
        msg = "degrees_of_freedom: q has the wrong number of components"
    end if
    if (info /= CM_SUCCESS) then
        call copy_message(msg, message)
        return
    end if
    call degrees_of_freedom(cs, t, q, r, project /= 0, rank_tol)
    info = r%info
    call copy_message(r%message, message)
    if (info /= CM_SUCCESS) return
    qout = r%q
    residual = r%residual
    rank_h = r%rank_h
    rank_nh = r%rank_nh
    dof = r%dof
    velocity_dof = r%velocity_dof
end subroutine flat_degrees_of_freedom
