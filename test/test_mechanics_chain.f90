!> Constrained systems that scale: the banded KKT path (diagonal mass, row-window
!! constraint Jacobian) agrees with the dense path to round-off; projections and residuals
!! at round-off for a chain of pendulums; redundant constraints still take the
!! rank-revealing dense path.
module test_chain_systems
    use conmech_kinds, only: dp
    use conmech_constrained_system, only: constrained_system
    use conmech_systems_chain, only: pendulum_chain_xy
    implicit none
    private
    public :: twice_pendulum, skew_mass, coupled_chain

    !> The chain of pendulums with a constant block-diagonal mass (2 x 2 blocks [m c; c m]
    !! per point): M^-1 is banded (bm = 1), kept by prepare_mass for the banded path.
    type, extends(pendulum_chain_xy) :: coupled_chain
        real(dp) :: c = 0.3_dp
    contains
        procedure :: mass => cc_mass
    end type coupled_chain



    !> A point mass with the same circle constraint twice (redundant: rank 1), with a
    !! declared diagonal mass and row windows of width 2 (the default band routines).
    type, extends(constrained_system) :: twice_pendulum
    contains
        procedure :: mass => tw_mass
        procedure :: forces => tw_forces
        procedure :: phi => tw_phi
        procedure :: phi_jac => tw_jac
        procedure :: phi_gamma => tw_gamma
    end type twice_pendulum

    !> A constant, non-diagonal mass on the unit circle (for the kept mass factor).
    type, extends(twice_pendulum) :: skew_mass
    contains
        procedure :: mass => sk_mass
        procedure :: phi => sk_phi
        procedure :: phi_jac => sk_jac
    end type skew_mass

