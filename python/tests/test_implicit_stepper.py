"""conmech.Radau with SciPy's OdeSolver interface: a step() loop reproduces
conmech.solve_ivp(method="Radau") bit for bit (steps, counters, dense output), solve_ivp
runs it as method=conmech.Radau, steps and accuracy as SciPy's Radau class, bad input."""
import numpy as np
import pytest
import scipy.integrate as si
from numpy.testing import assert_, assert_allclose, assert_equal, assert_raises

import conmech

EPS = 1e-6


def vdp(t, y):
    return [y[1], ((1 - y[0] ** 2) * y[1] - y[0]) / EPS]


def vdp_jac(t, y):
    return [[0.0, 1.0], [(-2 * y[0] * y[1] - 1) / EPS, (1 - y[0] ** 2) / EPS]]


def rober(t, y):
    return [-0.04 * y[0] + 1e4 * y[1] * y[2],
            0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] ** 2, 3e7 * y[1] ** 2]


def run_steps(solver):
    ts, ys = [solver.t], [solver.y]
    while solver.status == "running":
        assert solver.step() is None
        ts.append(solver.t)
        ys.append(solver.y)
    return np.array(ts), np.array(ys).T


@pytest.mark.parametrize("jac", [vdp_jac, None])
def test_step_loop_is_solve_ivp_bit_for_bit(jac):
    ref = conmech.solve_ivp(vdp, (0, 2), [2.0, -0.66], method="Radau", rtol=1e-6,
                            atol=1e-6, jac=jac, dense_output=True)
    s = conmech.Radau(vdp, 0.0, [2.0, -0.66], 2.0, rtol=1e-6, atol=1e-6, jac=jac)
    assert_equal(s.nlu, 0)
    t, y = run_steps(s)
    assert_equal(s.status, "finished")
    assert_equal(t, ref.t)
    assert_equal(y, ref.y)
    assert (s.nfev, s.njev, s.nlu) == (ref.nfev, ref.njev, ref.nlu)
    assert s.naccept == t.size - 1 and s.nreject == ref.nreject
    # the dense output of the last step is solve_ivp's on that step
    tm = np.linspace(s.t_old, s.t, 7)
    assert_allclose(s.dense_output()(tm), ref.sol(tm), rtol=1e-14, atol=1e-14)
    assert_allclose(s.dense_output()(s.t), s.y, rtol=1e-13, atol=1e-15)


def test_solve_ivp_with_the_class_and_scipy_driving_it():
    kw = dict(rtol=1e-6, atol=1e-10)
    a = conmech.solve_ivp(rober, (0, 1e5), [1.0, 0.0, 0.0], method="Radau", **kw)
    b = conmech.solve_ivp(rober, (0, 1e5), [1.0, 0.0, 0.0], method=conmech.Radau, **kw)
    assert_equal(a.t, b.t)
    assert_equal(a.y, b.y)
    assert (a.nfev, a.njev, a.nlu) == (b.nfev, b.njev, b.nlu)
    # the same steps as SciPy's Radau class, within a few per cent, and its accuracy
    s = conmech.Radau(rober, 0.0, [1.0, 0.0, 0.0], 1e5, **kw)
    r = si.Radau(rober, 0.0, [1.0, 0.0, 0.0], 1e5, **kw)
    tc, yc = run_steps(s)
    ts = [r.t]
    while r.status == "running":
        r.step()
        ts.append(r.t)
    assert abs(tc.size - len(ts)) <= 0.1 * len(ts)
    d = si.solve_ivp(rober, (0, 1e5), [1.0, 0.0, 0.0], method="Radau", rtol=1e-10,
                     atol=1e-14)
    assert_allclose(yc[:, -1], d.y[:, -1], rtol=1e-4, atol=1e-9)
    assert_allclose(r.y, d.y[:, -1], rtol=1e-4, atol=1e-9)


def test_unbounded_t_bound():
    # SciPy's OdeSolver pattern: t_bound = inf, step a while, the polynomial at both ends
    s = conmech.Radau(rober, 0.0, [1.0, 0.0, 0.0], np.inf, rtol=1e-6, atol=1e-10)
    assert_equal(s.t_bound, np.inf)
    assert s.step_size is None
    for _ in range(30):
        assert s.step() is None
    assert_equal(s.status, "running")
    assert s.t > 0 and s.step_size > 0 and s.njev >= 1 and s.nlu >= 2
    ref = conmech.solve_ivp(rober, (0, s.t), [1.0, 0.0, 0.0], method="Radau", rtol=1e-6,
                            atol=1e-10)
    assert_allclose(s.y, ref.y[:, -1], rtol=1e-5, atol=1e-12)
    d = s.dense_output()
    assert_allclose(d(s.t), s.y, rtol=1e-12, atol=1e-18)
    assert_allclose(d(s.t_old).sum(), 1.0, rtol=1e-12)     # mass conservation


def test_builtin_system_and_backwards():
    sysv = conmech.systems.vanderpol(mu=5.0)
    ref = conmech.solve_ivp(sysv, (0, 3), [2.0, 0.0], method="Radau", rtol=1e-8,
                            atol=1e-8)
    t, y = run_steps(conmech.Radau(sysv, 0.0, [2.0, 0.0], 3.0, rtol=1e-8, atol=1e-8))
    assert_equal(t, ref.t)
    assert_equal(y, ref.y)
    # backwards in time on y' = -y: y(t) = exp(-t)
    s = conmech.Radau(lambda t, y: -y, 1.0, [np.exp(-1.0)], 0.0, rtol=1e-10, atol=1e-12,
                      jac=[[-1.0]])
    assert_equal(s.direction, -1)
    run_steps(s)
    assert_equal(s.t, 0.0)
    assert_allclose(s.y, [1.0], rtol=1e-8)


