"""conmech.solve_ivp as a drop-in for SciPy's on the cases SciPy's users meet: long runs
without a step limit, infinite spans with terminal events, complex and empty states, the
shapes of the result, sparse and constant Jacobians in Radau, and events that do not miss
two crossings inside one step when asked (``resolution``)."""
import math
import warnings

import numpy as np
import pytest
import scipy.integrate as si
from scipy.sparse import csc_matrix, diags

import conmech


def _osc(t, y):
    return [y[1], -y[0]]


# ------------------------------------------------------------------ event resolution
def _roots_sin50():
    """The zeros of sin(50 t) + 0.9 on [0, 2], in closed form: 50 t = pi + asin(0.9) + 2 pi k
    (falling) and 2 pi - asin(0.9) + 2 pi k (rising)."""
    a = math.asin(0.9)
    roots = []
    for k in range(20):
        for base in (math.pi + a, 2 * math.pi - a):
            t = (base + 2 * math.pi * k) / 50
            if t <= 2:
                roots.append(t)
    return np.sort(roots)


def _rhs_t(t, y):
    return [1.0]


def test_resolution_finds_every_crossing_that_scipys_rule_misses():
    """sin(50 t) + 0.9 on [0, 2] has 32 zeros. With a state that does not constrain the
    steps, DOP853 takes long steps: SciPy's rule (default) misses crossings in pairs; a
    resolution of 0.01 (below the 0.018 between the closest zeros) finds all 32, each at
    its closed-form time."""
    truth = _roots_sin50()
    assert truth.size == 32

    def ev(t, y):
        return math.sin(50 * y[0]) + 0.9

    plain = conmech.solve_ivp(_rhs_t, (0, 2), [0.0], method="DOP853", rtol=1e-10,
                              atol=1e-10, events=ev)
    scipy = si.solve_ivp(_rhs_t, (0, 2), [0.0], method="DOP853", rtol=1e-10, atol=1e-10,
                         events=ev)
    # the default is SciPy's rule, under which both miss crossings (DOP853's steps of
    # Hairer's and of SciPy's initial step differ, so the ones missed differ)
    assert plain.t_events[0].size < 32 and scipy.t_events[0].size < 32

    ev.resolution = 0.01
    res = conmech.solve_ivp(_rhs_t, (0, 2), [0.0], method="DOP853", rtol=1e-10, atol=1e-10,
                            events=ev)
    assert res.status == 0
    assert res.t_events[0].size == 32
    np.testing.assert_allclose(res.t_events[0], truth, atol=1e-12)
    # the steps are those of the plain run (samples cost no evaluation of f)
    assert res.nfev == plain.nfev
    assert res.t.size == plain.t.size


@pytest.mark.parametrize("method", ["RK45", "DOP853", "Radau"])
def test_resolution_with_direction_and_terminal_count(method):
    """The sampled crossings obey direction and terminal as SciPy's rule does: the 3rd
    rising zero of sin(50 t) + 0.9 ends the run, at its closed-form time."""
    truth = _roots_sin50()
    a = math.asin(0.9)
    rising = truth[np.isclose(np.mod(50 * truth, 2 * np.pi), 2 * np.pi - a)]

    def ev(t, y):
        return math.sin(50 * y[0]) + 0.9
    ev.resolution = 0.005
    ev.direction = 1
    ev.terminal = 3
    res = conmech.solve_ivp(_rhs_t, (0, 2), [0.0], method=method, rtol=1e-10, atol=1e-10,
                            events=ev)
    assert res.status == 1
    np.testing.assert_allclose(res.t_events[0], rising[:3], atol=1e-9)
    assert res.t[-1] == res.t_events[0][-1]


def test_resolution_is_checked():
    def ev(t, y):
        return y[0]
    for bad in (-1.0, float("nan"), float("inf")):
        ev.resolution = bad
        with pytest.raises(ValueError, match="resolution"):
            conmech.solve_ivp(_osc, (0, 1), [1, 0], events=ev)
    ev.resolution = "0.1"
    with pytest.raises(TypeError, match="resolution"):
        conmech.solve_ivp(_osc, (0, 1), [1, 0], events=ev)


