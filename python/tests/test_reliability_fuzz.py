"""Fuzzing the Python API with hypothesis: >= 1,000 bad inputs in total,
deterministic (derandomize=True, no example database), bounded, a few seconds.

The property everywhere: a call either raises a clean exception (ValueError, TypeError or
RuntimeError, or the user's own exception re-raised unchanged) with a printable message,
or returns a result; a result called success has finite outputs of the right shapes, and
one not called success has a printable message. Never garbage, never a crash (a crash
would kill the test run, which test.sh reports as a failure), never a hang (every call is
bounded by max_steps / max_iter)."""
import math
import os
from pathlib import Path

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


# ------------------------------------------------------------------ symbolic front end
try:
    import sympy
except ImportError:           # conmech without its symbolic extra: nothing to fuzz here
    sympy = None
needs_sympy = pytest.mark.skipif(sympy is None, reason="sympy is not installed")
if sympy is not None:
    from conmech.symbolic.codegen import (check_source, generate,  # noqa: E402
                                          private_procedures)
    from conmech.symbolic.derive import derive_ode  # noqa: E402
    _X, _V, _K = sympy.symbols("x v k")
    junk_atom = st.one_of(
        st.sampled_from([_X, _V, _K, sympy.I, sympy.nan, sympy.zoo, sympy.oo, -sympy.oo,
                         sympy.pi, sympy.E, sympy.Integer(0), sympy.Rational(10 ** 400, 7),
                         sympy.Rational(1, 10 ** 330),
                         sympy.Rational(10 ** 20 + 1, 10 ** 19),
                         sympy.Float("1e308"), sympy.Float("1e-320"), sympy.Symbol("zz"),
                         sympy.Integral(_X, _X), sympy.Sum(_X / _K, (_K, 1, 2)),
                         sympy.Function("g")(_X), sympy.Matrix([_X, _V]), "x + v", None, True,
                         1j, [1.0], b"x", object()]),
        st.floats(allow_nan=True, allow_infinity=True, width=64),
        st.integers(-10 ** 400, 10 ** 400))
    junk_expr = st.recursive(
        junk_atom,
        lambda inner: st.one_of(
            st.builds(lambda a, b: _combine(a, b, "+"), inner, inner),
            st.builds(lambda a, b: _combine(a, b, "*"), inner, inner),
            st.builds(lambda a: _apply(a, sympy.sin), inner),
            st.builds(lambda a: _apply(a, sympy.sqrt), inner)),
        max_leaves=5)
else:
    junk_expr = st.none()


def _combine(a, b, op):
    try:
        return a + b if op == "+" else a * b
    except Exception:
        return a


def _apply(a, f):
    try:
        return f(a)
    except Exception:
        return a


@needs_sympy
@FUZZ
@given(f=st.lists(junk_expr, min_size=0, max_size=3),
       params=st.dictionaries(st.sampled_from(["k", "zz", "x", "k\n", "_k", "θ"]),
                              junk_scalar, max_size=2))
def test_fuzz_symbolic_front_end(f, params):
    """Derivation and code generation of junk: a clean exception naming the problem, or a
    record whose right-hand side is real, finite where sympy's is, and whose Fortran
    passes the source check (one procedure per entry point, printable ASCII)."""
    try:
        d = derive_ode(f, [_X, _V], params)
        src, entries = generate(d, model_values=d.param_values)
    except (ValueError, TypeError) as exc:
        check_text(str(exc), ascii_only=False)
        return
    c_names = [f"conmech_{e}" for e in entries] + [
        "conmech_model_info", "conmech_model_params", "conmech_model_param_names"]
    check_source(src, c_names + private_procedures(entries), c_names)
    assert len(d.f) == 2
    for e in d.f:
        assert not e.has(sympy.I, sympy.nan, sympy.zoo, sympy.oo, sympy.Integral, sympy.Sum)
    assert all(np.isfinite(d.param_values))


@needs_sympy
def test_fuzz_symbolic_compiled_agree_with_sympy(tmp_path, monkeypatch):
    """A sample of accepted random systems is compiled: the library's right-hand side
    equals sympy's evaluation of the same expressions (no term dropped, none changed)."""
    from conmech import symbolic
    monkeypatch.setenv("CONMECH_CACHE", str(tmp_path / "cache"))
    rng = np.random.default_rng(2024)
    atoms = [_X, _V, _K, sympy.pi, sympy.Rational(3, 7), sympy.Rational(10 ** 20 + 1,
                                                                          10 ** 19)]
    done = 0
    for trial in range(40):
        def rand_expr(depth=0):
            if depth > 2 or rng.random() < 0.3:
                return atoms[rng.integers(len(atoms))]
            a, b = rand_expr(depth + 1), rand_expr(depth + 1)
            return [a + b, a * b, sympy.sin(a) * b, sympy.exp(-a ** 2) + b,
                    a / (2 + b ** 2)][rng.integers(5)]
        f = [rand_expr(), rand_expr()]
        s = symbolic.ode_system(f, [_X, _V], params={_K: 1.5}, model_only=True)
        fn = sympy.lambdify([_X, _V, _K], f, "math")
        for _ in range(3):
            y = rng.uniform(-2, 2, 2)
            got = s.call("rhs", 0.0, y)
            want = np.array(fn(y[0], y[1], 1.5), dtype=float)
            np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13)
        done += 1
        if done == 8:
            break
    assert done == 8


