"""Ensembles of trees in SIMD lanes (conmech.symbolic.taylor_tree_batch): the ode systems'
batch coefficient routine on the articulated-body chain's decomposition, the pivots
checked per lane.

- the branched planar tree (prismatic and revolute joints, forces in q, v and t): each
  member its own solve_ivp(method="TAYLOR") run, bit for bit, with 2 and 4 lanes, and
  DOP853 at a tight tolerance to 1e-10;
- a zero mass at the leaf (a parameter of the call): every member fails with the scalar
  route's code, and the message names the joint whose articulated inertia is not
  positive.
"""
import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import conmech  # noqa: E402
from conmech import ensemble  # noqa: E402
from conmech.symbolic import planar_tree  # noqa: E402
from conmech.symbolic.pipeline import model_of  # noqa: E402
from test_taylor_tree import branched, chain  # noqa: E402

TOL = 1e-11


def test_tree_members_are_their_own_runs_in_lanes():
    bodies, params, forces, g = branched()
    system = planar_tree(bodies, params, gravity=(0, -g), forces=forces)
    rng = np.random.default_rng(11)
    y0s = np.column_stack([rng.uniform(-0.6, 0.6, (5, 4)), rng.uniform(-0.3, 0.3, (5, 4))])
    runs = [ensemble.solve(system, (0, 2.0), y0s, method="TAYLOR", rtol=TOL, atol=TOL,
                           lanes=k) for k in (2, 4)]
    paths = model_of(system).taylor_paths
    assert paths.get("batch2") is not None
    for ens in runs:
        assert ens.success
        assert np.array_equal(ens.y_final, runs[0].y_final)
        assert np.array_equal(ens.nfev, runs[0].nfev)
    for i, y0 in enumerate(y0s):
        r = conmech.solve_ivp(system, (0, 2.0), y0, method="TAYLOR", rtol=TOL, atol=TOL)
        assert np.array_equal(runs[0].y_final[i], r.y[:, -1])
        assert (runs[0].nfev[i], runs[0].naccept[i]) == (r.nfev, r.naccept)
        d = conmech.solve_ivp(system, (0, 2.0), y0, method="DOP853", rtol=3e-14,
                              atol=3e-14)
        scale = max(1.0, np.max(np.abs(d.y[:, -1])))
        assert np.max(np.abs(runs[0].y_final[i] - d.y[:, -1])) < 1e-10*scale


def test_a_non_positive_pivot_fails_the_members_naming_the_joint():
    bodies, params, g = chain(2)
    system = planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute")
    y0s = np.array([[0.3, 0.2, 0.0, 0.1], [0.1, -0.2, 0.3, 0.0], [0.5, 0.0, 0.0, 0.0]])
    ens = ensemble.solve(system, (0, 1.0), y0s, params={"m2": 0.0}, method="TAYLOR",
                         rtol=TOL, atol=TOL, lanes=2)
    assert model_of(system).taylor_paths.get("batch2") is not None
    r = conmech.solve_ivp(system.with_params(m2=0.0), (0, 1.0), y0s[0], method="TAYLOR",
                          rtol=TOL, atol=TOL)
    by_member = ensemble.solve(system, (0, 1.0), y0s, params={"m2": [0.0]*3},
                               method="TAYLOR", rtol=TOL, atol=TOL)
    assert not r.success and list(ens.status) == [-1, -1, -1]
    assert np.array_equal(ens.codes, by_member.codes)
    assert "articulated inertia of the joint of body 'link1'" in ens.message
    ok = ensemble.solve(system, (0, 1.0), y0s, params={"m2": 0.5}, method="TAYLOR",
                        rtol=TOL, atol=TOL, lanes=2)
    assert ok.success
