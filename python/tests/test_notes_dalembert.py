"""D'Alembert's route (the lecture notes): positions u_k(q, t), applied forces X_k, the
equations sum (m u'' - X) . du/dq_s = 0 and the generalized forces Q_s = sum X . du/dq_s;
the notes' pendulum and double pendulum reproduce the Lagrangian route; non-conservative and
time-dependent Cartesian forces; a planar body; the degrees of freedom n = 3N - R of every
built-in constrained system."""
import numpy as np
import pytest
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

import conmech
from conmech import constrained, symbolic, systems
from conmech.degrees_of_freedom import degrees_of_freedom

t = dynamicsymbols._t
G = 9.81


def _same(a, b):
    return sp.simplify(sp.sympify(a) - sp.sympify(b)) == 0


def _agree(a, b, n, states=6, seed=1):
    """max |M_a - M_b|, |Q_a - Q_b| over random states."""
    rng = np.random.default_rng(seed)
    err = 0.0
    for _ in range(states):
        q, v = rng.uniform(-2, 2, n), rng.uniform(-2, 2, n)
        ea = conmech.compiled.evaluate(a, 0.7, q, v)
        eb = conmech.compiled.evaluate(b, 0.7, q, v)
        err = max(err, np.max(np.abs(ea["M"] - eb["M"])), np.max(np.abs(ea["Q"] - eb["Q"])))
    return err


def test_notes_pendulum():
    """u = [l sin th, l - l cos th], X = [0, -m g]: m l^2 th'' + m g l sin th = 0."""
    th = dynamicsymbols("theta")
    m, l, g = sp.symbols("m l g")
    u = [l*sp.sin(th), l - l*sp.cos(th)]
    s = symbolic.dalembert_system([u], [m], [[0, -m*g]], [th], {m: 1.2, l: 0.9, g: G})
    assert _same(s.mass_matrix[0, 0], m*l**2)
    assert _same(s.generalized_forces[0], -m*g*l*sp.sin(th))
    assert s.cartesian_dimension == 2 and s.implicit_constraints == 1
    assert s.degrees_of_freedom == 1           # the notes' n = 2 - 1
    assert _same(sp.diff(s.potential, th), m*g*l*sp.sin(th))     # V = -m g l cos + const
    lag = symbolic.lagrangian_system(
        m*l**2*th.diff(t)**2/2 + m*g*l*sp.cos(th), [th], {m: 1.2, l: 0.9, g: G})
    assert _agree(s, lag, 1) <= 1e-12
    r = conmech.solve_ivp(s, (0, 10), [1.0, 0.0], rtol=1e-12, atol=1e-12)
    assert np.ptp(s.first_integrals.along(r)[0]) <= 1e-9      # energy T + V conserved


@pytest.fixture(scope="module")
def double():
    """The notes' double pendulum: x down (gravity along +x), relative angle th2,
    U = [[l1 cos th1, l1 cos th1 + l2 cos(th1 + th2)], [l1 sin th1, ...]], X = [m g, 0]."""
    th1, th2 = dynamicsymbols("theta1 theta2")
    m, l1, l2, g = sp.symbols("m l1 l2 g")
    U = sp.Matrix([[l1*sp.cos(th1), l1*sp.cos(th1) + l2*sp.cos(th1 + th2)],
                   [l1*sp.sin(th1), l1*sp.sin(th1) + l2*sp.sin(th1 + th2)]])
    X = sp.Matrix([[m*g, m*g], [0, 0]])
    P = {m: 1.0, l1: 1.0, l2: 0.7, g: G}
    dal = symbolic.dalembert_system(U, [m, m], X, [th1, th2], P)
    T = sum(m*(U[:, k].diff(t).T*U[:, k].diff(t))[0]/2 for k in range(2))
    V = -sum(m*g*U[0, k] for k in range(2))
    lag = symbolic.lagrangian_system(T - V, [th1, th2], P)
    return dal, lag, (th1, th2, m, l1, l2, g)


def test_notes_double_pendulum_is_lagrange(double):
    dal, lag, (th1, th2, m, l1, l2, g) = double
    assert _agree(dal, lag, 2) <= 1e-12
    y0 = [0.5, -0.3, 0.1, 0.2]
    tt = np.linspace(0, 3, 31)
    ra = conmech.solve_ivp(dal, (0, 3), y0, rtol=1e-12, atol=1e-12, t_eval=tt)
    rb = conmech.solve_ivp(lag, (0, 3), y0, rtol=1e-12, atol=1e-12, t_eval=tt)
    # the same equations to round-off: the same steps, the same motion (a short arc: the
    # double pendulum is chaotic and amplifies round-off later)
    assert ra.nfev == rb.nfev and np.max(np.abs(ra.y - rb.y)) <= 1e-12
    # the notes' generalized forces: Q_1 = -m g (2 l1 sin th1 + l2 sin(th1 + th2)),
    # Q_2 = -m g l2 sin(th1 + th2)
    Q = dal.generalized_forces
    assert _same(Q[0], -m*g*(2*l1*sp.sin(th1) + l2*sp.sin(th1 + th2)))
    assert _same(Q[1], -m*g*l2*sp.sin(th1 + th2))
    assert dal.cartesian_dimension == 4 and dal.implicit_constraints == 2   # n = 4 - 2
    # the equilibria agree (exact Jacobians on both routes)
    from conmech import stability
    for y in ([0, 0, 0, 0], [np.pi, 0, 0, 0]):
        ea, eb = stability.equilibrium(dal, y), stability.equilibrium(lag, y)
        assert ea.kind == eb.kind
        assert np.allclose(np.sort_complex(ea.eigenvalues), np.sort_complex(eb.eigenvalues),
                           rtol=0, atol=1e-12)


