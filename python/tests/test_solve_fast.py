"""solve_ivp's fast entry (conmech.ivp.solve_fast): a call with plain inputs on a native
system takes it, gives the result of the full path bit for bit, and every bad input still
gets the full path's message."""
import math

import numpy as np
import pytest

import conmech
from conmech.ivp import solve_fast

Y0 = [0.5, 0.0, 0.0, 3.0 ** 0.5]


@pytest.fixture
def counted(monkeypatch):
    """The calls of the fast entry's two one-call routes (the packed call, and the kept
    propagation of a repeated plain call)."""
    calls = []
    for name in ("run_native", "run_kept"):
        real = getattr(solve_fast, name)

        def wrapped(*a, real=real, **k):
            calls.append(a)
            return real(*a, **k)
        monkeypatch.setattr(solve_fast, name, wrapped)
    return calls


def _same(a, b):
    assert set(a) == set(b)
    for k in a:
        va, vb = a[k], b[k]
        if isinstance(va, np.ndarray):
            assert va.dtype == vb.dtype and va.shape == vb.shape
            assert np.array_equal(va, vb), k
        else:
            assert va == vb, k


@pytest.mark.parametrize("method", ["RK45", "dop853", "DOPRI5", "Radau", "VERNER98"])
@pytest.mark.parametrize("y0", [Y0, tuple(Y0), np.array(Y0), [0.5, 0, 0, np.sqrt(3.0)]])
def test_fast_equals_full_path(counted, method, y0):
    kep = conmech.systems.kepler()
    fast = conmech.solve_ivp(kep, (0.0, 3.0), y0, method=method, rtol=1e-9, atol=1e-10)
    assert len(counted) == 1
    # 0-d array tolerances are not a fast-path kind: the full checks run
    full = conmech.solve_ivp(kep, (0.0, 3.0), y0, method=method, rtol=np.array(1e-9),
                             atol=np.array(1e-10))
    assert len(counted) == 1
    assert fast.success and fast.t.size > 3
    _same(fast, full)


def test_fast_zero_span_and_backwards(counted):
    kep = conmech.systems.kepler()
    for span in [(1.0, 1.0), (2, 0)]:
        fast = conmech.solve_ivp(kep, span, Y0, method="DOP853")
        full = conmech.solve_ivp(kep, list(map(np.float64, span)), Y0, method="DOP853")
        _same(fast, full)
    assert len(counted) == 2
    r = conmech.solve_ivp(kep, (1.0, 1.0), Y0)
    assert r.t.tolist() == [1.0, 1.0] and r.y.shape == (4, 2)


def test_fast_input_not_modified():
    kep = conmech.systems.kepler()
    y0 = np.array(Y0)
    r = conmech.solve_ivp(kep, (0.0, 1.0), y0, method="DOP853")
    assert np.array_equal(y0, Y0)
    r.y[:, 0] = 7.0            # the result owns its arrays
    assert np.array_equal(y0, Y0)


@pytest.mark.parametrize("kw, exc, text", [
    (dict(y0=[0.5, 0.0, math.nan, 1.0]), ValueError, "must be finite"),
    (dict(y0=[0.5, 0.0, 1.0]), ValueError, "y0 must have shape (4,)"),
    (dict(y0=np.zeros((4, 1))), ValueError, "1-dimensional"),
    (dict(y0=[0.5, 0.0, 0.0, 1j]), TypeError, "y0 must be real"),
    (dict(y0=[0.5, 0.0, 0.0, True]), None, None),
    (dict(t_span=(0.0, math.inf)), ValueError, "infinite end"),
    (dict(t_span=(math.nan, 1.0)), ValueError, "t_span[0] must be finite"),
    (dict(t_span=(0.0, 1.0, 2.0)), ValueError, "two elements"),
    (dict(t_span=(0.0, "1")), TypeError, "t_span[1]"),
    (dict(rtol=-1.0), ValueError, "rtol must be non-negative"),
    (dict(atol=math.inf), ValueError, "atol must be finite"),
    (dict(method="NOPE"), ValueError, "method must be one of"),
    (dict(method="RK4"), ValueError, "first_step is required"),
])
def test_bad_inputs_keep_their_messages(kw, exc, text):
    args = dict(t_span=(0.0, 1.0), y0=Y0, method="DOP853", rtol=1e-6, atol=1e-8)
    args.update(kw)
    kep = conmech.systems.kepler()
    call = (lambda: conmech.solve_ivp(kep, args["t_span"], args["y0"], method=args["method"],
                                      rtol=args["rtol"], atol=args["atol"]))
    if exc is None:           # a bool entry: NumPy's float of it, as the full path
        assert call().success
        return
    with pytest.raises(exc) as info:
        call()
    assert text in str(info.value)


