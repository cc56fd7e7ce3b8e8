"""The Taylor recurrences of a compiled ode model are a library of their own, compiled on
first need (conmech.symbolic.taylor_library).

In a fresh compile cache (each test its own):
- a model built and solved with DOP853 leaves no Taylor library (one library in the cache,
  no Taylor source in the model's);
- the first TAYLOR solve builds it; its result is bit for bit that of the same model
  compiled with its recurrences inside (the complete library a model library for other
  programs holds), and agrees with DOP853;
- a second process finds the model and its Taylor library in the cache: no compilation
  (the cache's .so files unchanged, the build reported as a hit);
- each part is built when a call needs it: a solve the double routine only, stm its
  variational system, an ensemble the batch routine, taylor_quad the quadruple one;
- the copies of with_params share the lazy library (built once); stm(method="TAYLOR"),
  compiled events and Taylor ensembles build it on their first use;
- save_model writes a complete library (load_model finds its Taylor routines);
- LazyTaylor builds once, retries after a failure and refuses a wrong result.
"""
import glob
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import conmech  # noqa: E402
from conmech import ensemble, stability, symbolic  # noqa: E402
from conmech.mechanics.compiled import LazyTaylor, library_taylor, ode_system  # noqa: E402
from conmech.symbolic import build  # noqa: E402
from conmech.symbolic.codegen import generate  # noqa: E402

# a damped pendulum with a parameter: sin and cos recurrences, a linear term
_BUILD = textwrap.dedent("""
    import sympy as sp
    from conmech import symbolic
    th, om, g, c = sp.symbols("th om g c")
    model = symbolic.ode_system([om, -g*sp.sin(th) - c*om], [th, om],
                                params={g: 9.81, c: 0.1}, model_only=True)
    system = symbolic.pipeline._system(model)
""")
Y0 = [1.2, 0.0]
SPAN = (0.0, 5.0)


@pytest.fixture
def cache(tmp_path, monkeypatch):
    d = tmp_path / "cache"
    monkeypatch.setenv("CONMECH_CACHE", str(d))
    return d


def _make():
    scope = {}
    exec(_BUILD, scope)
    return scope["model"], scope["system"]


def _libraries(d):
    return sorted(glob.glob(os.path.join(str(d), "conmech_*.so")))


