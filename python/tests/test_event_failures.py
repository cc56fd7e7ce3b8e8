"""An event function that fails ends the run at once: an exception raised in a Python event
on a compiled system (whose right-hand side never sees the failure) reaches the caller
without integrating on, even over an infinite span; an event value that is NaN (no sign, so
no crossing can be told) stops the run with a message naming the event and the time."""
import subprocess
import sys

import numpy as np
import pytest
import scipy.integrate as si

import conmech


def test_raising_event_on_a_compiled_system_over_an_infinite_span_ends():
    # before, the event's later values were NaN and the compiled run went on for ever
    code = """
import conmech
calls = []
def ev(t, y):
    calls.append(t)
    if t > 1.0:
        raise RuntimeError("boom in the event")
    return y[0] - 5.0
ev.terminal = True
try:
    conmech.solve_ivp(conmech.systems.harmonic(), (0.0, float("inf")), [1.0, 0.0],
                      events=ev)
except RuntimeError as exc:
    print("raised", exc, len(calls))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    word, *_, ncalls = out.stdout.split()
    assert word == "raised" and "boom in the event" in out.stdout
    assert int(ncalls) < 50        # the calls up to the failing one, none after


@pytest.mark.parametrize("compiled", [True, False])
def test_nan_event_stops_with_a_message(compiled):
    fun = conmech.systems.harmonic() if compiled else (lambda t, y: [y[1], -y[0]])

    def ev(t, y):
        return np.nan if t > 1.0 else y[0] - 5.0
    r = conmech.solve_ivp(fun, (0.0, 10.0), [1.0, 0.0], method="DOP853", events=ev)
    assert r.status == -1 and not r.success
    assert "event function 1 of 1 is NaN at t =" in r.message
    t_fail = float(r.message.rsplit("=", 1)[1])
    assert 1.0 < t_fail < 10.0 and r.t[-1] < t_fail


def test_terminal_event_at_t0_on_a_compiled_system_stops_after_one_step():
    # SciPy's rule (the first step moves the event away from zero in its direction: it is
    # reported at t0 and the run stops there); the compiled run stops at that step too
    def ev(t, y):
        return y[0]
    ev.terminal = True
    r = conmech.solve_ivp(conmech.systems.harmonic(), (0.0, 100.0), [0.0, 1.0], events=ev)
    s = si.solve_ivp(lambda t, y: [y[1], -y[0]], (0.0, 100.0), [0.0, 1.0], events=ev)
    assert r.status == s.status == 1
    assert list(r.t) == list(s.t) == [0.0, 0.0]
    assert list(r.t_events[0]) == list(s.t_events[0]) == [0.0]
    assert r.nfev == s.nfev + 1     # conmech evaluates f at t0 once more (RK45)
