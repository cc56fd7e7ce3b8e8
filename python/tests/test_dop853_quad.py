"""DOP853 in quadruple precision (conmech.symbolic.taylor_quad.reference_dop853 and
reference(..., method="DOP853")):

- order 8 observed with equal steps on the circular Kepler orbit (exact solution cos, sin)
  at errors from 4e-18 down to 2e-25 (equal steps, 256 to 2048 a period), where double
  precision could not go;
- Kepler e = 0.5 against the exact solution (Newton on Kepler's equation in mpmath, 50
  digits) at t = 2.5 and after one period, to 1e-22 at rtol 1e-26;
- Arenstorf's orbit (published initial values and period, 30 digits) closes to 1e-20 at
  rtol 1e-25 and agrees with the quadruple-precision Taylor route (tol 1e-30) to the
  DOP853 run's own error: two independent methods on one reference;
- the decimal-string, Decimal, mpmath and float inputs give the same run; bad input is
  refused with the argument named.
"""
from decimal import Decimal

import mpmath
import numpy as np
import pytest

sp = pytest.importorskip("sympy")

from conmech import symbolic  # noqa: E402
from conmech.symbolic import taylor_quad  # noqa: E402



@pytest.fixture(autouse=True)
def _fifty_digits():
    """mpmath at 50 digits inside each test of this module (the global precision of the
    other modules' tests left as it was)."""
    with mpmath.workdps(50):
        yield

ARENSTORF_Y0 = ["0.994", "0", "0", "-2.00158510637908252240537862224"]
ARENSTORF_T = "17.0652165601579625588917206249"   # Hairer, Norsett, Wanner I, II.0
MU = "0.012277471"


@pytest.fixture(scope="module")
def kepler():
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    return symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])


@pytest.fixture(scope="module")
def arenstorf():
    x, y, u, w, mu = sp.symbols("x y u w mu")
    mup = 1 - mu
    d1 = ((x + mu)**2 + y**2)**sp.Rational(3, 2)
    d2 = ((x - mup)**2 + y**2)**sp.Rational(3, 2)
    f = [u, w, x + 2*w - mup*(x + mu)/d1 - mu*(x - mup)/d2,
         y - 2*u - mup*y/d1 - mu*y/d2]
    return symbolic.ode_system(f, [x, y, u, w], params={mu: 0.012277471})


def kepler_exact(e, t):
    """(x, y, u, v) at t of the orbit a = 1, mu = 1 from the pericentre (1 - e, 0) with
    velocity (0, sqrt((1 + e)/(1 - e))): Newton on Kepler's equation E - e sin E = t."""
    e, t = mpmath.mpf(e), mpmath.mpf(t)
    big_e = t
    for _ in range(100):
        step = (big_e - e*mpmath.sin(big_e) - t)/(1 - e*mpmath.cos(big_e))
        big_e -= step
        if abs(step) < mpmath.mpf(10)**-45:
            break
    b = mpmath.sqrt(1 - e**2)
    dedt = 1/(1 - e*mpmath.cos(big_e))
    return [mpmath.cos(big_e) - e, b*mpmath.sin(big_e),
            -mpmath.sin(big_e)*dedt, b*mpmath.cos(big_e)*dedt]


def max_diff(strings, exact):
    return max(abs(mpmath.mpf(s) - mpmath.mpf(x)) for s, x in zip(strings, exact))


def test_order_eight_in_quadruple_precision(kepler):
    two_pi = mpmath.nstr(2*mpmath.pi, 40)
    errors = []
    for n in (256, 512, 1024, 2048):
        r = taylor_quad.reference_dop853(kepler, (0, two_pi), [1, 0, 0, 1], rtol=1e-30,
                                         fixed_steps=n)
        assert r.success and r.nsteps == n and r.nfev == 12*n
        errors.append(max_diff(r.y_str, [1, 0, 0, 1]))
    assert errors[-1] < 1e-24 and errors[0] > 1e-18      # beyond double's reach
    orders = [float(mpmath.log(a/b, 2)) for a, b in zip(errors, errors[1:])]
    assert all(abs(p - 8) < 0.1 for p in orders), orders


def test_kepler_against_keplers_equation(kepler):
    e = "0.5"
    y0 = [str(v) for v in kepler_exact(e, 0)]
    period = mpmath.nstr(2*mpmath.pi, 40)
    for t in ("2.5", period):
        r = taylor_quad.reference_dop853(kepler, (0, t), y0, rtol=1e-26)
        assert r.success and r.status == 0 and r.nreject >= 0
        assert max_diff(r.y_str, kepler_exact(e, t)) < 1e-22
        # the doubles nearest are the pairs' sums
        assert np.allclose(r.y_float, [float(v) for v in kepler_exact(e, t)], rtol=0,
                           atol=1e-15)


