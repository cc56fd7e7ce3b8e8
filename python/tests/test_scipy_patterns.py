"""SciPy's own solve_ivp usage patterns (from its documentation and tests) run unchanged
against conmech.solve_ivp and compared with scipy.integrate.solve_ivp.

With the default method (RK45) conmech takes SciPy's steps (same initial step, same
controller), so the results agree to round-off and the step counts match; nfev is SciPy's
+ 1 (conmech evaluates f at t0 once more)."""
import numpy as np
import pytest

scipy_integrate = pytest.importorskip("scipy.integrate")
import conmech  # noqa: E402

SCIPY_KEYS = {"t", "y", "sol", "t_events", "y_events", "nfev", "njev", "nlu", "status",
              "message", "success"}


def both(*args, **kwargs):
    """The same call to SciPy and to conmech."""
    return (scipy_integrate.solve_ivp(*args, **kwargs),
            conmech.solve_ivp(*args, **kwargs))


def same(a, b, rtol=1e-9, atol=1e-12, steps=True, extra=1):
    assert a.status == b.status and a.success == b.success
    assert SCIPY_KEYS <= set(b.keys())
    if steps:
        assert a.t.shape == b.t.shape
        np.testing.assert_allclose(b.t, a.t, rtol=rtol, atol=atol)
        assert b.nfev == a.nfev + extra and b.njev == a.njev == 0 and b.nlu == a.nlu == 0
    assert a.y.shape == b.y.shape
    np.testing.assert_allclose(b.y, a.y, rtol=rtol, atol=atol)


# ------------------------------------------------------------------ from SciPy's docs
def exponential_decay(t, y):
    return -0.5 * y


def test_docs_basic_exponential_decay():
    a, b = both(exponential_decay, [0, 10], [2, 4, 8])
    same(a, b)


def test_docs_t_eval():
    a, b = both(exponential_decay, [0, 10], [2, 4, 8], t_eval=[0, 1, 2, 4, 10])
    same(a, b)
    np.testing.assert_array_equal(b.t, [0, 1, 2, 4, 10])


def upward_cannon(t, y):
    return [y[1], -0.5]


def hit_ground(t, y):
    return y[0]


hit_ground.terminal = True
hit_ground.direction = -1


def apex(t, y):
    return y[1]


def test_docs_cannon_events_terminal_and_apex():
    a, b = both(upward_cannon, [0, 100], [0, 10], events=(hit_ground, apex),
                dense_output=True)
    same(a, b)
    assert b.status == 1
    for ta, tb in zip(a.t_events, b.t_events):
        np.testing.assert_allclose(tb, ta, rtol=1e-10)
    np.testing.assert_allclose(b.t_events[0], [40.0], rtol=1e-10)
    np.testing.assert_allclose(b.t_events[1], [20.0], rtol=1e-10)
    for ya, yb in zip(a.y_events, b.y_events):
        assert ya.shape == yb.shape
        np.testing.assert_allclose(yb, ya, rtol=1e-8, atol=1e-10)


def lotkavolterra(t, z, a, b, c, d):
    x, y = z
    return [a * x - b * x * y, -c * y + d * x * y]


def test_docs_lotka_volterra_args_dense_output():
    a, b = both(lotkavolterra, [0, 15], [10, 5], args=(1.5, 1, 3, 1), dense_output=True)
    same(a, b)
    t = np.linspace(0, 15, 300)
    np.testing.assert_allclose(b.sol(t), a.sol(t), rtol=1e-8, atol=1e-10)
    assert b.sol(t).shape == (2, 300) and b.sol(7.5).shape == (2,)


def test_docs_lotka_volterra_dop853_tight():
    # a different method: not the same steps, the same solution to the tolerance
    a, b = both(lotkavolterra, [0, 15], [10, 5], method="DOP853", args=(1.5, 1, 3, 1),
                rtol=1e-10, atol=1e-10, t_eval=np.linspace(0, 15, 31))
    same(a, b, rtol=1e-7, atol=1e-8, steps=False)


# ------------------------------------------------------------------ from SciPy's tests
def fun_rational(t, y):
    return np.array([y[1] / t, y[1] * (y[0] + 2 * y[1] - 1) / (t * (y[0] - 1))])


def sol_rational(t):
    return np.asarray((t / (t + 10), 10 * t / (t + 10) ** 2))