def test_drag_and_time_dependent_forces():
    """X = -c u' (linear drag) and X = [F cos(W t), 0]: Q = -c l^2 th' and
    Q = F l cos(W t) cos th, closed forms; the energy decays by the drag's power."""
    th = dynamicsymbols("theta")
    m, l, g, c, F, W = sp.symbols("m l g c F W")
    u = sp.Matrix([l*sp.sin(th), -l*sp.cos(th)])
    X = -c*u.diff(t) + sp.Matrix([F*sp.cos(W*t), -m*g])
    P = {m: 1.0, l: 1.0, g: G, c: 0.3, F: 0.5, W: 2.0}
    s = symbolic.dalembert_system([u], [m], [X], [th], P)
    assert _same(s.generalized_forces[0],
                 -c*l**2*th.diff(t) + F*l*sp.cos(W*t)*sp.cos(th) - m*g*l*sp.sin(th))
    assert s.potential is None
    lag = symbolic.lagrangian_system(m*l**2*th.diff(t)**2/2 + m*g*l*sp.cos(th), [th], P,
                                     forces=[-c*l**2*th.diff(t) + F*l*sp.cos(W*t)*sp.cos(th)])
    assert _agree(s, lag, 1) <= 1e-12
    # a drag-only copy: dE/dt = -c l^2 th'^2 along the motion (E = T + m g l (1 - cos))
    s2 = s.with_params(F=0.0)
    r = conmech.solve_ivp(s2, (0, 5), [1.0, 0.0], rtol=1e-12, atol=1e-12, dense_output=True)
    E = 0.5*r.y[1]**2 + G*(1 - np.cos(r.y[0]))
    from scipy.integrate import quad
    lost, _ = quad(lambda tt: 0.3*r.sol(tt)[1]**2, 0, 5, limit=200, epsabs=1e-12)
    assert abs((E[0] - E[-1]) - lost) <= 1e-8


def test_compound_pendulum_planar_body():
    """A uniform rod of mass m, length L on a pivot: its centre at L/2, its angle theta,
    central inertia m L^2/12: (m L^2/3) th'' = -m g (L/2) sin th."""
    th = dynamicsymbols("theta")
    m, L, g = sp.symbols("m L g")
    u = [L/2*sp.sin(th), -L/2*sp.cos(th)]
    s = symbolic.dalembert_system([u], [m], [[0, -m*g]], [th], {m: 2.0, L: 1.5, g: G},
                                  angles=[th], inertias=[m*L**2/12])
    assert _same(s.mass_matrix[0, 0], m*L**2/3)
    assert _same(s.generalized_forces[0], -m*g*L/2*sp.sin(th))
    e = conmech.stability.equilibrium(s, [0.0, 0.0])
    assert abs(np.max(e.eigenvalues.imag) - np.sqrt(G*0.75/(1.5**2/3))) <= 1e-12


def test_rank_deficient_mapping():
    """Positions that depend on q1 + q2 only: the coordinates are not independent."""
    q1, q2 = dynamicsymbols("q1 q2")
    u = [sp.cos(q1 + q2), sp.sin(q1 + q2)]
    with pytest.raises(ValueError, match=r"mapping: its Jacobian du/dq has rank 1 < 2.*q1.*q2"):
        symbolic.dalembert_system([u], [1], None, [q1, q2])
    with pytest.raises(ValueError, match="masses\\[0\\] must be positive"):
        symbolic.dalembert_system([[sp.cos(q1), sp.sin(q1)]], [0], None, [q1])
    with pytest.raises(ValueError, match="masses has 2 entries for 1"):
        symbolic.dalembert_system([[sp.cos(q1), sp.sin(q1)]], [1, 1], None, [q1])
    with pytest.raises(ValueError, match="one force vector per particle"):
        symbolic.dalembert_system([[sp.cos(q1), sp.sin(q1)]], [1], [[0, 0, 1]], [q1])


# --------------------------------------------------------------- degrees of freedom