def test_small_rtol_warns_as_scipy(counted):
    # the fast entry gives the full path's warning, at the user's line, and its result
    kep = conmech.systems.kepler()
    with pytest.warns(UserWarning, match="rtol") as fast_w:
        r = conmech.solve_ivp(kep, (0.0, 0.5), Y0, method="DOP853", rtol=1e-20)
    assert r.success and len(counted) == 1
    with pytest.warns(UserWarning, match="rtol") as full_w:
        full = conmech.solve_ivp(kep, (0.0, 0.5), Y0, method="DOP853",
                                 rtol=np.array(1e-20))
    assert len(counted) == 1
    assert [w.filename for w in fast_w] == [w.filename for w in full_w] == [__file__]
    assert [str(w.message) for w in fast_w] == [str(w.message) for w in full_w]
    _same(r, full)


@pytest.mark.parametrize("method", ["TAYLOR", "DOP853"])
def test_fast_symbolic_with_params(counted, method):
    sp = pytest.importorskip("sympy")
    from conmech import symbolic
    x, y, u, v, mu = sp.symbols("x y u v mu")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    kep = symbolic.ode_system([u, v, -mu*x/r3, -mu*y/r3], [x, y, u, v], params={mu: 1.0})
    fast = conmech.solve_ivp(kep, (0.0, 2*np.pi), Y0, method=method, rtol=1e-12, atol=1e-12)
    full = conmech.solve_ivp(kep, (0.0, 2*np.pi), Y0, method=method,
                             rtol=np.array(1e-12), atol=np.array(1e-12))
    assert len(counted) == 1
    _same(fast, full)
    assert np.max(np.abs(fast.y[:, -1] - Y0)) < 1e-9      # one period closes the orbit


def test_prepared_call_reads_the_systems_parameters(counted):
    # the packed arguments are kept per system, method and tolerances; the parameters
    # are the system's at each call (changed in place or given a new array)
    k = conmech.systems.kepler(1.0)
    ref = {mu: conmech.solve_ivp(conmech.systems.kepler(mu), (0.0, 2.0), Y0,
                                 method="DOP853", rtol=1e-9, atol=1e-9) for mu in (1.0, 2.0)}
    r1 = conmech.solve_ivp(k, (0.0, 2.0), Y0, method="DOP853", rtol=1e-9, atol=1e-9)
    k.params[0] = 2.0
    r2 = conmech.solve_ivp(k, (0.0, 2.0), Y0, method="DOP853", rtol=1e-9, atol=1e-9)
    k.params = np.array([1.0])
    r3 = conmech.solve_ivp(k, (0.0, 2.0), Y0, method="DOP853", rtol=1e-9, atol=1e-9)
    assert len(counted) == 5
    _same(r1, ref[1.0])
    _same(r2, ref[2.0])
    _same(r3, ref[1.0])
    assert not np.array_equal(r1.y, r2.y)


_TEV = [0.25, 1.0, 1.5, 2.75]


@pytest.mark.parametrize("span, opts", [
    ((0.0, 3.0), dict(t_eval=_TEV)),
    ((0.0, 3.0), dict(t_eval=tuple(_TEV))),
    ((0.0, 3.0), dict(t_eval=np.array(_TEV))),
    ((0.0, 3.0), dict(t_eval=np.linspace(0.0, 3.0, 101))),     # the array checks
    ((0.0, 3.0), dict(t_eval=[0, 1, 3])),                       # ints, both ends
    ((0.0, 3.0), dict(t_eval=[])),                              # no point: SciPy's lists
    ((3.0, 0.5), dict(t_eval=[2.5, 1.0, 0.5])),                 # backwards
    ((3.0, 0.0), dict(t_eval=np.linspace(3.0, 0.0, 40))),
    ((0.0, 3.0), dict(first_step=1e-3)),
    ((0.0, 3.0), dict(first_step=3)),                           # the whole span
    ((0.0, 3.0), dict(max_step=0.05)),
    ((0.0, 3.0), dict(max_step=1)),
    ((0.0, 3.0), dict(max_steps=5)),                            # stops: status -1
    ((0.0, 3.0), dict(max_steps=10**6, max_step=0.5, first_step=0.01, t_eval=_TEV)),
])
@pytest.mark.parametrize("method", ["DOP853", "RK45", "Radau"])
def test_fast_options_equal_full_path(counted, span, opts, method):
    # t_eval, first_step, max_step and max_steps of plain kinds take the fast entry and
    # give the full path's result bit for bit (0-d array tolerances: the full checks)
    kep = conmech.systems.kepler()
    fast = conmech.solve_ivp(kep, span, Y0, method=method, rtol=1e-9, atol=1e-10, **opts)
    assert len(counted) == 1
    full = conmech.solve_ivp(kep, span, Y0, method=method, rtol=np.array(1e-9),
                             atol=np.array(1e-10), **opts)
    assert len(counted) == 1
    _same(fast, full)
    if "t_eval" in opts:
        assert list(fast.t) == [float(t) for t in opts["t_eval"]]
    if opts.get("max_steps") == 5:
        assert fast.status == -1 and not fast.success and "max_steps" in fast.message
    else:
        assert fast.success


