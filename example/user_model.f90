!> Users' models from Python formulas to a pure-Fortran run (no Python at run time):
!! cart_pendulum_model.f90 beside this file was written by
!!
!!     python -m conmech.symbolic emit example/models/cart_pendulum.py \
!!         -o example/cart_pendulum_model.f90
!!
!! from the pendulum on a cart of seed 000 (T and U in example/models/cart_pendulum.py), and
!! arenstorf_model.f90 likewise from example/models/arenstorf.py (a first-order system).
!! This program integrates them (DOP853, exact Jacobians in the variational equations),
!! checks the seed's conservation laws, and prints the final states for comparison.
!!   fpm run --example user_model
program user_model
    use conmech
    use arenstorf_model, only: arenstorf_sym, new_arenstorf_sym
    use cart_pendulum_model, only: cart_pendulum_sym, cart_pendulum_sym_mech, &
                                   new_cart_pendulum_sym, new_cart_pendulum_sym_mech
    implicit none
    type(cart_pendulum_sym) :: sys
    type(cart_pendulum_sym_mech) :: mech
    type(arenstorf_sym) :: aren
    type(ode_options) :: opt
    type(ode_result) :: res, gres
    real(dp) :: y0(4), y(4), phi(4, 4), jex(4, 4), jfd(4, 4), p0, e0, de, dp_max
    real(dp) :: m0(2, 2), m1(2, 2), fa(4), fb(4)
    integer :: info, i
    character(len=:), allocatable :: msg

    sys = new_cart_pendulum_sym()
    mech = new_cart_pendulum_sym_mech()
    sys%g = 9.81_dp          ! parameters are components: change them freely
    opt%rtol = 1.0e-12_dp
    opt%atol = 1.0e-12_dp
    y0 = [0.3_dp, 2.5_dp, 0.4_dp, 1.0_dp]

    call ode_solve(sys, [0.0_dp, 5.0_dp], y0, opt, res)
    if (.not. res%success) then
        write (*, '(a)') "integration failed: "//res%message
        stop 1
    end if
    ! seed 000: momentum P = 2 x' + cos(th) th' and the energy are conserved
    p0 = 2.0_dp*y0(3) + cos(y0(2))*y0(4)
    e0 = sys%energy(0.0_dp, y0)
    de = 0.0_dp
    dp_max = 0.0_dp
    do i = 1, res%nt
        de = max(de, abs(sys%energy(res%t(i), res%y(:, i)) - e0))
        dp_max = max(dp_max, abs(2.0_dp*res%y(3, i) + cos(res%y(2, i))*res%y(4, i) - p0))
    end do
    write (*, '(a, i0, a)') "steps: ", res%stats%naccept, " (DOP853, rtol 1e-12)"
    write (*, '(a, 4es24.16)') "y(5): ", res%y(:, res%nt)
    write (*, '(a, es10.2)') "energy drift: ", de
    write (*, '(a, es10.2)') "momentum drift: ", dp_max

    ! the same model as a generalized_system through generalized_solve
    call generalized_solve(mech, [0.0_dp, 5.0_dp], y0(1:2), y0(3:4), opt, gres)
    write (*, '(a, es10.2)') "generalized_solve vs ode_solve: ", &
        maxval(abs(gres%y(:, gres%nt) - res%y(:, res%nt)))

    ! the exact Jacobian against conmech's finite-difference default
    call sys%jacobian(0.0_dp, y0, jex)
    call fd_jac(sys, y0, jfd)
    write (*, '(a, es10.2)') "exact vs finite-difference Jacobian: ", maxval(abs(jex - jfd))

    ! state transition matrix over [0, 1] with the exact Jacobian; Liouville in (q, p = M v):
    ! det(STM) det M(q(1)) / det M(q(0)) = 1
    y = y0
    phi = 0.0_dp
    do i = 1, 4
        phi(i, i) = 1.0_dp
    end do
    call integrate_stm(sys, 0.0_dp, 1.0_dp, y, phi, opt, info, msg)
    call mech%mass(0.0_dp, y0(1:2), m0)
    call mech%mass(1.0_dp, y(1:2), m1)
    write (*, '(a, es10.2)') "Liouville det(STM) det M(q1)/det M(q0) - 1: ", &
        la_det(phi)*la_det(m1)/la_det(m0) - 1.0_dp

    ! the Arenstorf orbit: one period, and its monodromy matrix with the exact Jacobian
    aren = new_arenstorf_sym()
    ! its Jacobian product (integrate_stm's path: f and J Phi in one call, J not formed)
    ! against the dense Jacobian times the same block
    y = [0.7_dp, -0.4_dp, 0.3_dp, 0.9_dp]
    phi = reshape([(sin(0.9_dp*i), i=1, 16)], [4, 4])
    call aren%jacobian(0.0_dp, y, jex)
    call aren%rhs_jacobian_product(0.0_dp, 4, 4, y, fa, phi, jfd)
    call aren%rhs(0.0_dp, y, fb)
    write (*, '(a, 2es10.2)') "arenstorf J x vs dense J times x, f vs rhs: ", &
        maxval(abs(jfd - matmul(jex, phi)))/maxval(abs(jfd)), maxval(abs(fa - fb))
    y = [0.994_dp, 0.0_dp, 0.0_dp, -2.00158510637908252240537862224_dp]
    y0 = y
    phi = 0.0_dp
    do i = 1, 4
        phi(i, i) = 1.0_dp
    end do
    opt%rtol = 1.0e-13_dp
    opt%atol = 1.0e-13_dp
    call integrate_stm(aren, 0.0_dp, 17.0652165601579625588917206249_dp, y, phi, opt, info, &
                       msg)
    write (*, '(a, es10.2)') "arenstorf closure |y(T) - y(0)|: ", maxval(abs(y - y0))
    write (*, '(a, es24.16)') "arenstorf monodromy trace: ", phi(1, 1) + phi(2, 2) &
        + phi(3, 3) + phi(4, 4)
    write (*, '(a, es10.2)') "arenstorf det(monodromy) - 1: ", la_det(phi) - 1.0_dp

contains

    !> Central differences of the right-hand side (independent of the emitted Jacobian).
    subroutine fd_jac(s, yy, j)
        type(cart_pendulum_sym), intent(in) :: s
        real(dp), intent(in) :: yy(:)
        real(dp), intent(out) :: j(:, :)
        real(dp) :: yp(size(yy)), fp(size(yy)), fm(size(yy)), h
        integer :: k
        do k = 1, size(yy)
            h = 1.0e-6_dp*max(abs(yy(k)), 1.0_dp)
            yp = yy
            yp(k) = yy(k) + h
            call s%rhs(0.0_dp, yp, fp)
            yp(k) = yy(k) - h
            call s%rhs(0.0_dp, yp, fm)
            j(:, k) = (fp - fm)/(2.0_dp*h)
        end do
    end subroutine fd_jac

end program user_model