def test_arenstorf_closes_and_agrees_with_taylor(arenstorf):
    d = taylor_quad.reference(arenstorf, (0, ARENSTORF_T), ARENSTORF_Y0, tol=1e-25,
                              params={"mu": MU}, method="DOP853")
    assert d.success and d.method == "DOP853" and d.order == 8
    closure = max_diff(d.y_str, ARENSTORF_Y0)
    assert closure < 1e-20
    t = taylor_quad.reference(arenstorf, (0, ARENSTORF_T), ARENSTORF_Y0, tol=1e-30,
                              params={"mu": MU})
    assert t.success and t.method == "TAYLOR"
    taylor_closure = max_diff(t.y_str, ARENSTORF_Y0)
    assert taylor_closure < 1e-25
    # the two methods agree to the DOP853 run's own error (its closure), which the
    # Taylor run's far smaller error does not mask
    gap = max_diff(d.y_str, t.y_str)
    assert gap < 1e-20 and abs(gap - closure) < 10*taylor_closure + 1e-26


def test_inputs_in_every_form_give_one_run(kepler):
    y0 = ["0.5", "0", "0", "1.7320508075688772935274463415058723669"]
    runs = [taylor_quad.reference_dop853(kepler, (0, "1"), y0, rtol="1e-20"),
            taylor_quad.reference_dop853(kepler, (Decimal(0), Decimal(1)),
                                         [Decimal(v) for v in y0], rtol=Decimal("1e-20")),
            taylor_quad.reference_dop853(kepler, (0, mpmath.mpf(1)),
                                         [mpmath.mpf(v) for v in y0], rtol=mpmath.mpf("1e-20"))]
    assert all(r.y_str == runs[0].y_str and r.nfev == runs[0].nfev for r in runs)
    # a float y0 is a different (rounded) initial value: same to double precision only
    f = taylor_quad.reference_dop853(kepler, (0, 1.0), [float(v) for v in y0], rtol=1e-20)
    assert np.allclose(f.y_float, runs[0].y_float, rtol=0, atol=1e-14)
    assert f.y_str != runs[0].y_str


def test_bad_input_refused(kepler):
    y0 = ["0.5", "0", "0", "1.7"]
    ref = taylor_quad.reference_dop853
    with pytest.raises(ValueError, match="rtol"):
        ref(kepler, (0, 1), y0, rtol=1e-33)
    with pytest.raises(ValueError, match="rtol"):
        ref(kepler, (0, 1), y0, rtol="nan")
    with pytest.raises(ValueError, match="rtol"):
        ref(kepler, (0, 1), y0, rtol=1)
    # the bound itself is accepted, as a float or a decimal string
    for tol in (1e-32, "1e-32"):
        assert ref(kepler, (0, "0.01"), y0, rtol=tol).success
    with pytest.raises(ValueError, match="atol"):
        ref(kepler, (0, 1), y0, rtol=1e-20, atol=0)
    with pytest.raises(ValueError, match="atol"):
        ref(kepler, (0, 1), y0, rtol=1e-20, atol=float("inf"))
    with pytest.raises(TypeError, match="rtol"):
        ref(kepler, (0, 1), y0, rtol=None)
    with pytest.raises(ValueError, match="y0"):
        ref(kepler, (0, 1), y0[:3])
    with pytest.raises(ValueError, match=r"y0\[1\]"):
        ref(kepler, (0, 1), ["0.5", "abc", "0", "1"])
    with pytest.raises(ValueError, match=r"y0\[3\]"):
        ref(kepler, (0, 1), [0.5, 0, 0, float("nan")])
    with pytest.raises(ValueError, match=r"t_span\[1\]"):
        ref(kepler, (0, float("inf")), y0)
    with pytest.raises(ValueError, match="t_span"):
        ref(kepler, 1.0, y0)
    with pytest.raises(ValueError, match="fixed_steps"):
        ref(kepler, (0, 1), y0, fixed_steps=0)
    with pytest.raises(ValueError, match="max_steps"):
        ref(kepler, (0, 1), y0, max_steps=-1)
    with pytest.raises(ValueError, match="method"):
        taylor_quad.reference(kepler, (0, 1), y0, method="RK45")
    with pytest.raises(ValueError, match="unknown parameter"):
        ref(kepler, (0, 1), y0, params={"mu": 1})
    # too few steps: reported as a failure, never dressed as the answer
    r = ref(kepler, (0, 10), y0, rtol=1e-25, max_steps=5)
    assert not r.success and r.status == -1 and "too many steps" in r.message


def test_system_without_quad_code_refused():
    with pytest.raises(ValueError, match="quadruple-precision"):
        taylor_quad.reference_dop853(type("S", (), {"taylor": None})(), (0, 1), [1, 0])
