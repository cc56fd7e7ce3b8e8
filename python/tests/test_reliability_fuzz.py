"""Fuzzing the Python API with hypothesis (issue 13): >= 1,000 bad inputs in total,
deterministic (derandomize=True, no example database), bounded, a few seconds.

The property everywhere: a call either raises a clean exception (ValueError, TypeError or
RuntimeError, or the user's own exception re-raised unchanged) with a printable message,
or returns a result; a result called success has finite outputs of the right shapes, and
one not called success has a printable message. Never garbage, never a crash (a crash
would kill the test run, which test.sh reports as a failure), never a hang (every call is
bounded by max_steps / max_iter)."""
import math

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import conmech  # noqa: E402
from conmech import constrained, hill, stability, systems  # noqa: E402

CLEAN = (ValueError, TypeError, RuntimeError)
N = 200                                    # examples per test (6 tests: 1,200 inputs)
FUZZ = settings(max_examples=N, derandomize=True, database=None, deadline=None,
                suppress_health_check=list(HealthCheck), print_blob=False)


class UserError(Exception):
    """Raised by fuzzed callbacks: must come back unchanged."""


# ------------------------------------------------------------------ strategies
junk_scalar = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, width=64),
    st.sampled_from([0.0, -0.0, -1.0, 1e-300, 1e300, -1e300, math.inf, -math.inf,
                     math.nan, 5e-324]),
    st.integers(-3, 3), st.none(), st.booleans(), st.text(max_size=3),
    st.complex_numbers(max_magnitude=10, allow_nan=False), st.just(b"\xff"),
    st.lists(st.floats(allow_nan=True), max_size=3))
junk_array = st.one_of(
    junk_scalar,
    st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=0, max_size=4),
    st.lists(st.lists(st.floats(-2, 2), min_size=1, max_size=2), min_size=1, max_size=2),
    st.sampled_from([[], [[1.0, 2.0]], np.zeros((2, 2)), np.array([1.0 + 1j, 0.0]),
                     np.array(["a", "b"]), [1.0, None], (1.0, 0.0)]))
# what a misbehaving callback returns (after a few good calls)
junk_return = st.one_of(
    st.sampled_from(["none", "short", "long", "nan", "inf", "complex", "string", "raise",
                     "matrix", "scalar", "object", "huge"]))


def _bad(kind, good):
    """A callback result of kind ``kind`` in place of ``good`` (an array)."""
    good = np.asarray(good, dtype=float)
    make = {"none": lambda: None, "short": lambda: good[:-1] if good.size > 1 else [],
            "long": lambda: np.append(good, 1.0), "nan": lambda: good * np.nan,
            "inf": lambda: good + np.inf, "complex": lambda: good + 1j,
            "string": lambda: "x" * good.size, "matrix": lambda: np.eye(3),
            "scalar": lambda: 1.0 if good.size > 1 else [1.0, 2.0],
            "object": lambda: [object()] * good.size,
            "huge": lambda: np.full(good.shape, 1e308)}
    with np.errstate(all="ignore"):
        return make[kind]()


def _misbehaving(good_fun, kind, after):
    calls = [0]

    def f(*args):
        calls[0] += 1
        out = good_fun(*args)
        if calls[0] <= after:
            return out
        if kind == "raise":
            raise UserError("from the callback")
        return _bad(kind, out)
    return f


def check_text(text, ascii_only=True):
    """A message: non-empty and printable; ASCII unless it quotes the user's input."""
    assert isinstance(text, str) and text.strip() and text.isprintable(), repr(text)
    if ascii_only:
        assert all(ord(c) < 128 for c in text), repr(text)


def outcome(call):
    """Run call(); check the property; return 'raised', 'failed' or 'success'."""
    try:
        res = call()
    except UserError:
        return "raised"
    except CLEAN as exc:
        check_text(str(exc), ascii_only=False)
        return "raised"
    return res


def check_ode_result(r, n):
    if isinstance(r, str):
        return
    assert r.status in (-1, 0, 1) and r.success == (r.status >= 0)
    check_text(r.message)
    assert r.y.shape == (n, r.t.size)
    if r.success:
        assert np.all(np.isfinite(r.t)) and np.all(np.isfinite(r.y))
        assert r.nfev >= 0 and r.njev == 0 and r.nlu == 0


# ------------------------------------------------------------------ solve_ivp arguments
@FUZZ
@given(name=st.sampled_from(["t_span", "y0", "rtol", "atol", "max_step", "first_step",
                             "t_eval", "method", "max_steps", "args", "terminal",
                             "direction", "vectorized", "dense_output"]),
       value=junk_array, builtin=st.booleans())
