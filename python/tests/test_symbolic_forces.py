"""M(q) and generalized forces given directly (lagrangian_system / constrained_system with
mass=), and forces at points of bodies of trees (PointForce), against the same systems
from T and U with the generalized forces J^T F written by hand."""

import numpy as np
import pytest

sp = pytest.importorskip("sympy")
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402

from conmech import constrained, solve_ivp, symbolic  # noqa: E402
from conmech.symbolic import Body, PointForce, SpatialBody  # noqa: E402
import symbolic_seeds as seeds  # noqa: E402

t = dynamicsymbols._t


@pytest.fixture(scope="session", autouse=True)
def symbolic_cache(tmp_path_factory):
    """The test session's one compile cache (symbolic_seeds.use_test_cache)."""
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


rel = seeds.rel


def test_mass_and_forces_given_directly():
    """The cart pendulum of the lecture notes as M(q) and Q(q, q') equals its Lagrangian
    form: M, Q, the Jacobian R, the energy, a trajectory."""
    x, th = dynamicsymbols("x theta")
    M_, m, l, g = sp.symbols("M m l g")
    T = (M_ + m)*x.diff(t)**2/2 + m*l*sp.cos(th)*x.diff(t)*th.diff(t) \
        + m*l**2*th.diff(t)**2/2
    U = m*g*l*sp.cos(th)
    P = {M_: 1.3, m: 0.7, l: 0.9, g: 9.81}
    ref = symbolic.lagrangian_system(T - U, [x, th], P)
    Mm = [[M_ + m, m*l*sp.cos(th)], [m*l*sp.cos(th), m*l**2]]
    Q = [m*l*sp.sin(th)*th.diff(t)**2, m*g*l*sp.sin(th)]
    mine = symbolic.lagrangian_system(None, [x, th], P, forces=Q, mass=Mm, energy=T + U)
    mr, mm = symbolic.model_of(ref), symbolic.model_of(mine)
    rng = np.random.default_rng(2)
    for _ in range(3):
        q, v, a = rng.uniform(-2, 2, 2), rng.uniform(-2, 2, 2), rng.uniform(-2, 2, 2)
        for e, args in (("mass", (q,)), ("forces", (q, v)), ("forces_jac", (q, v, a)),
                        ("energy", (q, v))):
            assert rel(mm.call(e, 0.0, *args), mr.call(e, 0.0, *args)) <= 1e-14
    kw = dict(method="DOP853", rtol=1e-12, atol=1e-12)
    r1 = solve_ivp(mine, (0, 5), [0, 2.5, 0.3, 0], **kw)
    r2 = solve_ivp(ref, (0, 5), [0, 2.5, 0.3, 0], **kw)
    assert rel(r1.y[:, -1], r2.y[:, -1]) <= 1e-10


def test_constrained_mass_given_directly():
    """The Cartesian pendulum with M = m 1, U = m g y, phi = x^2 + y^2 - l^2 follows the
    built-in pendulum_xy; the energy is v^T M v / 2 + U."""
    X, Y = dynamicsymbols("X Y")
    m, g, l = sp.symbols("m g l")
    cs = symbolic.constrained_system(None, m*g*Y, [X, Y], holonomic=[X**2 + Y**2 - l**2],
                                     params={m: 1.0, g: 9.81, l: 1.0},
                                     mass=[[m, 0], [0, m]])
    q0 = [np.sin(0.5), -np.cos(0.5)]
    r = constrained.solve(cs, (0, 5), q0, [0, 0], rtol=1e-11, atol=1e-11)
    ref = constrained.solve("pendulum_xy", (0, 5), q0, [0, 0], rtol=1e-11, atol=1e-11)
    assert r.success and rel(r.q[:, -1], ref.q[:, -1]) <= 1e-10
    assert rel(r.reaction, ref.reaction) <= 1e-8    # (lambda depends on phi's scale)
    assert abs(r.energy[0] - (-9.81*np.cos(0.5))) <= 1e-12


def test_bad_mass():
    x, th = dynamicsymbols("x theta")
    with pytest.raises(ValueError, match="not symmetric"):
        symbolic.lagrangian_system(None, [x, th], {}, forces=[0, 0],
                                   mass=[[1, sp.cos(th)], [0, 1]])
    with pytest.raises(ValueError, match="depends on the velocities"):
        symbolic.lagrangian_system(None, [x, th], {}, forces=[0, 0],
                                   mass=[[1, 0], [0, 1 + th.diff(t)**2]])
    with pytest.raises(ValueError, match="2 x 2"):
        symbolic.lagrangian_system(None, [x, th], {}, forces=[0, 0], mass=[[1]])
    with pytest.raises(ValueError, match="either the Lagrangian"):
        symbolic.lagrangian_system(x.diff(t)**2, [x, th], {}, mass=[[1, 0], [0, 1]])
    with pytest.raises(ValueError, match="singular"):
        symbolic.lagrangian_system(None, [x, th], {}, forces=[0, 0],
                                   mass=[[1, 1], [1, 1]])
    with pytest.raises(ValueError, match="energy= goes with mass="):
        symbolic.lagrangian_system(x.diff(t)**2, [x], {}, energy=x)