def test_failures_and_bad_input():
    # y' = y^2, y(0) = 1 blows up at t = 1: Newton fails, the step shrinks to the minimum
    kw = dict(rtol=1e-8, atol=1e-8, jac=lambda t, y: [[2 * y[0]]])
    s = conmech.Radau(lambda t, y: y ** 2, 0.0, [1.0], 2.0, **kw)
    msg = None
    while s.status == "running":
        msg = s.step()
    assert_equal(s.status, "failed")
    r = conmech.solve_ivp(lambda t, y: y ** 2, (0, 2), [1.0], method="Radau", **kw)
    assert not r.success and msg == r.message
    assert "step size too small" in msg and "t =" in msg
    assert abs(s.t - 1.0) < 1e-3 and s.t == r.t[-1]
    assert_raises(RuntimeError, s.step)
    # an exception in fun is re-raised unchanged; a bad Jacobian is named
    def boom(t, y):
        if t > 0.1:
            raise KeyError("boom")
        return -y
    s = conmech.Radau(boom, 0.0, [1.0], 1.0)
    with pytest.raises(KeyError, match="boom"):
        while s.status == "running":
            s.step()
    assert_equal(s.status, "failed")
    with pytest.raises(ValueError, match="shape"):
        conmech.Radau(vdp, 0.0, [2.0, -0.66], 2.0, jac=np.eye(3))
    s = conmech.Radau(vdp, 0.0, [2.0, -0.66], 2.0, jac=lambda t, y: np.eye(3))
    with pytest.raises(ValueError, match=r"`jac` is expected to have shape \(2, 2\)"):
        s.step()
    with pytest.raises(ValueError, match="jac_sparsity"):
        conmech.Radau(vdp, 0.0, [2.0, -0.66], 2.0, jac_sparsity=np.ones((3, 3)))
    with pytest.raises(TypeError, match="built-in"):
        conmech.Radau(conmech.systems.vanderpol(), 0.0, [2.0, 0.0], 1.0, jac=np.eye(2))
    with pytest.raises(ValueError, match="rtol"):
        conmech.Radau(vdp, 0.0, [2.0, -0.66], 2.0, rtol=-1.0)
    # a singular iteration matrix five times in a row (eigenvalues gamma/h * 2^k): the
    # message, status failed
    h = 0.01
    J = np.diag(3.6378342527444957322 / h * 2.0 ** np.arange(5))
    s = conmech.Radau(lambda t, y: J @ y, 0.0, np.ones(5), 1.0, first_step=h, jac=J)
    msg = s.step()
    assert_equal(s.status, "failed")
    assert "singular iteration matrix" in msg


def kepler(t, y):
    r3 = np.hypot(y[0], y[1]) ** 3
    return [y[2], y[3], -y[0] / r3, -y[1] / r3]


@pytest.mark.parametrize("cls,name", [(conmech.Gauss4, "GAUSS4"), (conmech.Gauss6, "GAUSS6")])
def test_gauss_step_loop_is_solve_ivp_bit_for_bit(cls, name):
    y0 = [0.4, 0.0, 0.0, 2.0]          # Kepler, e = 0.6
    ref = conmech.solve_ivp(kepler, (0, 7), y0, method=name, first_step=0.05,
                            dense_output=True)
    s = cls(kepler, 0.0, y0, 7.0, first_step=0.05)
    t, y = run_steps(s)
    assert_equal(s.status, "finished")
    assert_equal(t, ref.t)
    assert_equal(y, ref.y)
    assert s.nfev == ref.nfev and s.naccept == t.size - 1 and (s.njev, s.nlu) == (0, 0)
    tm = np.linspace(s.t_old, s.t, 5)
    assert_allclose(s.dense_output()(tm), ref.sol(tm), rtol=1e-13, atol=1e-14)
    b = conmech.solve_ivp(kepler, (0, 7), y0, method=cls, first_step=0.05)
    assert_equal(b.y, ref.y)
    # angular momentum, a quadratic invariant, to round-off
    L = y[0] * y[3] - y[1] * y[2]
    assert np.abs(L - L[0]).max() < 1e-13


def test_gauss_builtin_and_bad_input():
    k = conmech.systems.kepler()
    y0 = [0.4, 0.0, 0.0, 2.0]
    ref = conmech.solve_ivp(k, (0, 3), y0, method="GAUSS6", first_step=0.1)
    t, y = run_steps(conmech.Gauss6(k, 0.0, y0, 3.0, first_step=0.1))
    assert_equal(t, ref.t)
    assert_equal(y, ref.y)
    with pytest.raises(ValueError, match="first_step is required"):
        conmech.Gauss6(kepler, 0.0, y0, 1.0)
    with pytest.raises(ValueError, match="finite"):
        conmech.Gauss4(kepler, 0.0, y0, np.inf, first_step=0.1)
    # a stiff system and a large step: the iteration does not converge, failed with the time
    s = conmech.Gauss4(lambda t, y: -1e4 * y, 0.0, [1.0], 1.0, first_step=0.1)
    msg = s.step()
    assert_equal(s.status, "failed")
    assert "did not converge at t =" in msg
