!> A multibody tree from Python to a pure-Fortran run: tree_chain_model.f90 beside this
!! file was written by
!!
!!     python -m conmech.symbolic emit example/models/tree_chain.py \
!!         -o example/tree_chain_model.f90
!!
!! from a triple pendulum described as bodies on revolute joints (conmech.symbolic.Body,
!! absolute angles). The emitted type's right-hand side is the articulated-body algorithm
!! (O(n), no matrix); its `_mech` twin gives M and Q from the Lagrangian, which
!! generalized_solve factorises (Cholesky). This program integrates both, checks that they
!! agree and that the energy is conserved, and prints the final state.
!!   fpm run --example user_tree
program user_tree
    use conmech
    use tree_chain_model, only: tree_chain_sym, tree_chain_sym_mech, new_tree_chain_sym, &
                                new_tree_chain_sym_mech
    implicit none
    type(tree_chain_sym) :: sys
    type(tree_chain_sym_mech) :: mech
    type(ode_options) :: opt
    type(ode_result) :: res, gres
    real(dp) :: y0(6), e0, de
    integer :: i

    sys = new_tree_chain_sym()
    mech = new_tree_chain_sym_mech()
    opt%rtol = 1.0e-12_dp
    opt%atol = 1.0e-12_dp
    y0 = [0.9_dp, 0.6_dp, 0.3_dp, 0.0_dp, 0.5_dp, -0.4_dp]

    call ode_solve(sys, [0.0_dp, 5.0_dp], y0, opt, res)
    if (.not. res%success) then
        write (*, '(a)') "integration failed: "//res%message
        stop 1
    end if
    e0 = sys%energy(0.0_dp, y0)
    de = 0.0_dp
    do i = 1, res%nt
        de = max(de, abs(sys%energy(res%t(i), res%y(:, i)) - e0))
    end do
    write (*, '(a, i0, a)') "steps: ", res%stats%naccept, " (DOP853, rtol 1e-12)"
    write (*, '(a, 6es24.16)') "y(5): ", res%y(:, res%nt)
    write (*, '(a, es10.2)') "energy drift: ", de

    ! the same tree through M and Q of its Lagrangian (Cholesky in generalized_solve)
    call generalized_solve(mech, [0.0_dp, 5.0_dp], y0(1:3), y0(4:6), opt, gres)
    if (.not. gres%success) then
        write (*, '(a)') "generalized_solve failed: "//gres%message
        stop 1
    end if
    write (*, '(a, es10.2)') "articulated-body vs Cholesky: ", &
        maxval(abs(gres%y(:, gres%nt) - res%y(:, res%nt)))
end program user_tree
