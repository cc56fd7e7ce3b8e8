"""Events of conmech.constrained.solve (RATTLE, Radau, the projected explicit methods):
the crossings of theta = 0
by pendulum_xy (released at rest from theta0 = 1) at (2k+1) T/4, T from the complete
elliptic integral; terminal events; t_eval with events; bad input."""
import numpy as np
import pytest
from scipy.special import ellipk

from conmech import constrained

G, L, TH0 = 9.81, 1.0, 1.0
T = 4 * np.sqrt(L / G) * ellipk(np.sin(TH0 / 2) ** 2)
Q0 = [L * np.sin(TH0), -L * np.cos(TH0)]
V0 = [0.0, 0.0]


def x_cross(t, q, v):
    return q[0]


def falling_terminal(t, q, v):
    return q[0]


falling_terminal.terminal = True
falling_terminal.direction = -1


def test_rattle_crossings_order_two():
    # all crossings in two periods, event states on the circle to round-off; the errors of
    # the first crossing time fall as h^2
    errs = []
    for k in (40, 80, 160):
        r = constrained.solve("pendulum_xy", (0, 2 * T), Q0, V0, method="RATTLE",
                              first_step=T / k, events=x_cross)
        assert r.success and r.status == 0
        te = r.t_events[0]
        assert te.size == 4
        assert np.all(np.abs(te - np.array([1, 3, 5, 7]) * T / 4) < 50 / k ** 2)
        qe = r.q_events[0]
        assert qe.shape == (4, 2) and r.v_events[0].shape == (4, 2)
        assert np.abs(qe[:, 0]).max() < 1e-13
        assert np.abs(np.hypot(qe[:, 0], qe[:, 1]) - L).max() < 1e-14
        # velocity constraint q . v = 0 at the events
        assert np.abs((qe * r.v_events[0]).sum(axis=1)).max() < 1e-13
        errs.append(abs(te[0] - T / 4))
    p = np.log2(np.array(errs[:-1]) / errs[1:])
    assert np.all(np.abs(p - 2) < 0.2), p


def test_rattle_terminal_event_and_t_eval():
    r = constrained.solve("pendulum_xy", (0, 2 * T), Q0, V0, method="RATTLE",
                          first_step=T / 200, events=[x_cross, falling_terminal])
    assert r.success and r.status == 1
    # the first crossing is falling (the bob swings from x > 0 through x = 0): both
    # events there, the run ends at it
    assert r.t_events[0].size == 1 and r.t_events[1].size == 1
    assert r.t_events[1][0] == r.t[-1] and abs(r.t[-1] - T / 4) < 1e-3
    assert np.array_equal(r.q[:, -1], r.q_events[1][0])
    assert r.res_pos[-1] < 1e-14
    te = np.linspace(0, 2 * T, 21)
    r2 = constrained.solve("pendulum_xy", (0, 2 * T), Q0, V0, method="RATTLE",
                           first_step=T / 200, events=falling_terminal, t_eval=te)
    assert r2.status == 1 and np.array_equal(r2.t, te[te <= r.t[-1]])
    assert r2.t_events[0][0] == r.t_events[1][0]


def test_radau_events_and_t_eval():
    # Radau IIA on the index-2 DAE: event times to the tolerance, t_eval exact
    te = np.linspace(0, 2 * T, 11)
    r = constrained.solve("pendulum_xy", (0, 2 * T), Q0, V0, method="Radau", rtol=1e-10,
                          atol=1e-10, events=x_cross, t_eval=te)
    assert r.success and r.status == 0 and np.array_equal(r.t, te)
    assert np.abs(r.t_events[0] - np.array([1, 3, 5, 7]) * T / 4).max() < 1e-7
    assert np.abs(r.q_events[0][:, 0]).max() < 1e-9
    assert np.abs(np.hypot(*r.q_events[0].T) - L).max() < 1e-8
    r2 = constrained.solve("pendulum_xy", (0, 2 * T), Q0, V0, method="Radau", rtol=1e-10,
                           atol=1e-10, events=falling_terminal, t_eval=te)
    assert r2.status == 1 and np.array_equal(r2.t, te[te <= T / 4])
    assert abs(r2.t_events[0][0] - T / 4) < 1e-7
    agrees_with_rattle(r2.t_events[0][0])


