"""conmech.constrained: built-in and user-defined constrained systems, projections,
multipliers and reactions against closed forms, bad input."""
import math

import numpy as np
import pytest

from conmech import constrained, solve_ivp

G = 9.81


def ellipk_agm(k):
    a, b = 1.0, math.sqrt(1.0 - k * k)
    for _ in range(60):
        a, b = 0.5 * (a + b), math.sqrt(a * b)
        if abs(a - b) <= 4e-16 * a:
            break
    return math.pi / (2.0 * a)


def pendulum_callables(m=1.0, l=1.0, with_jac=True):
    kw = dict(n=2, n_hol=1, energy=lambda t, q, v: 0.5 * m * (v @ v) + m * G * q[1],
              mass=lambda t, q: m * np.eye(2),
              forces=lambda t, q, v: np.array([0.0, -m * G]),
              phi=lambda t, q: [0.5 * (q @ q - l * l)])
    if with_jac:
        kw.update(jac=lambda t, q: q.reshape(1, 2), gamma=lambda t, q, v: [-(v @ v)])
    return constrained.ConstrainedSystem(**kw)


def test_builtin_pendulum_multiplier_and_period():
    m, l, th0 = 0.7, 1.3, 1.1
    period = 4.0 * math.sqrt(l / G) * ellipk_agm(math.sin(th0 / 2))
    t_eval = np.linspace(0.0, 10 * period, 201)
    r = constrained.solve("pendulum_xy", (0, t_eval[-1]), [l * math.sin(th0), -l * math.cos(th0)],
                          [0, 0], params=[m, G, l], t_eval=t_eval, rtol=1e-12, atol=1e-12)
    assert r.success and r.status == 0
    assert r.q.shape == (2, 201) and r.lam.shape == (1, 201) and r.rank == 1
    lam_seed = m / l**2 * (r.q[1] * G - r.v[0] ** 2 - r.v[1] ** 2)
    assert np.max(np.abs(r.lam[0] - lam_seed)) < 1e-10
    assert np.allclose(r.reaction, r.lam[0] * r.q, atol=1e-12)
    assert np.max(r.res_pos) < 1e-13 and np.max(r.res_vel) < 1e-12
    assert np.max(np.abs(r.power)) < 1e-9
    # every 20th sample is a full period: back at the start
    assert np.max(np.abs(r.q[:, ::20] - r.q[:, :1])) < 1e-8


def test_excessive_vs_generalized_coordinates():
    """pendulum_xy vs the generalized pendulum (solve_ivp on the built-in 'pendulum_angle')."""
    from conmech.systems import BuiltinSystem
    th0, tf = 0.9, 20.0
    t_eval = np.linspace(0, tf, 101)
    r = constrained.solve("pendulum_xy", (0, tf), [math.sin(th0), -math.cos(th0)], [0, 0],
                          t_eval=t_eval, rtol=1e-12, atol=1e-12)
    s = solve_ivp(BuiltinSystem("pendulum_angle", [1.0, G, 1.0]), (0, tf), [th0, 0.0],
                  t_eval=t_eval, rtol=1e-12, atol=1e-12)
    assert s.success
    assert np.max(np.abs(r.q[0] - np.sin(s.y[0]))) < 1e-9
    assert np.max(np.abs(r.q[1] + np.cos(s.y[0]))) < 1e-9


def test_user_callables_match_builtin():
    t_eval = np.linspace(0, 5, 51)
    q0, v0 = [math.sin(1.0), -math.cos(1.0)], [0.0, 0.0]
    rb = constrained.solve("pendulum_xy", (0, 5), q0, v0, t_eval=t_eval, rtol=1e-11, atol=1e-11)
    for with_jac in (True, False):   # analytic, then the finite-difference defaults
        ru = constrained.solve(pendulum_callables(with_jac=with_jac), (0, 5), q0, v0,
                               t_eval=t_eval, rtol=1e-11, atol=1e-11)
        assert ru.success
        assert np.max(np.abs(ru.energy - rb.energy)) < 1e-8     # the callable energy
        assert 1 <= ru.proj_iter_max <= 3
        assert np.max(np.abs(ru.q - rb.q)) < 1e-8
        assert np.max(np.abs(ru.lam - rb.lam)) < 1e-7