@pytest.mark.parametrize("t_span", [[5, 9], [5, 1]])   # forward and backward
def test_tests_integration_rational(t_span):
    y0 = sol_rational(t_span[0])
    a, b = both(fun_rational, t_span, y0, rtol=1e-3, atol=1e-6)
    same(a, b)
    err = np.abs(b.y - sol_rational(b.t))
    assert np.all(err < 5 * (1e-6 + 1e-3 * np.abs(sol_rational(b.t))))


def test_tests_vectorized_fun_gets_a_column():
    seen = []

    def fun(t, y):
        seen.append(y.shape)
        return np.vstack((y[1], -y[0]))
    a, b = both(fun, [0, 2], [1.0, 0.0], vectorized=True)
    same(a, b)
    assert set(seen) == {(2, 1)}


def test_tests_max_step_and_first_step():
    a, b = both(fun_rational, [5, 9], sol_rational(5), max_step=0.5, first_step=0.01)
    same(a, b, extra=0)     # a given first step: no initial-step evaluations on either side
    assert np.all(np.diff(b.t) <= 0.5 + 1e-12) and abs(b.t[1] - 5.01) < 1e-12


@pytest.mark.parametrize("y0", [[1, 0], (1, 0), np.array([1.0, 0.0]), [1.0, 0]])
def test_tests_list_tuple_array_int_y0(y0):
    a, b = both(lambda t, y: [y[1], -y[0]], [0, 3], y0)
    same(a, b)


def test_tests_rtol_atol_arrays():
    a, b = both(exponential_decay, [0, 10], [2, 4, 8], rtol=[1e-3, 1e-5, 1e-7],
                atol=[1e-6, 1e-8, 1e-9])
    same(a, b)


def test_tests_event_terminal_count():
    # SciPy >= 1.11: terminal=2 stops at the second occurrence
    def cross(t, y):
        return y[0]
    cross.terminal = 2
    a, b = both(lambda t, y: [y[1], -y[0]], [0, 10], [1.0, 0.0], events=cross,
                rtol=1e-10, atol=1e-10)
    assert a.status == b.status == 1
    np.testing.assert_allclose(b.t_events[0], a.t_events[0], rtol=1e-9)
    np.testing.assert_allclose(b.t_events[0], [np.pi / 2, 3 * np.pi / 2], rtol=1e-9)
    np.testing.assert_allclose(b.t[-1], a.t[-1], rtol=1e-9)
    np.testing.assert_allclose(b.y[:, -1], a.y[:, -1], atol=1e-8)


@pytest.mark.parametrize("direction", [0, 1, -1])
def test_tests_event_zero_at_t0(direction):
    # SciPy's rule: an event zero at t0 counts at t0 when the first step moves it in its
    # direction (here y[0] = sin t rises)
    def ev(t, y):
        return y[0]
    ev.direction = direction
    a, b = both(lambda t, y: [y[1], -y[0]], [0, 7], [0.0, 1.0], events=ev,
                rtol=1e-10, atol=1e-10)
    assert len(a.t_events[0]) == len(b.t_events[0])
    np.testing.assert_allclose(b.t_events[0], a.t_events[0], rtol=1e-9, atol=1e-12)


def test_tests_terminal_event_zero_at_t0_stops_at_once():
    def ev(t, y):
        return y[0]
    ev.terminal = True
    a, b = both(lambda t, y: [y[1], -y[0]], [0, 7], [0.0, 1.0], events=ev)
    assert a.status == b.status == 1
    np.testing.assert_array_equal(b.t, a.t)
    np.testing.assert_array_equal(b.t_events[0], a.t_events[0])


def test_tests_events_with_t_eval_and_no_events_found():
    def never(t, y):
        return y[0] + 10.0
    a, b = both(exponential_decay, [0, 2], [1.0], events=[never], t_eval=[0.5, 1.5])
    same(a, b)
    assert b.t_events[0].shape == a.t_events[0].shape == (0,)
    assert b.y_events[0].shape == a.y_events[0].shape == (0,)


def test_terminal_count_with_t_eval_before_the_events():
    # the run restarts after the first of two terminal occurrences with no t_eval point
    # left: t holds t_eval's points only (no step of the later part), as SciPy's
    def cross(t, y):
        return y[0]
    cross.terminal = 2
    a, b = both(lambda t, y: [y[1], -y[0]], [0, 10], [1.0, 0.0], events=cross,
                t_eval=[0.1, 0.5], rtol=1e-10, atol=1e-10)
    assert a.status == b.status == 1
    np.testing.assert_array_equal(b.t, a.t)
    np.testing.assert_allclose(b.y, a.y, rtol=1e-8)
    np.testing.assert_allclose(b.t_events[0], a.t_events[0], rtol=1e-9)