def test_fuzz_solve_ivp_arguments(name, value, builtin):
    kw = dict(t_span=(0.0, 1.0), y0=[1.0, 0.0], max_steps=2000)   # bounded work
    fun = systems.harmonic() if builtin else (lambda t, y, *a: -np.asarray(y))
    if name in ("terminal", "direction"):
        def ev(t, y, *a):
            return y[0]
        setattr(ev, name, value)
        kw["events"] = ev
    elif name == "args":
        kw["args"] = value
        fun = lambda t, y, *a: -np.asarray(y)  # noqa: E731
    else:
        kw[name] = value
    r = outcome(lambda: conmech.solve_ivp(fun, **kw))
    n = np.size(kw["y0"]) if not isinstance(r, str) else 0
    check_ode_result(r, n)


# ------------------------------------------------------------------ callbacks returning junk
@FUZZ
@given(kind=junk_return, after=st.integers(0, 12),
       where=st.sampled_from(["rhs", "event", "rhs_dense", "rhs_vectorized"]),
       method=st.sampled_from(["RK45", "DOP853", "VERNER98", "DOPRI5"]))
def test_fuzz_solve_ivp_callbacks(kind, after, where, method):
    good_rhs = lambda t, y: np.array([y[1], -y[0]])  # noqa: E731
    rhs = good_rhs
    kw = dict(method=method)
    if where == "event":
        kw["events"] = _misbehaving(lambda t, y: y[0], kind, after)
    else:
        rhs = _misbehaving(good_rhs, kind, after)
        kw["dense_output"] = where == "rhs_dense"
        if where == "rhs_vectorized":
            kw["vectorized"] = True
            rhs = _misbehaving(lambda t, y: np.vstack((y[1], -y[0])), kind, after)
    r = outcome(lambda: conmech.solve_ivp(rhs, (0.0, 2.0), [1.0, 0.0], **kw))
    check_ode_result(r, 2)
    if not isinstance(r, str) and r.success:
        # only a callback that never misbehaved in a way that matters can succeed: the
        # solution must then be the true one
        np.testing.assert_allclose(r.y[0, -1], math.cos(2.0), atol=1e-2)


# ------------------------------------------------------------------ stability
@FUZZ
@given(func=st.sampled_from(["equilibrium_tol", "stm_rtol", "stm_atol", "stm_span",
                             "orbit_period", "orbit_iter", "orbit_free", "hill_eq_period",
                             "hill_eq_samples", "hill_eq_rtol", "floquet", "monodromy"]),
       value=junk_array)
def test_fuzz_stability_arguments(func, value):
    h = systems.harmonic()
    calls = {
        "equilibrium_tol": lambda: stability.equilibrium(h, [0.0, 0.0], tol=value),
        "stm_rtol": lambda: stability.stm(h, (0, 1), [1.0, 0.0], rtol=value),
        "stm_atol": lambda: stability.stm(h, (0, 1), [1.0, 0.0], atol=value),
        "stm_span": lambda: stability.stm(h, value, [1.0, 0.0]),
        "orbit_period": lambda: stability.periodic_orbit(h, [1.0, 0.0], value,
                                                         fixed_period=True, max_iter=5),
        "orbit_iter": lambda: stability.periodic_orbit(h, [1.0, 0.0], 6.3,
                                                       fixed_period=True, max_iter=value),
        "orbit_free": lambda: stability.symmetric_orbit(h, [1.0, 0.0], value, [1], 6.3,
                                                        max_iter=5),
        "hill_eq_period": lambda: stability.hill_equation(lambda t: 1.0, value),
        "hill_eq_samples": lambda: stability.hill_equation(value, 2 * np.pi),
        "hill_eq_rtol": lambda: stability.hill_equation(lambda t: 1.0, 1.0, rtol=value),
        "floquet": lambda: stability.floquet(value, 1.0),
        "monodromy": lambda: stability.monodromy(h, value, 1.0),
    }
    r = outcome(calls[func])
    if isinstance(r, tuple):
        assert all(np.all(np.isfinite(np.asarray(x, dtype=complex))) for x in r
                   if isinstance(x, np.ndarray))
    elif isinstance(r, stability.PeriodicOrbit):
        assert np.all(np.isfinite(r.monodromy)) and np.isfinite(r.period)
    elif isinstance(r, stability.HillEquationResult):
        assert np.all(np.isfinite(r.monodromy))


@FUZZ
@given(kind=junk_return, after=st.integers(0, 6),
       func=st.sampled_from(["stm", "equilibrium", "orbit", "hill_eq", "stm_jac"]))
