"""Differential test of conmech.solve_ivp against scipy.integrate.solve_ivp: the same calls,
with combinations of the options drawn by hypothesis (derandomized, no example database),
on a few small Python right-hand sides and on compiled systems with the same equations.

The reference is SciPy's result. With method RK45 conmech takes SciPy's steps (the same
initial step and controller), so the structure of the two results must be the same
(list or array, shape, dtype, the number of points and of events per event function,
status, message, sol present or not) and the values must agree to round-off: the step
times, the states, the event times (to 1e-8 relative) and the dense output.

This holds for terminal counts above one too (terminal=2: the run goes on with SciPy's
steps after the first occurrence) and for events exactly zero at t0 (SciPy's rule).

Documented differences: nfev is SciPy's + 1 without first_step (SciPy's initial-step
heuristic is counted once more), and conmech's extra keys (naccept, nreject)."""
import math
import os
import warnings

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

scipy_integrate = pytest.importorskip("scipy.integrate")
import conmech  # noqa: E402
from conmech import systems  # noqa: E402

# examples per test (2 tests); CONMECH_DIFF_EXAMPLES for a longer search
DIFF = settings(max_examples=int(os.environ.get("CONMECH_DIFF_EXAMPLES", "250")),
                derandomize=True, database=None, deadline=None, print_blob=True,
                suppress_health_check=list(HealthCheck))


# ------------------------------------------------------------------ right-hand sides
# written with array operations, so that they also serve vectorized=True (y of shape (n, 1))
def decay(t, y, k=0.5):
    return -k * np.asarray(y)


def oscillator(t, y, w=1.0):
    return np.array([y[1], -w * w * y[0]])


def lotka_volterra(t, y, a=1.5):
    return np.array([a * y[0] - y[0] * y[1], -3.0 * y[1] + y[0] * y[1]])


def kepler_rhs(t, y, mu=1.0):
    r3 = (y[0] ** 2 + y[1] ** 2) ** 1.5
    return np.array([y[2], y[3], -mu * y[0] / r3, -mu * y[1] / r3])


PROBLEMS = {
    "decay": (decay, [2.0, 4.0, 8.0], 0.7),
    "oscillator": (oscillator, [1.0, 0.5], 1.3),
    "lotka_volterra": (lotka_volterra, [4.0, 2.0], 1.2),
}


# ------------------------------------------------------------------ events
def make_event(kind, t0, tf, y0, param, terminal, direction):
    """An event function of the kind (with SciPy's attributes); every kind takes *args."""
    if kind == "time":          # one crossing inside the span
        tc = t0 + param * (tf - t0)

        def event(t, y, *args):
            return t - tc
    elif kind == "level":       # a level of y[0] between its start and a fraction of it
        level = y0[0] * (1.0 - 0.4 * param)

        def event(t, y, *args):
            return y[0] - level
    elif kind == "periodic":    # several crossings (for terminal counts)
        omega = 4.0 + 3.0 * param

        def event(t, y, *args):
            return math.sin(omega * (t - t0)) + 0.3
    elif kind == "zero_at_t0":  # exactly zero at t0 (SciPy's rule at the start)
        def event(t, y, *args):
            return t - t0
    else:                       # zero at t0 through the state, moving with f
        def event(t, y, *args):
            return y[0] - y0[0]
    if terminal is not None:
        event.terminal = terminal
    if direction is not None:
        event.direction = direction
    return event


EVENT_KINDS = ["time", "level", "periodic", "zero_at_t0", "state_at_t0"]
event_spec = st.tuples(st.sampled_from(EVENT_KINDS), st.floats(0.05, 0.95),
                       st.sampled_from([None, False, True, 2]),
                       st.sampled_from([None, -1, 0, 1]))


def t_eval_from(spec, t0, tf):
    """None, or times in [t0, tf] (strictly monotonic towards tf) from fractions; 0 and 1
    give t0 and tf exactly."""
    if spec is None:
        return None
    kind, fracs = spec
    fr = sorted(set(fracs))
    pts = [t0 if f == 0.0 else tf if f == 1.0 else t0 + f * (tf - t0) for f in fr]
    return np.array(pts) if kind == "array" else pts


t_eval_spec = st.one_of(
    st.none(),
    st.tuples(st.sampled_from(["list", "array"]),
              st.one_of(st.just([]), st.lists(st.sampled_from([0.0, 1.0]), min_size=1,
                                              max_size=2),
                        st.lists(st.one_of(st.sampled_from([0.0, 1.0]),
                                           st.floats(0.01, 0.99).map(lambda f:
                                                                     round(f, 3))),
                                 min_size=1, max_size=6))))