def test_projection_removes_drift():
    kw = dict(rtol=1e-6, atol=1e-6, t_eval=np.linspace(0, 100, 11))
    rn = constrained.solve("double_pendulum_xy", (0, 100), projection="none", **kw)
    rp = constrained.solve("double_pendulum_xy", (0, 100), projection="position+velocity", **kw)
    rb = constrained.solve("double_pendulum_xy", (0, 100), projection="baumgarte", **kw)
    rv = constrained.solve("double_pendulum_xy", (0, 100), projection="velocity", **kw)
    assert rn.nproj == 0 and rp.nproj == rp.naccept
    assert rn.res_pos[-1] > 1e-6
    assert np.max(rp.res_pos) < 1e-12 and np.max(rp.res_vel) < 1e-12
    assert rb.res_pos[-1] < 1e-2 * rn.res_pos[-1]
    assert np.max(rv.res_vel) < 1e-12


def test_atwood_and_skate_closed_forms():
    m1, m2 = 3.0, 1.0
    t = np.linspace(0, 3, 31)
    r = constrained.solve("atwood_xy", (0, 3), [1.0, 1.0], [0.0, 0.0], params=[m1, m2, G, 2.0],
                          t_eval=t, rtol=1e-12, atol=1e-12)
    a = (m1 - m2) * G / (m1 + m2)
    assert np.max(np.abs(r.q[0] - (1 + 0.5 * a * t**2))) < 1e-10
    assert np.max(np.abs(r.lam[0] - 2 * m1 * m2 * G / (m1 + m2))) < 1e-10
    alpha, w = 0.3, 1.2
    r = constrained.solve("skate", (0, 3), [0, 0, 0], [0, 0, w], params=[1.0, 1.0, G, alpha],
                          t_eval=t, rtol=1e-12, atol=1e-12)
    c = G * math.sin(alpha) / (2 * w * w)
    assert np.max(np.abs(r.q[0] - c * np.sin(w * t) ** 2)) < 1e-10
    assert np.max(np.abs(r.q[1] - c * (w * t - 0.5 * np.sin(2 * w * t)))) < 1e-10


def test_non_holonomic_callables_rolling_disk():
    R = 0.5

    def nh(t, q):
        return (np.array([[1, 0, 0, -R * math.cos(q[2])], [0, 1, 0, -R * math.sin(q[2])]]),
                np.zeros(2))

    sys = constrained.ConstrainedSystem(4, lambda t, q: np.diag([1.0, 1.0, 0.2, 0.4]),
                                        lambda t, q, v: np.zeros(4), nh=nh, n_nh=2)
    om, ph = 0.8, 3.0
    r = constrained.solve(sys, (0, 5), [0, 0, 0, 0], [R * ph, 0, om, ph], rtol=1e-11,
                          atol=1e-11)
    assert r.success and r.lam.shape[0] == 2
    rho = R * ph / om
    assert np.max(np.abs(np.hypot(r.q[0], r.q[1] - rho) - rho)) < 1e-9
    assert np.max(r.res_vel) < 1e-12


def test_redundant_constraint_minimum_norm():
    sys = constrained.ConstrainedSystem(
        2, lambda t, q: np.eye(2), lambda t, q, v: np.array([0.0, -G]),
        phi=lambda t, q: [0.5 * (q @ q - 1), 0.5 * (q @ q - 1)],
        jac=lambda t, q: np.vstack([q, q]), gamma=lambda t, q, v: [-(v @ v)] * 2, n_hol=2)
    t = np.linspace(0, 3, 7)
    q0, v0 = [math.sin(1.0), -math.cos(1.0)], [0, 0]
    r2 = constrained.solve(sys, (0, 3), q0, v0, t_eval=t, rtol=1e-11, atol=1e-11)
    r1 = constrained.solve("pendulum_xy", (0, 3), q0, v0, t_eval=t, rtol=1e-11, atol=1e-11)
    assert r2.rank == 1
    assert np.max(np.abs(r2.q - r1.q)) < 1e-9
    assert np.max(np.abs(r2.reaction - r1.reaction)) < 1e-8
    assert np.max(np.abs(r2.lam - 0.5 * r1.lam)) < 1e-8


