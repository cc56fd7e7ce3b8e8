"""Gauss-Legendre collocation (solve_ivp method "GAUSS4", "GAUSS6"): orders 4 and 6,
Kepler e = 0.6: bounded energy error, angular momentum to round-off, linear phase error."""
import numpy as np
import pytest

import conmech

E = 0.6
Y0 = [1 - E, 0.0, 0.0, np.sqrt((1 + E) / (1 - E))]
T = 2 * np.pi


def kepler(t, y):
    r3 = np.hypot(y[0], y[1]) ** 3
    return [y[2], y[3], -y[0] / r3, -y[1] / r3]


@pytest.mark.parametrize("method,order,ks", [("GAUSS4", 4, (100, 200, 400)),
                                             ("GAUSS6", 6, (50, 100, 200))])
def test_order(method, order, ks):
    sysk = conmech.systems.kepler(mu=1.0)
    errs = []
    for k in ks:
        r = conmech.solve_ivp(sysk, (0, T), Y0, method=method, first_step=T / k)
        assert r.success and r.naccept == k
        errs.append(np.abs(r.y[:, -1] - Y0).max())    # periodic orbit: back at Y0
    p = np.log2(np.array(errs[:-1]) / errs[1:])
    assert np.all(np.abs(p - order) < 0.3), p


def test_kepler_long_run_invariants():
    n_per = 300
    h = T / 100
    # outputs on step points (every 7th step: all phases of the orbit), where the state
    # is the method's own (between steps it would be the collocation polynomial's)
    te = np.arange(0, n_per * 100 + 1, 7) * h
    r = conmech.solve_ivp(conmech.systems.kepler(mu=1.0), (0, n_per * T), Y0,
                          method="GAUSS6", first_step=h, t_eval=te)
    assert r.success
    x, y, vx, vy = r.y
    energy = 0.5 * (vx ** 2 + vy ** 2) - 1 / np.hypot(x, y)
    ang = x * vy - y * vx
    dE = np.abs(energy - energy[0])
    k = dE.size // 10
    assert dE.max() < 1e-6 and dE[-k:].max() <= 1.01 * dE[:k].max()
    # a quadratic invariant: kept to round-off (compensated summation)
    assert np.abs(ang - ang[0]).max() < 2e-14
    # phase error grows linearly: the error at whole periods, after 300 ~ 3 x after 100
    r = conmech.solve_ivp(conmech.systems.kepler(mu=1.0), (0, n_per * T), Y0,
                          method="GAUSS6", first_step=h, t_eval=np.arange(n_per + 1) * T)
    err = np.abs(r.y[:2] - np.array(Y0[:2])[:, None]).max(axis=0)
    assert abs(err[300] / err[100] - 3) < 0.1 and abs(err[100] / err[10] - 10) < 0.3


def test_python_callback_dense_and_events():
    ev = lambda t, y: y[1]
    ev.direction = -1
    r = conmech.solve_ivp(kepler, (0, 3 * T), Y0, method="GAUSS4", first_step=T / 400,
                          dense_output=True, events=ev)
    assert r.success
    # y crosses 0 downwards at the apocentre, t = T/2 + k T
    assert np.allclose(r.t_events[0], [T / 2, 3 * T / 2, 5 * T / 2], atol=1e-6)
    assert np.abs(r.sol(r.t) - r.y).max() < 1e-12


def test_bad_input():
    with pytest.raises(ValueError, match="first_step"):
        conmech.solve_ivp(kepler, (0, 1), Y0, method="GAUSS6")
    # a stiff problem with a large step: the fixed-point iteration cannot converge
    r = conmech.solve_ivp(lambda t, y: -1e4 * y, (0, 1), [1.0], method="GAUSS6",
                          first_step=0.1)
    assert not r.success and "did not converge at t =" in r.message