# ------------------------------------------------------------------ no step limit
def test_a_million_steps_succeed():
    """SciPy has no step limit: a run of more than 1e6 steps (max_step 1e-6 on [0, 1.2])
    succeeds, with every step stored (growing buffers), and ends on the exact solution."""
    res = conmech.solve_ivp(conmech.systems.harmonic(), (0, 1.2), [1.0, 0.0],
                            max_step=1e-6, rtol=1e-8, atol=1e-10)
    assert res.status == 0 and res.success
    assert res.t.size > 1_000_000
    # every step within max_step (to the rounding of t), the last one Hairer's stretch to
    # tf (at most 1 % longer)
    h = np.diff(res.t)
    assert np.all(h[:-1] <= 1e-6 * (1 + 1e-9)) and h[-1] <= 1.01e-6
    np.testing.assert_allclose(res.y[:, -1], [math.cos(1.2), -math.sin(1.2)], atol=1e-8)


def test_max_steps_is_still_honoured_when_given():
    res = conmech.solve_ivp(_osc, (0, 10), [1, 0], max_steps=5)
    assert res.status == -1 and not res.success


# ------------------------------------------------------------------ infinite spans
@pytest.mark.parametrize("method", ["RK45", "DOP853", "Radau"])
def test_infinite_span_ends_at_terminal_event(method):
    """t_span = [0, inf]: y = exp(-t) reaches 1e-3 at t = ln 1000."""
    def ev(t, y):
        return y[0] - 1e-3
    ev.terminal = True
    res = conmech.solve_ivp(lambda t, y: -y, (0, np.inf), [1.0], method=method,
                            events=ev, rtol=1e-10, atol=1e-12)
    assert res.status == 1
    assert res.t_events[0][0] == pytest.approx(math.log(1000), rel=1e-7)
    assert res.t[-1] == res.t_events[0][0]


# ------------------------------------------------------------------ complex and empty
@pytest.mark.parametrize("method", ["RK45", "DOP853"])
def test_complex_state(method):
    """y' = i y, y(0) = 1: y = exp(i t), also from the dense output; SciPy's result."""
    res = conmech.solve_ivp(lambda t, y: 1j * y, (0, 5), [1.0 + 0j], method=method,
                            rtol=1e-10, atol=1e-12, dense_output=True)
    ref = si.solve_ivp(lambda t, y: 1j * y, (0, 5), [1.0 + 0j], method=method,
                       rtol=1e-10, atol=1e-12)
    assert res.y.dtype == complex
    np.testing.assert_allclose(res.y[0], np.exp(1j * res.t), atol=1e-8)
    np.testing.assert_allclose(res.sol(2.5)[0], np.exp(2.5j), atol=1e-8)
    np.testing.assert_allclose(res.y[0, -1], ref.y[0, -1], atol=1e-8)


def test_complex_state_refused_by_radau_as_scipy():
    with pytest.raises(ValueError, match="complex"):
        conmech.solve_ivp(lambda t, y: 1j * y, (0, 1), [1j], method="Radau")


def test_empty_state():
    ref = si.solve_ivp(lambda t, y: y, (0, 1), [])
    res = conmech.solve_ivp(lambda t, y: y, (0, 1), [])
    assert res.success and res.y.shape == ref.y.shape == (0, 2)
    np.testing.assert_array_equal(res.t, ref.t)


# ------------------------------------------------------------------ shapes
def test_shapes_as_scipy():
    """sol present with dense_output even without a step; an event that never fires gives
    SciPy's empty shapes; a zero-length span gives t = [t0, t0]."""
    def never(t, y):
        return 2.0 + y[0]
    for mod in (si, conmech):
        a = mod.solve_ivp(_osc, (4, 4), [1.0, 0.0], dense_output=True)
        assert a.sol is not None
        np.testing.assert_array_equal(a.t, [4.0, 4.0])
        np.testing.assert_allclose(a.sol(4.0), [1.0, 0.0])
    a = si.solve_ivp(_osc, (0, 3), [1.0, 0.0], events=never)
    b = conmech.solve_ivp(_osc, (0, 3), [1.0, 0.0], events=never)
    assert b.y_events[0].shape == a.y_events[0].shape
    assert b.t_events[0].shape == a.t_events[0].shape == (0,)