def test_consistent_initial_values_reported():
    r = constrained.solve("pendulum_xy", (0, 1), [1.1, 0.0], [0.5, 1.0])
    assert r.success
    assert abs(r.dq0 - 0.1) < 1e-12 and abs(r.dv0 - 0.5) < 1e-12
    assert r.res_pos[0] < 1e-14


def test_failures_and_bad_input():
    with pytest.raises(ValueError, match="unknown built-in"):
        constrained.solve("no_such_system", (0, 1))
    with pytest.raises(ValueError, match="q0"):
        constrained.solve("pendulum_xy", (0, 1), [1, 0, 0], [0, 0])
    with pytest.raises(ValueError, match="projection"):
        constrained.solve("pendulum_xy", (0, 1), projection="sideways")
    with pytest.raises(ValueError, match="method"):
        constrained.solve("pendulum_xy", (0, 1), method="EULER")
    with pytest.raises(ValueError, match="t_eval"):
        constrained.solve("pendulum_xy", (0, 1), t_eval=[0.5, 0.2])
    with pytest.raises(ValueError, match="mass"):
        bad = constrained.ConstrainedSystem(2, lambda t, q: np.eye(3),
                                            lambda t, q, v: np.zeros(2))
        constrained.solve(bad, (0, 1), [0, 0], [0, 0])
    with pytest.raises(TypeError):
        constrained.solve(42, (0, 1))
    # a built-in's mass m = 0 is refused up front, naming the parameter
    with pytest.raises(ValueError, match="m of the system 'pendulum_xy' must be positive"):
        constrained.solve("pendulum_xy", (0, 1), params=[0.0, G, 1.0])
    # singular mass matrix of a user system: a clear failure, not an exception
    zero_mass = constrained.ConstrainedSystem(
        2, lambda t, q: np.zeros((2, 2)), lambda t, q, v: np.array([0.0, -G]),
        phi=lambda t, q: [0.5 * (q @ q - 1)], n_hol=1)
    r = constrained.solve(zero_mass, (0, 1), [0.0, -1.0], [0.0, 0.0])
    assert not r.success and "singular mass matrix" in r.message
    # inconsistent constraints: no position satisfies both
    sys = constrained.ConstrainedSystem(
        2, lambda t, q: np.eye(2), lambda t, q, v: np.zeros(2),
        phi=lambda t, q: [0.5 * (q @ q - 1), q[0] - 5.0], n_hol=2)
    r = constrained.solve(sys, (0, 1), [0.0, -1.0], [0.0, 0.0])
    assert not r.success and "did not converge" in r.message
    # a callback exception reaches the caller
    def boom(t, q, v):
        raise RuntimeError("boom")
    sys = constrained.ConstrainedSystem(2, lambda t, q: np.eye(2), boom)
    with pytest.raises(RuntimeError, match="boom"):
        constrained.solve(sys, (0, 1), [0, 0], [0, 0])


def test_plot_helpers(tmp_path):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    kw = dict(rtol=1e-6, atol=1e-6)
    rn = constrained.solve("pendulum_xy", (0, 20), projection="none", **kw)
    rp = constrained.solve("pendulum_xy", (0, 20), **kw)
    ax = constrained.plot_trajectory(rp)
    ax2 = constrained.plot_drift({"none": rn, "projection": rp})
    ax2.figure.savefig(tmp_path / "drift.png")
    assert (tmp_path / "drift.png").stat().st_size > 0
    assert len(ax.lines) == 1 and len(ax2.lines) == 2


