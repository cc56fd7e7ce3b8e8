"""IFToMM multibody benchmark A01 (the simple pendulum) against its closed form."""
import numpy as np
import pytest

from conmech import constrained
from conmech.benchmarks import iftomm


@pytest.fixture(scope="module")
def a01():
    return iftomm.a01_pendulum()


def test_a01_closed_form_is_a_motion():
    # the elliptic-function solution keeps the link length and the energy (m g y + |v|^2/2
    # = 0 from the horizontal release at rest) and starts where the benchmark says
    t = np.linspace(0, 50, 501)
    q, v = iftomm.a01_exact(t)
    assert np.allclose(q[:, 0], [1.0, 0.0], atol=1e-15) and np.allclose(v[:, 0], 0.0)
    assert np.max(np.abs(q[0] ** 2 + q[1] ** 2 - 1)) < 1e-14
    assert np.max(np.abs(0.5 * (v ** 2).sum(0) + 9.81 * q[1])) < 1e-12
    # v is the derivative of q (central differences)
    h = 1e-5
    qp, _ = iftomm.a01_exact(t + h)
    qm, _ = iftomm.a01_exact(t - h)
    assert np.max(np.abs((qp - qm) / (2 * h) - v)) < 1e-8


def test_a01_full_benchmark_high_precision(a01):
    # the benchmark's run: 2000 s, 4000 output steps; its high-precision criterion is a
    # position error below 1e-3; the default method at rtol 1e-10 stays below 1e-4
    te = np.linspace(0, 2000, 4001)
    r = constrained.solve(a01.system, a01.t_span, a01.q0, a01.v0, rtol=1e-10, atol=1e-10,
                          t_eval=te)
    assert r.success, r.message
    qe, _ = iftomm.a01_exact(te)
    assert np.max(np.abs(r.q - qe)) < 1e-4
    assert np.max(r.res_pos) < 1e-10


@pytest.mark.parametrize("method,kw,tol", [("Radau", dict(rtol=1e-9, atol=1e-9), 1e-7),
                                           ("RATTLE", dict(first_step=1e-3), 1e-4)])
def test_a01_first_seconds_other_methods(a01, method, kw, tol):
    te = np.linspace(0, 10, 21)
    r = constrained.solve(a01.system, (0, 10), a01.q0, a01.v0, method=method, t_eval=te,
                          **kw)
    assert r.success, r.message
    qe, _ = iftomm.a01_exact(te)
    assert np.max(np.abs(r.q - qe)) < tol
