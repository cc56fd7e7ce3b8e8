"""conmech's stepper classes (conmech.DOP853, RK45, VERNER98, RK4) with SciPy's OdeSolver
interface: SciPy-style tests that drive scipy.integrate.RK45 / DOP853 step by step run
unchanged on conmech's classes (parametrised over both), and a step() loop reproduces
conmech.solve_ivp bit for bit."""
import numpy as np
import pytest
import scipy.integrate as si
from numpy.testing import assert_, assert_allclose, assert_equal, assert_raises

import conmech


def fun_rational(t, y):
    return np.array([y[1] / t, y[1] * (y[0] + 2 * y[1] - 1) / (t * (y[0] - 1))])


def sol_rational(t):
    return np.asarray((t / (t + 10), 10 * t / (t + 10) ** 2))


def kepler(t, y):
    r3 = np.hypot(y[0], y[1]) ** 3
    return [y[2], y[3], -y[0] / r3, -y[1] / r3]


RK45_LIKE = [si.RK45, conmech.RK45]
DOP853_LIKE = [si.DOP853, conmech.DOP853]
ALL = [si.RK45, si.DOP853, conmech.RK45, conmech.DOP853, conmech.VERNER98]


# ------------------------------------------------ SciPy's test_classes, unchanged
@pytest.mark.parametrize("cls", ALL)
def test_classes(cls):
    y0 = [1 / 3, 2 / 9]
    solver = cls(fun_rational, 5, y0, np.inf)
    assert_equal(solver.n, 2)
    assert_equal(solver.status, 'running')
    assert_equal(solver.t_bound, np.inf)
    assert_equal(solver.direction, 1)
    assert_equal(solver.t, 5)
    assert_equal(solver.y, y0)
    assert_(solver.step_size is None)
    assert_(solver.nfev > 0)
    assert_(solver.njev >= 0)
    assert_equal(solver.nlu, 0)
    assert_raises(RuntimeError, solver.dense_output)
    message = solver.step()
    assert_equal(solver.status, 'running')
    assert_equal(message, None)
    assert_equal(solver.n, 2)
    assert_equal(solver.t_bound, np.inf)
    assert_equal(solver.direction, 1)
    assert_(solver.t > 5)
    assert_(not np.all(np.equal(solver.y, y0)))
    assert_(solver.step_size > 0)
    assert_(solver.nfev > 0)
    assert_(solver.njev >= 0)
    assert_(solver.nlu >= 0)
    sol = solver.dense_output()
    assert_allclose(sol(5), y0, rtol=1e-15, atol=0)


# ------------------------------------------------ a step loop to the end, both directions
@pytest.mark.parametrize("cls", ALL)
@pytest.mark.parametrize("t_span", [(5, 9), (5, 1)])
def test_step_loop_reaches_t_bound(cls, t_span):
    rtol, atol = 1e-6, 1e-9
    y0 = sol_rational(t_span[0])
    solver = cls(fun_rational, t_span[0], y0, t_span[1], rtol=rtol, atol=atol)
    ts, ys = [solver.t], [solver.y]
    while solver.status == 'running':
        message = solver.step()
        assert_(message is None)
        ts.append(solver.t)
        ys.append(solver.y)
        # the dense output of the step matches the step's ends (at the end to well
        # within the tolerances: Verner's interpolant is of order 8, not the step's 9)
        sol = solver.dense_output()
        assert_allclose(sol(solver.t_old), ys[-2], rtol=1e-12, atol=1e-14)
        assert_allclose(sol(solver.t), ys[-1], rtol=1e-9, atol=1e-12)
        assert_(sol.t_min == min(solver.t_old, solver.t))
    assert_equal(solver.status, 'finished')
    assert_equal(solver.t, t_span[1])
    ts = np.array(ts)
    assert_(np.all(np.diff(ts) * np.sign(t_span[1] - t_span[0]) > 0))
    err = np.abs(np.array(ys).T - sol_rational(ts))
    assert_(np.all(err < 100 * (atol + rtol * np.abs(sol_rational(ts)))))
    assert_raises(RuntimeError, solver.step)


@pytest.mark.parametrize("cls", ALL)
def test_max_step_respected(cls):
    solver = cls(fun_rational, 5, sol_rational(5), 9, max_step=0.5, rtol=1e-3)
    while solver.status == 'running':
        solver.step()
        assert_(solver.step_size <= 0.5 + 1e-15)
    assert_equal(solver.status, 'finished')


@pytest.mark.parametrize("cls", ALL)
def test_first_step_is_taken(cls):
    solver = cls(fun_rational, 5, sol_rational(5), 9, first_step=1e-3, rtol=1e-3)
    solver.step()
    assert_allclose(solver.step_size, 1e-3, rtol=1e-12)