def test_planar_point_force_is_j_transpose_f():
    """A spring from the tip of a double pendulum to a fixed point (world components,
    in q) and a follower force along the first link (body frame): forces, accelerations
    and the Jacobian equal those of the Lagrangian route with J^T F written by hand, in
    absolute and relative angles."""
    th1, th2 = dynamicsymbols("th1 th2")
    m, l, g, k, f = sp.symbols("m l g k f")
    bodies = [Body("a", None, "revolute", th1, mass=m, com=(l/2, 0), inertia=m*l**2/12),
              Body("b", "a", "revolute", th2, at=(l, 0), mass=m, com=(l/2, 0),
                   inertia=m*l**2/12)]
    params = {m: 1.0, l: 1.0, g: 9.81, k: 5.0, f: 0.7}
    for coords in ("absolute", "relative"):
        phi2 = th2 if coords == "absolute" else th1 + th2
        x = l*sp.cos(th1) + l*sp.cos(phi2)
        y = l*sp.sin(th1) + l*sp.sin(phi2)
        F = (-k*(x - 1), -k*(y + 1))
        # the follower force f along link a at its middle: (f cos th1, f sin th1) there
        xa, ya = l/2*sp.cos(th1), l/2*sp.sin(th1)
        Qs = [sp.diff(x, q)*F[0] + sp.diff(y, q)*F[1]
              + sp.diff(xa, q)*f*sp.cos(th1) + sp.diff(ya, q)*f*sp.sin(th1)
              for q in (th1, th2)]
        pf = [PointForce("b", (l, 0), F), PointForce("a", (l/2, 0), (f, 0), frame="body")]
        mr = symbolic.planar_tree(bodies, params, gravity=(0, -g), coordinates=coords,
                                  point_forces=pf, model_only=True)
        ml = symbolic.planar_tree(bodies, params, gravity=(0, -g), coordinates=coords,
                                  forces=Qs, method="lagrangian", model_only=True)
        rng = np.random.default_rng(0)
        for _ in range(3):
            q, v, a = rng.uniform(-2, 2, 2), rng.uniform(-2, 2, 2), rng.uniform(-2, 2, 2)
            for e, args in (("forces", (q, v)), ("accel", (q, v)), ("forces_jac", (q, v, a))):
                assert rel(mr.call(e, 0.3, *args), ml.call(e, 0.3, *args)) <= 1e-12
            _, J = mr.call("accel_jac", 0.3, q, v)
            M = ml.call("mass", 0.3, q)
            acc = np.linalg.solve(M, ml.call("forces", 0.3, q, v))
            assert rel(J, np.linalg.solve(M, ml.call("forces_jac", 0.3, q, v, acc))) <= 1e-12


def test_spatial_point_force_in_the_body_frame():
    """A thrust along the second link's own x axis at its end (a body-frame force that
    turns with it) plus a velocity-dependent drag there (world frame): the recursive
    system equals the Lagrangian route with J^T F from hand-written kinematics."""
    q1, q2 = dynamicsymbols("q1 q2")
    g, F0, c = sp.symbols("g F0 c")
    bodies = [SpatialBody("a", None, "revolute", q1, axis=(0, 0, 1), mass=1,
                          com=(0.5, 0, 0), inertia=[[0.01, 0, 0], [0, 0.08, 0], [0, 0, 0.08]]),
              SpatialBody("b", "a", "revolute", q2, axis=(0, 1, 0), at=(1, 0, 0), mass=0.5,
                          com=(0.4, 0, 0), inertia=[[0.005, 0, 0], [0, 0.03, 0], [0, 0, 0.03]])]
    Rz = sp.Matrix([[sp.cos(q1), -sp.sin(q1), 0], [sp.sin(q1), sp.cos(q1), 0], [0, 0, 1]])
    Ry = sp.Matrix([[sp.cos(q2), 0, sp.sin(q2)], [0, 1, 0], [-sp.sin(q2), 0, sp.cos(q2)]])
    tip = Rz*sp.Matrix([1, 0, 0]) + Rz*Ry*sp.Matrix([0.8, 0, 0])
    vel = tip.diff(t)
    thrust = Rz*Ry*sp.Matrix([F0, 0, 0])
    drag = -c*vel
    Fw = thrust + drag
    Qs = [sum(sp.diff(tip[i], q)*Fw[i] for i in range(3)) for q in (q1, q2)]
    params = {g: 9.81, F0: 2.0, c: 0.4}
    pf = [PointForce("b", (0.8, 0, 0), (F0, 0, 0), frame="body"),
          PointForce("b", (0.8, 0, 0), list(drag))]
    mr = symbolic.spatial_tree(bodies, params, gravity=(0, 0, -g), point_forces=pf,
                               model_only=True)
    ml = symbolic.spatial_tree(bodies, params, gravity=(0, 0, -g), forces=Qs,
                               method="lagrangian", model_only=True)
    rng = np.random.default_rng(5)
    for _ in range(3):
        q, v, a = rng.uniform(-2, 2, 2), rng.uniform(-2, 2, 2), rng.uniform(-2, 2, 2)
        for e, args in (("forces", (q, v)), ("accel", (q, v)), ("forces_jac", (q, v, a))):
            assert rel(mr.call(e, 0.0, *args), ml.call(e, 0.0, *args)) <= 1e-12


def test_bad_point_forces():
    q1 = dynamicsymbols("q1")
    b = [Body("a", None, "revolute", q1, mass=1, com=(1, 0))]
    with pytest.raises(ValueError, match="unknown body 'x'"):
        symbolic.planar_tree(b, {}, point_forces=[PointForce("x", (0, 0), (1, 0))])
    with pytest.raises(ValueError, match="frame must be"):
        symbolic.planar_tree(b, {}, point_forces=[PointForce("a", (0, 0), (1, 0), "local")])
    with pytest.raises(ValueError, match="2 components"):
        symbolic.planar_tree(b, {}, point_forces=[PointForce("a", (0, 0), (1, 0, 0))])
    with pytest.raises(TypeError, match="PointForce records"):
        symbolic.planar_tree(b, {}, point_forces=[("a", (0, 0), (1, 0))])
    with pytest.raises(ValueError, match="method='recursive'"):
        symbolic.planar_tree(b, {}, point_forces=[PointForce("a", (0, 0), (1, 0))],
                             method="lagrangian")