tolerances = st.sampled_from([(1e-3, 1e-6), (1e-6, 1e-9), (1e-8, 1e-10), (1e-5, "array")])


# ------------------------------------------------------------------ comparison
def run(solver, *args, **kwargs):
    """The result of solver(*args, **kwargs), or the type of the exception it raised."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return solver(*args, **kwargs)
    except (ValueError, TypeError) as exc:
        return type(exc)


def same_array_structure(a, b, what):
    assert type(a) is type(b), (what, type(a), type(b))
    if isinstance(a, np.ndarray):
        assert a.shape == b.shape, (what, a.shape, b.shape)
        assert a.dtype == b.dtype, (what, a.dtype, b.dtype)
    else:
        assert len(a) == len(b), (what, a, b)


def compare(a, b, n, scale, t0, tf, with_t_eval=False, nfev_extra=None, vtol=1e-8,
            ttol=1e-6, same_grid=True):
    """SciPy's result a and conmech's b: the structure exactly, the values to the
    round-off of the same steps. nfev_extra: conmech's nfev - SciPy's, when pinned.
    Not same_grid (other steps): without t_eval, t and y at the ends only."""
    if isinstance(a, type) or isinstance(b, type):
        assert a is b, (a, b)          # both raise the same kind of exception
        return
    assert b.status == a.status and b.success == a.success, (a.status, b.status,
                                                             b.message)
    assert b.message == a.message
    span = abs(tf - t0)
    sgn = math.copysign(1.0, tf - t0)
    if same_grid or with_t_eval:
        same_array_structure(a.t, b.t, "t")
        same_array_structure(a.y, b.y, "y")
    else:
        assert type(b.t) is type(a.t) is np.ndarray and b.t.dtype == a.t.dtype
        assert type(b.y) is np.ndarray and b.y.shape[0] == a.y.shape[0]
    ta, tb, ya, yb = (np.asarray(a.t), np.asarray(b.t), np.asarray(a.y),
                      np.asarray(b.y))
    if not same_grid and not with_t_eval:
        assert b.t.size >= 2 and b.y.shape == (n, b.t.size)
        ends = [0, -1]
        ta, ya, tb, yb = ta[ends], ya[:, ends], tb[ends], yb[:, ends]
    # the step sizes agree to the round-off of the error estimates, which the controller
    # amplifies (up to ~1e-7 of the span at rtol 1e-10); y at those times agrees to that
    # shift times its rate of change
    np.testing.assert_allclose(tb, ta, rtol=0, atol=ttol * span)
    shift = np.max(np.abs(tb - ta), initial=0.0)
    np.testing.assert_allclose(yb, ya, rtol=vtol, atol=vtol * scale + 10 * shift * scale)
    if nfev_extra is not None:
        assert b.nfev == a.nfev + nfev_extra, (a.nfev, b.nfev)
    assert (a.sol is None) == (b.sol is None)
    if a.sol is not None:
        assert callable(b.sol)
        ends_a, ends_b = (a.sol.t_min, a.sol.t_max), (b.sol.t_min, b.sol.t_max)
        t_end = a.sol.t_max if sgn > 0 else a.sol.t_min
        np.testing.assert_allclose(ends_b, ends_a, rtol=0, atol=vtol * span)
        tt = t0 + np.linspace(0.0, 1.0, 8)[:-1] * (t_end - t0)
        sa, sb = a.sol(tt), b.sol(tt)
        assert sa.shape == sb.shape
        np.testing.assert_allclose(sb, sa, rtol=vtol,
                                   atol=vtol * scale + 10 * shift * scale)
    assert (a.t_events is None) == (b.t_events is None)
    assert (a.y_events is None) == (b.y_events is None)
    if a.t_events is None:
        return
    assert type(b.t_events) is list and type(b.y_events) is list
    assert len(b.t_events) == len(a.t_events) == len(b.y_events) == len(a.y_events)
    for k, (tea, teb, yea, yeb) in enumerate(zip(a.t_events, b.t_events, a.y_events,
                                                 b.y_events)):
        same_array_structure(tea, teb, f"t_events[{k}]")
        same_array_structure(yea, yeb, f"y_events[{k}]")
        np.testing.assert_allclose(teb, tea, rtol=vtol, atol=vtol * span)
        np.testing.assert_allclose(yeb, yea, rtol=vtol,
                                   atol=vtol * scale + 10 * shift * scale)


def options(draw_t_eval, events, dense, max_step, first_step, tol, vectorized, args,
            t0, tf, y0, single_event):
    """solve_ivp's keyword arguments of one drawn example."""
    te = t_eval_from(draw_t_eval, t0, tf)
    evs = None if events is None else [make_event(k, t0, tf, y0, p, term, d)
                                       for k, p, term, d in events]
    if evs is not None and single_event and len(evs) == 1:
        evs = evs[0]                    # a callable, not a list
    rtol, atol = tol
    if atol == "array":
        atol = np.geomspace(1e-8, 1e-6, len(y0))
    return dict(t_eval=te, dense_output=dense, events=evs, vectorized=vectorized,
                args=args, rtol=rtol, atol=atol, max_step=max_step, first_step=first_step)


