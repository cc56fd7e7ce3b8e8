"""The Test Set for IVP Solvers' (University of Bari) index-3 mechanical problems,
Andrews' squeezing mechanism and the car axis, against the test set's published reference
solutions (andrews.f: PSIDE at rtol = atol = 1e-14; caraxis.f), in the test set's measure
of accuracy (mixed significant correct digits, atol = rtol)."""
import numpy as np
import pytest

from conmech import constrained
from conmech.benchmarks import bari


@pytest.fixture(scope="module")
def andrews():
    return bari.andrews()


@pytest.fixture(scope="module")
def car_axis():
    return bari.car_axis()


def _solve(p, tol, **kw):
    r = constrained.solve(p.system, p.t_span, p.q0, p.v0, rtol=tol, atol=tol,
                          t_eval=[p.t_span[1]], **kw)
    assert r.success, r.message
    return r


@pytest.mark.parametrize("problem", ["andrews", "car_axis"])
@pytest.mark.parametrize("method", ["DOP853", "Radau"])
def test_positions_to_the_reference(problem, method, request):
    # >= 9.5 correct digits in the positions at rtol = atol = 1e-10 with the default
    # method (projected DOP853) and with Radau IIA (index-2 form, exact Jacobian)
    p = request.getfixturevalue(problem)
    r = _solve(p, 1e-10, method=method)
    assert bari.mescd(r.q[:, -1], p.q_ref, 1e-10, 1e-10) >= 9.5
    # the velocities and multipliers follow (index 2 and 3 quantities: fewer digits)
    assert bari.mescd(r.v[:, -1], p.v_ref, 1e-10, 1e-10) >= 7.0
    assert r.res_pos[-1] < 1e-9


def test_car_axis_multipliers(car_axis):
    r = _solve(car_axis, 1e-10, method="Radau")
    assert bari.mescd(r.lam[:, -1], car_axis.lam_ref, 1e-10, 1e-10) >= 9.0


def test_andrews_multipliers_and_accelerations(andrews):
    # the result carries the accelerations and the multipliers: at t = 0 they are the
    # test set's consistent initial values y(15:27), at t = 0.03 its reference (these are
    # index-3 quantities, large and sensitive: 6 and 8 digits relative to their size)
    r = constrained.solve(andrews.system, andrews.t_span, andrews.q0, andrews.v0,
                          rtol=1e-10, atol=1e-10, t_eval=[0.0, 0.03])
    scale_a = np.max(np.abs(andrews.a0_ref))
    assert np.max(np.abs(r.a[:, 0] - andrews.a0_ref)) < 1e-10 * scale_a
    assert np.max(np.abs(r.lam[:, 0] - andrews.lam0_ref)) < 1e-10 * 100.0
    assert np.max(np.abs(r.a[:, 1] - andrews.a_ref)) < 1e-6 * np.max(np.abs(andrews.a_ref))
    assert np.max(np.abs(r.lam[:, 1] - andrews.lam_ref)) < 1e-5 * 200.0
    assert r.accelerations is r.a


def test_andrews_index3_form(andrews):
    # the test set's own formulation, y = [q, v, a, lambda], with RADAU5's index-aware
    # error weights: q is of order 5 but its error is controlled through an h^2-weighted
    # algebraic part, so it reaches fewer digits than the index-2 form at the same rtol
    r = _solve(andrews, 1e-10, method="Radau", dae_index=3)
    assert bari.mescd(r.q[:, -1], andrews.q_ref, 1e-10, 1e-10) >= 8.0
    r8 = _solve(andrews, 1e-8, method="Radau", dae_index=3)
    d8 = bari.mescd(r8.q[:, -1], andrews.q_ref, 1e-8, 1e-8)
    d10 = bari.mescd(r.q[:, -1], andrews.q_ref, 1e-10, 1e-10)
    assert d10 > d8 + 1.0     # tolerance proportionality: digits follow the tolerance


def test_radau_refuses_before_the_first_step():
    # redundant constraints (a pendulum's constraint given twice) are integrated by every
    # method (test_rattle_redundant.py); a constraint with a vanishing gradient at the
    # start is refused before integrating; projection and dae_index misuses too
    sysm = constrained.ConstrainedSystem(
        2, lambda t, q: np.eye(2), lambda t, q, v: [0.0, -9.81],
        phi=lambda t, q: [0.5 * (q[0] ** 2 + q[1] ** 2 - 1)] * 2, n_hol=2)
    args = (sysm, (0, 1), [np.sin(1), -np.cos(1)], [0.0, 0.0])
    calls = []

    def counting(t, q, v):
        calls.append(t)
        return q[0]
    flat = constrained.ConstrainedSystem(
        2, lambda t, q: np.eye(2), lambda t, q, v: [0.0, -9.81],
        phi=lambda t, q: [0.5 * (q[0] ** 2 + q[1] ** 2) ** 2 - 0.5], n_hol=1,
        jac=lambda t, q: [[0.0 * q[0], 0.0 * q[1]]])
    for meth, kw in (("Radau", {}), ("RATTLE", dict(first_step=0.01))):
        with pytest.raises(ValueError, match="constraint Jacobian is zero"):
            constrained.solve(flat, (0, 1), [np.sin(1), -np.cos(1)], [0.0, 0.0],
                              method=meth, events=counting, **kw)
    assert all(t == 0.0 for t in calls)
    r = constrained.solve(*args, rtol=1e-9, atol=1e-9)   # projected DOP853 handles it
    assert r.success and r.res_pos[-1] < 1e-9
    with pytest.raises(ValueError, match="projection"):
        constrained.solve(*args, method="Radau", projection="velocity")
    with pytest.raises(ValueError, match="dae_index"):
        constrained.solve(*args, method="DOP853", dae_index=3)
    with pytest.raises(ValueError, match="dae_index"):
        constrained.solve(*args, method="Radau", dae_index=1)