def agrees_with_rattle(t_event):
    """RATTLE's first falling crossing agrees with t_event to the RATTLE order (h^2)."""
    h = T / 400
    r3 = constrained.solve("pendulum_xy", (0, 2 * T), Q0, V0, method="RATTLE",
                           first_step=h, events=falling_terminal)
    assert abs(r3.t_events[0][0] - t_event) < 5 * h ** 2


def test_events_on_a_user_system():
    # the same pendulum as Python callables (the general-mass RATTLE path; DOP853)
    s = constrained.ConstrainedSystem(
        2, mass=lambda t, q: np.eye(2), forces=lambda t, q, v: np.array([0.0, -G]),
        phi=lambda t, q: np.array([0.5 * (q @ q - L ** 2)]),
        jac=lambda t, q: q.reshape(1, 2), n_hol=1)
    rd = constrained.solve(s, (0, 2 * T), Q0, V0, rtol=1e-11, atol=1e-11, events=x_cross)
    assert rd.success and np.abs(rd.t_events[0] - np.array([1, 3, 5, 7]) * T / 4).max() < 1e-9
    r = constrained.solve(s, (0, 2 * T), Q0, V0, method="RATTLE", first_step=T / 200,
                          events=x_cross)
    rb = constrained.solve("pendulum_xy", (0, 2 * T), Q0, V0, method="RATTLE",
                           first_step=T / 200, events=x_cross)
    assert np.allclose(r.t_events[0], rb.t_events[0], rtol=0, atol=1e-12)


def test_events_bad_input():
    def twice(t, q, v):
        return q[0]
    twice.terminal = 2
    with pytest.raises(ValueError, match="terminal"):
        constrained.solve("pendulum_xy", (0, 1), Q0, V0, method="RATTLE", first_step=0.01,
                          events=twice)
    with pytest.raises(TypeError, match="callable"):
        constrained.solve("pendulum_xy", (0, 1), Q0, V0, method="RATTLE", first_step=0.01,
                          events=[1.0])

    def broken(t, q, v):
        raise RuntimeError("boom")
    with pytest.raises(RuntimeError, match="boom"):
        constrained.solve("pendulum_xy", (0, 1), Q0, V0, method="RATTLE", first_step=0.01,
                          events=broken)

    def vector(t, q, v):
        return q
    with pytest.raises(ValueError, match="events"):
        constrained.solve("pendulum_xy", (0, 1), Q0, V0, method="RATTLE", first_step=0.01,
                          events=vector)


def rising(t, q, v):
    return q[0]


rising.direction = 1
EXACT = np.array([1, 3, 5, 7]) * T / 4


@pytest.mark.parametrize("method", ["DOP853", "VERNER98", "DOPRI5"])
def test_explicit_crossings(method):
    # located on the dense output, then projected: times to ~1e-9 at rtol 1e-11, states on
    # the circle (position+velocity projection) to round-off
    r = constrained.solve("pendulum_xy", (0, 2 * T), Q0, V0, method=method, rtol=1e-11,
                          atol=1e-11, events=[x_cross, rising])
    assert r.success and r.status == 0 and r.t[-1] == 2 * T
    assert np.abs(r.t_events[0] - EXACT).max() < 1e-9
    assert np.abs(r.t_events[1] - EXACT[1::2]).max() < 1e-9   # direction +1 only
    qe, ve = r.q_events[0], r.v_events[0]
    assert qe.shape == (4, 2) and ve.shape == (4, 2)
    assert np.abs(qe[:, 0]).max() < 1e-10
    assert np.abs(np.hypot(qe[:, 0], qe[:, 1]) - L).max() < 1e-14
    assert np.abs((qe * ve).sum(axis=1)).max() < 1e-14
    # energy conservation gives the speed at the bottom: v^2 = 2 g l (1 - cos theta0)
    speed = np.hypot(ve[:, 0], ve[:, 1])
    assert np.abs(speed - np.sqrt(2 * G * L * (1 - np.cos(TH0)))).max() < 1e-9