contains

    subroutine tw_mass(self, t, q, mm)
        class(twice_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = 0.0_dp
        mm(1, 1) = 1.0_dp
        mm(2, 2) = 1.0_dp
    end subroutine tw_mass
    subroutine tw_forces(self, t, q, v, f)
        class(twice_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: f(:)
        f = [0.0_dp, -9.81_dp]
    end subroutine tw_forces
    subroutine tw_phi(self, t, q, c)
        class(twice_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c = 0.5_dp*(q(1)**2 + q(2)**2 - 1.0_dp)
    end subroutine tw_phi
    subroutine tw_jac(self, t, q, g)
        class(twice_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        g(1, :) = q
        g(2, :) = q
    end subroutine tw_jac
    subroutine tw_gamma(self, t, q, v, gam)
        class(twice_pendulum), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp), intent(out) :: gam(:)
        gam = -sum(v**2)
    end subroutine tw_gamma

    subroutine sk_mass(self, t, q, mm)
        class(skew_mass), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        mm = reshape([2.0_dp, 0.5_dp, 0.5_dp, 1.0_dp], [2, 2])
    end subroutine sk_mass
    subroutine sk_phi(self, t, q, c)
        class(skew_mass), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: c(:)
        c(1) = 0.5_dp*(q(1)**2 + q(2)**2 - 1.0_dp)
    end subroutine sk_phi
    subroutine sk_jac(self, t, q, g)
        class(skew_mass), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: g(:, :)
        g(1, :) = q
    end subroutine sk_jac

    subroutine cc_mass(self, t, q, mm)
        class(coupled_chain), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        real(dp), intent(out) :: mm(:, :)
        integer :: i
        mm = 0.0_dp
        do i = 1, size(q), 2
            mm(i, i) = self%m
            mm(i + 1, i + 1) = self%m
            mm(i, i + 1) = self%c*self%m
            mm(i + 1, i) = self%c*self%m
        end do
    end subroutine cc_mass

end module test_chain_systems

program test_mechanics_chain
    use conmech
    use conmech_systems_chain, only: pendulum_chain_xy
    use conmech_testing, only: test_suite
    use test_chain_systems, only: twice_pendulum, skew_mass, coupled_chain
    use conmech_systems_trailer, only: trailer_chain, trailer_initial_state
    implicit none
    type(test_suite) :: ts
    class(constrained_system), allocatable :: band, dense, pend
    type(constrained_options) :: opt
    type(constrained_result) :: res
    type(twice_pendulum) :: tw
    type(skew_mass) :: sk
    type(coupled_chain) :: cc, ccd
    type(trailer_chain) :: tr, trd
    type(constrained_result) :: res2
    real(dp), allocatable :: q0(:), v0(:), q(:), v(:), qd(:), vd(:)
    real(dp), allocatable :: a1(:), a2(:), l1(:), l2(:)
    real(dp) :: e0, rp, rv, rp2, rv2
    integer :: info, it, rk, nl, i
    character(len=:), allocatable :: msg

    ts%name = "test_mechanics_chain"
    nl = 7
    call make_constrained("pendulum_chain_xy", [real(nl, dp), 1.3_dp, 0.7_dp, 9.81_dp], band, &
                          info, msg)
    call ts%check(info == CM_SUCCESS .and. band%n == 2*nl .and. band%n_hol == nl .and. &
                  band%diagonal_mass .and. band%jac_width == 4, "chain: built, band declared")
    allocate (dense, source=band)
    dense%diagonal_mass = .false.
    dense%jac_width = 0
    call mech_initial_state("pendulum_chain_xy", [real(nl, dp), 1.3_dp, 0.7_dp], q0, v0, info)
    ! a moving, slightly inconsistent state
    q = q0 + 1.0e-3_dp*[(sin(1.0_dp*i), i=1, 2*nl)]
    v = [(cos(0.7_dp*i), i=1, 2*nl)]
    allocate (a1(2*nl), a2(2*nl), l1(nl), l2(nl))

    ! ---- accelerations and multipliers: banded = dense
    call constrained_accel(band, 0.0_dp, q, v, a1, l1, info, rank=rk)
    call constrained_accel(dense, 0.0_dp, q, v, a2, l2, info)
    call ts%check(rk == nl, "banded path: full rank")
    call ts%check_less(maxval(abs(a1 - a2))/maxval(abs(a2)), 1.0e-12_dp, &
                      "accelerations: banded vs dense (relative)")
    call ts%check_less(maxval(abs(l1 - l2))/maxval(abs(l2)), 1.0e-12_dp, &
                      "multipliers: banded vs dense (relative)")
    call constrained_accel(band, 0.0_dp, q, v, a1, l1, info, alpha=3.0_dp, beta=4.0_dp)
    call constrained_accel(dense, 0.0_dp, q, v, a2, l2, info, alpha=3.0_dp, beta=4.0_dp)
    call ts%check_less(maxval(abs(a1 - a2))/maxval(abs(a2)), 1.0e-12_dp, &
                      "Baumgarte accelerations: banded vs dense")

    ! ---- one link is the Cartesian pendulum
    call make_constrained("pendulum_chain_xy", [1.0_dp, 1.3_dp, 0.7_dp], band, info, msg)
    call make_constrained("pendulum_xy", [1.3_dp, 9.81_dp, 0.7_dp], pend, info, msg)
    call constrained_accel(band, 0.0_dp, q(1:2), v(1:2), a1(1:2), l1(1:1), info)
    call constrained_accel(pend, 0.0_dp, q(1:2), v(1:2), a2(1:2), l2(1:1), info)
    call ts%check_less(maxval(abs(a1(1:2) - a2(1:2))) + abs(l1(1) - l2(1)), 1.0e-13_dp, &
                      "N = 1 is pendulum_xy")

    ! ---- projections: banded = dense, residuals at round-off
    call make_constrained("pendulum_chain_xy", [real(nl, dp), 1.3_dp, 0.7_dp, 9.81_dp], band, &
                          info, msg)
    qd = q
    vd = v
    call project_position(band, 0.0_dp, q, 1.0e-14_dp, 10, it, info, msg)
    call project_position(dense, 0.0_dp, qd, 1.0e-14_dp, 10, it, info, msg)
    call ts%check(info == CM_SUCCESS, "position projection converges")
    call ts%check_less(maxval(abs(q - qd)), 1.0e-13_dp, "position projection: banded = dense")
    call project_velocity(band, 0.0_dp, q, v, info, msg)
    call project_velocity(dense, 0.0_dp, q, vd, info, msg)
    call ts%check_less(maxval(abs(v - vd)), 1.0e-13_dp, "velocity projection: banded = dense")
    call constraint_residuals(band, 0.0_dp, q, v, rp, rv)
    call constraint_residuals(dense, 0.0_dp, q, v, rp2, rv2)
    call ts%check_less(max(rp, rv), 1.0e-13_dp, "residuals after projection at round-off")
    call ts%check_less(abs(rv - rv2), 1.0e-14_dp, "velocity residual: banded = dense")

    ! ---- a projected run: residuals at round-off, energy kept
    opt%ode%method = METHOD_DOP853
    opt%ode%rtol = 1.0e-10_dp
    opt%ode%atol = 1.0e-10_dp
    opt%save_steps = .false.
    call constrained_solve(band, [0.0_dp, 3.0_dp], q0, v0, opt, res)
    call ts%check(res%success, "chain of 7: constrained_solve succeeds: "//res%message)
    call ts%check_less(maxval(res%res_pos) + maxval(res%res_vel), 1.0e-12_dp, &
                      "chain of 7: residuals at round-off")
    e0 = res%energy(1)
    call ts%check_less(abs(res%energy(res%nt) - e0)/abs(e0), 1.0e-8_dp, &
                      "chain of 7: energy conserved")

    ! ---- redundant constraints with a declared band: the dense rank-revealing path
    tw%n = 2
    tw%n_hol = 2
    tw%diagonal_mass = .true.
    tw%jac_width = 2
    call make_constrained("pendulum_xy", [1.0_dp, 9.81_dp, 1.0_dp], pend, info, msg)
    q = [0.6_dp, -0.8_dp]
    v = [0.8_dp, 0.6_dp]
    call constrained_accel(tw, 0.0_dp, q, v, a1(1:2), l1(1:2), info, rank=rk)
    call constrained_accel(pend, 0.0_dp, q, v, a2(1:2), l2(1:1), info)
    call ts%check(info == CM_SUCCESS .and. rk == 1, "redundant pair: rank 1")
    call ts%check_less(maxval(abs(a1(1:2) - a2(1:2))), 1.0e-12_dp, &
                      "redundant pair: the pendulum's acceleration")
    call ts%check_less(abs(l1(1) - 0.5_dp*l2(1)) + abs(l1(2) - 0.5_dp*l2(1)), 1.0e-12_dp, &
                      "redundant pair: minimum-norm multipliers (halves)")

    ! ---- a constant mass: factorised once (prepare_mass), the same results
    sk%n = 2
    sk%n_hol = 1
    q = [0.6_dp, -0.8_dp]
    v = [0.8_dp, 0.6_dp]
    call constrained_accel(sk, 0.0_dp, q, v, a2(1:2), l2(1:1), info)
    sk%constant_mass = .true.
    call prepare_mass(sk, 0.0_dp, q)
    call ts%check(allocated(sk%mass_factor), "constant mass: factor kept")
    call constrained_accel(sk, 0.0_dp, q, v, a1(1:2), l1(1:1), info)
    call ts%check(all(a1(1:2) == a2(1:2)) .and. l1(1) == l2(1), &
                  "constant mass: the kept factor gives the same accelerations")
    call constrained_solve(sk, [0.0_dp, 2.0_dp], q, v, opt, res)
    call ts%check(res%success .and. maxval(res%res_pos) < 1.0e-13_dp, &
                  "constant mass: projected run, residual at round-off")
    sk%constant_mass = .false.
    call prepare_mass(sk, 0.0_dp, q)
    call ts%check(.not. allocated(sk%mass_factor), "not constant: no factor kept")

    ! ---- a constant block-diagonal mass: M^-1 kept in band form, banded = dense
    cc%n = 2*nl
    cc%n_hol = nl
    cc%m = 1.3_dp
    cc%l = 0.7_dp
    cc%constant_mass = .true.
    cc%jac_width = 4
    ccd = cc
    ccd%jac_width = 0
    call prepare_mass(cc, 0.0_dp, q0)
    call prepare_mass(ccd, 0.0_dp, q0)
    call ts%check(allocated(cc%mass_inv_band) .and. allocated(cc%mass_factor), &
                  "block-diagonal constant mass: M^-1 kept in band form")
    if (allocated(cc%mass_inv_band)) call ts%check(lbound(cc%mass_inv_band, 2) == -1, &
                                                   "block-diagonal constant mass: bm = 1")
    q = q0 + 1.0e-3_dp*[(sin(1.0_dp*i), i=1, 2*nl)]
    v = [(cos(0.7_dp*i), i=1, 2*nl)]
    call constrained_accel(cc, 0.0_dp, q, v, a1, l1, info, rank=rk)
    call constrained_accel(ccd, 0.0_dp, q, v, a2, l2, info)
    call ts%check(info == CM_SUCCESS .and. rk == nl, "coupled mass: banded path, full rank")
    call ts%check_less(maxval(abs(a1 - a2))/maxval(abs(a2)) + &
                      maxval(abs(l1 - l2))/maxval(abs(l2)), 1.0e-12_dp, &
                      "coupled mass: accelerations and multipliers banded = dense")
    call constrained_accel(cc, 0.0_dp, q, v, a1, l1, info, alpha=3.0_dp, beta=4.0_dp)
    call constrained_accel(ccd, 0.0_dp, q, v, a2, l2, info, alpha=3.0_dp, beta=4.0_dp)
    call ts%check_less(maxval(abs(a1 - a2))/maxval(abs(a2)), 1.0e-12_dp, &
                      "coupled mass: Baumgarte accelerations banded = dense")
    qd = q
    vd = v
    call project_position(cc, 0.0_dp, q, 1.0e-14_dp, 10, it, info, msg)
    call project_position(ccd, 0.0_dp, qd, 1.0e-14_dp, 10, it, info, msg)
    call ts%check(info == CM_SUCCESS .and. maxval(abs(q - qd)) < 1.0e-13_dp, &
                  "coupled mass: position projection banded = dense")
    call project_velocity(cc, 0.0_dp, q, v, info, msg)
    call project_velocity(ccd, 0.0_dp, q, vd, info, msg)
    call ts%check(info == CM_SUCCESS .and. maxval(abs(v - vd)) < 1.0e-13_dp, &
                  "coupled mass: velocity projection banded = dense")
    call constrained_solve(cc, [0.0_dp, 2.0_dp], q0, v0, opt, res)
    call constrained_solve(ccd, [0.0_dp, 2.0_dp], q0, v0, opt, res2)
    call ts%check(res%success .and. res2%success, "coupled mass: both runs succeed")
    call ts%check_less(maxval(abs(res%q(:, res%nt) - res2%q(:, res2%nt))), 1.0e-8_dp, &
                      "coupled mass: banded run = dense run (to the tolerance)")
    call ts%check_less(maxval(res%res_pos) + maxval(res%res_vel), 1.0e-12_dp, &
                      "coupled mass: residuals at round-off")

    ! ---- holonomic and Pfaffian rows interleaved (an N-trailer): banded = dense
    tr%n = 2*nl
    tr%n_hol = nl - 1
    tr%n_nh = nl - 1
    tr%diagonal_mass = .true.
    tr%constant_mass = .true.
    tr%jac_width = 4
    tr%nh_width = 2
    trd = tr
    trd%jac_width = 0
    trd%nh_width = 0
    q = [(0.7_dp*i, 0.2_dp*sin(1.0_dp*i), i=1, nl)]
    q = q + 1.0e-3_dp*[(cos(1.3_dp*i), i=1, 2*nl)]
    v = [(sin(0.9_dp*i), i=1, 2*nl)]
    call project_position(trd, 0.0_dp, q, 1.0e-14_dp, 20, it, info, msg, newton=.true.)
    call ts%check(info == CM_SUCCESS, "trailer: consistent positions (dense)")
    qd = q
    vd = v
    call project_velocity(tr, 0.0_dp, q, v, info, msg)
    call project_velocity(trd, 0.0_dp, q, vd, info, msg)
    call ts%check(info == CM_SUCCESS .and. maxval(abs(v - vd)) < 1.0e-13_dp, &
                  "trailer: velocity projection banded = dense")
    call constraint_residuals(tr, 0.0_dp, q, v, rp, rv)
    call constraint_residuals(trd, 0.0_dp, q, v, rp2, rv2)
    call ts%check(rv < 1.0e-13_dp .and. abs(rv - rv2) < 1.0e-14_dp .and. rp == rp2, &
                  "trailer: residuals banded = dense, at round-off")
    deallocate (l1, l2)
    allocate (l1(2*nl - 2), l2(2*nl - 2))
    call constrained_accel(tr, 0.0_dp, q, v, a1, l1, info, rank=rk)
    call constrained_accel(trd, 0.0_dp, q, v, a2, l2, info)
    call ts%check(info == CM_SUCCESS .and. rk == 2*nl - 2, "trailer: banded path, full rank")
    call ts%check_less(maxval(abs(a1 - a2))/maxval(abs(a2)) + &
                      maxval(abs(l1 - l2))/maxval(abs(l2)), 1.0e-12_dp, &
                      "trailer: accelerations and multipliers banded = dense")
    call constrained_accel(tr, 0.0_dp, q, v + 0.01_dp, a1, l1, info, alpha=3.0_dp, beta=4.0_dp)
    call constrained_accel(trd, 0.0_dp, q, v + 0.01_dp, a2, l2, info, alpha=3.0_dp, &
                           beta=4.0_dp)
    call ts%check_less(maxval(abs(a1 - a2))/maxval(abs(a2)), 1.0e-12_dp, &
                      "trailer: Baumgarte accelerations banded = dense")
    call constraint_reaction(tr, 0.0_dp, q, l1, a1)
    call constraint_reaction(trd, 0.0_dp, q, l1, a2)
    call ts%check_less(maxval(abs(a1 - a2)), 1.0e-14_dp*maxval(abs(a2)), &
                      "trailer: reactions banded = dense")
    call constrained_solve(tr, [0.0_dp, 2.0_dp], q, v, opt, res)
    call constrained_solve(trd, [0.0_dp, 2.0_dp], q, v, opt, res2)
    call ts%check(res%success .and. res2%success, "trailer: both runs succeed")
    call ts%check_less(maxval(abs(res%q(:, res%nt) - res2%q(:, res2%nt))), 1.0e-8_dp, &
                      "trailer: banded run = dense run (to the tolerance)")
    call ts%check_less(maxval(res%res_pos) + maxval(res%res_vel), 1.0e-12_dp, &
                      "trailer: residuals at round-off")

    ! ---- bad N
    call make_constrained("pendulum_chain_xy", [2.5_dp], band, info, msg)
    call ts%check(info == CM_BAD_INPUT .and. index(msg, "whole number") > 0, &
                  "N = 2.5: bad input")
    ! gfortran keeps the main program's allocatables on its stack, not in static storage:
    ! free them, or LeakSanitizer reports them as leaked
    if (allocated(msg)) deallocate (msg)
    if (allocated(q0)) deallocate (q0, v0)
    if (allocated(q)) deallocate (q)
    if (allocated(v)) deallocate (v)
    if (allocated(qd)) deallocate (qd)
    if (allocated(vd)) deallocate (vd)
    if (allocated(a1)) deallocate (a1, a2, l1, l2)
    if (allocated(band)) deallocate (band)
    if (allocated(dense)) deallocate (dense)
    if (allocated(pend)) deallocate (pend)
    call ts%finish()
end program test_mechanics_chain
