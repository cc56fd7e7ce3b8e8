"""conmech.Propagator: a state carried from one time to the next.

Properties checked: one propagation gives the bits of solve_ivp's last point over the same
span (the same Fortran run, its only output point the end); a chain of propagations and a
propagation back to the start agree with the exact solution within the tolerances; a
failure leaves the state as it was and says why; bad input is refused with solve_ivp's
messages; a Python right-hand side takes solve_ivp's route with the same answer."""
import math

import numpy as np
import pytest

import conmech
from conmech import systems

ARENSTORF_T = 17.0652165601579625588917206249
ARENSTORF_Y0 = [0.994, 0.0, 0.0, -2.00158510637908252240537862224]


@pytest.mark.parametrize("method", ["DOP853", "RK45", "VERNER98", "Radau"])
def test_one_propagation_is_solve_ivps_last_point(method):
    sys_ = systems.arenstorf()
    p = conmech.Propagator(sys_, ARENSTORF_Y0, method=method, rtol=1e-10, atol=1e-10)
    out = p.propagate_until(ARENSTORF_T)
    r = conmech.solve_ivp(sys_, (0.0, ARENSTORF_T), ARENSTORF_Y0, method=method,
                          rtol=1e-10, atol=1e-10)
    assert out.success and out.status == 0 and r.success
    assert p.t == ARENSTORF_T
    np.testing.assert_array_equal(p.y, r.y[:, -1])
    # the same steps: the run stores no point but its end, it takes no other step
    assert (out.naccept, out.nreject) == (r.naccept, r.nreject)
    assert out.nfev == r.nfev


