"""conmech.ensemble: each member is its own solve_ivp bit for bit; threads do not change
the results; parameters per member; events (first k, terminal); progress; bad input."""
import numpy as np
import pytest

import conmech
from conmech import ensemble

KEP = conmech.systems.kepler()


def kepler_states(m):
    e = np.linspace(0.0, 0.8, m)
    return np.column_stack([1 - e, 0 * e, 0 * e, np.sqrt((1 + e) / (1 - e))])


def test_members_equal_solve_ivp_bit_for_bit_t_eval():
    y0 = kepler_states(7)
    t_eval = np.linspace(0, 9, 10)
    res = ensemble.solve(KEP, (0, 9), y0, t_eval=t_eval, method="DOP853", rtol=1e-9,
                         atol=1e-9)
    assert res.success and res.y.shape == (7, 4, 10) and res.done == 7
    for i in range(7):
        s = conmech.solve_ivp(KEP, (0, 9), y0[i], t_eval=t_eval, method="DOP853", rtol=1e-9,
                              atol=1e-9)
        assert np.array_equal(res.y[i], s.y)
        assert np.array_equal(res.y_final[i], s.y[:, -1]) and res.t_final[i] == 9.0
        assert res.nfev[i] == s.nfev and res.naccept[i] == s.naccept
        assert res.nreject[i] == s.nreject and res.status[i] == s.status == 0


def test_final_states_and_backward_in_time():
    y0 = kepler_states(5)
    for method, span in (("RK45", (0, 5)), ("VERNER98", (3, -2))):
        res = ensemble.solve(KEP, span, y0, method=method, rtol=1e-8, atol=1e-8)
        assert res.y is None and res.t_events is None
        # (the ensemble's RK45 is Hairer's DOPRI5; solve_ivp's RK45 uses SciPy's controller)
        m_ivp = "DOPRI5" if method == "RK45" else method
        for i in range(5):
            s = conmech.solve_ivp(KEP, span, y0[i], method=m_ivp, rtol=1e-8, atol=1e-8)
            assert np.array_equal(res.y_final[i], s.y[:, -1]) and res.t_final[i] == span[1]
            assert res.nfev[i] == s.nfev


def test_one_and_two_threads_identical():
    y0 = kepler_states(40)
    kw = dict(t_eval=np.linspace(0, 12, 7), method="DOP853", rtol=1e-8, atol=1e-8,
              events=ensemble.crossing(1, 0.0, direction=1), max_events=3)
    r1 = ensemble.solve(KEP, (0, 12), y0, threads=1, **kw)
    r2 = ensemble.solve(KEP, (0, 12), y0, threads=2, **kw)
    for key in ("y", "y_final", "t_final", "nfev", "t_events", "y_events", "n_events"):
        assert np.array_equal(r1[key], r2[key], equal_nan=True), key


def test_parameters_per_member():
    lengths = np.array([0.5, 1.0, 2.0, 3.0])
    res = ensemble.solve(conmech.systems.pendulum(g=9.81), (0, 4), [1.0, 0.0],
                         params={"l": lengths}, method="DOP853", rtol=1e-10, atol=1e-10)
    table = np.column_stack([np.full(4, 9.81), lengths])
    res2 = ensemble.solve(conmech.systems.pendulum(), (0, 4), [1.0, 0.0], params=table,
                          method="DOP853", rtol=1e-10, atol=1e-10)
    for i, ell in enumerate(lengths):
        s = conmech.solve_ivp(conmech.systems.pendulum(g=9.81, l=ell), (0, 4), [1.0, 0.0],
                              method="DOP853", rtol=1e-10, atol=1e-10)
        assert np.array_equal(res.y_final[i], s.y[:, -1]) and res.nfev[i] == s.nfev
        assert np.array_equal(res2.y_final[i], s.y[:, -1])
    # initial states and parameters both per member; solve_ivp's default tolerances (the
    # ensemble's default RK45 is Hairer's DOPRI5, solve_ivp's RK45 SciPy's controller)
    y0 = np.column_stack([np.linspace(0.1, 1.0, 4), np.zeros(4)])
    res = ensemble.solve(conmech.systems.pendulum(), (0, 2), y0, params={"l": lengths})
    for i in range(4):
        s = conmech.solve_ivp(conmech.systems.pendulum(l=lengths[i]), (0, 2), y0[i],
                              method="DOPRI5")
        assert np.array_equal(res.y_final[i], s.y[:, -1])


