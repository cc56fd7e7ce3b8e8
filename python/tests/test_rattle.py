"""RATTLE (conmech.constrained.solve(method="RATTLE")): order 2, bounded energy error with
no trend, constraints at round-off, multipliers, outputs off the step grid, bad input."""
import numpy as np
import pytest
from scipy.special import ellipk

from conmech import constrained

G, L, TH0 = 9.81, 1.0, 1.0
T = 4 * np.sqrt(L / G) * ellipk(np.sin(TH0 / 2) ** 2)
Q0 = [L * np.sin(TH0), -L * np.cos(TH0)]


def energy(r):
    return 0.5 * (r.v ** 2).sum(axis=0) + G * r.q[1]


def test_order_two():
    # at t = 0.37 T (after a full period the error of a symmetric method cancels to
    # higher order on this reversible orbit)
    tf = 0.37 * T
    ref = constrained.solve("pendulum_xy", (0, tf), Q0, [0.0, 0.0], method="DOP853",
                            rtol=1e-13, atol=1e-13)
    errs = []
    for k in (50, 100, 200):
        r = constrained.solve("pendulum_xy", (0, tf), Q0, [0.0, 0.0], method="RATTLE",
                              first_step=tf / k)
        assert r.success and r.naccept == k
        errs.append(max(np.abs(r.q[:, -1] - ref.q[:, -1]).max(),
                        np.abs(r.v[:, -1] - ref.v[:, -1]).max()))
    p = np.log2(np.array(errs[:-1]) / errs[1:])
    assert np.all(np.abs(p - 2) < 0.15), p


def test_energy_bounded_no_trend_and_residuals():
    tf = 2000 * T
    r = constrained.solve("pendulum_xy", (0, tf), Q0, [0.0, 0.0], method="RATTLE",
                          first_step=T / 50, t_eval=np.linspace(0, tf, 4001))
    assert r.success
    dE = np.abs(energy(r) - energy(r)[0])
    k = dE.size // 10
    assert dE[-k:].max() <= 1.05 * dE[:k].max() and dE.max() < 0.05
    assert np.abs(r.res_pos).max() <= 1e-12 and np.abs(r.res_vel).max() <= 1e-12
    # the system's own energy agrees
    assert np.allclose(r.energy, energy(r), rtol=0, atol=1e-12)


def test_double_pendulum_energy_bounded():
    sysd = constrained.builtin("double_pendulum_xy")
    q0, v0 = sysd.initial_state()
    tf = 500.0
    r = constrained.solve(sysd, (0, tf), q0, v0, method="RATTLE", first_step=0.005,
                          t_eval=np.linspace(0, tf, 2001))
    assert r.success
    dE = np.abs(r.energy - r.energy[0])
    k = dE.size // 10
    assert dE[-k:].max() <= 1.5 * dE[:k].max()
    assert np.abs(r.res_pos).max() <= 1e-12 and np.abs(r.res_vel).max() <= 1e-12


def test_multipliers_and_off_grid_outputs():
    # outputs between grid points come from a side step: on the manifold, and close to
    # an accurate projected DOP853 solution; multipliers = m/l^2 (y g - |v|^2)
    te = np.linspace(0, T, 37)
    r = constrained.solve("pendulum_xy", (0, T), Q0, [0.0, 0.0], method="RATTLE",
                          first_step=T / 400, t_eval=te)
    ref = constrained.solve("pendulum_xy", (0, T), Q0, [0.0, 0.0], method="DOP853",
                            rtol=1e-12, atol=1e-12, t_eval=te)
    assert r.success and np.array_equal(r.t, te)
    assert np.abs(r.q - ref.q).max() < 1e-3 and np.abs(r.v - ref.v).max() < 5e-3
    assert np.abs(r.res_pos).max() <= 1e-12 and np.abs(r.res_vel).max() <= 1e-12
    lam = (r.q[1] * G - (r.v ** 2).sum(axis=0)) / L ** 2
    assert np.allclose(r.lam[0], lam, atol=1e-10)
    assert np.allclose(r.reaction, r.lam[0] * r.q, atol=1e-10)


def test_bad_input():
    with pytest.raises(ValueError, match="first_step"):
        constrained.solve("pendulum_xy", (0, 1), Q0, [0.0, 0.0], method="RATTLE")
    with pytest.raises(ValueError, match="holonomic"):
        constrained.solve("rod_two_masses", (0, 1), method="RATTLE", first_step=0.01)
    r = constrained.solve("pendulum_xy", (0, 10), Q0, [0.0, 0.0], method="RATTLE",
                          first_step=1e-3, max_steps=100)
    assert not r.success and "max_steps" in r.message


def test_rheonomic_constraint():
    # pendulum on a moving support: phi depends on t, G v + phi_t = 0 holds at round-off
    s = constrained.builtin("pendulum_moving_xy")
    ref = constrained.solve(s, (0, 3), method="DOP853", rtol=1e-12, atol=1e-12)
    errs = []
    for h in (0.01, 0.005):
        r = constrained.solve(s, (0, 3), method="RATTLE", first_step=h)
        assert r.success
        assert np.abs(r.res_pos).max() <= 1e-12 and np.abs(r.res_vel).max() <= 1e-12
        errs.append(np.abs(r.q[:, -1] - ref.q[:, -1]).max())
    assert abs(np.log2(errs[0] / errs[1]) - 2) < 0.2
