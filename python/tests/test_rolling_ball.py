"""The rolling rubber ball on a plane (the lecture notes), built in as ``rolling_ball``:
closed forms (straight line / parabola, rotation about a fixed axis, friction force as the
multiplier), constraints and energy, and agreement with the same system derived
symbolically from its T, U and constraints (conmech.symbolic.derive) to 1e-10."""
import math

import numpy as np
import pytest

from conmech import constrained, systems

M_, R_, I_, G_ = 1.3, 0.7, 0.2, 9.81


def qmul(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.concatenate([[a[0] * b[0] - a[1:] @ b[1:]],
                           a[0] * b[1:] + b[0] * a[1:] + np.cross(a[1:], b[1:])])


def rolling_state(e0, u, w, R=R_):
    """(q0, v0) rolling with centre velocity (u, w) and no spin: w_space = (-w/R, u/R, 0)."""
    om = np.array([-w / R, u / R, 0.0])
    e0 = np.asarray(e0, float) / np.linalg.norm(e0)
    return np.concatenate([[0.0, 0.0], e0]), np.concatenate([[u, w], 0.5 * qmul([0, *om], e0)])


def test_factory_and_default_state():
    s = systems.rolling_ball()
    assert (s.n, s.n_hol, s.n_nh) == (6, 1, 3)
    assert "rolling_ball" in constrained.BUILTIN_NAMES
    r = constrained.solve(s, (0, 2), rtol=1e-11, atol=1e-11)
    assert r.success, r.message
    assert r.dq0 < 1e-14 and r.dv0 < 1e-14  # the default state is consistent
    assert np.max(r.res_pos) < 1e-12 and np.max(r.res_vel) < 1e-12
    # flat plane: straight line at the default speed (1, 0.5)
    assert np.max(np.abs(r.q[0] - r.t)) < 1e-10 and np.max(np.abs(r.q[1] - 0.5 * r.t)) < 1e-10
    assert np.max(np.abs(r.energy - r.energy[0])) < 1e-11


def test_plane_rotation_about_a_fixed_axis():
    u, w = 0.8, -0.5
    e0 = [0.6, 0.0, 0.8, 0.0]
    q0, v0 = rolling_state(e0, u, w)
    t = np.linspace(0, 4, 41)
    r = constrained.solve(systems.rolling_ball(M_, R_, I_, G_, 0.0), (0, 4), q0, v0,
                          t_eval=t, rtol=1e-12, atol=1e-12)
    assert r.success
    om = np.array([-w / R_, u / R_, 0.0])
    wn = np.linalg.norm(om)
    err = max(np.max(np.abs(qmul([math.cos(wn * ti / 2), *(math.sin(wn * ti / 2) * om / wn)],
                                 e0) - r.q[2:, k])) for k, ti in enumerate(t))
    assert err < 1e-10
    assert np.max(np.abs(r.lam[1:])) < 1e-10          # no contact force, no spin torque
    assert np.max(np.abs(r.lam[0] + I_ * wn ** 2)) < 1e-10


def test_incline_parabola_and_friction():
    alpha, u, w = 0.3, 0.4, 1.1
    q0, v0 = rolling_state([0.5, 0.5, -0.5, 0.5], u, w)
    t = np.linspace(0, 3, 31)
    r = constrained.solve(systems.rolling_ball(M_, R_, I_, G_, alpha), (0, 3), q0, v0,
                          t_eval=t, rtol=1e-12, atol=1e-12)
    assert r.success
    acc = G_ * math.sin(alpha) / (1 + I_ / (M_ * R_ ** 2))
    assert np.max(np.abs(r.q[0] - u * t - acc * t ** 2 / 2)) < 1e-10
    assert np.max(np.abs(r.q[1] - w * t)) < 1e-10
    assert np.max(np.abs(r.lam[1] + I_ * acc / R_ ** 2)) < 1e-9   # F_x = -I x''/R^2
    assert np.max(np.abs(r.lam[2:])) < 1e-9
    assert np.max(np.abs(r.energy - r.energy[0])) < 1e-10
    assert np.max(np.abs(r.power)) < 1e-10


def test_homogeneous_ball_five_sevenths():
    """I = 2/5 m R^2: the centre accelerates at 5/7 g sin(alpha) down the incline."""
    alpha, R = 0.2, 0.5
    q0, v0 = rolling_state([1, 0, 0, 0], 0.0, 0.0, R=R)
    r = constrained.solve(systems.rolling_ball(2.0, R, 0.4 * 2.0 * R ** 2, G_, alpha),
                          (0, 2), q0, v0, t_eval=[2.0], rtol=1e-12, atol=1e-12)
    assert abs(r.q[0, -1] - 5 / 7 * G_ * math.sin(alpha) * 2.0) < 1e-10


def test_bad_params():
    with pytest.raises(ValueError, match="finite"):
        systems.rolling_ball(m=float("nan"))


# ------------------------------------------------------------------ symbolic derivation
sp = pytest.importorskip("sympy")


def derived_ball(alpha):
    """The ball from T, U and the constraints as written: T = m/2 |c'|^2 + I/2 |w|^2 with
    |w|^2 = 4 |e'|^2 on |e| = 1, e.e' = 0; U = -m g sin(alpha) x; no slip x' = R w_y,
    y' = -R w_x; no spin w_z = 0; w = 2 H(e) e'."""
    from conmech.symbolic.derive import derive_constrained
    x, y, e0, e1, e2, e3 = q = sp.symbols("x y e0 e1 e2 e3")
    v = sp.symbols("xd yd e0d e1d e2d e3d")
    m, R, I, g, al = sp.symbols("m R I g alpha")
    ed = sp.Matrix(v[2:])
    H = sp.Matrix([[-e1, e0, -e3, e2], [-e2, e3, e0, -e1], [-e3, -e2, e1, e0]])
    wv = 2 * H * ed
    T = m / 2 * (v[0] ** 2 + v[1] ** 2) + 2 * I * (ed.T * ed)[0, 0]
    U = -m * g * sp.sin(al) * x
    d = derive_constrained(T, U, q, holonomic=[(e0 ** 2 + e1 ** 2 + e2 ** 2 + e3 ** 2 - 1) / 2],
                           nonholonomic=[v[0] - R * wv[1], v[1] + R * wv[0], wv[2]],
                           params={m: M_, R: R_, I: I_, g: G_, al: alpha}, velocities=v)
    return d


def lambdified_system(d):
    args = [d.t] + list(d.coords) + list(d.speeds) + list(d.params)
    f = {k: sp.lambdify(args, getattr(d, k), "numpy") for k in
         ("M", "Q", "phi", "G", "gamma_h", "A", "b", "gamma_n")}
    p = d.param_values

    def call(k, t, q, v=None):
        v = np.zeros(len(q)) if v is None else v
        return np.array(f[k](t, *q, *v, *p), dtype=float)

    return constrained.ConstrainedSystem(
        6, lambda t, q: call("M", t, q), lambda t, q, v: call("Q", t, q, v).ravel(),
        phi=lambda t, q: call("phi", t, q).ravel(), jac=lambda t, q: call("G", t, q),
        gamma=lambda t, q, v: call("gamma_h", t, q, v).ravel(), n_hol=1,
        nh=lambda t, q: (call("A", t, q), call("b", t, q).ravel()),
        nh_gamma=lambda t, q, v: call("gamma_n", t, q, v).ravel(), n_nh=3)


def test_symbolic_derivation_agrees_with_builtin():
    alpha = 0.3
    d = derived_ball(alpha)
    assert sp.simplify(d.gamma_n) == sp.zeros(3, 1)   # H(e') e' = 0: gamma_n vanishes
    q0, v0 = rolling_state([0.5, 0.5, -0.5, 0.5], 0.4, 1.1)
    t = np.linspace(0, 3, 16)
    kw = dict(t_eval=t, rtol=1e-12, atol=1e-12)
    rb = constrained.solve(systems.rolling_ball(M_, R_, I_, G_, alpha), (0, 3), q0, v0, **kw)
    rs = constrained.solve(lambdified_system(d), (0, 3), q0, v0, **kw)
    assert rb.success and rs.success
    scale = np.max(np.abs(rb.q), axis=1, keepdims=True)
    assert np.max(np.abs(rs.q - rb.q) / scale) < 1e-10
    assert np.max(np.abs(rs.v - rb.v)) < 1e-10
    assert np.max(np.abs(rs.lam - rb.lam)) < 1e-10 * max(1.0, np.max(np.abs(rb.lam)))


def test_compiled_symbolic_ball_agrees_with_builtin():
    """conmech.symbolic.constrained_system (derived, emitted, compiled with gfortran) from the
    same T, U and constraints: trajectory and multipliers equal the built-in's to 1e-10."""
    from conmech import symbolic
    x, y, e0, e1, e2, e3 = q = sp.symbols("x y e0 e1 e2 e3")
    v = sp.symbols("xd yd e0d e1d e2d e3d")
    m, R, I, g, al = sp.symbols("m R I g alpha")
    ed = sp.Matrix(v[2:])
    H = sp.Matrix([[-e1, e0, -e3, e2], [-e2, e3, e0, -e1], [-e3, -e2, e1, e0]])
    wv = 2 * H * ed
    alpha = 0.3
    ball = symbolic.constrained_system(
        m / 2 * (v[0] ** 2 + v[1] ** 2) + 2 * I * (ed.T * ed)[0, 0],
        -m * g * sp.sin(al) * x, q,
        holonomic=[(e0 ** 2 + e1 ** 2 + e2 ** 2 + e3 ** 2 - 1) / 2],
        nonholonomic=[v[0] - R * wv[1], v[1] + R * wv[0], wv[2]],
        params={m: M_, R: R_, I: I_, g: G_, al: alpha}, velocities=v)
    q0, v0 = rolling_state([0.5, 0.5, -0.5, 0.5], 0.4, 1.1)
    t = np.linspace(0, 3, 16)
    kw = dict(t_eval=t, rtol=1e-12, atol=1e-12)
    rb = constrained.solve(systems.rolling_ball(M_, R_, I_, G_, alpha), (0, 3), q0, v0, **kw)
    rs = constrained.solve(ball, (0, 3), q0, v0, **kw)
    assert rb.success and rs.success
    assert np.max(np.abs(rs.q - rb.q)) < 1e-10 * np.max(np.abs(rb.q))
    assert np.max(np.abs(rs.v - rb.v)) < 1e-10 * np.max(np.abs(rb.v))
    assert np.max(np.abs(rs.lam - rb.lam)) < 1e-10 * np.max(np.abs(rb.lam))
    assert np.max(np.abs(rs.energy - rb.energy)) < 1e-10 * np.max(np.abs(rb.energy))
    # with_params: a flat plane without recompiling gives the straight line
    flat = ball.with_params(alpha=0.0)
    rf = constrained.solve(flat, (0, 3), q0, v0, **kw)
    assert np.max(np.abs(rf.q[0] - 0.4 * t)) < 1e-10
