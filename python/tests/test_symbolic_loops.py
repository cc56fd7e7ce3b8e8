"""Closed kinematic loops on trees (conmech.symbolic.Loop): the parallelogram four-bar
through its singular configurations against its exact one-degree-of-freedom motion, a
slider-crank (closed by a revolute and by a prismatic joint) against the Lagrangian of its
one coordinate, the multipliers against the Newton-Euler equations of single bodies, spatial
loops (a spherical closure, a revolute closure of a 7R linkage) against the same mechanisms
written by hand as T, U and constraints, consistent initial states, bad input."""

import numpy as np
import pytest

sp = pytest.importorskip("sympy")
from scipy.integrate import solve_ivp as sp_ivp  # noqa: E402
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402

from conmech import compiled, constrained, symbolic  # noqa: E402
from conmech.symbolic import Body, Loop, SpatialBody  # noqa: E402
import symbolic_seeds as seeds  # noqa: E402

t = dynamicsymbols._t


@pytest.fixture(scope="session", autouse=True)
def symbolic_cache(tmp_path_factory):
    """The test session's one compile cache (symbolic_seeds.use_test_cache)."""
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


rel = seeds.rel


def fourbar(coordinates="absolute", lengths=(1.0, 1.0, 1.0, 1.0)):
    """Uniform rods (mass m, length l_i): crank1 pinned at the origin, the coupler at its
    tip, crank2 pinned at (d, 0); the loop closes the coupler's tip on crank2's tip."""
    phi1, psi, phi2 = dynamicsymbols("phi1 psi phi2")
    m, l1, l2, l3, d, g = sp.symbols("m l1 l2 l3 d g")

    def rod(l):
        return dict(mass=m, com=(l/2, 0), inertia=m*l**2/12)
    bodies = [Body("crank1", None, "revolute", phi1, at=(0, 0), **rod(l1)),
              Body("coupler", "crank1", "revolute", psi, at=(l1, 0), **rod(l2)),
              Body("crank2", None, "revolute", phi2, at=(d, 0), **rod(l3))]
    params = {m: 1.0, l1: lengths[0], l2: lengths[1], l3: lengths[2], d: lengths[3],
              g: 9.81}
    mech = symbolic.planar_tree(bodies, params, gravity=(0, -g), coordinates=coordinates,
                                loops=[Loop("coupler", (l2, 0), "crank2", (l3, 0))])
    return mech, (phi1, psi, phi2)


def test_parallelogram_through_its_singular_configurations():
    """The parallelogram of uniform rods started horizontal (all bars collinear: the two
    loop constraints are dependent there, rank 1) follows phi'' = -(6/5) g cos phi; the
    cranks pass the horizontal again and again (REFERENCE.md; IFToMM A02 starts here)."""
    te = np.linspace(0, 10, 201)
    ref = sp_ivp(lambda s, y: [y[1], -1.2*9.81*np.cos(y[0])], (0, 10), [0.0, 1.0],
                 t_eval=te, method="DOP853", rtol=1e-13, atol=1e-13)
    crossings = np.sum(np.diff(np.sign(np.round(np.sin(ref.y[0]), 12))) != 0)
    assert crossings >= 3          # the motion passes the singular configurations
    for coordinates, v0 in (("absolute", [1.0, 0.0, 1.0]), ("relative", [1.0, -1.0, 1.0])):
        mech, _ = fourbar(coordinates)
        r = constrained.solve(mech, (0, 10), [0.0, 0.0, 0.0], v0, t_eval=te, rtol=1e-11,
                              atol=1e-11)
        assert r.success, r.message
        assert r.rank == 1                      # the redundant start
        assert np.max(np.abs(r.q[0] - ref.y[0])) <= 1e-6
        assert np.max(np.abs(r.q[2] - ref.y[0])) <= 1e-6
        coupler = r.q[1] if coordinates == "absolute" else r.q[0] + r.q[1]
        assert np.max(np.abs(coupler)) <= 1e-6          # the coupler translates
        assert np.max(r.res_pos) <= 1e-10
        E = r.energy         # (the singular crossings cost a few 1e-8 of it)
        assert np.max(np.abs(E - E[0])) <= 1e-7*abs(E[0])