def test_generalized_seed_systems_in_solve_ivp():
    """The generalized seed systems are compiled built-ins of solve_ivp: the cart pendulum
    conserves P = 2 x' + cos(th) th' and follows x(t) = -sin(th)/2 + C0 + C1 t (as in the
    lecture notes)."""
    from conmech import systems
    y0 = [0.3, 2.5, 0.4, 1.0]
    t = np.linspace(0, 5, 51)
    s = solve_ivp(systems.cart_pendulum(), (0, 5), y0, t_eval=t, rtol=1e-12, atol=1e-12)
    assert s.success
    p0 = 2 * y0[2] + math.cos(y0[1]) * y0[3]
    assert np.max(np.abs(2 * s.y[2] + np.cos(s.y[1]) * s.y[3] - p0)) < 1e-10
    x = y0[0] + 0.5 * math.sin(y0[1]) - 0.5 * np.sin(s.y[1]) + 0.5 * p0 * t
    assert np.max(np.abs(s.y[0] - x)) < 1e-10
    for f in (systems.double_pendulum, systems.spring_pendulum, systems.bead_hoop,
              systems.three_springs, systems.polar_particle, systems.atwood,
              systems.double_spring_pendulum, systems.pendulum_moving, systems.yoyo_angle,
              systems.pendulum_angle):
        assert f().dimension >= 2


def test_constrained_factories_in_systems():
    from conmech import systems
    r = constrained.solve(systems.atwood_xy(m1=3.0, m2=1.0), (0, 1), [1.0, 1.0], [0.0, 0.0],
                          rtol=1e-12, atol=1e-12)
    assert r.success
    assert np.max(np.abs(r.lam[0] - 2 * 3.0 * 1.0 * G / 4.0)) < 1e-10
    for f in (systems.pendulum_xy, systems.rod_two_masses, systems.double_pendulum_xy,
              systems.pendulum_moving_xy, systems.yoyo, systems.skate, systems.rolling_disk):
        s = f()
        r = constrained.solve(s, (0, 1), rtol=1e-9, atol=1e-9)
        assert r.success, (s, r.message)
        assert r.q.shape[0] == s.n and r.lam.shape[0] == s.n_hol + s.n_nh
        assert np.max(r.res_pos) < 1e-12 and np.max(r.res_vel) < 1e-12


def test_callback_exception_in_constraints_is_reraised_unchanged():
    calls = []

    class Boom(Exception):
        pass

    def phi(t, q):
        calls.append(t)
        if len(calls) > 50:
            raise Boom("phi failed")
        return [0.5 * (q @ q - 1.0)]

    sys = constrained.ConstrainedSystem(2, lambda t, q: np.eye(2),
                                        lambda t, q, v: np.array([0.0, -G]), phi=phi,
                                        n_hol=1)
    with pytest.raises(Boom, match="phi failed"):
        constrained.solve(sys, (0, 10), [1.0, 0.0], [0.0, 0.0])
    n_calls = len(calls)
    assert n_calls == 51      # not called again after the exception


@pytest.mark.parametrize("method", ["DOPRI5", "DOP853", "VERNER98"])
def test_methods_agree(method):
    t = np.linspace(0, 5, 11)
    ref = constrained.solve("double_pendulum_xy", (0, 5), t_eval=t, rtol=1e-12, atol=1e-12)
    r = constrained.solve("double_pendulum_xy", (0, 5), t_eval=t, method=method, rtol=1e-11,
                          atol=1e-11)
    assert r.success and np.max(np.abs(r.q - ref.q)) < 1e-7
    assert np.max(r.res_pos) < 1e-13
    rk = constrained.solve("double_pendulum_xy", (0, 5), t_eval=t, method="RK4",
                           first_step=1e-3)
    assert rk.success and np.max(np.abs(rk.q - ref.q)) < 1e-6
