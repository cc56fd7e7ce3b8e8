"""Radau IIA (order 5) in conmech.solve_ivp: stiff problems against SciPy and published
values, the order, dense output and events, failures."""
import numpy as np
import pytest
import scipy.integrate as si

import conmech

EPS = 1e-6
GAM0 = 3.6378342527444957322   # real eigenvalue of the inverse Radau IIA matrix


def vdp(t, y):
    return [y[1], ((1 - y[0] ** 2) * y[1] - y[0]) / EPS]


def vdp_jac(t, y):
    return [[0.0, 1.0], [(-2 * y[0] * y[1] - 1) / EPS, (1 - y[0] ** 2) / EPS]]


def rober(t, y):
    return [-0.04 * y[0] + 1e4 * y[1] * y[2],
            0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] ** 2, 3e7 * y[1] ** 2]


def rober_jac(t, y):
    return [[-0.04, 1e4 * y[2], 1e4 * y[1]],
            [0.04, -1e4 * y[2] - 6e7 * y[1], -1e4 * y[1]], [0.0, 6e7 * y[1], 0.0]]


def test_van_der_pol_against_scipy():
    y0 = [2.0, -0.66]
    # reference y(2): SciPy's Radau at rtol = atol = 1e-12 (35 s, so stored here; conmech's
    # Radau at 1e-12 agrees to 4e-13)
    ref = np.array([1.706167437543211, -0.8928100165510839])
    r = conmech.solve_ivp(vdp, (0, 2), y0, method="Radau", rtol=1e-5, atol=1e-5, jac=vdp_jac)
    s = si.solve_ivp(vdp, (0, 2), y0, method="Radau", rtol=1e-5, atol=1e-5, jac=vdp_jac)
    assert r.success
    err, err_s = np.abs(r.y[:, -1] - ref).max(), np.abs(s.y[:, -1] - ref).max()
    assert err < 3 * err_s and err < 1e-6
    # same algorithmic family: steps, Jacobians and LUs within 20 % of SciPy's
    assert abs(r.naccept - (s.t.size - 1)) <= 0.2 * (s.t.size - 1)
    assert abs(r.njev - s.njev) <= 0.2 * s.njev
    assert abs(r.nlu - s.nlu) <= 0.2 * s.nlu
    # finite-difference Jacobian: same solution to the tolerance
    rf = conmech.solve_ivp(vdp, (0, 2), y0, method="Radau", rtol=1e-5, atol=1e-5)
    assert rf.success and np.abs(rf.y[:, -1] - ref).max() < 1e-6
    assert rf.nfev >= r.nfev + 2 * rf.njev - 2    # n = 2 evaluations per FD Jacobian


def test_robertson_to_1e11():
    r = conmech.solve_ivp(rober, (0, 1e11), [1.0, 0.0, 0.0], method="Radau", rtol=1e-6,
                          atol=1e-10, jac=rober_jac)
    assert r.success
    # conservation of y1 + y2 + y3 = 1 (a linear invariant: kept to round-off by any RK)
    assert np.abs(r.y.sum(axis=0) - 1).max() < 1e-13
    # published reference (Hairer-Wanner test set, RADAU5 at tol 1e-14) at t = 1e11
    ref = np.array([0.2083340149701255e-07, 0.8333360770334713e-13, 0.9999999791665050])
    assert np.allclose(r.y[:, -1], ref, rtol=2e-5, atol=0)
    assert r.naccept < 600


def test_order_five_work_precision():
    # harmonic oscillator: error at t = 10 against the number of steps -> slope -5
    ex = np.array([np.cos(10.0), -np.sin(10.0)])
    f = lambda t, y: [y[1], -y[0]]
    steps, errs = [], []
    for tol in (1e-6, 1e-8, 1e-10):
        r = conmech.solve_ivp(f, (0, 10), [1.0, 0.0], method="Radau", rtol=tol, atol=tol,
                              jac=[[0.0, 1.0], [-1.0, 0.0]])
        assert r.success
        steps.append(r.naccept)
        errs.append(np.abs(r.y[:, -1] - ex).max())
    slope = np.polyfit(np.log(steps), np.log(errs), 1)[0]
    assert -6.0 < slope < -4.0, slope


def test_dense_output_and_events():
    f = lambda t, y: [y[1], -y[0]]
    ev = lambda t, y: y[0]
    ev.direction = -1
    r = conmech.solve_ivp(f, (0, 10), [1.0, 0.0], method="Radau", rtol=1e-9, atol=1e-9,
                          dense_output=True, events=ev, t_eval=np.linspace(0, 10, 11))
    assert r.success and r.njev >= 1
    assert np.allclose(r.t_events[0], [np.pi / 2, 5 * np.pi / 2], atol=1e-7)
    tt = np.linspace(0, 10, 101)
    assert np.abs(r.sol(tt)[0] - np.cos(tt)).max() < 1e-6
    assert np.abs(r.y[0] - np.cos(r.t)).max() < 1e-7
    ev.terminal = True
    r = conmech.solve_ivp(f, (0, 10), [1.0, 0.0], method="Radau", rtol=1e-9, atol=1e-9,
                          events=ev)
    assert r.status == 1 and abs(r.t[-1] - np.pi / 2) < 1e-7


