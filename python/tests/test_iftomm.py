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


def test_a02_closed_form_is_a_motion():
    # B0 stays on the unit circle about the first pivot; its velocity is the derivative
    # of its position; the one-degree-of-freedom energy is conserved
    N = 4
    t = np.linspace(0, 20, 401)
    b, bv = iftomm.a02_exact(t, N)
    assert np.allclose(b[:, 0], [0.0, 1.0], atol=1e-15) and np.allclose(bv[:, 0], [1, 0])
    assert np.max(np.abs(b[0] ** 2 + b[1] ** 2 - 1)) < 1e-14
    h = 1e-5
    bp, _ = iftomm.a02_exact(t + h, N)
    bm, _ = iftomm.a02_exact(t - h, N)
    assert np.max(np.abs((bp - bm) / (2 * h) - bv)) < 1e-8
    phi_d2 = bv[0] ** 2 + bv[1] ** 2          # L = 1: |v_B0| = |phi'|
    energy = (0.5 * ((N + 1) / 3 + N) * phi_d2 + 9.81 * b[1] * ((N + 1) / 2 + N))
    assert np.max(np.abs(energy - energy[0])) < 1e-11


def test_a02_passes_the_singular_configurations():
    # N = 4 windows (the closed form holds for every N; the benchmark's N = 40 is the
    # example in the guide): the default method follows the closed form through the flat
    # (singular) positions, where the constraints lose N ranks, over the benchmark's 20 s
    # and 400 outputs, far inside its high-precision tolerance 1e-3
    N = 4
    p = iftomm.a02_n_four_bar(N)
    te = np.linspace(0, 20, 401)
    r = constrained.solve(p.system, p.t_span, p.q0, p.v0, rtol=1e-10, atol=1e-10, t_eval=te)
    assert r.success, r.message
    b, bv = iftomm.a02_exact(te, N)
    phi, phi_d = r.q[0], r.v[0]
    assert np.max(np.abs(np.array([np.cos(phi), np.sin(phi)]) - b)) < 1e-4
    assert np.max(np.abs(np.array([-np.sin(phi), np.cos(phi)]) * phi_d - bv)) < 1e-3
    # the parallelogram is kept: every crank at the same angle, the couplers flat
    assert np.max(np.abs(r.q[:N + 1] - r.q[0])) < 1e-6
    assert np.max(np.abs(np.sin(r.q[N + 1:]))) < 1e-6
    assert np.max(r.res_pos) < 1e-10
    assert np.isclose(p.q_ref[0], b[0, -1]) and np.isclose(p.q_ref[1], b[1, -1])