@pytest.mark.parametrize("cls", RK45_LIKE + DOP853_LIKE)
def test_zero_interval_finishes_at_once(cls):
    solver = cls(lambda t, y: -y, 4, [2.0, 3.0], 4)
    assert_equal(solver.step(), None)
    assert_equal(solver.status, 'finished')
    assert_equal(solver.t, 4)
    assert_allclose(solver.dense_output()(4), [2.0, 3.0])


# ------------------------------------------------ conmech's own properties
# conmech.RK45 is Dormand-Prince with SciPy's step control and initial step, as the string
# "RK45" of solve_ivp (SciPy's default method); conmech.DOPRI5 is Hairer's control, as
# the string "DOPRI5"
@pytest.mark.parametrize("cls,name", [(conmech.DOP853, "DOP853"), (conmech.RK45, "RK45"),
                                      (conmech.RK45, conmech.RK45),
                                      (conmech.RK45, si.RK45),
                                      (conmech.DOPRI5, "DOPRI5"),
                                      (conmech.DOPRI5, conmech.DOPRI5),
                                      (conmech.VERNER98, "VERNER98")])
def test_step_loop_is_solve_ivp_bit_for_bit(cls, name):
    y0 = [0.4, 0.0, 0.0, 2.0]
    s = cls(kepler, 0.0, y0, 2 * np.pi, rtol=1e-9, atol=1e-9)
    ts, ys = [s.t], [s.y]
    while s.status == "running":
        s.step()
        ts.append(s.t)
        ys.append(s.y)
    r = conmech.solve_ivp(kepler, (0, 2 * np.pi), y0, method=name, rtol=1e-9, atol=1e-9)
    assert s.status == "finished"
    assert np.array_equal(np.array(ts), r.t)
    assert np.array_equal(np.array(ys).T, r.y)
    assert s.nfev == r.nfev
    assert s.naccept == r.naccept and s.nreject == r.nreject


@pytest.mark.parametrize("rtol", [1e-3, 1e-6, 1e-9])
@pytest.mark.parametrize("t_span", [(0.0, 6.0), (6.0, 0.5)])
def test_rk45_takes_scipys_steps(rtol, t_span):
    # the same loop drives scipy.integrate.RK45 and conmech.RK45: the same number of
    # steps at the same times (to round-off), the same states; nfev is SciPy's + 1
    # (conmech's initial-step heuristic evaluates f(t0, y0) once more)
    y0 = [0.4, 0.0, 0.0, 2.0]
    runs = []
    for cls in (si.RK45, conmech.RK45):
        s = cls(kepler, t_span[0], y0, t_span[1], rtol=rtol, atol=rtol * 1e-3)
        ts, ys, hs = [], [], []
        while s.status == "running":
            assert s.step() is None
            ts.append(s.t)
            ys.append(s.y)
            hs.append(s.step_size)
        runs.append((np.array(ts), np.array(ys), np.array(hs), s.nfev))
    (ta, ya, ha, na), (tb, yb, hb, nb) = runs
    assert len(ta) == len(tb)
    # (round-off differences of the two codes grow through the step control: to ~1e-9
    # relative over the 140 steps at rtol 1e-9)
    assert_allclose(tb, ta, rtol=1e-8, atol=1e-12)
    assert_allclose(hb, ha, rtol=1e-6)
    assert_allclose(yb, ya, rtol=0, atol=1e-8)
    assert nb == na + 1
    assert conmech.RK45 is not conmech.DOPRI5


def test_dopri5_is_hairers_control():
    # conmech.DOPRI5 (Lund-stabilised, Hairer's initial step) takes other steps than
    # conmech.RK45 (SciPy's control) on the same problem
    y0 = [0.4, 0.0, 0.0, 2.0]
    counts = []
    for cls in (conmech.RK45, conmech.DOPRI5):
        s = cls(kepler, 0.0, y0, 6.0, rtol=1e-6, atol=1e-9)
        while s.status == "running":
            s.step()
        counts.append((s.naccept, s.nfev, s.t))
    assert counts[0][2] == counts[1][2] == 6.0
    assert counts[0][:2] != counts[1][:2]


def test_builtin_system_steps_like_solve_ivp():
    sysm = conmech.systems.kepler(mu=1.0)
    y0 = [0.4, 0.0, 0.0, 2.0]
    s = conmech.DOP853(sysm, 0.0, y0, 2 * np.pi, rtol=1e-10, atol=1e-10)
    while s.status == "running":
        s.step()
    r = conmech.solve_ivp(sysm, (0, 2 * np.pi), y0, method="DOP853", rtol=1e-10, atol=1e-10)
    assert np.array_equal(s.y, r.y[:, -1]) and s.t == r.t[-1]
    assert_allclose(s.y, y0, atol=1e-7)      # one period of the e = 0.6 orbit closes


