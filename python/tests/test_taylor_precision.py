"""Taylor's method at tight tolerances (method "TAYLOR", rtol = atol = 1e-14) on Kepler's
orbit of eccentricity 0.9 over one period, measured against a quadruple-precision Taylor
reference (conmech.symbolic.taylor_quad, tol 1e-30) started from the exact values of the
doubles the run starts from (their full decimal expansions: the decimal initial values
"0.1", "4.3588989435406735..." are other initial values, whose orbit differs from the
doubles' by 6.8e-13 in u after one period, more than heyoka's error at this tolerance).

What limits the error there is the rounding of the state to doubles, not the truncation:
at the pericentre (r = 0.1, |v| = 4.36) one unit in the last place of the velocity changes
the energy by ~4e-15 and the period by ~1e-14 relative, which puts ~1e-12 into u at the
end of the period (du/dt = -100 there). A rotation of the orbit changes every rounding
but not the exact solution, so the median over rotations is the floor of the method in
double precision; heyoka 7.13.2 (taylor_adaptive, the same orders and steps, measured
against the same references for the same 12 rotations th = 0.37 k) gives a median of
3.9e-12 at 1e-14 and 2.9e-12 at 1e-15 (conmech: 3.7e-12 and 3.4e-12).
"""
import math
from decimal import Decimal

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import conmech  # noqa: E402
from conmech import symbolic  # noqa: E402
from conmech.symbolic import taylor_quad  # noqa: E402

VP = math.sqrt(19.0)        # the pericentre speed sqrt((1 + e)/(1 - e)), e = 0.9, a = 1


@pytest.fixture(scope="module")
def kepler():
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    return symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])


def exact(a):
    """The exact decimal value of the double a."""
    return str(Decimal(float(a)))


def errors(kepler, tol, count):
    """The end-of-period errors (max norm) of `count` rotations of the orbit."""
    period = 2*math.pi
    out = []
    for k in range(count):
        c, s = math.cos(0.37*k), math.sin(0.37*k)
        y0 = np.array([0.1*c, 0.1*s, -VP*s, VP*c])
        ref = taylor_quad.reference(kepler, (0, exact(period)), [exact(a) for a in y0],
                                    tol=1e-30)
        assert ref.success
        r = conmech.solve_ivp(kepler, (0, period), y0, method="TAYLOR", rtol=tol, atol=tol)
        assert r.success
        out.append(float(np.max(np.abs(r.y[:, -1] - ref.y_float))))
    return np.array(out)


@pytest.mark.filterwarnings("ignore:.*rtol")
def test_kepler_at_tol_1e14_reaches_the_round_off_floor(kepler):
    tight = errors(kepler, 1e-14, 12)
    loose = errors(kepler, 1e-11, 4)
    # the truncation error is gone: two orders of magnitude below tol 1e-11 ...
    assert np.median(tight) < 1e-2*np.median(loose)
    # ... down to the floor of a double-precision state, where heyoka is (median 3.9e-12
    # over the same rotations; the bound leaves room for the scatter of 12 samples)
    assert np.median(tight) < 6e-12
    assert np.max(tight) < 3e-11