def test_taylor_on_a_symbolic_system_is_solve_ivps_last_point():
    sp = pytest.importorskip("sympy")
    from conmech import symbolic
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    kep = symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])
    e = 0.9
    y0 = [1 - e, 0.0, 0.0, math.sqrt((1 + e)/(1 - e))]
    p = conmech.Propagator(kep, y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
    out = p.propagate_until(2*math.pi)
    r = conmech.solve_ivp(kep, (0.0, 2*math.pi), y0, method="TAYLOR", rtol=1e-12,
                          atol=1e-12)
    assert out.success
    np.testing.assert_array_equal(p.y, r.y[:, -1])
    assert out.nfev == r.nfev
    # the orbit closes after one period (Kepler's exact solution)
    assert np.max(np.abs(p.y - y0)) < 1e-9


def test_a_chain_of_propagations_follows_the_exact_solution():
    omega = 2.0
    p = conmech.Propagator(systems.harmonic(omega), [1.0, 0.0], method="DOP853",
                           rtol=1e-12, atol=1e-12)
    for t in np.linspace(0.1, 10.0, 25):
        assert p.propagate_until(t).success
        assert p.t == t
        exact = [math.cos(omega*t), -omega*math.sin(omega*t)]
        np.testing.assert_allclose(p.y, exact, atol=1e-9)
    # and back to the start, backwards in time
    assert p.propagate_until(0.0).success
    np.testing.assert_allclose(p.y, [1.0, 0.0], atol=1e-9)
    y_before = p.y
    assert p.propagate_for(0.5).success and p.t == 0.5
    assert p.y is not y_before
    np.testing.assert_allclose(y_before, [1.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(p.y, [math.cos(1.0), -omega*math.sin(1.0)], atol=1e-9)


def test_the_arrays_returned_are_not_overwritten():
    p = conmech.Propagator(systems.harmonic(), [1.0, 0.0], method="DOP853", rtol=1e-10,
                           atol=1e-10)
    p.propagate_until(1.0)
    y1 = p.y
    kept = y1.copy()
    p.propagate_until(2.0)
    np.testing.assert_array_equal(y1, kept)
    assert not np.array_equal(p.y, kept)


def test_a_failure_keeps_the_state_and_says_why():
    p = conmech.Propagator(systems.arenstorf(), ARENSTORF_Y0, method="DOP853", rtol=1e-10,
                           atol=1e-10, max_steps=5)
    out = p.propagate_until(ARENSTORF_T)
    assert not out.success and out.status < 0
    assert "max_steps" in out.message
    assert p.t == 0.0
    np.testing.assert_array_equal(p.y, ARENSTORF_Y0)


def test_a_zero_length_propagation_does_nothing():
    p = conmech.Propagator(systems.harmonic(), [1.0, 0.5], t0=3.0)
    out = p.propagate_until(3.0)
    assert out.success and out.nfev == 0 and p.t == 3.0
    np.testing.assert_array_equal(p.y, [1.0, 0.5])


def test_a_python_right_hand_side_takes_solve_ivps_route():
    def f(t, y):
        return [y[1], -y[0]]
    p = conmech.Propagator(f, [1.0, 0.0], method="DOP853", rtol=1e-11, atol=1e-11)
    assert p.propagate_until(math.pi).success
    r = conmech.solve_ivp(f, (0.0, math.pi), [1.0, 0.0], method="DOP853", rtol=1e-11,
                          atol=1e-11)
    np.testing.assert_array_equal(p.y, r.y[:, -1])
    np.testing.assert_allclose(p.y, [-1.0, 0.0], atol=1e-9)


def test_new_parameters_are_packed_again():
    sys_ = systems.harmonic(1.0)
    p = conmech.Propagator(sys_, [1.0, 0.0], method="DOP853", rtol=1e-11, atol=1e-11)
    sys_.params = np.array([3.0])
    assert p.propagate_until(1.0).success
    np.testing.assert_allclose(p.y[0], math.cos(3.0), atol=1e-9)


@pytest.mark.parametrize("kwargs, err, text", [
    (dict(y0=[1.0]), ValueError, "y0"),
    (dict(y0=[1.0, math.nan]), ValueError, "finite"),
    (dict(method="NOPE"), ValueError, "method"),
    (dict(rtol=-1.0), ValueError, "rtol"),
    (dict(t0=math.inf), ValueError, "t0"),
    (dict(max_steps=0), ValueError, "max_steps"),
])
def test_bad_input_is_refused_with_a_message(kwargs, err, text):
    args = dict(fun=systems.harmonic(), y0=[1.0, 0.0])
    args.update(kwargs)
    with pytest.raises(err, match=text):
        conmech.Propagator(**args)


@pytest.mark.parametrize("t", [math.nan, math.inf, "1.0", None])
def test_a_bad_time_is_refused(t):
    p = conmech.Propagator(systems.harmonic(), [1.0, 0.0])
    with pytest.raises((TypeError, ValueError), match="t"):
        p.propagate_until(t)
    assert p.t == 0.0


def test_small_rtol_warns_once_at_construction():
    # solve_ivp's warning about an rtol below 100 eps, given once when the Propagator is
    # made, at the caller's line (for a number or an array); the propagations (and a
    # repacking after new parameters) give none, without touching the global warning
    # filters
    import warnings
    k = conmech.systems.kepler(1.0)
    with pytest.warns(UserWarning, match="rtol") as record:
        p = conmech.Propagator(k, [0.5, 0.0, 0.0, 3.0 ** 0.5], method="DOP853", rtol=1e-20,
                               atol=1e-12)
    assert len(record) == 1
    assert record[0].filename == __file__      # at the user's call, not inside conmech
    with pytest.warns(UserWarning, match="rtol") as record:
        conmech.Propagator(k, [0.5, 0.0, 0.0, 3.0 ** 0.5], method="DOP853",
                           rtol=np.full(4, 1e-20), atol=1e-12)
    assert len(record) == 1 and record[0].filename == __file__
    filters = list(warnings.filters)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert p.propagate_until(1.0).success
        k.params = np.array([2.0])          # new parameters: packed again
        assert p.propagate_until(2.0).success
    assert warnings.filters == filters


def test_a_copy_is_a_propagator_of_its_own():
    # the system and stepper live in Fortran memory each Propagator owns: a copy (copy,
    # deepcopy, pickle) makes its own, propagates as the original, and outlives it
    import copy
    import gc
    import pickle
    sys_ = systems.arenstorf()
    p = conmech.Propagator(sys_, ARENSTORF_Y0, method="DOP853", rtol=1e-10, atol=1e-10)
    assert p.propagate_until(1.0).success
    copies = [copy.copy(p), copy.deepcopy(p), pickle.loads(pickle.dumps(p))]
    assert p.propagate_until(2.0).success
    want = p.y.copy()
    del p
    gc.collect()
    for q in copies:
        assert q.t == 1.0
        assert q.propagate_until(2.0).success
        np.testing.assert_array_equal(q.y, want)


def test_its_fortran_memory_is_freed_with_it():
    import gc
    p = conmech.Propagator(systems.harmonic(), [1.0, 0.0], method="DOP853")
    free = p._free
    assert free.alive
    del p
    gc.collect()
    assert not free.alive


def test_parameters_changed_in_place_are_read():
    # the system reads its parameters at every propagation (as solve_ivp's packed route)
    sys_ = systems.harmonic(1.0)
    p = conmech.Propagator(sys_, [1.0, 0.0], method="DOP853", rtol=1e-11, atol=1e-11)
    assert p.propagate_until(1.0).success
    np.testing.assert_allclose(p.y[0], math.cos(1.0), atol=1e-9)
    sys_.params[0] = 3.0
    p.t, p.y = 0.0, np.array([1.0, 0.0])
    assert p.propagate_until(1.0).success
    np.testing.assert_allclose(p.y[0], math.cos(3.0), atol=1e-9)


def test_a_state_of_the_wrong_size_set_by_hand_is_refused():
    p = conmech.Propagator(systems.harmonic(), [1.0, 0.0], method="DOP853")
    p.y = np.array([1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="size"):
        p.propagate_until(1.0)
    assert p.t == 0.0


def test_a_taylor_chain_continues_the_run_with_its_bits():
    # a propagation that starts where the last one ended continues its Taylor stepper:
    # the expansion at the end of one is the start of the next, so each propagation
    # after the first takes one evaluation less than a new run from that state, and
    # (an autonomous system) gives its bits
    sp = pytest.importorskip("sympy")
    from conmech import symbolic
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    kep = symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])
    y0 = [0.5, 0.0, 0.0, 3.0 ** 0.5]
    p = conmech.Propagator(kep, y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
    t_prev, y_prev = 0.0, np.array(y0)
    for k, t in enumerate(np.linspace(0.7, 12.0, 9)):
        out = p.propagate_until(float(t))
        r = conmech.solve_ivp(kep, (t_prev, float(t)), y_prev, method="TAYLOR",
                              rtol=1e-12, atol=1e-12)
        assert out.success and r.success
        np.testing.assert_array_equal(p.y, r.y[:, -1])
        assert (out.naccept, out.nreject) == (r.naccept, r.nreject)
        assert out.nfev == r.nfev - (k > 0)
        t_prev, y_prev = p.t, p.y
    # a state set by hand starts a new run: solve_ivp's count again
    p.t, p.y = 0.0, np.array(y0)
    out = p.propagate_until(0.7)
    r = conmech.solve_ivp(kep, (0.0, 0.7), y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(p.y, r.y[:, -1])
    assert out.nfev == r.nfev
    # and backwards: a new run too (the stepper continues in its own direction only)
    out = p.propagate_until(0.1)
    r = conmech.solve_ivp(kep, (0.7, 0.1), r.y[:, -1], method="TAYLOR", rtol=1e-12,
                          atol=1e-12)
    np.testing.assert_array_equal(p.y, r.y[:, -1])
    assert out.nfev == r.nfev


def test_a_taylor_chain_of_a_time_dependent_system_keeps_the_tolerance():
    # y' = cos(t) y: the continued expansion was made at t_old + h_done, which may differ
    # from t by a rounding; the chain still follows y = exp(sin t) within the tolerance
    sp = pytest.importorskip("sympy")
    from conmech import symbolic
    t, y = sp.symbols("t y")
    m = symbolic.ode_system([sp.cos(t)*y], [y])
    p = conmech.Propagator(m, [1.0], method="TAYLOR", rtol=1e-13, atol=1e-13)
    for tk in np.linspace(0.3, 20.0, 40):
        out = p.propagate_until(float(tk))
        assert out.success
        assert abs(p.y[0] - math.exp(math.sin(tk))) < 1e-11


@pytest.mark.parametrize("method", ["TAYLOR", "DOP853", "Radau"])
def test_a_grid_is_solve_ivps_t_eval(method):
    # propagate_grid (one Fortran call) gives the bits and counts of solve_ivp with
    # t_eval over the same span; a second grid continues a Taylor run (one evaluation
    # less than a new run from that state, the same bits: an autonomous system)
    sp = pytest.importorskip("sympy")
    from conmech import symbolic
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    kep = symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])
    y0 = [0.5, 0.0, 0.0, 3.0 ** 0.5]
    times = [0.0, 0.5, 1.3, 2.0, 6.0]
    p = conmech.Propagator(kep, y0, method=method, rtol=1e-11, atol=1e-11)
    out, ys = p.propagate_grid(times)
    r = conmech.solve_ivp(kep, (0.0, 6.0), y0, method=method, t_eval=times, rtol=1e-11,
                          atol=1e-11)
    assert out.success and r.success
    np.testing.assert_array_equal(ys, r.y)
    assert (out.nfev, out.naccept, out.nreject) == (r.nfev, r.naccept, r.nreject)
    assert p.t == 6.0
    np.testing.assert_array_equal(p.y, r.y[:, -1])
    later = [6.5, 7.0, 9.0]
    out, ys = p.propagate_grid(later)
    r = conmech.solve_ivp(kep, (6.0, 9.0), r.y[:, -1], method=method, t_eval=later,
                          rtol=1e-11, atol=1e-11)
    np.testing.assert_array_equal(ys, r.y)
    assert out.nfev == r.nfev - (method == "TAYLOR")
    # and back to the start
    out, back = p.propagate_grid([3.0, 0.0])
    assert out.success and p.t == 0.0
    np.testing.assert_allclose(back[:, -1], y0, atol=1e-8)


def test_a_grid_of_a_python_function_and_its_failures():
    def f(t, y):
        return [y[1], -y[0]]
    p = conmech.Propagator(f, [1.0, 0.0], method="DOP853", rtol=1e-11, atol=1e-11)
    out, ys = p.propagate_grid([1.0, 2.0])
    assert out.success and p.t == 2.0
    np.testing.assert_allclose(ys[0], np.cos([1.0, 2.0]), atol=1e-9)
    with pytest.raises(ValueError, match="sorted"):
        p.propagate_grid([3.0, 2.5])
    with pytest.raises(ValueError, match="sorted"):
        p.propagate_grid([3.0, 3.0])
    with pytest.raises(ValueError, match="sorted"):
        p.propagate_grid([1.0, 3.0])            # 1.0 lies behind t = 2.0
    with pytest.raises(ValueError, match="finite"):
        p.propagate_grid([3.0, math.nan])
    # a run that fails (max_steps) ends the grid: NaN from there, the state at the last
    # time reached
    def arenstorf(t, z):
        mu = 0.012277471
        x, y, u, v = z
        d1 = ((x + mu)**2 + y**2)**1.5
        d2 = ((x - 1 + mu)**2 + y**2)**1.5
        return [u, v, x + 2*v - (1 - mu)*(x + mu)/d1 - mu*(x - 1 + mu)/d2,
                y - 2*u - (1 - mu)*y/d1 - mu*y/d2]
    for fun in (systems.arenstorf(), arenstorf):
        q = conmech.Propagator(fun, ARENSTORF_Y0, method="DOP853", rtol=1e-10,
                               atol=1e-10, max_steps=30)
        out, ys = q.propagate_grid([0.01, 0.02, ARENSTORF_T])
        assert not out.success and out.status < 0 and "step" in out.message
        assert np.isfinite(ys[:, :2]).all() and np.isnan(ys[:, 2]).all()
        assert q.t == 0.02
        np.testing.assert_array_equal(q.y, ys[:, 1])


@pytest.mark.parametrize("method", ["TAYLOR", "DOP853"])
def test_new_parameter_array_is_read(method):
    """A symbolic system given a new parameter array after the Propagator was made: the
    next propagation runs with it (the Taylor route's written-out system shares the
    array it had, and is made again for the new one)."""
    sp = pytest.importorskip("sympy")
    from conmech import symbolic
    x, v, k = sp.symbols("x v k")
    system = symbolic.ode_system([v, -k*x], [x, v], params={k: 1.0})
    p = conmech.Propagator(system, [1.0, 0.0], method=method, rtol=1e-12, atol=1e-12)
    assert p.propagate_until(1.0).success and abs(p.y[0] - np.cos(1.0)) < 1e-10
    system.params = np.array([4.0])
    p.t, p.y = 0.0, np.array([1.0, 0.0])
    assert p.propagate_until(1.0).success and abs(p.y[0] - np.cos(2.0)) < 1e-10
    system.params[0] = 9.0
    p.t, p.y = 0.0, np.array([1.0, 0.0])
    assert p.propagate_until(1.0).success and abs(p.y[0] - np.cos(3.0)) < 1e-10