def test_builtin_system():
    sys = conmech.systems.kepler(mu=1.0) if hasattr(conmech.systems, "kepler") else None
    if sys is None:
        pytest.fail("conmech.systems.kepler missing")
    y0 = [1.0, 0.0, 0.0, 1.0]
    r = conmech.solve_ivp(sys, (0, 2 * np.pi), y0, method="Radau", rtol=1e-10, atol=1e-10)
    assert r.success and np.abs(r.y[:, -1] - y0).max() < 1e-7
    with pytest.raises(TypeError):
        conmech.solve_ivp(sys, (0, 1), y0, method="Radau", jac=np.eye(4))


def test_newton_failure_stops_with_time():
    # y' = y^2, y(0) = 1 blows up at t = 1: the Newton iteration stops converging, the
    # step shrinks to the minimum, the run ends with success False near t = 1
    r = conmech.solve_ivp(lambda t, y: [y[0] ** 2], (0, 2), [1.0], method="Radau",
                          rtol=1e-8, atol=1e-8, jac=lambda t, y: [[2 * y[0]]])
    assert not r.success and r.status == -1
    assert "step size too small" in r.message
    assert abs(r.t[-1] - 1.0) < 1e-3
    # NaN beyond t = 1: the Newton iteration meets non-finite values, same ending
    f = lambda t, y: [-y[0] if t < 1 else np.nan]
    r = conmech.solve_ivp(f, (0, 2), [1.0], method="Radau", jac=[[-1.0]])
    assert not r.success and "at t =" in r.message and abs(r.t[-1] - 1.0) < 1e-6


def test_singular_iteration_matrix_message():
    # eigenvalues of J at gamma/h * 2^k: the iteration matrix gamma/h I - J is singular
    # for h, h/2, ..., h/16 (each halving after a singular LU hits the next one)
    h = 0.01
    lam = GAM0 / h * 2.0 ** np.arange(5)
    J = np.diag(lam)
    r = conmech.solve_ivp(lambda t, y: J @ y, (0, 1), np.ones(5), method="Radau",
                          first_step=h, jac=J)
    assert not r.success and "singular iteration matrix" in r.message
    # one singular LU only (at h; J has a positive eigenvalue gamma/h): the step is
    # halved and the run goes on
    J1 = np.array([[GAM0 / h]])
    r = conmech.solve_ivp(lambda t, y: J1 @ y, (0, 0.05), [1.0], method="Radau",
                          first_step=h, jac=J1, rtol=1e-8, atol=1e-8)
    assert r.success and abs(r.y[0, -1] / np.exp(J1[0, 0] * 0.05) - 1) < 1e-5


def test_bad_jac():
    with pytest.raises(ValueError, match="jac"):
        conmech.solve_ivp(vdp, (0, 1), [2.0, 0.0], method="Radau", jac=np.eye(3))
    with pytest.raises(ValueError, match="shape"):
        conmech.solve_ivp(vdp, (0, 1), [2.0, 0.0], method="Radau",
                          jac=lambda t, y: np.eye(3))
    with pytest.warns(UserWarning, match="jac"):
        conmech.solve_ivp(vdp, (0, 0.001), [2.0, 0.0], method="DOP853", jac=vdp_jac)


def test_constrained_dae_form():
    from conmech import constrained
    # the stabilised index-2 DAE: both constraint levels to the tolerance, no projection
    r = constrained.solve("double_pendulum_xy", (0, 10), method="Radau", rtol=1e-8,
                          atol=1e-8, t_eval=np.linspace(0, 10, 11))
    ref = constrained.solve("double_pendulum_xy", (0, 10), method="DOP853", rtol=1e-12,
                            atol=1e-12, t_eval=np.linspace(0, 10, 11))
    assert r.success and r.nproj == 0
    assert np.abs(r.q - ref.q).max() < 1e-7
    assert np.abs(r.res_pos).max() < 1e-9 and np.abs(r.res_vel).max() < 1e-7
    assert np.abs(r.lam - ref.lam).max() < 1e-5 * np.abs(ref.lam).max()
    # tighter tolerance, smaller residuals and errors
    r2 = constrained.solve("double_pendulum_xy", (0, 10), method="Radau", rtol=1e-10,
                           atol=1e-10, t_eval=np.linspace(0, 10, 11))
    assert np.abs(r2.q - ref.q).max() < 0.05 * np.abs(r.q - ref.q).max()


def test_constrained_dae_configuration_dependent_mass():
    # a mass matrix that depends on q: Radau IIA (both DAE forms) agrees with projected
    # DOP853, an independent method, and keeps the constraint without projection (the
    # constraint Jacobian given: a finite-difference G limits the Newton iteration of the
    # index-2 form to tolerances above ~1e-9)
    from conmech import constrained
    sysm = constrained.ConstrainedSystem(
        2, lambda t, q: np.diag([1.0 + q[0] ** 2, 1.0]), lambda t, q, v: [0.0, -9.81],
        phi=lambda t, q: [0.5 * (q[0] ** 2 + q[1] ** 2 - 1)], n_hol=1,
        jac=lambda t, q: [[q[0], q[1]]])
    args = (sysm, (0, 1), [np.sin(1), -np.cos(1)], [0.0, 0.0])
    ref = constrained.solve(*args, rtol=1e-12, atol=1e-12, t_eval=[1.0])
    for idx, tol in ((2, 1e-7), (3, 1e-5)):
        r = constrained.solve(*args, method="Radau", rtol=1e-9, atol=1e-9, t_eval=[1.0],
                              dae_index=idx)
        assert r.success, r.message
        assert np.max(np.abs(r.q[:, -1] - ref.q[:, -1])) < tol
        assert r.res_pos[-1] < 1e-9