def test_fast_t_eval_taylor_symbolic(counted):
    # method TAYLOR on a symbolic system with output times: its polynomial at each time
    sp = pytest.importorskip("sympy")
    from conmech import symbolic
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    kep = symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])
    t_eval = np.linspace(0.0, 2*np.pi, 7)
    fast = conmech.solve_ivp(kep, (0.0, 2*np.pi), Y0, method="TAYLOR", t_eval=t_eval,
                             rtol=1e-12, atol=1e-12)
    full = conmech.solve_ivp(kep, (0.0, 2*np.pi), Y0, method="TAYLOR", t_eval=t_eval,
                             rtol=np.array(1e-12), atol=np.array(1e-12))
    assert len(counted) == 1
    _same(fast, full)
    ref = conmech.solve_ivp(conmech.systems.kepler(), (0.0, 2*np.pi), Y0, method="DOP853",
                            t_eval=t_eval, rtol=1e-13, atol=1e-13)
    assert np.max(np.abs(fast.y - ref.y)) < 1e-9


@pytest.mark.parametrize("kw, exc, text", [
    (dict(t_eval=[0.5, 2.0]), ValueError, "not within t_span"),
    (dict(t_eval=[-0.5, 0.5]), ValueError, "not within t_span"),
    (dict(t_eval=[0.5, 0.25]), ValueError, "not properly sorted"),
    (dict(t_eval=[0.5, 0.5]), ValueError, "not properly sorted"),
    (dict(t_eval=[0.5, math.nan]), ValueError, "NaN or Inf"),
    (dict(t_eval=np.linspace(0.0, 2.0, 50)), ValueError, "not within t_span"),
    (dict(t_eval=np.linspace(1.0, 0.0, 50)), ValueError, "not properly sorted"),
    (dict(t_eval=np.zeros((2, 2))), ValueError, "1-dimensional"),
    (dict(t_eval=["a"]), TypeError, "t_eval must be an array of real numbers"),
    (dict(first_step=2.0), ValueError, "first_step exceeds the length of t_span"),
    (dict(first_step=-0.1), ValueError, "first_step must be a positive"),
    (dict(first_step=math.nan), ValueError, "first_step must be a positive"),
    (dict(max_step=0.0), ValueError, "max_step must be a positive"),
    (dict(max_step=math.nan), ValueError, "max_step must be a positive"),
    (dict(max_steps=0), ValueError, "max_steps must be positive"),
    (dict(max_steps=2**31), ValueError, "max_steps must be positive"),
    (dict(max_steps=1.5), TypeError, "max_steps must be None or an integer"),
    (dict(max_steps=True), TypeError, "max_steps must be None or an integer"),
])
def test_bad_options_keep_their_messages(counted, kw, exc, text):
    kep = conmech.systems.kepler()
    with pytest.raises(exc) as info:
        conmech.solve_ivp(kep, (0.0, 1.0), Y0, method="DOP853", rtol=1e-6, atol=1e-8, **kw)
    assert text in str(info.value)
    assert not counted


def test_numpy_double_tolerances_take_the_fast_entry(counted):
    # tolerances from NumPy (np.logspace's values in a work-precision loop) are plain
    # doubles: the fast entry, with the result of the same Python floats
    kep = conmech.systems.kepler()
    for tol in np.logspace(-6, -10, 3):
        assert type(tol) is np.float64
        a = conmech.solve_ivp(kep, (0.0, 2.0), Y0, method="DOP853", rtol=tol, atol=tol)
        b = conmech.solve_ivp(kep, (0.0, 2.0), Y0, method="DOP853", rtol=float(tol),
                              atol=float(tol))
        _same(a, b)
    assert len(counted) == 6