def newton_euler_reaction(q, v, a, L=(1.0, 1.3, 1.1, 1.5), m=1.0, g=9.81):
    """The loop force on the coupler at its tip (world components) from the Newton-Euler
    equations of single rods: crank2 about its fixed pivot, and the coupler's moments about
    its pin (where the unknown pin force acts), given the accelerations (absolute angles)."""
    l1, l2, l3, d = L
    p1, ps, p2 = q
    w1, ws, w2 = v
    a1, as_, a2 = a
    e = lambda th: np.array([np.cos(th), np.sin(th)])
    n = lambda th: np.array([-np.sin(th), np.cos(th)])
    cross = lambda r, f: r[0]*f[1] - r[1]*f[0]
    # crank2 about its pivot: (m l^2/3) a2 = r_c x (m g) + r_tip x (-lam)
    r_c2, r_t2 = l3/2*e(p2), l3*e(p2)
    row1 = np.array([-r_t2[1], r_t2[0]]) * -1.0        # r_tip x (-lam) = row1 . lam
    rhs1 = m*l3**2/3*a2 - cross(r_c2, [0, -m*g])
    # coupler: pin P at crank1's tip; moments about P: r_tip x lam + r_c x m g =
    # I_c alpha + r_c x m a_c (a_c the COM's acceleration)
    aP = l1*(a1*n(p1) - w1**2*e(p1))
    r_c, r_t = l2/2*e(ps), l2*e(ps)
    a_c = aP + l2/2*(as_*n(ps) - ws**2*e(ps))
    row2 = np.array([-r_t[1], r_t[0]])
    rhs2 = m*l2**2/12*as_ + cross(r_c, m*a_c) - cross(r_c, [0, -m*g])
    return np.linalg.solve(np.array([row1, row2]), [rhs1, rhs2])


def test_multipliers_are_the_joint_force():
    """lambda of the revolute loop = the force of the joint on the coupler (world
    components): the Newton-Euler equations of crank2 and of the coupler, written by hand,
    give the same force at states along a motion of a generic four-bar."""
    L = (1.0, 1.3, 1.1, 1.5)
    mech, _ = fourbar("absolute", L)
    q0, v0 = symbolic.consistent_state(mech, [1.2, 0.4, 1.0], [2.0, 0, 0], independent=[0])
    r = constrained.solve(mech, (0, 2), q0, v0, t_eval=np.linspace(0, 2, 9), rtol=1e-11,
                          atol=1e-11)
    assert r.success
    for k in range(r.t.size):
        q, v = r.q[:, k], r.v[:, k]
        ev = compiled.evaluate(mech, r.t[k], q, v)
        a = np.linalg.solve(ev["M"], ev["Q"] + ev["G"].T @ r.lam[:, k])
        ref = newton_euler_reaction(q, v, a, L)
        assert rel(r.lam[:, k], ref) <= 1e-9