def test_dense_output_matches_solve_ivp_dense():
    y0 = [0.4, 0.0, 0.0, 2.0]
    r = conmech.solve_ivp(kepler, (0, 3.0), y0, method="DOP853", rtol=1e-8, atol=1e-8,
                          dense_output=True)
    s = conmech.DOP853(kepler, 0.0, y0, 3.0, rtol=1e-8, atol=1e-8)
    while s.status == "running":
        s.step()
        sol = s.dense_output()
        tm = np.linspace(s.t_old, s.t, 5)[:-1]   # the end belongs to the next step
        assert np.array_equal(sol(tm), r.sol(tm))


def test_solve_ivp_accepts_classes():
    y0 = [0.4, 0.0, 0.0, 2.0]
    a = conmech.solve_ivp(kepler, (0, 1), y0, method="DOP853", rtol=1e-8)
    b = conmech.solve_ivp(kepler, (0, 1), y0, method=conmech.DOP853, rtol=1e-8)
    c = conmech.solve_ivp(kepler, (0, 1), y0, method=si.DOP853, rtol=1e-8)
    d = conmech.solve_ivp(kepler, (0, 1), y0, method=si.RK45, rtol=1e-8)
    e = conmech.solve_ivp(kepler, (0, 1), y0, method="RK45", rtol=1e-8)
    assert np.array_equal(a.y, b.y) and np.array_equal(a.y, c.y)
    assert np.array_equal(d.y, e.y)
    f = conmech.solve_ivp(kepler, (0, 1), y0, method=si.Radau, rtol=1e-8)
    g = conmech.solve_ivp(kepler, (0, 1), y0, method="Radau", rtol=1e-8)
    assert f.success and np.array_equal(f.y, g.y) and f.njev == g.njev
    with pytest.raises(ValueError, match="BDF"):     # no counterpart in conmech
        conmech.solve_ivp(kepler, (0, 1), y0, method=si.BDF)


def test_rk4_fixed_steps():
    s = conmech.RK4(lambda t, y: -y, 0.0, [1.0], 1.0, first_step=0.1)
    n = 0
    while s.status == "running":
        s.step()
        n += 1
    assert n == 10 and s.t == 1.0
    assert abs(s.y[0] - np.exp(-1.0)) < 1e-6
    with pytest.raises(ValueError, match="first_step"):
        conmech.RK4(lambda t, y: -y, 0.0, [1.0], 1.0)


def test_failure_is_reported_and_stepping_stops():
    s = conmech.DOP853(lambda t, y: y * y, 0.0, [1.0], 2.0)
    msg = None
    while s.status == "running":
        msg = s.step()
    assert s.status == "failed" and ("finite" in msg or "small" in msg)
    assert abs(s.t - 1.0) < 1e-2
    with pytest.raises(RuntimeError):
        s.step()


def test_exception_in_fun_reaches_the_caller():
    calls = []

    def f(t, y):
        calls.append(t)
        if len(calls) > 20:
            raise KeyError("boom")
        return -y
    s = conmech.DOP853(f, 0.0, [1.0], 10.0)
    with pytest.raises(KeyError):
        while s.status == "running":
            s.step()
    assert s.status == "failed"


@pytest.mark.parametrize("kw,exc,pat", [
    (dict(rtol=-1), ValueError, "rtol"), (dict(atol=[1e-6, 1e-6]), ValueError, "atol"),
    (dict(max_step=0), ValueError, "max_step"), (dict(first_step=-1), ValueError,
                                                  "first_step"),
    (dict(y0=[np.nan]), ValueError, "y0"), (dict(fun=3), TypeError, "fun")])
def test_bad_input(kw, exc, pat):
    args = dict(fun=lambda t, y: -y, t0=0.0, y0=[1.0], t_bound=1.0)
    args.update(kw)
    with pytest.raises(exc, match=pat):
        conmech.DOP853(**args)


def test_independent_objects_interleave():
    y0 = [0.4, 0.0, 0.0, 2.0]
    a = conmech.DOP853(kepler, 0.0, y0, 5.0, rtol=1e-9, atol=1e-9)
    b = conmech.DOP853(kepler, 0.0, y0, 5.0, rtol=1e-9, atol=1e-9)
    c = conmech.RK45(kepler, 0.0, y0, 5.0)
    while a.status == "running":
        a.step()
        if c.status == "running":
            c.step()
    while b.status == "running":
        b.step()
    assert np.array_equal(a.y, b.y) and a.nfev == b.nfev


