"""The Taylor recurrences' cheaper history sums (conmech.symbolic.taylor): a square's (and a
square root's) symmetric sum computed over half the products, a power's two sums folded
into one weighted by ((r + 1) j - k).

- the generated coefficients equal the Taylor series of exact solutions (y' = y**2,
  sqrt(y), y**r: (a + b t)**c, its binomial series in 30-digit arithmetic) for squares,
  square roots and powers with half-integer, rational, irrational and run-time parameter
  exponents, at even and odd orders;
- the three forms the integrators use, the loop routine (``taylor["jet"]``), the routine
  written out for one order (solve_ivp) and the batch routine (ensemble.solve), give the
  same coefficients to the last bit, at even and odd orders (the middle term of a square),
  for squares, square roots, rational and parameter exponents;
- the power columns need no column of j a[j]: the work array is one column narrower.
"""
import ctypes

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import conmech  # noqa: E402
from conmech import symbolic  # noqa: E402
from conmech.symbolic import taylor as T  # noqa: E402

_P = ctypes.POINTER(ctypes.c_double)


def _call(fnptr, t, order, w, p):
    fn = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_int, _P, _P)(
        conmech.compiled.function_address(fnptr))
    fn(t, order, w.ctypes.data_as(_P), p.ctypes.data_as(_P))


def _params(system):
    return np.ascontiguousarray(system.params if system.params.size else np.zeros(1))


def loop_jet(system, y, order):
    tay = system.taylor
    w = np.zeros((tay["nw"], order + 1))
    w[:len(y), 0] = y
    _call(tay["jet"], 0.0, order, w, _params(system))
    return w[:len(y)]


def binomial_series(a, b, c, order):
    """Coefficients of (a + b t)**c at t = 0: a**c binom(c, k) (b/a)**k (mpmath, 30
    digits): the exact solutions below are of this form."""
    import mpmath
    with mpmath.workdps(30):
        a, b, c = mpmath.mpf(a), mpmath.mpf(b), mpmath.mpf(c)
        return np.array([float(a**c*mpmath.binomial(c, k)*(b/a)**k)
                         for k in range(order + 1)])


# y' = f(y) with y(t) = (a + b t)**c in closed form (separation of variables):
#   y' = y**2:        y = (1/y0 - t)**(-1)          (a square)
#   y' = sqrt(y):     y = (sqrt(y0) + t/2)**2        (a square root)
#   y' = y**r:        y = (y0**(1 - r) + (1 - r) t)**(1/(1 - r))   (a power)
def _scalar_cases():
    y, r = sp.symbols("y r")
    y0 = 0.7
    out = {"square": (y**2, {}, (1/y0, -1.0, -1.0)),
           "sqrt": (sp.sqrt(y), {}, (np.sqrt(y0), 0.5, 2.0))}
    for name, rv, expo in (("half", -1.5, sp.Rational(-3, 2)), ("third", 1/3, sp.Rational(1, 3)),
                           ("irrational", 2**0.5, sp.sqrt(2)), ("param", 0.37, r)):
        out[name] = (y**expo, {r: rv} if expo == r else {},
                     (y0**(1 - rv), 1 - rv, 1/(1 - rv)))
    return y, y0, out


@pytest.mark.parametrize("name", ["square", "sqrt", "half", "third", "irrational", "param"])
def test_coefficients_are_the_series_of_the_exact_solution(name):
    y, y0, cases = _scalar_cases()
    f, params, (a, b, c) = cases[name]
    system = symbolic.ode_system([f], [y], params=params)
    order = 16                                     # even: a square's middle term enters
    want = binomial_series(a, b, c, order)
    got = loop_jet(system, [y0], order)[0]
    assert np.max(np.abs(got - want)/np.max(np.abs(want))) < 1e-14
    got15 = loop_jet(system, [y0], 15)[0]           # odd: no middle term
    assert np.max(np.abs(got15 - want[:16])/np.max(np.abs(want))) < 1e-14


def _systems():
    x, y, r = sp.symbols("x y r")
    return {
        # squares (x**2 + y**2) and a half-integer power: a Kepler-like field
        "half": ([y, -x*(x**2 + y**2)**sp.Rational(-3, 2)], [x, y], {}, [0.8, 0.3]),
        # a square root and a rational power
        "root": ([sp.sqrt(1 + x**2), (x + y**2)**sp.Rational(1, 3)], [x, y], {}, [0.4, 1.1]),
        # a run-time parameter exponent
        "param": ([x*y**2, -(x + y)**r], [x, y], {r: 0.37}, [1.3, 0.6]),
    }


@pytest.fixture(scope="module")
def systems():
    return {name: (symbolic.ode_system(f, state, params=params), y0)
            for name, (f, state, params, y0) in _systems().items()}


@pytest.mark.parametrize("name", ["half", "root", "param"])
@pytest.mark.parametrize("tol", [1e-9, 1e-12])     # orders 12 and 15 (even and odd)
def test_loop_written_out_and_batch_agree_bit_for_bit(systems, name, tol):
    from conmech.ivp.taylor import taylor_order, with_fixed_order
    system, y0 = systems[name]
    order = taylor_order(tol)
    loop = loop_jet(system, y0, order)
    fixed = with_fixed_order(system, tol, tol)
    tay = fixed.taylor
    assert tay["order"] == order
    w = np.zeros((tay["nw"], order + 1))
    w[:2, 0] = y0
    _call(tay["jet_fixed"], 0.0, order, w, _params(system))
    assert np.all(np.isfinite(loop)) and np.array_equal(w[:2], loop)
    # the batch routine (compiled on first need): members in the fastest dimension,
    # w(width, 0:order, nw)
    batch = system.taylor_parts("batch")
    width = batch["width"]
    wb = np.zeros((batch["nw"], order + 1, width))
    wb[:2, 0, :] = np.array(y0)[:, None]
    tb = np.zeros(width)
    fnb = ctypes.CFUNCTYPE(None, _P, ctypes.c_int, _P, _P)(
        conmech.compiled.function_address(batch["batch"]))
    fnb(tb.ctypes.data_as(_P), order, wb.ctypes.data_as(_P),
        _params(system).ctypes.data_as(_P))
    for m in range(width):
        assert np.array_equal(wb[:2, :, m], loop)


def test_powers_need_no_weighted_column():
    x, y = sp.symbols("x y")
    dec = T.decompose([y, -x*(x**2 + y**2)**sp.Rational(-3, 2)], [x, y], sp.Symbol("t"), [])
    kinds = dec.counts()
    assert kinds.get("pow") == 1 and kinds.get("sq") == 2
    # columns: 2 state, 2 squares, their sum, the power, the product; no j a[j] column
    assert dec.ncol == 7 and dec.jcol == {}