def test_events_first_k_and_terminal_equal_solve_ivp():
    y0 = kepler_states(6)
    ev = ensemble.crossing(1, 0.0, direction=1)
    kw = dict(method="DOP853", rtol=1e-10, atol=1e-10)
    res = ensemble.solve(KEP, (0, 20), y0, events=[ev, ensemble.crossing(0, 0.0)],
                         max_events=4, **kw)
    for i in range(6):
        s = conmech.solve_ivp(KEP, (0, 20), y0[i], events=[ev, ev.__class__(0, 0.0)], **kw)
        times = np.concatenate(s.t_events)
        ids = np.concatenate([np.full(len(t), j) for j, t in enumerate(s.t_events)])
        states = np.concatenate(s.y_events)
        # y = 0 at t0: solve_ivp follows SciPy's rule (an event at t0), the ensemble does
        # not count a function that starts at zero
        later = times > 0
        times, ids, states = times[later], ids[later], states[later]
        order = np.argsort(times, kind="stable")[:4]
        assert res.n_events[i] == 4
        assert np.array_equal(res.t_events[i], times[order])
        assert np.array_equal(res.event_index[i], ids[order])
        assert np.array_equal(res.y_events[i], states[order])
    # period of every orbit: 2 pi (a = 1), the first upward crossing of y = 0
    res = ensemble.solve(KEP, (0, 20), y0, events=ev, max_events=2, **kw)
    assert np.allclose(res.t_events[:, 0], 2 * np.pi, rtol=1e-8)
    assert np.allclose(res.t_events[:, 1], 4 * np.pi, rtol=1e-8)

    # terminal at the first event: solve_ivp with a terminal event, t_eval included
    def g(t, y):
        return y[1]
    g.terminal = True
    g.direction = 1
    t_eval = np.linspace(0, 20, 11)
    y0 = y0.copy()
    y0[:, 1] = -1e-3     # not on the crossing at t0 (SciPy's rule would stop solve_ivp there)
    res = ensemble.solve(KEP, (0, 20), y0, t_eval=t_eval, events=ev, terminal=True, **kw)
    for i in range(6):
        s = conmech.solve_ivp(KEP, (0, 20), y0[i], t_eval=t_eval, events=g, **kw)
        assert res.status[i] == s.status == 1
        assert res.t_final[i] == s.t_events[0][0]
        assert np.array_equal(res.y_final[i], s.y_events[0][0])
        nt = s.t.size
        assert np.array_equal(res.y[i][:, :nt], s.y) and np.isnan(res.y[i][:, nt:]).all()
        assert res.nfev[i] == s.nfev
    # terminal at the third event
    y0 = kepler_states(6)
    res = ensemble.solve(KEP, (0, 20), y0, events=ev, max_events=3, terminal=True, **kw)
    assert (res.status == 1).all() and np.array_equal(res.t_final, res.t_events[:, 2])
    assert np.allclose(res.t_final, 6 * np.pi, rtol=1e-8)


def test_failures_are_reported_per_member():
    y0 = kepler_states(4)
    y0[2, 3] = 1e-3          # nearly radial fall: needs many steps
    res = ensemble.solve(KEP, (0, 10), y0, max_steps=500, method="DOP853", rtol=1e-8,
                         atol=1e-8)
    assert not res.success and res.status[2] == -1 and "member 3" in res.message
    assert res.member_success.sum() == 3


def test_progress_reports_and_cancel():
    calls = []
    res = ensemble.solve(KEP, (0, 1), kepler_states(10), chunk=3,
                         progress=lambda d, t: calls.append((d, t)))
    assert calls == [(3, 10), (6, 10), (9, 10), (10, 10)] and res.success

    class Stop(Exception):
        pass

    def stop(done, total):
        raise Stop(f"{done}")
    with pytest.raises(Stop, match="4"):
        ensemble.solve(KEP, (0, 1), kepler_states(10), chunk=4, progress=stop)


@pytest.mark.parametrize("kwargs, exc, text", [
    (dict(system=lambda t, y: y), TypeError, "Python function"),
    (dict(system=conmech.systems.pendulum_xy()), TypeError, "constrained"),
    (dict(y0=np.zeros((3, 3))), ValueError, "shape"),
    (dict(y0=np.full((2, 4), np.nan)), ValueError, "NaN"),
    (dict(params=np.ones((3, 2))), ValueError, "params"),
    (dict(params={"m": [1.0, 2.0]}), ValueError, "unknown parameter"),
    (dict(params={"mu": [1.0, 2.0, 3.0]}), ValueError, "rows"),
    (dict(events=lambda t, y: y[0]), TypeError, "built-in event"),
    (dict(events=ensemble.crossing(4)), ValueError, "out of range"),
    (dict(events=ensemble.crossing(1), max_events=0), ValueError, "max_events"),
    (dict(terminal=True), ValueError, "terminal"),
    (dict(threads=0), ValueError, "threads"),
    (dict(t_eval=[0.5, 2.0]), ValueError, "t_eval"),
    (dict(method="Euler"), ValueError, "method"),
    (dict(rtol=-1.0), ValueError, "rtol"),
    (dict(progress=3), TypeError, "progress"),
])
def test_bad_input(kwargs, exc, text):
    args = dict(system=KEP, t_span=(0, 1), y0=kepler_states(2))
    args.update(kwargs)
    with pytest.raises(exc, match=text):
        ensemble.solve(**args)


def test_compiled_system_members_equal_solve_ivp(tmp_path):
    """A compiled (C) system runs in the ensemble as the built-ins do: each member, with
    its own parameter, equals solve_ivp of the same compiled system bit for bit."""
    import ctypes
    import os
    import shutil
    import subprocess
    from conmech import compiled
    cc = shutil.which("gcc") or shutil.which("cc")
    assert cc is not None, "a C compiler is needed (gfortran's gcc)"
    src = os.path.join(os.path.dirname(__file__), "data", "c_systems.c")
    out = tmp_path / "libcsys.so"
    subprocess.run([cc, "-O2", "-fPIC", "-shared", src, "-o", str(out), "-lm"], check=True)
    lib = ctypes.CDLL(str(out))
    sys_c = compiled.ode_system(4, lib.kepler_rhs, lib.kepler_jac, params={"mu": 1.0},
                                keep=lib, name="kepler_c")
    y0 = kepler_states(5)
    mus = np.linspace(0.9, 1.3, 5)
    kw = dict(method="DOP853", rtol=1e-9, atol=1e-9, t_eval=np.linspace(0, 5, 6))
    res = ensemble.solve(sys_c, (0, 5), y0, params={"mu": mus}, threads=2, **kw)
    assert res.success
    for i in range(5):
        s = conmech.solve_ivp(sys_c.with_params(mu=mus[i]), (0, 5), y0[i], **kw)
        assert np.array_equal(res.y[i], s.y) and res.nfev[i] == s.nfev