def test_joint_reactions_in_the_joint_frame():
    """joint_reactions: the loop force of a generic four-bar on the coupler, in the
    coupler's frame, is the Newton-Euler force (world components) turned by the coupler's
    angle; with relative coordinates (the coupler's frame then composed of two joint
    rotations) the same along the same motion."""
    L = (1.0, 1.3, 1.1, 1.5)
    te = np.linspace(0, 2, 9)
    out = {}
    for coordinates in ("absolute", "relative"):
        mech, _ = fourbar(coordinates, L)
        qa, va = symbolic.consistent_state(fourbar("absolute", L)[0], [1.2, 0.4, 1.0],
                                           [2.0, 0, 0], independent=[0])
        q0, v0 = qa.copy(), va.copy()
        if coordinates == "relative":
            q0[1], v0[1] = qa[1] - qa[0], va[1] - va[0]
        r = constrained.solve(mech, (0, 2), q0, v0, t_eval=te, rtol=1e-11, atol=1e-11)
        assert r.success
        jr = symbolic.joint_reactions(mech, r)
        assert list(jr) == ["loop 0 (coupler-crank2)"]
        j = jr["loop 0 (coupler-crank2)"]
        assert (j.kind, j.body_a, j.body_b, j.moment) == ("revolute", "coupler", "crank2",
                                                          None)
        assert j.force.shape == (2, te.size) and j.rows == slice(0, 2)
        out[coordinates] = j.force
        if coordinates == "absolute":
            for k in range(te.size):
                q, v = r.q[:, k], r.v[:, k]
                ev = compiled.evaluate(mech, r.t[k], q, v)
                a = np.linalg.solve(ev["M"], ev["Q"] + ev["G"].T @ r.lam[:, k])
                f = newton_euler_reaction(q, v, a, L)          # world components
                c, s_ = np.cos(q[1]), np.sin(q[1])
                assert rel(j.force[:, k], [c*f[0] + s_*f[1], -s_*f[0] + c*f[1]]) <= 1e-9
    assert rel(out["relative"], out["absolute"]) <= 1e-8
    with pytest.raises(ValueError, match="result: its q must have 3 rows"):
        symbolic.joint_reactions(mech, type("R", (), {"q": np.zeros((2, 1)),
                                                      "lam": np.zeros((2, 1))})())


def slider_crank_reference(r_, l_, m1, m2, m3, g, th0, w0, t_eval):
    """The slider-crank in its one coordinate theta (crank angle), by the Lagrangian of the
    exact kinematics: slider x = r cos th + sqrt(l^2 - r^2 sin^2 th) on the x axis."""
    th = dynamicsymbols("theta_ref")
    r, l = sp.nsimplify(r_), sp.nsimplify(l_)
    s = sp.sqrt(l**2 - r**2*sp.sin(th)**2)
    xb = r*sp.cos(th) + s
    A = sp.Matrix([r*sp.cos(th), r*sp.sin(th)])          # crank tip
    B = sp.Matrix([xb, 0])
    c1, c2 = A/2, (A + B)/2
    psi = sp.atan2(-r*sp.sin(th), s)                      # rod angle
    v = lambda p: p.diff(t)
    T = (m1*v(c1).dot(v(c1)) + m1*r**2/12*th.diff(t)**2 + m2*v(c2).dot(v(c2))
         + m2*l**2/12*psi.diff(t)**2 + m3*v(B).dot(v(B)))/2
    U = g*(m1*c1[1] + m2*c2[1])
    sysr = symbolic.lagrangian_system(T - U, [th], {}, simplify=False)
    from conmech import solve_ivp
    return solve_ivp(sysr, (0, t_eval[-1]), [th0, w0], t_eval=t_eval, method="DOP853",
                     rtol=1e-12, atol=1e-12)