def test_public_odesolution():
    """conmech.OdeSolution(ts, interpolants) from a run's own interpolants reproduces sol."""
    res = conmech.solve_ivp(_osc, (0, 3), [1.0, 0.0], dense_output=True, rtol=1e-8)
    again = conmech.OdeSolution(res.sol.ts, res.sol.interpolants)
    tt = np.linspace(0, 3, 17)
    np.testing.assert_array_equal(again(tt), res.sol(tt))


def test_small_rtol_warns_as_scipy():
    with pytest.warns(UserWarning, match="rtol"):
        conmech.solve_ivp(_osc, (0, 1), [1, 0], rtol=1e-20)


# ------------------------------------------------------------------ Jacobians in Radau
def _band(n=200):
    """A stiff diffusion chain y_i' = y_{i-1} - 2 y_i + y_{i+1} (scaled), tridiagonal."""
    k = 100.0

    def f(t, y):
        d = -2 * y
        d[1:] += y[:-1]
        d[:-1] += y[1:]
        return k * d - y ** 3

    pattern = diags([1, 1, 1], [-1, 0, 1], shape=(n, n), format="csc")
    return f, pattern, np.linspace(1.0, 0.0, n)


def test_jac_sparsity_groups_columns():
    """With the tridiagonal pattern, each finite-difference Jacobian takes 3 evaluations
    (Curtis-Powell-Reid groups) instead of 200; the solution agrees with the dense
    differences' run, and the step sequence is the same."""
    f, pattern, y0 = _band()
    dense = conmech.solve_ivp(f, (0, 1), y0, method="Radau", rtol=1e-6, atol=1e-9)
    grouped = conmech.solve_ivp(f, (0, 1), y0, method="Radau", rtol=1e-6, atol=1e-9,
                                jac_sparsity=pattern)
    assert dense.success and grouped.success
    assert grouped.njev == dense.njev and grouped.nlu == dense.nlu
    assert grouped.nfev - dense.nfev == -(200 - 3) * dense.njev
    np.testing.assert_allclose(grouped.y[:, -1], dense.y[:, -1], rtol=1e-6, atol=1e-9)


def test_sparse_jacobian_callable_and_constant():
    """A callable returning a sparse matrix and a constant sparse matrix both work, and
    agree with the dense constant Jacobian (njev 0 for a constant one, as SciPy)."""
    J = np.array([[-1.0, -5.0], [1.0, 1.0]])

    def f(t, y):
        return J @ y
    runs = [conmech.solve_ivp(f, (0, 2), [0.0, 2.0], method="Radau", jac=jac, rtol=1e-8,
                              atol=1e-10)
            for jac in (J, csc_matrix(J), lambda t, y: csc_matrix(J))]
    assert all(r.success for r in runs)
    assert runs[0].njev == runs[1].njev == 0
    assert runs[2].njev >= 1
    for r in runs[1:]:
        np.testing.assert_allclose(r.y[:, -1], runs[0].y[:, -1], rtol=1e-9, atol=1e-12)


def test_contract_counts_unchanged():
    """Radau on Van der Pol (mu = 1000, Hairer's test) without jac: the same steps with and
    without a full sparsity pattern (a full pattern groups nothing)."""
    mu = 1000.0

    def f(t, y):
        return [y[1], mu * ((1 - y[0] ** 2) * y[1]) - y[0]]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        a = conmech.solve_ivp(f, (0, 100), [2.0, 0.0], method="Radau", rtol=1e-6,
                              atol=1e-6)
        b = conmech.solve_ivp(f, (0, 100), [2.0, 0.0], method="Radau", rtol=1e-6,
                              atol=1e-6, jac_sparsity=np.ones((2, 2)))
    assert (a.nfev, a.njev, a.nlu, a.naccept) == (b.nfev, b.njev, b.nlu, b.naccept)


def test_infinite_span_without_an_end_is_refused():
    """Nothing would end the run (SciPy integrates for ever): refused, naming t_span; with
    max_steps it ends there (status -1)."""
    with pytest.raises(ValueError, match="t_span"):
        conmech.solve_ivp(lambda t, y: -y, (0, np.inf), [1.0])
    res = conmech.solve_ivp(lambda t, y: -y, (0, np.inf), [1.0], max_steps=50)
    assert res.status == -1 and 2 <= res.t.size <= 51   # attempts include rejections
    assert np.all(np.isfinite(res.t)) and np.all(np.diff(res.t) > 0)