def test_explicit_projection_of_the_event_state():
    # velocity projection only: q . v = 0 to round-off, |q| = l to the tolerance; no
    # projection: the dense-output state, on the constraints only to the tolerance
    kw = dict(method="DOP853", rtol=1e-11, atol=1e-11, events=x_cross)
    rv = constrained.solve("pendulum_xy", (0, 2 * T), Q0, V0, projection="velocity", **kw)
    qe = rv.q_events[0]
    assert np.abs((qe * rv.v_events[0]).sum(axis=1)).max() < 1e-14
    assert np.abs(rv.t_events[0] - EXACT).max() < 1e-9
    rn = constrained.solve("pendulum_xy", (0, 2 * T), Q0, V0, projection="none", **kw)
    assert np.abs(rn.t_events[0] - EXACT).max() < 1e-9
    assert np.abs(np.hypot(*rn.q_events[0].T) - L).max() < 1e-9


def test_explicit_terminal_t_eval_and_agreement():
    kw = dict(method="DOP853", rtol=1e-11, atol=1e-11)
    r = constrained.solve("pendulum_xy", (0, 2 * T), Q0, V0,
                          events=[x_cross, falling_terminal], **kw)
    assert r.success and r.status == 1
    assert r.t_events[0].size == 1 and r.t_events[1].size == 1
    assert r.t[-1] == r.t_events[1][0] and abs(r.t[-1] - T / 4) < 1e-9
    # the run ends at the projected event state
    assert np.array_equal(r.q[:, -1], r.q_events[1][0])
    assert np.array_equal(r.v[:, -1], r.v_events[1][0])
    assert r.res_pos[-1] < 1e-14 and r.res_vel[-1] < 1e-14
    te = np.linspace(0, 2 * T, 21)
    r2 = constrained.solve("pendulum_xy", (0, 2 * T), Q0, V0, events=falling_terminal,
                           t_eval=te, **kw)
    assert r2.status == 1 and np.array_equal(r2.t, te[te <= T / 4])
    assert abs(r2.t_events[0][0] - T / 4) < 1e-9
    # RK4 (fixed step, dense output): order-4 event time
    r4 = constrained.solve("pendulum_xy", (0, 2 * T), Q0, V0, method="RK4",
                           first_step=T / 400, events=falling_terminal)
    assert r4.status == 1 and abs(r4.t_events[0][0] - T / 4) < 1e-7
    # the same event as Radau (to its tolerance) and RATTLE (to its order h^2)
    ra = constrained.solve("pendulum_xy", (0, 2 * T), Q0, V0, method="Radau", rtol=1e-10,
                           atol=1e-10, events=falling_terminal, t_eval=te)
    assert np.array_equal(ra.t, r2.t)
    assert abs(ra.t_events[0][0] - r2.t_events[0][0]) < 1e-7
    agrees_with_rattle(r2.t_events[0][0])


@pytest.mark.parametrize("ret, err, match", [
    (lambda t, q, v: None, ValueError, "returned None"),
    (lambda t, q, v: np.nan, ValueError, "finite"),
    (lambda t, q, v: q, ValueError, "shape"),
    (lambda t, q, v: "x", TypeError, "real numbers"),
])
def test_explicit_bad_event_return(ret, err, match):
    with pytest.raises(err, match=match):
        constrained.solve("pendulum_xy", (0, 1), Q0, V0, method="DOP853", events=ret)