@pytest.fixture
def routes(monkeypatch):
    """Which route each plain call took: "kept" or "packed"."""
    taken = []
    for name, label in (("run_native", "packed"), ("run_kept", "kept")):
        real = getattr(solve_fast, name)

        def wrapped(*a, real=real, label=label, **k):
            taken.append(label)
            return real(*a, **k)
        monkeypatch.setattr(solve_fast, name, wrapped)
    return taken


def _packed_only(monkeypatch):
    monkeypatch.setattr(solve_fast, "_KEPT_SIZE", 0)
    solve_fast._PREPARED.clear()


@pytest.mark.parametrize("method", ["RK45", "DOP853", "DOPRI5", "Radau", "VERNER98", "TAYLOR"])
def test_kept_route_equals_packed_call(routes, monkeypatch, method):
    # a plain call runs the system and stepper kept with its packed arguments: the
    # points, counts and bits of the packed call, at every repetition (the stepper
    # starts each run anew: nothing is carried over from the run before)
    sp = pytest.importorskip("sympy")
    from conmech import symbolic
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    kep = symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])
    solve_fast._PREPARED.clear()
    spans = [(0.0, 3.0), (3.0, 6.0), (0.0, 3.0), (2.0, -1.0), (1.0, 1.0)]
    kept = [conmech.solve_ivp(kep, s, Y0, method=method, rtol=1e-9, atol=1e-10) for s in spans]
    assert routes == ["kept"]*len(spans)
    _packed_only(monkeypatch)
    packed = [conmech.solve_ivp(kep, s, Y0, method=method, rtol=1e-9, atol=1e-10)
              for s in spans]
    assert routes[len(spans):] == ["packed"]*len(spans)
    for a, b in zip(kept, packed):
        _same(a, b)
    assert kept[0].nfev > 10 and kept[0].success


@pytest.mark.parametrize("opts", [
    dict(t_eval=_TEV), dict(t_eval=[]), dict(t_eval=np.linspace(0.0, 3.0, 400)),
    dict(first_step=1e-3), dict(max_step=0.05), dict(max_steps=5),
    dict(max_steps=10**6, max_step=0.5, first_step=0.01, t_eval=_TEV)])
@pytest.mark.parametrize("method", ["RK45", "DOP853", "Radau"])
def test_kept_route_with_options_equals_packed_call(routes, monkeypatch, method, opts):
    # the step options and output times of each call are set on the kept run: a call
    # with them and the plain call after it (the options do not stay) give the packed
    # call's results
    kep = conmech.systems.kepler()
    solve_fast._PREPARED.clear()

    def runs():
        return [conmech.solve_ivp(kep, (0.0, 3.0), Y0, method=method, rtol=1e-9, atol=1e-10,
                                  **opts),
                conmech.solve_ivp(kep, (0.0, 3.0), Y0, method=method, rtol=1e-9, atol=1e-10)]

    kept = runs()
    assert routes == ["kept", "kept"]
    _packed_only(monkeypatch)
    packed = runs()
    assert routes[2:] == ["packed", "packed"]
    for a, b in zip(kept, packed):
        _same(a, b)
    assert kept[1].success


def test_kept_route_long_run_failure_and_parameters(routes, monkeypatch):
    # more points than one call's room (handed over by flat_solve_take), a run that
    # fails, and parameters changed in place: as the packed call
    k = conmech.systems.kepler(1.0)
    solve_fast._PREPARED.clear()

    def runs():
        k.params[0] = 1.0
        out = [conmech.solve_ivp(k, (0.0, 400.0), Y0, method="DOP853", rtol=1e-10, atol=1e-10)]
        k.params[0] = 2.0
        out.append(conmech.solve_ivp(k, (0.0, 400.0), Y0, method="DOP853", rtol=1e-10,
                                     atol=1e-10))
        # a collision orbit: the right-hand side is not finite at the origin
        out.append(conmech.solve_ivp(k, (0.0, 5.0), [0.0, 0.0, 0.0, 0.0], method="DOP853",
                                     rtol=1e-10, atol=1e-10))
        return out

    kept = runs()
    assert routes == ["kept"]*3
    assert kept[0].t.size > 1000 and kept[0].success
    assert not np.array_equal(kept[0].y, kept[1].y)
    assert not kept[2].success and kept[2].status == -1
    _packed_only(monkeypatch)
    packed = runs()
    assert routes[3:] == ["packed"]*3
    for a, b in zip(kept, packed):
        _same(a, b)