# ------------------------------------------------------------------ model libraries and the cache
def _good_library(tmp_path_factory):
    from conmech import symbolic
    d = tmp_path_factory.mktemp("fuzzlib")
    s = symbolic.ode_system([_V, -_K * _X], [_X, _V], params={_K: 2.0})
    return Path(symbolic.save_model(s, d / "good.so"))


@pytest.fixture(scope="module")
def good_library(tmp_path_factory):
    import symbolic_seeds as seeds
    seeds.use_test_cache(tmp_path_factory.getbasetemp())
    return _good_library(tmp_path_factory)


def _corruptions(data, rng, n):
    """Damaged copies of an ELF shared library that no loader may map: truncations, random
    bytes, and header fields (table offsets and counts, segment sizes) pointed outside."""
    import struct
    out = []
    phoff, shoff = struct.unpack_from("<QQ", data, 32)
    phnum, shnum = struct.unpack_from("<HH", data, 56)[0], struct.unpack_from("<H", data,
                                                                               60)[0]
    for _ in range(n):
        kind = rng.integers(6)
        b = bytearray(data)
        if kind == 0:                                   # truncated anywhere
            b = b[:rng.integers(0, len(data))]
        elif kind == 1:                                 # random garbage, any size
            b = bytearray(rng.integers(0, 256, rng.integers(0, 4096), dtype=np.uint8))
        elif kind == 2:                                 # ELF magic, then garbage
            b = bytearray(b"\x7fELF" + bytes(rng.integers(0, 256, rng.integers(0, 200),
                                                           dtype=np.uint8)))
        elif kind == 3:                                 # a table offset past the end
            struct.pack_into("<Q", b, [32, 40][rng.integers(2)],
                             len(data) + int(rng.integers(1, 1 << 40)))
        elif kind == 4:                                 # a segment's file image past it
            k = rng.integers(phnum)
            struct.pack_into("<Q", b, phoff + 56 * k + [8, 32][rng.integers(2)],
                             len(data) + int(rng.integers(1, 1 << 30)))
        else:                                           # a section past the end
            k = rng.integers(1, shnum)
            struct.pack_into("<Q", b, shoff + 64 * k + 24, len(data) + int(rng.integers(
                1, 1 << 30)))
            struct.pack_into("<I", b, shoff + 64 * k + 4, 1)          # with contents
        out.append(bytes(b))
    return out


@needs_sympy
def test_fuzz_damaged_model_libraries_are_refused(good_library, tmp_path):
    """200 damaged copies: the Python check refuses every one (nothing is mapped), and so
    does the Fortran check of the programs (sweep --model, exit 2, no signal)."""
    from conmech._core.elf import LibraryError, check_library
    data = good_library.read_bytes()
    check_library(good_library, ["conmech_model_info"])
    rng = np.random.default_rng(7)
    cases = _corruptions(data, rng, 200)
    for k, b in enumerate(cases):
        p = tmp_path / f"bad{k}.so"
        p.write_bytes(b)
        with pytest.raises(LibraryError):
            check_library(p, ["conmech_model_info"])
    import shutil
    import subprocess
    root = Path(__file__).resolve().parents[2]
    if shutil.which("fpm") is None:
        pytest.fail("fpm is not on PATH: run the tests through scripts/test.sh")
    out = subprocess.run(["fpm", "run", "sweep", "--runner", "echo"], cwd=root,
                         capture_output=True, text=True, check=True).stdout
    exe = str(root / out.strip().splitlines()[-1].strip())
    for k in range(0, 200, 5):
        r = subprocess.run([exe, "--model", str(tmp_path / f"bad{k}.so"), "--y0", "1,0",
                            "--vary", "y0:1", "--from", "0", "--to", "1", "--count", "2"],
                           cwd=tmp_path, capture_output=True, text=True, timeout=60)
        assert r.returncode == 2 and "cannot load the model library" in r.stderr, \
            (k, r.returncode, r.stderr)