#: (dof, velocity dof) of every built-in constrained system: coordinates minus independent
#: holonomic constraints; Pfaffian constraints reduce only the velocities (the rubber
#: ball's 2 is the lecture notes' count of its independent motions)
BUILTIN_DOF = {"pendulum_xy": (1, 1), "rod_two_masses": (3, 2), "double_pendulum_xy": (2, 2),
               "atwood_xy": (1, 1), "pendulum_moving_xy": (1, 1), "yoyo": (1, 1),
               "skate": (3, 2), "rolling_disk": (4, 2), "rolling_ball": (5, 2)}


def test_degrees_of_freedom_of_every_builtin():
    assert set(BUILTIN_DOF) == set(constrained.BUILTIN_NAMES)
    for name, (dof, vdof) in BUILTIN_DOF.items():
        s = constrained.builtin(name)
        r = degrees_of_freedom(s)
        assert (r.dof, r.velocity_dof) == (dof, vdof), name
        assert r.dof == s.n - r.rank_h and r.redundant == 0, name
        assert r.residual <= 1e-12 and s.degrees_of_freedom == dof
    assert degrees_of_freedom(systems.pendulum_chain_xy(7)).dof == 7
    generalized = {"cart_pendulum": 2, "pendulum_angle": 1, "double_pendulum": 2,
                   "atwood": 1, "spring_pendulum": 2, "double_spring_pendulum": 4,
                   "three_springs": 6, "bead_hoop": 1, "polar_particle": 2,
                   "pendulum_moving": 1, "yoyo_angle": 1}
    for name, n in generalized.items():
        assert getattr(systems, name)().degrees_of_freedom == n, name
    assert systems.kepler().degrees_of_freedom is None


def test_degrees_of_freedom_symbolic_and_redundant():
    """A symbolic constrained system without a default state (projected from seeded
    points), and a redundant constraint counted once."""
    x, y = dynamicsymbols("x y")
    l, g = sp.symbols("l g")
    T = (x.diff(t)**2 + y.diff(t)**2)/2
    s = symbolic.constrained_system(T, g*y, [x, y], holonomic=[x**2 + y**2 - l**2],
                                    params={l: 1.0, g: G})
    r = degrees_of_freedom(s)
    assert r.dof == 1 and abs(np.hypot(*r.q) - 1.0) <= 1e-12
    # a bead on a vertical cylinder x^2 + y^2 = l^2, the constraint given twice
    z = dynamicsymbols("z")
    T3 = (x.diff(t)**2 + y.diff(t)**2 + z.diff(t)**2)/2
    s2 = symbolic.constrained_system(T3, g*z, [x, y, z],
                                     holonomic=[x**2 + y**2 - l**2, 2*(x**2 + y**2 - l**2)],
                                     params={l: 1.0, g: G})
    r2 = degrees_of_freedom(s2, q=[0.6, -0.7, 0.3])
    assert r2.dof == 2 and r2.rank_h == 1 and r2.redundant == 1
    # a symbolic generalized system: its coordinates
    th = dynamicsymbols("theta")
    assert symbolic.lagrangian_system(th.diff(t)**2/2 + sp.cos(th), [th]).degrees_of_freedom \
        == 1
    with pytest.raises(ValueError, match="q must have 2"):
        degrees_of_freedom(s, q=[1.0])


def test_virtual_work_of_a_link_and_of_a_spring():
    """Seed 002: two particles A, B with coordinates (x_A, y_A, phi) and a rigid link: the
    link's internal forces +-R along AB do no virtual work (Q = 0); with a spring instead
    (coordinates x_A, y_A, L, phi) only L is worked on: Q_L = -k (L - L0)."""
    xA, yA, L, ph = dynamicsymbols("x_A y_A L phi")
    R, k, L0, l = sp.symbols("R k L0 l")
    A = sp.Matrix([xA, yA])
    e = sp.Matrix([sp.cos(ph), sp.sin(ph)])
    link = symbolic.dalembert_system([A, A + l*e], [1, 1], [-R*e, R*e], [xA, yA, ph],
                                     {R: 2.5, l: 1.0})
    assert all(q == 0 for q in map(sp.simplify, link.generalized_forces))
    assert link.implicit_constraints == 1                  # 4 - 3: the link's length
    spring = symbolic.dalembert_system([A, A + L*e], [1, 1],
                                       [k*(L - L0)*e, -k*(L - L0)*e], [xA, yA, L, ph],
                                       {k: 40.0, L0: 1.0})
    Q = [sp.simplify(q) for q in spring.generalized_forces]
    assert Q[0] == 0 and Q[1] == 0 and Q[3] == 0
    assert _same(Q[2], -k*(L - L0))
    assert spring.implicit_constraints == 0 and spring.degrees_of_freedom == 4
    # conservative: V = k (L - L0)^2 / 2 up to a constant
    assert _same(sp.diff(spring.potential, L), k*(L - L0))