def test_large_system_takes_the_packed_call(routes, monkeypatch):
    # the kept stepper's arrays live as long as the prepared entry: kept for small
    # systems only
    monkeypatch.setattr(solve_fast, "_KEPT_SIZE", 3)
    solve_fast._PREPARED.clear()
    kep = conmech.systems.kepler()
    a = conmech.solve_ivp(kep, (0.0, 1.0), Y0, method="DOP853")
    monkeypatch.setattr(solve_fast, "_KEPT_SIZE", 4)
    solve_fast._PREPARED.clear()
    b = conmech.solve_ivp(kep, (0.0, 1.0), Y0, method="DOP853")
    assert routes == ["packed", "kept"]
    _same(a, b)


def test_kept_memory_freed_with_its_entry():
    kep = conmech.systems.kepler()
    solve_fast._PREPARED.clear()
    conmech.solve_ivp(kep, (0.0, 1.0), Y0, method="DOP853")
    (entry,) = solve_fast._PREPARED.values()
    kept = entry[2]
    assert kept is not None and kept.handle
    import weakref
    gone = weakref.ref(kept)
    del entry, kept
    solve_fast._PREPARED.clear()
    assert gone() is None       # its finalizer (flat_propagation_free) has run


@pytest.mark.parametrize("kind, method", [("ode", "TAYLOR"), ("ode", "DOP853"),
                                          ("generalized", "TAYLOR")])
def test_new_parameter_array_is_read(counted, kind, method):
    """A symbolic system given a new parameter array (or one changed in place) between
    calls: each call runs with the parameters it has then, on the Taylor routes too (whose
    written-out system and a generalized system's first-order view share the array)."""
    sp = pytest.importorskip("sympy")
    from conmech import symbolic
    if kind == "ode":
        x, v, k = sp.symbols("x v k")
        system = symbolic.ode_system([v, -k*x], [x, v], params={k: 1.0})
    else:
        from sympy.physics.mechanics import dynamicsymbols
        q = dynamicsymbols("q")
        k = sp.Symbol("k")
        system = symbolic.lagrangian_system(q.diff()**2/2 - k*q**2/2, [q], params={k: 1.0})

    def end():
        r = conmech.solve_ivp(system, (0.0, 1.0), [1.0, 0.0], method=method, rtol=1e-12,
                              atol=1e-12)
        assert r.success
        return r.y[0, -1]
    assert abs(end() - np.cos(1.0)) < 1e-10
    system.params = np.array([4.0])
    assert abs(end() - np.cos(2.0)) < 1e-10
    system.params[0] = 9.0
    assert abs(end() - np.cos(3.0)) < 1e-10
    assert len(counted) == 3            # each call by the fast entry


def test_generalized_taylor_takes_the_fast_entry(counted):
    """M(q) q'' = Q with method TAYLOR: the fast entry runs its first-order view, as the
    full path does (the same result, bit for bit), with t_eval too; a failed run's message
    names the mass matrix there as well."""
    pytest.importorskip("sympy")
    import taylor_jets
    dp = taylor_jets.double_pendulum()
    y0 = [1.2, -0.4, 0.3, 0.1]
    for kw in ({}, dict(t_eval=[0.5, 1.0, 2.5])):
        fast = conmech.solve_ivp(dp, (0.0, 3.0), y0, method="TAYLOR", rtol=1e-12, atol=1e-12,
                                 **kw)
        full = conmech.solve_ivp(dp, (0.0, 3.0), y0, method="TAYLOR",
                                 rtol=np.array(1e-12), atol=np.array(1e-12), **kw)
        assert fast.success
        _same(fast, full)
    assert len(counted) == 2
    from sympy.physics.mechanics import dynamicsymbols
    from conmech import symbolic
    q = dynamicsymbols("q")
    singular = symbolic.lagrangian_system(q**2*q.diff()**2/2, [q])
    r = conmech.solve_ivp(singular, (0, 1), [1.0, -1.0], method="TAYLOR", rtol=1e-10,
                          atol=1e-10)
    assert len(counted) == 3
    assert not r.success and "mass matrix" in r.message
