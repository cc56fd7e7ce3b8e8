"""Accelerations and per-constraint reaction forces in the results of conmech.constrained."""
import numpy as np
import pytest

from conmech import constrained

G = 9.81


@pytest.mark.parametrize("method,kw", [("DOP853", {}), ("Radau", {}),
                                       ("Radau", {"dae_index": 3}),
                                       ("RATTLE", {"first_step": 1e-3})])
def test_pendulum_tension_closed_form(method, kw):
    # the Cartesian pendulum (m = 1, L = 1): the rod's reaction on the mass is the
    # tension T = m (|v|^2 - g y)/L along -q/L (energy and the radial balance), and the
    # accelerations satisfy m a = (0, -m g) + reaction
    tol = {} if method == "RATTLE" else dict(rtol=1e-10, atol=1e-10)
    r = constrained.solve("pendulum_xy", (0, 2), [np.sin(1), -np.cos(1)], [0, 0],
                          method=method, t_eval=[0.0, 0.7, 1.3, 2.0], **tol, **kw)
    assert r.success, r.message
    x, y = r.q
    tension = (r.v[0] ** 2 + r.v[1] ** 2 - G * y)
    assert np.allclose(r.reaction, -tension * r.q, atol=1e-6)
    assert np.allclose(r.a, r.reaction + np.array([[0.0], [-G]]), atol=1e-9)
    assert r.reactions.shape == (1, 2, 4)
    assert np.allclose(r.reactions[0], r.reaction, atol=1e-14)


def test_double_pendulum_per_constraint_reactions():
    # two rods: constraint 1 (upper rod) acts on the first mass only, constraint 2 (lower
    # rod) with equal and opposite forces on the two masses (Newton's third law); the
    # per-constraint forces sum to C^T lambda
    r = constrained.solve("double_pendulum_xy", (0, 1), rtol=1e-10, atol=1e-10,
                          t_eval=[0.0, 0.5, 1.0])
    assert r.success, r.message
    assert r.reactions.shape == (2, 4, 3)
    assert np.allclose(r.reactions.sum(axis=0), r.reaction, atol=1e-12)
    assert np.allclose(r.reactions[0, 2:], 0.0, atol=1e-12)
    assert np.allclose(r.reactions[1, :2], -r.reactions[1, 2:], atol=1e-9)
    # and each lower-rod force is along the rod
    d = r.q[:2] - r.q[2:]
    cross = d[0] * r.reactions[1, 1] - d[1] * r.reactions[1, 0]
    assert np.max(np.abs(cross)) < 1e-9
