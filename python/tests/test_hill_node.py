"""Hill's problem in space (systems.hill_spatial) and the node constant of the variation
orbit (hill.node_constant, Adams 1877)."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp as scipy_solve_ivp

from conmech import compiled, hill, systems


def _g_full_period(m, kappa=1.0):
    """Independent route (SciPy only): the planar variation orbit (its start from
    hill.variation_orbit) and the vertical variational equation dz'' = -(m^2 + kappa/r^3)
    dz integrated together over the whole synodic month 2 pi with SciPy's DOP853; the half
    trace of the 2 x 2 monodromy is cos(2 pi g), g in (1, 3/2) here."""
    o = hill.variation_orbit(m, kappa)

    def rhs(t, s):
        x, y, u, v = s[:4]
        r3 = (x*x + y*y)**1.5
        z = s[4:].reshape(2, 2)
        return np.concatenate([[u, v, 2*m*v - kappa*x/r3 + 3*m*m*x, -2*m*u - kappa*y/r3],
                               np.array([z[1], -(m*m + kappa/r3)*z[0]]).ravel()])
    s0 = np.concatenate([o.y0, np.eye(2).ravel()])
    end = scipy_solve_ivp(rhs, (0, 2*np.pi), s0, method="DOP853", rtol=1e-13,
                          atol=1e-14).y[:, -1]
    z = end[4:].reshape(2, 2)
    half_trace = 0.5*(z[0, 0] + z[1, 1])
    return 1 + np.arccos(half_trace)/(2*np.pi)


def test_node_constant_at_hill_m():
    """At Hill's m the node constant from the quarter-month products (conmech's spatial
    problem, its exact Jacobian) agrees to 1e-12 with the full-month half-trace computed
    independently with SciPy; the Wronskian is 1; g = 1.08517142655819. (The observed
    ratio of the synodic to the draconic month, 29.530589/27.212221 = 1.08520, differs by
    the terms the main problem leaves out: the eccentricities and the solar parallax.)"""
    g, info = hill.node_constant(hill.M_HILL, full_output=True)
    assert abs(info["wronskian"] - 1) < 1e-12
    assert abs(g - _g_full_period(hill.M_HILL)) < 1e-12
    assert g == pytest.approx(1.08517142655819, abs=1e-13)
    assert abs(g - 29.530589/27.212221) < 1e-4


@pytest.mark.parametrize("m", [1e-4, 1e-3])
def test_node_constant_small_m(m):
    """As m -> 0: g = 1 + m + 3 m^2/4 + O(m^3) (the node regresses at the rate at which
    the perigee advances, to first order: c = 1 + m - 3 m^2/4 + O(m^3), whose cubic term
    is the large one, 225/32 in the classical series)."""
    g = hill.node_constant(m)
    assert abs(g - (1 + m + 0.75*m*m)) < 2*m**3
    c = hill.variation_orbit(m).c
    assert abs((g - 1 - m) + (c - 1 - m)) < 10*m**3


def test_hill_spatial_reduces_to_planar():
    """In the plane z = 0 the spatial problem is Hill's planar problem (same right-hand
    side and Jacobian block), and its Jacobi integral is the planar one."""
    m = 0.1
    sp3, sp2 = systems.hill_spatial(m=m), systems.hill(m=m)
    y4 = np.array([0.7, -0.2, 0.1, 0.5])
    y6 = np.array([0.7, -0.2, 0.0, 0.1, 0.5, 0.0])
    e3, e2 = compiled.evaluate(sp3, 0, y6), compiled.evaluate(sp2, 0, y4)
    assert np.allclose(e3["f"][[0, 1, 3, 4]], e2["f"], atol=1e-15)
    assert np.allclose(e3["jac"][np.ix_([0, 1, 3, 4], [0, 1, 3, 4])], e2["jac"], atol=1e-14)
    assert sp3.energy(y6) == pytest.approx(sp2.energy(y4), abs=1e-14)
    # z'' = -(m^2 + 1/r^3) z
    yz = np.array([0.7, -0.2, 0.05, 0.1, 0.5, 0.0])
    r3 = np.sum(yz[:3]**2)**1.5
    assert compiled.evaluate(sp3, 0, yz)["f"][5] == pytest.approx(-(m*m + 1/r3)*0.05)


def test_bad_input():
    with pytest.raises(ValueError, match="m"):
        hill.node_constant(-0.1)
    with pytest.raises(ValueError, match="rtol"):
        hill.node_constant(0.08, rtol=0.1)
    with pytest.raises(ValueError, match="kappa"):
        systems.hill_spatial(kappa=0.0)