@pytest.mark.filterwarnings("ignore::RuntimeWarning")   # SciPy overflows in its own norms
@pytest.mark.parametrize("method", ["DOP853", "RK45"])
@pytest.mark.parametrize("y0", [1e-150, 5e149])
def test_extreme_magnitudes_work_as_in_scipy(method, y0):
    # scale-safe norms: the initial-step heuristic and DOP853's error norm neither
    # overflow (|f/sk| ~ 1e155) nor divide 0 by an underflowed denominator
    for yy, f, exact in (([y0], lambda t, y: -y, np.exp(-1.0)),
                         ([y0, 0.0], lambda t, y: [y[1], -y[0]], np.cos(1.0))):
        r = conmech.solve_ivp(f, (0, 1), yy, method=method, rtol=1e-6, atol=1e-6 * y0)
        assert r.success, r.message
        assert abs(r.y[0, -1] / (y0 * exact) - 1) < 1e-4
        s = si.solve_ivp(f, (0, 1), yy, method=method)
        c = conmech.solve_ivp(f, (0, 1), yy, method=method)
        assert s.success and c.success
        assert abs(c.y[0, -1] / s.y[0, -1] - 1) < 1e-3


def test_stepper_by_name_is_the_class():
    # conmech.Stepper(..., method=NAME) runs any method of the Fortran table by name: the
    # same steps as the method's class, bit for bit (one flat routine serves them all)
    y0 = [0.4, 0.0, 0.0, 2.0]
    for name, cls, kw in (("DOP853", conmech.DOP853, dict(rtol=1e-8, atol=1e-8)),
                          ("vern9", conmech.VERNER98, dict(rtol=1e-8, atol=1e-8)),
                          ("Radau", conmech.Radau, dict(rtol=1e-6, atol=1e-8)),
                          ("GAUSS6", conmech.Gauss6, dict(first_step=0.1))):
        a = conmech.Stepper(kepler, 0.0, y0, 3.0, method=name, **kw)
        b = cls(kepler, 0.0, y0, 3.0, **kw)
        while a.status == "running":
            a.step()
            b.step()
            assert a.t == b.t and np.array_equal(a.y, b.y)
        assert b.status == "finished" and (a.nfev, a.njev, a.nlu) == (b.nfev, b.njev, b.nlu)
    with pytest.raises(ValueError, match="method"):
        conmech.Stepper(kepler, 0.0, y0, 3.0, method="RK23")
    with pytest.raises(ValueError, match="method"):
        conmech.Stepper(kepler, 0.0, y0, 3.0, method="RATTLE")    # constrained systems only
    with pytest.raises(ValueError, match="first_step"):
        conmech.Stepper(kepler, 0.0, y0, 3.0, method="GAUSS4")    # a fixed-step method
    # Taylor's method needs generated coefficients (conmech.symbolic): a Python function
    # has none, and the stepper says so (test_taylor_generalized.py steps symbolic systems)
    with pytest.raises(ValueError, match="no Taylor coefficients"):
        conmech.Stepper(kepler, 0.0, y0, 3.0, method="TAYLOR")


def test_step_failure_messages_through_the_buffer():
    """A failed step's message comes from the stepper's message buffer (the step routines
    write it only on failure): the text must be the Fortran message, the same for a
    built-in system, a Python callable and Radau with a sparse pattern (the full routine
    behind the step), and a later failure must not show an earlier message's tail."""
    import scipy.sparse as sps

    def blow_up(t, y):
        return y**2

    runs = [conmech.DOP853(blow_up, 0.0, [1.0], 2.0, max_steps=50),
            conmech.Radau(blow_up, 0.0, [1.0], 2.0, max_steps=50),
            conmech.Radau(lambda t, y: y**2, 0.0, np.ones(120), 2.0, max_steps=50,
                          jac_sparsity=sps.identity(120, format="csc")),
            conmech.DOP853(conmech.systems.kepler(), 0.0, [1e-3, 0.0, 0.0, 0.0], 10.0,
                           max_steps=20)]
    for s in runs:
        message = None
        while s.status == "running":
            message = s.step()
        assert s.status == "failed"
        assert message.startswith("too many steps: max_steps reached at t = "), message
        assert message == message.strip() and message.isprintable()
    # the routine writes the whole buffer on failure (blank-padded): nothing of what was
    # there before is left, and the text is the Fortran message
    from conmech._core.callback import message_text
    s = conmech.DOP853(conmech.systems.kepler(), 0.0, [0.4, 0.0, 0.0, 2.0], 10.0)
    s.step()
    routine, args = s._step_call
    buf = np.full(256, ord("x"), dtype=np.int8)
    info = routine("no_such_system", *args[1:-1], buf)
    assert info != 0 and not np.any(buf == ord("x"))
    assert message_text(buf) == "bad input: unknown built-in system 'no_such_system'"