def test_fuzz_stability_callbacks(kind, after, func):
    good = lambda t, y: np.array([y[1], -y[0]])  # noqa: E731
    bad = _misbehaving(good, kind, after)
    calls = {
        "stm": lambda: stability.stm(bad, (0, 1), [1.0, 0.0], rtol=1e-8, atol=1e-8),
        "stm_jac": lambda: stability.stm(
            good, (0, 1), [1.0, 0.0], rtol=1e-8, atol=1e-8,
            jac=_misbehaving(lambda t, y: np.array([[0.0, 1.0], [-1.0, 0.0]]), kind,
                             after)),
        "equilibrium": lambda: stability.equilibrium(bad, [0.0, 0.0]),
        "orbit": lambda: stability.symmetric_orbit(bad, [1.0, 0.0], [0], [1], 6.3,
                                                   free_time=True, rtol=1e-8, atol=1e-8,
                                                   max_iter=8),
        "hill_eq": lambda: stability.hill_equation(
            _misbehaving(lambda t: np.array(1.0), kind, after), 2 * np.pi, rtol=1e-8),
    }
    r = outcome(calls[func])
    if isinstance(r, tuple):            # stm: the exact answer or an exception
        np.testing.assert_allclose(r[1], [[math.cos(1), math.sin(1)],
                                          [-math.sin(1), math.cos(1)]], atol=1e-6)
    elif isinstance(r, stability.Equilibrium):
        assert r.kind == "centre"
    elif isinstance(r, stability.PeriodicOrbit):
        assert abs(r.period - 2 * np.pi) < 1e-6
    elif isinstance(r, stability.HillEquationResult):
        np.testing.assert_allclose(r.monodromy, np.eye(2), atol=1e-6)


# ------------------------------------------------------------------ hill and systems
@FUZZ
@given(func=st.sampled_from(["m", "kappa", "nsteps", "guess", "family", "transverse_rtol",
                             "transverse_t", "kepler", "pendulum_l", "arenstorf"]),
       value=junk_array)
def test_fuzz_hill_and_systems(func, value):
    calls = {
        "m": lambda: hill.variation_orbit(value),
        "kappa": lambda: hill.variation_orbit(0.08, kappa=value),
        "nsteps": lambda: hill.variation_orbit(0.08, nsteps=value),
        "guess": lambda: hill.variation_orbit(0.08, guess=value),
        "family": lambda: hill.family(value),
        "transverse_rtol": lambda: hill.transverse(hill.variation_orbit(0.08), rtol=value),
        "transverse_t": lambda: hill.transverse(hill.variation_orbit(0.08), t=value),
        "kepler": lambda: systems.kepler(mu=value),
        "pendulum_l": lambda: systems.pendulum(l=value),
        "arenstorf": lambda: systems.arenstorf(mu=value),
    }
    r = outcome(calls[func])
    if isinstance(r, hill.HillOrbit):
        assert np.isfinite(r.c) or abs(r.stability_index) > 1
        assert r.residual < 1e-6 and np.all(np.isfinite(r.monodromy))
    elif isinstance(r, hill.HillFamily):
        ok = r.success
        assert np.all(np.isfinite(r.y0[ok])) and np.all(np.isnan(r.y0[~ok]))


# ------------------------------------------------------------------ constrained
@FUZZ
@given(name=st.sampled_from(["rtol", "atol", "every", "proj_tol", "proj_max_iter",
                             "t_eval", "max_step", "first_step", "params", "q0",
                             "t_span", "mass", "forces", "phi", "jac"]),
       value=junk_array, kind=junk_return, after=st.integers(0, 8))
def test_fuzz_constrained(name, value, kind, after):
    user = name in ("mass", "forces", "phi", "jac")
    if user:
        fns = dict(mass=lambda t, q: np.eye(2), forces=lambda t, q, v: np.array([0.0, -9.81]),
                   phi=lambda t, q: np.array([0.5 * (q @ q - 1)]),
                   jac=lambda t, q: q[None, :].copy())
        fns[name] = _misbehaving(fns[name], kind, after)
        s = constrained.ConstrainedSystem(2, n_hol=1, **fns)
        call = lambda: constrained.solve(s, (0, 0.5), [0.6, -0.8], [0.0, 0.0])  # noqa: E731
    else:
        kw = {name: value}
        if name == "t_span":
            call = lambda: constrained.solve("pendulum_xy", value)  # noqa: E731
        else:
            call = lambda: constrained.solve("pendulum_xy", (0, 0.5), max_steps=2000,  # noqa
                                             **kw)
    r = outcome(call)
    if not isinstance(r, str):
        check_text(r.message)
        assert r.success == (r.status >= 0)
        if r.success:
            assert np.all(np.isfinite(r.q)) and np.all(np.isfinite(r.v))
            assert np.max(r.res_pos, initial=0.0) < 1e-6