def test_dop853_leaves_no_taylor_library_and_taylor_builds_it(cache):
    model, system = _make()
    assert "conmech_taylor" not in model.source
    assert system.taylor_pending
    assert len(_libraries(cache)) == 1
    ref = conmech.solve_ivp(system, SPAN, Y0, method="DOP853", rtol=1e-12, atol=1e-12)
    assert ref.success
    assert system.taylor_pending and len(_libraries(cache)) == 1
    assert not hasattr(model, "taylor_path")

    res = conmech.solve_ivp(system, SPAN, Y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
    assert res.success
    assert not system.taylor_pending and model.taylor_cache_hit is False
    assert model.taylor_path in _libraries(cache)
    # a solve needs the double routine only: no batch, quadruple or variational code
    assert set(model.taylor_paths) == {"core"}
    np.testing.assert_allclose(res.y[:, -1], ref.y[:, -1], rtol=0, atol=1e-9)

    # the same model compiled with its recurrences inside (one complete library): the
    # same coefficients, so the same steps and the same result to the last bit
    src, entries = generate(model.derived, taylor=True)
    assert "conmech_taylor" in src and "taylor_var" in entries
    path, _ = build.compile_source(src, None, entries)
    lib, addr = build.load(path, entries)
    whole = ode_system(2, addr["rhs"], jac=addr["jac"], params=system.params,
                       param_names=system.param_names, keep=lib,
                       taylor=library_taylor(lib))
    one = conmech.solve_ivp(whole, SPAN, Y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(one.t, res.t)
    np.testing.assert_array_equal(one.y, res.y)


def test_second_process_reuses_the_taylor_library(cache):
    model, system = _make()
    first = conmech.solve_ivp(system, SPAN, Y0, method="TAYLOR", rtol=1e-10, atol=1e-10)
    before = _libraries(cache)
    stamps = {p: os.stat(p).st_mtime_ns for p in before}
    code = _BUILD + textwrap.dedent("""
        import conmech
        assert system.taylor_pending
        r = conmech.solve_ivp(system, (0.0, 5.0), [1.2, 0.0], method="TAYLOR",
                              rtol=1e-10, atol=1e-10)
        print(model.cache_hit, model.taylor_cache_hit, repr(float(r.y[0, -1])))
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=dict(os.environ), timeout=600)
    assert out.returncode == 0, out.stderr
    hit, taylor_hit, y_end = out.stdout.split()
    assert hit == "True" and taylor_hit == "True"
    assert float(y_end) == first.y[0, -1]
    assert _libraries(cache) == before
    assert {p: os.stat(p).st_mtime_ns for p in before} == stamps


def test_with_params_shares_and_stm_builds(cache):
    model, system = _make()
    other = system.with_params(c=0.3)
    assert other.taylor_pending and system.taylor_pending
    # stm by Taylor's method on the copy: builds the (shared) library
    y1, phi = stability.stm(other, (0.0, 2.0), Y0, method="TAYLOR")
    y1d, phid = stability.stm(other, (0.0, 2.0), Y0)
    np.testing.assert_allclose(phi, phid, rtol=0, atol=1e-8)
    np.testing.assert_allclose(y1, y1d, rtol=0, atol=1e-10)
    assert set(model.taylor_paths) == {"core", "var"}
    n = len(_libraries(cache))
    assert not system.taylor_pending        # the original's lazy set is the same one
    assert system.taylor["jet"] is other.taylor["jet"]
    res = conmech.solve_ivp(system, SPAN, Y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
    ref = conmech.solve_ivp(system, SPAN, Y0, method="DOP853", rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.y[:, -1], ref.y[:, -1], rtol=0, atol=1e-9)
    # only the library written out for the solve's order was added
    assert len(_libraries(cache)) == n + 1


def test_events_and_ensemble_build_it(cache):
    model, system = _make()
    th = model.derived.coords[0]
    ev = symbolic.event(system, th, direction=-1)
    res = conmech.solve_ivp(system, SPAN, Y0, method="TAYLOR", rtol=1e-12, atol=1e-12,
                            events=[ev])
    ref = conmech.solve_ivp(system, SPAN, Y0, method="DOP853", rtol=1e-12, atol=1e-12,
                            events=[lambda t, y: y[0]])
    down = [t for t, y in zip(ref.t_events[0], ref.y_events[0]) if y[1] < 0]
    assert len(res.t_events[0]) == len(down) >= 2
    np.testing.assert_allclose(res.t_events[0], down, rtol=0, atol=1e-9)

    _, fresh = _make()         # the same model from the cache: its lazy set not built
    assert fresh.taylor_pending
    y0s = np.array([[1.2, 0.0], [0.5, 0.1], [-0.3, 1.0]])
    ens = ensemble.solve(fresh, SPAN, y0s, method="TAYLOR", rtol=1e-12, atol=1e-12)
    assert ens.success and not fresh.taylor_pending
    assert set(symbolic.model_of(fresh).taylor_paths) == {"core", "batch"}
    for k in range(3):
        one = conmech.solve_ivp(fresh, SPAN, y0s[k], method="TAYLOR", rtol=1e-12,
                                atol=1e-12)
        # the same steps (the batch routine's coefficients may differ from the written-out
        # ones in the last bit: a sin/cos recurrence vectorised over the members)
        assert ens.naccept[k] == one.naccept
        np.testing.assert_allclose(ens.y_final[k], one.y[:, -1], rtol=0, atol=1e-14)


def test_save_model_keeps_the_taylor_routines(cache, tmp_path):
    model, system = _make()
    path = symbolic.save_model(system, tmp_path / "pendulum.so")
    assert system.taylor_pending        # the saved library is compiled on its own
    loaded = conmech.compiled.load_model(path)
    assert loaded.taylor is not None and loaded.taylor["nw"] >= 2
    a = conmech.solve_ivp(loaded, SPAN, Y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
    b = conmech.solve_ivp(system, SPAN, Y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(a.y[:, -1], b.y[:, -1], rtol=0, atol=1e-12)


def test_quadruple_precision_part(cache):
    model, system = _make()
    from conmech.symbolic import taylor_quad
    r = taylor_quad.reference(system, (0, "1"), ["1.2", "0"], tol=1e-25)
    assert r.success and set(model.taylor_paths) == {"core", "qp"}
    ref = conmech.solve_ivp(system, (0, 1.0), Y0, method="DOP853", rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(r.y_float, ref.y[:, -1], rtol=0, atol=1e-11)


def test_non_smooth_model_has_no_taylor_library(cache):
    x = sp.Symbol("x")
    system = symbolic.ode_system([-sp.Abs(x)], [x])
    assert system.taylor_pending
    with pytest.raises(ValueError):
        conmech.solve_ivp(system, (0, 1), [1.0], method="TAYLOR")
    assert system.taylor is None and not system.taylor_pending
    assert len(_libraries(cache)) == 1
    assert conmech.solve_ivp(system, (0, 1), [1.0]).success


def test_lazy_taylor_builds_once_and_retries_after_a_failure():
    calls = []

    def build_fails_first():
        calls.append(1)
        if len(calls) == 1:
            raise build.CompileError("no compiler")
        return None

    def build_part(part):
        if part == "core":
            return build_fails_first()
        raise AssertionError("no part is built for a system without recurrences")

    lazy = LazyTaylor(build_part)
    with pytest.raises(build.CompileError):
        lazy.get()
    assert not lazy.built
    assert lazy.get("var") is None and lazy.built and not lazy.has("var")
    assert lazy.get() is None and len(calls) == 2
    parts = []
    two = LazyTaylor(lambda part: parts.append(part) or {part: 1})
    assert two.get() == {"core": 1} and two.get("var", "var") == {"core": 1, "var": 1}
    assert two.get("var") == {"core": 1, "var": 1} and parts == ["core", "var"]
    with pytest.raises(TypeError):
        LazyTaylor(42)
    with pytest.raises(TypeError):
        LazyTaylor(lambda part: 42).get()