def test_slider_crank_matches_the_one_coordinate_lagrangian():
    """Crank (revolute to the ground), rod, slider: closed by a revolute joint between the
    rod's end and a slider on a prismatic joint, and closed by a prismatic joint (slider
    on the rod, sliding on the ground's x axis); both follow the exact one-coordinate
    motion."""
    th, ps, x, s = dynamicsymbols("th ps x s")
    r, l, m1, m2, m3, g = sp.symbols("r l m1 m2 m3 g")
    vals = {r: 0.5, l: 1.4, m1: 1.0, m2: 0.7, m3: 0.4, g: 9.81}
    te = np.linspace(0, 3, 31)
    ref = slider_crank_reference(0.5, 1.4, 1.0, 0.7, 0.4, 9.81, 0.7, 3.0, te)
    assert ref.success
    crank = Body("crank", None, "revolute", th, mass=m1, com=(r/2, 0), inertia=m1*r**2/12)
    rod = Body("rod", "crank", "revolute", ps, at=(r, 0), mass=m2, com=(l/2, 0),
               inertia=m2*l**2/12)
    # closed by a revolute joint: the slider slides on the ground's x axis
    slider = Body("slider", None, "prismatic", x, axis=(1, 0), mass=m3)
    mech1 = symbolic.planar_tree([crank, rod, slider], vals, gravity=(0, -g),
                                 coordinates="absolute",
                                 loops=[Loop("rod", (l, 0), "slider", (0, 0))])
    # closed by a prismatic joint: the slider pinned to the rod's end (its inertia does
    # not enter: the joint keeps it from turning)
    slider2 = Body("slider", "rod", "revolute", s, at=(l, 0), mass=m3, inertia=0.01)
    mech2 = symbolic.planar_tree([crank, rod, slider2], vals, gravity=(0, -g),
                                 coordinates="absolute",
                                 loops=[Loop(None, (0, 0), "slider", (0, 0), "prismatic",
                                             axis=(1, 0))])
    for mech, guess in ((mech1, [0.7, -0.2, 1.7]), (mech2, [0.7, -0.2, 0.1])):
        q0, v0 = symbolic.consistent_state(mech, guess, [3.0, 0, 0], independent=[th])
        res = constrained.solve(mech, (0, 3), q0, v0, t_eval=te, rtol=1e-11, atol=1e-11)
        assert res.success, res.message
        assert np.max(np.abs(res.q[0] - ref.y[0])) <= 1e-8
        assert np.max(res.res_pos) <= 1e-10