common = dict(t0=st.sampled_from([0.0, 1.5]), length=st.sampled_from([2.0, 5.0]),
              backwards=st.booleans(), t_eval=t_eval_spec,
              events=st.one_of(st.none(), st.lists(event_spec, min_size=1, max_size=2)),
              dense=st.booleans(), max_step=st.sampled_from([np.inf, 0.7]),
              first_step=st.sampled_from([None, 1e-3, 0.05]), tol=tolerances,
              single_event=st.booleans())


# ------------------------------------------------------------------ Python right-hand sides
@DIFF
@given(problem=st.sampled_from(sorted(PROBLEMS)), vectorized=st.booleans(),
       use_args=st.booleans(), **common)
def test_rk45_python_rhs_agrees_with_scipy(problem, t0, length, backwards, t_eval, events,
                                           dense, max_step, first_step, tol, vectorized,
                                           use_args, single_event):
    fun, y0, param = PROBLEMS[problem]
    tf = t0 - length if backwards else t0 + length
    kw = options(t_eval, events, dense, max_step, first_step, tol, vectorized,
                 (param,) if use_args else None, t0, tf, y0, single_event)
    a = run(scipy_integrate.solve_ivp, fun, (t0, tf), y0, **kw)
    b = run(conmech.solve_ivp, fun, (t0, tf), y0, **kw)
    compare(a, b, len(y0), max(map(abs, y0)) * 10, t0, tf, kw["t_eval"] is not None,
            nfev_extra=1 if first_step is None else 0)


# ------------------------------------------------------------------ compiled systems
COMPILED = {
    "harmonic": (lambda: systems.harmonic(1.3), lambda t, y: oscillator(t, y, 1.3),
                 [1.0, 0.5]),
    "kepler": (lambda: systems.kepler(1.0), kepler_rhs, [0.6, 0.0, 0.0, 1.5]),
}


@DIFF
@given(system=st.sampled_from(sorted(COMPILED)), method=st.sampled_from(["RK45", "DOP853"]),
       **common)
def test_compiled_system_agrees_with_scipy(system, method, t0, length, backwards, t_eval,
                                           events, dense, max_step, first_step, tol,
                                           single_event):
    make, rhs, y0 = COMPILED[system]
    tf = t0 - length if backwards else t0 + length
    if method == "DOP853":
        # its steps are not SciPy's: steps of at most 0.25, shorter than the gaps between
        # the events' crossings, so that SciPy's rule (signs at the step ends) misses none
        # in either run and the events can be compared
        max_step = 0.25
    kw = options(t_eval, events, dense, max_step, first_step, tol, False, None, t0, tf, y0,
                 single_event)
    a = run(scipy_integrate.solve_ivp, rhs, (t0, tf), y0, method=method, **kw)
    b = run(conmech.solve_ivp, make(), (t0, tf), y0, method=method, **kw)
    scale, with_t_eval = max(map(abs, y0)) * 10, kw["t_eval"] is not None
    if method == "RK45":
        compare(a, b, len(y0), scale, t0, tf, with_t_eval)
    else:
        # DOP853: Hairer's initial step (documented), so other steps: the t grid of a run
        # without t_eval is not SciPy's; the values agree to the solution's accuracy
        compare(a, b, len(y0), scale, t0, tf, with_t_eval,
                vtol=max(100 * kw["rtol"], 1e-7), same_grid=False)
    if isinstance(b, type) or kw["events"] is not None or dense:
        return
    # the fast entry (plain float tolerances) and the full checks (NumPy floats): the
    # same Fortran call with the same numbers, bit for bit
    full = dict(kw, rtol=np.float64(kw["rtol"]), atol=np.asarray(kw["atol"], dtype=float))
    c = conmech.solve_ivp(make(), (t0, tf), y0, method=method, **full)
    assert type(c.t) is type(b.t)
    assert np.array_equal(c.t, b.t) and np.array_equal(c.y, b.y) and c.nfev == b.nfev