@pytest.mark.parametrize("kw", [dict(), dict(method="DOP853"), dict(dense_output=True),
                                dict(events=lambda t, y: y[0] - 0.5), dict(t_span=(1, 1)),
                                dict(y0=[1.0 + 1.0j])])
def test_empty_t_eval_gives_empty_lists(kw):
    # t_eval=[]: the span is integrated (events, dense output, counts) and t, y are the
    # empty lists SciPy returns, for a Python right-hand side and a compiled system
    args = dict(t_span=(0, 2), y0=[1.0])
    args.update(kw)
    t_span, y0 = args.pop("t_span"), args.pop("y0")
    a, b = both(exponential_decay, t_span, y0, t_eval=[], **args)
    assert a.t == b.t == [] and a.y == b.y == []
    assert a.status == b.status == 0
    if "events" in kw:
        np.testing.assert_allclose(b.t_events[0], a.t_events[0], rtol=1e-3)
    if "dense_output" in kw:
        np.testing.assert_allclose(b.sol(1.0), a.sol(1.0), rtol=1e-3)
    sys = conmech.systems.harmonic()
    for opts in [dict(rtol=1e-6), dict(rtol=np.float64(1e-6)), dict(dense_output=True)]:
        r = conmech.solve_ivp(sys, t_span, [1.0, 0.0], t_eval=[], **opts)
        assert r.t == [] and r.y == [] and r.success


def test_tests_ode_solution_attributes():
    a, b = both(exponential_decay, [0, 10], [2, 4, 8], dense_output=True)
    sa, sb = a.sol, b.sol
    assert sb.n_segments == sa.n_segments and sb.ascending == sa.ascending
    np.testing.assert_allclose(sb.ts, sa.ts, rtol=1e-12)
    assert sb.t_min == sa.t_min and sb.t_max == sa.t_max
    assert len(sb.interpolants) == len(sa.interpolants)
    ia, ib = sa.interpolants[3], sb.interpolants[3]
    assert ib.t_old == pytest.approx(ia.t_old) and ib.t == pytest.approx(ia.t)
    tm = 0.5 * (ia.t_old + ia.t)
    np.testing.assert_allclose(ib(tm), ia(tm), rtol=1e-9)
    # backward
    a, b = both(exponential_decay, [10, 0], [2, 4, 8], dense_output=True)
    assert a.sol.ascending is b.sol.ascending is False
    np.testing.assert_allclose(b.sol(np.array([9.0, 3.0])), a.sol(np.array([9.0, 3.0])),
                               rtol=1e-8)


def test_tests_result_fields_and_messages():
    a, b = both(exponential_decay, [0, 1], [1.0])
    assert a.message == b.message and a.success is b.success is True


def test_tests_complex_y0_integrated_or_refused_cleanly():
    # a complex y0 is integrated as SciPy does (explicit methods); Radau refuses it, as
    # SciPy's; a complex right-hand side for a real y0 is refused
    r = conmech.solve_ivp(lambda t, y: -1j * y, [0, 1], [1.0 + 0j], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(r.y[0, -1], np.exp(-1j), atol=1e-8)
    with pytest.raises(ValueError, match="complex"):
        conmech.solve_ivp(lambda t, y: -1j * y, [0, 1], [1.0 + 0j], method="Radau")
    with pytest.raises(TypeError, match="complex"):
        conmech.solve_ivp(lambda t, y: -1j * y, [0, 1], [1.0])


def test_tests_wrong_shapes_raise_value_error_like_scipy():
    for fun in (lambda t, y: [1.0, 2.0, 3.0], lambda t, y: None):
        with pytest.raises(ValueError):
            conmech.solve_ivp(fun, [0, 1], [1.0, 0.0])


def test_tests_jac_option_is_accepted():
    # the explicit methods do not use jac (SciPy's RK45 neither): njev stays 0
    jac = lambda t, y: [[-0.5]]  # noqa: E731
    with pytest.warns(UserWarning, match="no effect for a chosen solver: `jac`"):
        a, b = both(exponential_decay, [0, 1], [1.0], jac=jac)
    same(a, b)
    with pytest.raises(ValueError, match="jac"):
        conmech.solve_ivp(exponential_decay, [0, 1], [1.0], jac=np.ones((2, 2)))
    with pytest.warns(UserWarning, match="no effect"):
        conmech.solve_ivp(exponential_decay, [0, 1], [1.0], min_step=1e-3)