def rodrigues(k, q):
    k = sp.Matrix(k)
    K = sp.Matrix([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return sp.cos(q)*sp.eye(3) + sp.sin(q)*K + (1 - sp.cos(q))*k*k.T


def pose(bodies, name):
    """World rotation and origin of a body (hand-written forward kinematics)."""
    by = {b.name: b for b in bodies}
    chain = []
    while name is not None:
        chain.append(by[name])
        name = by[name].parent
    R, p = sp.eye(3), sp.zeros(3, 1)
    for b in reversed(chain):
        p = p + R*sp.Matrix(b.at)
        R = R*rodrigues(b.axis, b.q)
    return R, p


def rssr():
    th, a1, a2, a3, ph = dynamicsymbols("th a1 a2 a3 ph")
    g = sp.Symbol("g")

    def I3(a, b, c):
        return [[a, 0, 0], [0, b, 0], [0, 0, c]]
    bodies = [SpatialBody("crank", None, "revolute", th, axis=(0, 0, 1), mass=1,
                          com=(0.2, 0, 0), inertia=I3(0.001, 0.01, 0.01)),
              SpatialBody("c1", "crank", "revolute", a1, axis=(1, 0, 0), at=(0.4, 0, 0)),
              SpatialBody("c2", "c1", "revolute", a2, axis=(0, 1, 0)),
              SpatialBody("coupler", "c2", "revolute", a3, axis=(0, 0, 1), mass=1.5,
                          com=(0.6, 0, 0), inertia=I3(0.002, 0.18, 0.18)),
              SpatialBody("rocker", None, "revolute", ph, axis=(0, 1, 0), at=(1.0, 0.3, 0.2),
                          mass=0.8, com=(0.4, 0, 0), inertia=I3(0.001, 0.04, 0.04))]
    return bodies, g


def test_spatial_spherical_loop_matches_hand_written_constraints():
    """An RSSR linkage (crank, coupler on a spherical joint made of three revolutes,
    rocker; closed by a spherical joint): M, Q, phi, G, gamma and a motion equal those of
    constrained_system on the tree's T and U with phi written by hand."""
    bodies, g = rssr()
    mech = symbolic.spatial_tree(bodies, {g: 9.81}, gravity=(0, 0, -g),
                                 loops=[Loop("coupler", (1.2, 0, 0), "rocker", (0.8, 0, 0),
                                             joint="spherical")])
    model = symbolic.model_of(mech)
    parts = symbolic.spatial.build_spatial_tree(bodies, (0, 0, -g))
    Rc, pc = pose(bodies, "coupler")
    Rr, pr = pose(bodies, "rocker")
    phi = list(pc + Rc*sp.Matrix([1.2, 0, 0]) - pr - Rr*sp.Matrix([0.8, 0, 0]))
    ref_sys = symbolic.constrained_system(parts["T"], parts["U"], parts["q"], holonomic=phi,
                                          params={g: 9.81})
    ref = symbolic.model_of(ref_sys)
    rng = np.random.default_rng(3)
    for _ in range(3):
        q, v = rng.uniform(-2, 2, 5), rng.uniform(-2, 2, 5)
        for entry, args in (("mass", (q,)), ("forces", (q, v)), ("phi", (q,)),
                            ("phi_jac", (q,)), ("phi_gamma", (q, v))):
            assert rel(model.call(entry, 0.0, *args), ref.call(entry, 0.0, *args)) <= 1e-12
    q0, v0 = symbolic.consistent_state(mech, [0.3, 0.1, 0.2, -0.4, 0.5], [2.0, 0, 0, 0, 0],
                                       independent=["th"])
    te = np.linspace(0, 3, 7)
    r1 = constrained.solve(mech, (0, 3), q0, v0, t_eval=te, rtol=1e-11, atol=1e-11)
    r2 = constrained.solve(ref_sys, (0, 3), q0, v0, t_eval=te, rtol=1e-11, atol=1e-11)
    assert r1.success and r2.success
    assert rel(r1.q, r2.q) <= 1e-8
    assert np.max(np.abs(r1.energy - r1.energy[0])) <= 1e-8*abs(r1.energy[0])


def test_spatial_revolute_loop_of_a_7r_linkage():
    """A closed chain of seven revolute joints with skew axes (one degree of freedom):
    closed by a revolute joint to the ground (3 + 2 constraints); its motion equals that of
    constrained_system with the point and axis conditions written by hand."""
    qs = dynamicsymbols("r1:7")
    g = sp.Symbol("g")
    axes = [(0, 0, 1), (1, 0, 0), (0, 1, 0), (0, sp.Rational(3, 5), sp.Rational(4, 5)),
            (1, 0, 0), (0, 0, 1)]
    bodies = []
    for i in range(6):
        bodies.append(SpatialBody(f"b{i}", None if i == 0 else f"b{i - 1}", "revolute",
                                  qs[i], axis=axes[i],
                                  at=(0, 0, 0) if i == 0 else (0.3, 0.05*(i % 2), 0.1),
                                  mass=1, com=(0.15, 0, 0.05),
                                  inertia=[[0.01, 0, 0], [0, 0.012, 0], [0, 0, 0.008]]))
    # the ground side of the closing joint: where body b5's point and axis are at q*
    qstar = [0.3, -0.4, 0.5, 0.2, -0.3, 0.6]
    R5, p5 = pose(bodies, "b5")
    sub = dict(zip(qs, qstar))
    pw = [float(x) for x in (p5 + R5*sp.Matrix([0.3, 0, 0])).subs(sub)]
    uw = [float(x) for x in (R5*sp.Matrix([0, 1, 0])).subs(sub)]
    mech = symbolic.spatial_tree(bodies, {g: 9.81}, gravity=(0, 0, -g),
                                 loops=[Loop("b5", (0.3, 0, 0), None, pw, joint="revolute",
                                             axis=(0, 1, 0), axis_b=uw)])
    parts = symbolic.spatial.build_spatial_tree(bodies, (0, 0, -g))
    u = R5*sp.Matrix([0, 1, 0])
    w1 = np.cross(uw, [1.0, 0, 0])
    w1 /= np.linalg.norm(w1)
    w2 = np.cross(uw, w1)
    hol = list(p5 + R5*sp.Matrix([0.3, 0, 0]) - sp.Matrix(pw)) + \
        [u.dot(sp.Matrix(w1)), u.dot(sp.Matrix(w2))]
    ref = symbolic.constrained_system(parts["T"], parts["U"], parts["q"], holonomic=hol,
                                      params={g: 9.81})
    q0, v0 = symbolic.consistent_state(mech, qstar, [1.0, 0, 0, 0, 0, 0], independent=[0])
    assert np.max(np.abs(q0 - qstar)) <= 1e-12
    te = np.linspace(0, 1.5, 7)
    r1 = constrained.solve(mech, (0, 1.5), q0, v0, t_eval=te, rtol=1e-11, atol=1e-11)
    r2 = constrained.solve(ref, (0, 1.5), q0, v0, t_eval=te, rtol=1e-11, atol=1e-11)
    assert r1.success and r2.success
    assert np.max(np.abs(r1.q - r2.q)) <= 1e-8
    assert np.max(r1.res_pos) <= 1e-10


def test_rattle_on_a_generic_fourbar():
    """Away from singular configurations RATTLE (fixed step, second order) follows the
    DOP853 motion of a generic four-bar, on the constraints to round-off. (Radau IIA on
    constrained systems needs a constant mass matrix today: a loop system has M(q).)"""
    mech, _ = fourbar("absolute", (1.0, 1.3, 1.1, 1.5))
    q0, v0 = symbolic.consistent_state(mech, [1.2, 0.4, 1.0], [1.0, 0, 0], independent=[0])
    ref = constrained.solve(mech, (0, 1), q0, v0, rtol=1e-12, atol=1e-12)
    rt1 = constrained.solve(mech, (0, 1), q0, v0, method="RATTLE", first_step=2e-3)
    rt2 = constrained.solve(mech, (0, 1), q0, v0, method="RATTLE", first_step=1e-3)
    assert ref.success and rt1.success and rt2.success
    e1 = np.max(np.abs(rt1.q[:, -1] - ref.q[:, -1]))
    e2 = np.max(np.abs(rt2.q[:, -1] - ref.q[:, -1]))
    assert 3.0 <= e1/e2 <= 5.0                       # second order
    assert np.max(rt2.res_pos) <= 1e-10


def test_consistent_state():
    mech, (phi1, psi, phi2) = fourbar("absolute", (1.0, 1.3, 1.1, 1.5))
    model = symbolic.model_of(mech)
    for ind in ([0], [phi1], ["phi1"]):
        q, v = symbolic.consistent_state(mech, [1.2, 0.4, 1.0], [2.0, 5.0, 5.0],
                                         independent=ind)
        assert q[0] == 1.2 and v[0] == 2.0
        assert np.max(np.abs(model.call("phi", 0.0, q))) <= 1e-12
        assert np.max(np.abs(model.call("phi_jac", 0.0, q) @ v)) <= 1e-12
    # no independent coordinate: the minimum-norm correction
    q, v = symbolic.consistent_state(mech, [1.2, 0.4, 1.0], [2.0, 0.0, 0.0])
    assert np.max(np.abs(model.call("phi", 0.0, q))) <= 1e-12
    # a loop that cannot close: the pivots too far apart for the links
    with pytest.raises(ValueError, match=r"loop 0 \(coupler-crank2\).*cannot close"):
        symbolic.consistent_state(mech.with_params(d=4.0), [1.2, 0.4, 1.0], [1, 0, 0],
                                  independent=[0])
    with pytest.raises(ValueError, match="not a coordinate"):
        symbolic.consistent_state(mech, [1.2, 0.4, 1.0], independent=["nope"])
    with pytest.raises(ValueError, match="3 finite values"):
        symbolic.consistent_state(mech, [1.2, 0.4])


def test_a_loop_that_cannot_close_is_a_value_error_naming_it():
    """A four-bar (crank 1, coupler and rocker 0.6, pivots 1.2 apart) cannot take the crank
    angle pi (the coupler and rocker reach 1.2, the crank tip is 2.2 from the rocker's
    pivot): consistent_state and constrained.solve raise ValueError naming the loop's joint,
    bodies and points and the residual, before any step."""
    mech, _ = fourbar("absolute", (1.0, 0.6, 0.6, 1.2))
    model = symbolic.model_of(mech)
    where = (r"loop 0 \(coupler-crank2\) \(revolute joint of 'coupler' at \(l2, 0\) = "
             r"\(0\.6, 0\) and 'crank2' at \(l3, 0\) = \(0\.6, 0\)\)")
    with pytest.raises(ValueError, match=where + ".*residual"):
        symbolic.consistent_state(mech, [np.pi, 0.0, 0.0], independent=[0])
    # the same crank angle reachable from a closing position: fine
    q, _ = symbolic.consistent_state(mech, [0.5, 1.0, 2.0], independent=[0])
    assert np.max(np.abs(model.call("phi", 0.0, q))) <= 1e-12
    # the pivots 4 apart: no position closes the loop; solve says so instead of
    # returning success=False
    far = mech.with_params(d=4.0)
    q0 = np.array([0.3, 0.2, 0.1])
    res = np.max(np.abs(model.call("phi", 0.0, q0, params=np.asarray(far.params))))
    with pytest.raises(ValueError, match=where + f" cannot close at the initial positions "
                       rf"q0 \(residual {res:.3g};"):
        constrained.solve(far, (0, 1), q0, [0.0, 0.0, 0.0])


def test_bad_loops():
    phi1, psi = dynamicsymbols("phi1 psi")
    m, l = sp.symbols("m l")
    bodies = [Body("a", None, "revolute", phi1, mass=m, com=(l/2, 0)),
              Body("b", "a", "revolute", psi, at=(l, 0), mass=m, com=(l/2, 0))]
    p = {m: 1.0, l: 1.0}
    with pytest.raises(ValueError, match="unknown body 'c'"):
        symbolic.planar_tree(bodies, p, loops=[Loop("b", (l, 0), "c", (0, 0))])
    with pytest.raises(ValueError, match="unknown joint 'spherical' for a planar tree"):
        symbolic.planar_tree(bodies, p, loops=[Loop("b", (l, 0), None, (0, 0), "spherical")])
    with pytest.raises(ValueError, match="needs axis="):
        symbolic.planar_tree(bodies, p, loops=[Loop("b", (l, 0), None, (0, 0), "prismatic")])
    with pytest.raises(ValueError, match="2 components"):
        symbolic.planar_tree(bodies, p, loops=[Loop("b", (l, 0, 0), None, (0, 0))])
    with pytest.raises(ValueError, match="to itself"):
        symbolic.planar_tree(bodies, p, loops=[Loop("b", (l, 0), "b", (0, 0))])
    with pytest.raises(ValueError, match="unknown symbol.*'k'"):
        symbolic.planar_tree(bodies, p, loops=[Loop("b", (sp.Symbol("k"), 0), None, (0, 0))])
    with pytest.raises(ValueError, match="method='recursive'"):
        symbolic.planar_tree(bodies, p, loops=[Loop("b", (l, 0), None, (0, 0))],
                             method="lagrangian")
    with pytest.raises(TypeError, match="Loop records"):
        symbolic.planar_tree(bodies, p, loops=[("b", (l, 0), None, (0, 0))])
    q1 = dynamicsymbols("q1")
    sb = [SpatialBody("a", None, "revolute", q1, mass=1, com=(1, 0, 0))]
    with pytest.raises(ValueError, match="needs axis="):
        symbolic.spatial_tree(sb, {}, loops=[Loop("a", (1, 0, 0), None, (1, 0, 0))])
    with pytest.raises(ValueError, match="not a unit vector"):
        symbolic.spatial_tree(sb, {}, loops=[Loop("a", (1, 0, 0), None, (1, 0, 0),
                                                  axis=(1, 1, 0))])
    with pytest.raises(ValueError, match="unknown joint 'prismatic' for a spatial"):
        symbolic.spatial_tree(sb, {}, loops=[Loop("a", (1, 0, 0), None, (1, 0, 0),
                                                  "prismatic")])


def test_fourbar_example_runs():
    """example/fourbar.py: a crank-rocker closed by a Loop, on its constraints."""
    import os
    import re
    import subprocess
    import sys
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    r = subprocess.run([sys.executable, os.path.join(root, "example", "fourbar.py")],
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr
    res = float(re.search(r"max \|phi\| = (\S+);", r.stdout).group(1))
    assert "success" in r.stdout and res <= 1e-10