# ------------------------------------------------------------------ regressions
def test_rk45_last_step_is_cut_not_stretched_as_scipys():
    """SciPy's RK45 cuts a step only where it would pass tf: a step ending 0.016 % short
    of tf is taken and followed by a tiny last step (Hairer's rule would stretch it onto
    tf, one step fewer). The step-by-step class RK45 takes the same steps."""
    kw = dict(rtol=1e-6, atol=1e-9)
    a = scipy_integrate.solve_ivp(oscillator, (0.0, -5.0), [1.0, 0.5], **kw)
    b = conmech.solve_ivp(oscillator, (0.0, -5.0), [1.0, 0.5], **kw)
    assert a.t.size == b.t.size == 27
    assert 0 < a.t[-2] - a.t[-1] < 1e-3            # the short last step
    # the same steps up to the rounding of the error estimate, a sum of seven stages that
    # cancels to ~1e-8 of its terms: its summation order (NumPy's dot, which depends on
    # the machine and the NumPy build, against Fortran's loop) moves it by ~1e-8 of itself
    # (here np.dot, a loop and an exact sum differ by 1.4e-8) and the next step by ~3e-9
    np.testing.assert_allclose(b.t, a.t, rtol=1e-7)
    assert b.nfev == a.nfev + 1
    ts = []
    s = conmech.RK45(oscillator, 0.0, [1.0, 0.5], -5.0, **kw)
    while s.status == "running":
        s.step()
        ts.append(s.t)
    np.testing.assert_allclose(ts, a.t[1:], rtol=1e-7)
    assert np.array_equal(ts, b.t[1:])      # the step-by-step class: solve_ivp's bits


def test_no_event_reported_after_the_terminating_one_at_the_same_time():
    """SciPy's handle_events orders the roots of a step by time, ties by event index, and
    reports none after the event that ends the run: of two events with the same zero, the
    later one in the list is dropped when the first is terminal, kept when it is the
    terminal one itself."""
    def level(t, y):
        return y[0] - 1.5

    def terminal(t, y):
        return y[0] - 1.5
    terminal.terminal = True
    for evs, counts in (([terminal, level], [1, 0]), ([level, terminal], [1, 1]),
                        ([terminal, terminal], [1, 0])):
        a = scipy_integrate.solve_ivp(decay, (0.0, 3.0), [2.0, 4.0], events=evs)
        b = conmech.solve_ivp(decay, (0.0, 3.0), [2.0, 4.0], events=evs)
        assert [t.size for t in a.t_events] == [t.size for t in b.t_events] == counts
        assert [y.shape for y in a.y_events] == [y.shape for y in b.y_events]
        assert b.status == a.status == 1
        np.testing.assert_allclose(b.t, a.t, rtol=1e-10)


def test_terminal_event_at_t0_counts_the_first_step_only():
    """A terminal event zero at t0 that the first step moves in its direction stops the
    run at t0 (SciPy's rule) after that one step: nfev is SciPy's + 1 (its initial-step
    heuristic), the first step's evaluations and no more."""
    def at_start(t, y):
        return t
    at_start.terminal = True
    a = scipy_integrate.solve_ivp(decay, (0.0, 5.0), [2.0, 4.0], events=at_start)
    b = conmech.solve_ivp(decay, (0.0, 5.0), [2.0, 4.0], events=at_start)
    assert b.status == a.status == 1 and list(b.t) == list(a.t) == [0.0, 0.0]
    np.testing.assert_array_equal(b.t_events[0], [0.0])
    assert b.nfev == a.nfev + 1


def test_terminal_count_takes_scipys_steps_after_each_occurrence():
    """terminal=3 on an event that crosses zero every 0.5: the run goes on with SciPy's
    steps past the first two occurrences (no restart, no new initial step), so t, y, the
    events, the dense output and nfev are SciPy's (compare's criteria), forwards and
    backwards."""
    def wave(t, y):
        return math.sin(2 * math.pi * t) + 0.3
    wave.terminal = 3
    for tf in (5.0, -5.0):
        for dense in (False, True):
            kw = dict(events=wave, dense_output=dense, rtol=1e-6, atol=1e-9)
            a = scipy_integrate.solve_ivp(oscillator, (0.0, tf), [1.0, 0.5], **kw)
            b = conmech.solve_ivp(oscillator, (0.0, tf), [1.0, 0.5], **kw)
            assert b.status == a.status == 1 and b.t_events[0].size == 3
            assert b.t.size == a.t.size > 4 and b.naccept == a.t.size - 1
            compare(a, b, 2, 10.0, 0.0, tf, nfev_extra=1)