CACHE_FUZZ = """
import json, os, random, shutil, sys, warnings
import numpy as np, sympy as sp
from conmech import symbolic
base, work, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
x, v, k = sp.symbols("x v k")
make = lambda: symbolic.ode_system([v, -k*x - v**3/5], [x, v], params={k: 2.0},
                                   model_only=True)
os.environ["CONMECH_CACHE"] = base
ref = make().call("rhs", 0.3, [0.7, -0.2])
rng = random.Random(99)
for case in range(n):
    shutil.rmtree(work, ignore_errors=True)
    shutil.copytree(base, work)
    os.environ["CONMECH_CACHE"] = work
    so = [f for f in os.listdir(work) if f.endswith(".so")][0]
    lib = os.path.join(work, so)
    man = lib[:-3] + ".json"
    data = open(lib, "rb").read()
    kind = rng.randrange(8)
    if kind == 0:
        open(lib, "wb").write(data[:rng.randrange(len(data))])
    elif kind == 1:
        i = rng.randrange(len(data))
        open(lib, "wb").write(data[:i] + bytes([data[i] ^ (1 << rng.randrange(8))]) + data[i+1:])
    elif kind == 2:
        open(lib, "wb").write(bytes(rng.randrange(256) for _ in range(rng.randrange(5000))))
    elif kind == 3:
        open(lib, "wb").write(b"")
    elif kind == 4:
        os.unlink(man)
    elif kind == 5:
        open(man, "w").write(json.dumps({"format": 1, "size": rng.randrange(10**6),
                                         "sha256": "%064x" % rng.getrandbits(256)}))
    elif kind == 6:
        open(man, "wb").write(bytes(rng.randrange(256) for _ in range(rng.randrange(300))))
    else:
        open(lib, "ab").write(b"appended")
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        m = make()
    got = m.call("rhs", 0.3, [0.7, -0.2])
    assert np.array_equal(got, ref), (case, kind, got, ref)
    assert not m.cache_hit and any("rebuilding" in str(x.message) for x in w), (case, kind)
    left = [f for f in os.listdir(work) if f.startswith((".build-", ".tmp-"))]
    assert not left, left
print("OK", n)
"""


@needs_sympy
def test_fuzz_damaged_cache_entries_are_rebuilt(tmp_path):
    """Random damage to a cache entry (truncation, a flipped bit, garbage, an empty file,
    appended bytes, a missing, forged or garbage manifest), 24 cases in one child process
    (a SIGBUS would kill it and fail the test): every one is detected, rebuilt with a
    warning, and gives the same numbers; no temporary file is left."""
    import subprocess
    import sys
    base = tmp_path / "base"
    r = subprocess.run([sys.executable, "-c", CACHE_FUZZ, str(base), str(tmp_path / "w"),
                        "24"], capture_output=True, text=True, timeout=900)
    assert r.returncode == 0 and "OK 24" in r.stdout, (r.returncode, r.stderr[-3000:])


FULL_FUZZ = """
import os, sys, numpy as np, sympy as sp
from conmech import symbolic
cache = sys.argv[1]
os.environ["CONMECH_CACHE"] = cache
x, v = sp.symbols("x v")
outcomes = []
for i, free in enumerate([0, 512, 2048, 6144, 12288, 24576, 65536, 200000]):
    filler = os.path.join(cache, "filler")
    if os.path.exists(filler):
        os.unlink(filler)
    st = os.statvfs(cache)
    room = st.f_bavail * st.f_frsize
    with open(filler, "wb") as fh:
        fh.write(b"\\0" * max(room - free, 0))
    try:
        s = symbolic.ode_system([v, -x - x**3/(i + 2)], [x, v], model_only=True)
        assert np.allclose(s.call("rhs", 0.0, [1.0, 0.0]), [0.0, -1 - 1/(i + 2)])
        outcomes.append("built")
    except symbolic.CacheError as e:
        assert "is full" in str(e) and "No space left on device" in str(e), str(e)
        outcomes.append("full")
    names = os.listdir(cache)
    assert not [f for f in names if f.startswith((".build-", ".tmp-"))], names
    for f in names:
        if f.endswith(".so"):
            assert f[:-3] + ".json" in names, (f, names)
print("OUTCOMES", " ".join(outcomes))
"""


def _tmpfs_prefix():
    import shutil
    import subprocess
    if shutil.which("unshare") is None:
        return None
    for pre in (["unshare", "-m"], ["unshare", "-rm"]):
        r = subprocess.run(pre + ["sh", "-c", "d=$(mktemp -d) && mount -t tmpfs -o size=64k "
                                              "tmpfs $d && umount $d && rmdir $d"],
                           capture_output=True)
        if r.returncode == 0:
            return pre
    return None


@needs_sympy
@pytest.mark.skipif(_tmpfs_prefix() is None, reason="no private mount namespace here "
                    "(unshare -m / -rm refused); test_reliability_cache simulates full and "
                    "read-only caches instead")
def test_fuzz_cache_on_a_filling_tmpfs(tmp_path):
    """Builds into a 1 MB tmpfs left with 0 .. 200 kB free: each either succeeds and runs
    or says the cache is full; never a library without its manifest, never a partial
    file."""
    import subprocess
    import sys
    mnt = tmp_path / "mnt"
    mnt.mkdir()
    (tmp_path / "t.py").write_text(FULL_FUZZ)
    cmd = (f"mount -t tmpfs -o size=1m,mode=0700 tmpfs {mnt} && "
           f"{sys.executable} {tmp_path / 't.py'} {mnt}")
    r = subprocess.run(_tmpfs_prefix() + ["sh", "-c", cmd], capture_output=True, text=True,
                       timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    out = r.stdout.split("OUTCOMES")[1].split()
    assert out[0] == "full" and out[-1] == "built", out
