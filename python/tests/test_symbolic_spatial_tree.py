"""conmech.symbolic.spatial_tree: the spatial articulated-body accelerations (conmech_accel)
against M^-1 Q of the same tree's Lagrangian, a planar tree written as a spatial tree
against planar_tree, a trajectory against lagrangian_system of the same T and U, energy
conservation, a stability function, bad input."""

import re

import numpy as np
import pytest

sp = pytest.importorskip("sympy")
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402

import conmech  # noqa: E402
from conmech import symbolic  # noqa: E402
from conmech.symbolic import Body, SpatialBody, planar_tree, spatial_tree  # noqa: E402
import symbolic_seeds as seeds  # noqa: E402

t = dynamicsymbols._t


@pytest.fixture(scope="session", autouse=True)
def symbolic_cache(tmp_path_factory):
    """The test session's one compile cache (symbolic_seeds.use_test_cache)."""
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


rel = seeds.rel


def accel_vs_lagrangian(model, n, rng, k=4, t0=0.37):
    worst = 0.0
    for _ in range(k):
        q, v = rng.uniform(-2.5, 2.5, n), rng.uniform(-2, 2, n)
        a = model.call("accel", t0, q, v)
        ref = np.linalg.solve(model.call("mass", t0, q), model.call("forces", t0, q, v))
        worst = max(worst, rel(a, ref))
    return worst


def rigid_inertia(rng, dims, mass=1.0):
    """The inertia tensor of a box (sides `dims`) turned by a random rotation: symmetric,
    positive definite, with products of inertia (rounded: exact rationals)."""
    R, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    a, b, c = dims
    I = R @ np.diag([b*b + c*c, a*a + c*c, a*a + b*b]) @ R.T * mass / 12
    I = np.round((I + I.T) / 2, 5)
    return [[sp.Rational(str(x)) for x in row] for row in I]


def double_pendulum():
    """Two links, the first about x, the second about a tilted axis (0, 3/5, 4/5): the
    motion is not planar."""
    q1, q2 = dynamicsymbols("q1 q2")
    m1, m2, l1, l2, g = sp.symbols("m1 m2 l1 l2 g")
    bodies = [SpatialBody("a", None, "revolute", q1, axis=(1, 0, 0), mass=m1,
                          com=(0, 0.1, -l1)),
              SpatialBody("b", "a", "revolute", q2, axis=(0, sp.Rational(3, 5),
                                                          sp.Rational(4, 5)),
                          at=(0, 0, -l1), mass=m2, com=(0.2, 0, -l2))]
    params = {m1: 1.0, m2: 0.7, l1: 1.0, l2: 0.8, g: 9.81}
    return bodies, params, (q1, q2), g


def test_double_pendulum_accel_matches_lagrangian():
    bodies, params, q, g = double_pendulum()
    model = spatial_tree(bodies, params, gravity=(0, 0, -g), model_only=True)
    assert "accel" in model.addresses
    assert accel_vs_lagrangian(model, 2, np.random.default_rng(1)) <= 1e-12
    src = model.source[model.source.find("subroutine conmech_accel"):]
    src = src[:src.find("end subroutine")]
    assert src.count("sin(") == 2 and src.count("cos(") == 2
    assert "chol" not in src.lower()


ARM_JOINTS = 6


def arm(n=ARM_JOINTS):
    """A robot arm: revolute joints about z, y, x, y, x, one prismatic joint (the third,
    along z), offsets between the joints, COM offsets, full inertia tensors (products of
    inertia). Coordinate axes: with a tilted axis among six joints the construction (M
    and Q) takes ~65 s instead of ~25 s (tilted axes: the double pendulum, the branched
    tree)."""
    qs = dynamicsymbols(f"j1:{n + 1}")
    g = sp.Symbol("g")
    rng = np.random.default_rng(5)
    axes = [(0, 0, 1), (0, 1, 0), (0, 0, 1), (1, 0, 0), (0, 1, 0), (1, 0, 0)]
    bodies = []
    for i in range(n):
        com = tuple(sp.Rational(str(round(x, 3))) for x in rng.normal(size=3) * 0.1)
        bodies.append(SpatialBody(
            f"link{i}", None if i == 0 else f"link{i - 1}",
            "prismatic" if i == 2 else "revolute", qs[i], axis=axes[i % 6],
            at=(0, 0, 0) if i == 0 else (0, sp.Rational(1, 10), sp.Rational(3, 10)),
            mass=sp.Rational(12 - i, 10), com=com,
            inertia=rigid_inertia(rng, rng.uniform(0.05, 0.3, 3), 1.0)))
    return bodies, {g: 9.81}, qs, g


def test_arm_accel_matches_lagrangian():
    bodies, params, qs, g = arm()
    damp = {b.q: -0.1 * b.q.diff(t) for b in bodies}
    model = spatial_tree(bodies, params, gravity=(0, 0, -g), forces=damp, jacobian=False,
                         model_only=True)
    assert accel_vs_lagrangian(model, len(bodies), np.random.default_rng(2)) <= 1e-12
    # straight-line code: one sine and cosine per revolute joint, one division per joint
    src = model.source[model.source.find("subroutine conmech_accel"):]
    src = src[:src.find("end subroutine")]
    assert src.count("sin(") == 5 and src.count("cos(") == 5
    # (at most: the leaf's pivot is a constant here)
    assert len(re.findall(r"= 1\.0_dp/b\d+$", src, re.M)) <= len(bodies)
    assert src.count("/") - len(re.findall(r"_dp/[0-9]", src)) <= len(bodies)


def branched():
    """A torso sliding vertically (spring, damper), two arms on it about non-parallel
    axes, a hand on one arm (motor torque depending on t), with a fixed joint rotation."""
    z, a1, a2, a3 = dynamicsymbols("z a1 a2 a3")
    m0, m1, m2, m3, k, c, tau0, w, g = sp.symbols("m0 m1 m2 m3 k c tau0 w g")
    rng = np.random.default_rng(9)
    ct, st = sp.Rational(3, 5), sp.Rational(4, 5)
    rot = [[1, 0, 0], [0, ct, -st], [0, st, ct]]      # 53 degrees about x
    bodies = [SpatialBody("torso", None, "prismatic", z, axis=(0, 0, 1), mass=m0,
                          inertia=rigid_inertia(rng, (0.3, 0.2, 0.5), 2.0)),
              SpatialBody("arm1", "torso", "revolute", a1, axis=(0, 1, 0), at=(0.2, 0, 0.4),
                          mass=m1, com=(0.3, 0, -0.05),
                          inertia=rigid_inertia(rng, (0.6, 0.1, 0.1))),
              SpatialBody("arm2", "torso", "revolute", a2, axis=(1, 0, 0),
                          at=(-0.2, 0, 0.4), mass=m2, com=(0, 0.05, -0.3),
                          inertia=rigid_inertia(rng, (0.1, 0.1, 0.6))),
              SpatialBody("hand", "arm1", "revolute", a3, axis=(0, 0, 1), at=(0.6, 0, 0),
                          rot=rot, mass=m3, com=(0.1, 0.05, 0.02),
                          inertia=rigid_inertia(rng, (0.1, 0.15, 0.05), 0.4))]
    params = {m0: 2.0, m1: 1.0, m2: 0.7, m3: 0.4, k: 30.0, c: 0.3, tau0: 0.5, w: 1.7,
              g: 9.81}
    forces = {"torso": -k * z - c * z.diff(t), "arm2": -c * a2.diff(t),
              a3: tau0 * sp.sin(w * t) - c * a3.diff(t)}
    return bodies, params, forces, g


def test_branched_tree_accel_matches_lagrangian():
    bodies, params, forces, g = branched()
    model = spatial_tree(bodies, params, gravity=(0, 0, -g), forces=forces,
                         model_only=True)
    rng = np.random.default_rng(7)
    for t0 in (0.0, 0.9, 2.3):       # the motor torque depends on t
        assert accel_vs_lagrangian(model, 4, rng, k=2, t0=t0) <= 1e-12


def test_compact_kinetic_energy_equals_the_plain_one():
    """T in the compact form (column products in the deeper joint's frame) is the plain
    sum of (m |v_c|^2 + omega . I omega)/2 of the recursive body velocities; same U."""
    rng = np.random.default_rng(8)
    for bodies, params, *_ in (arm(4), branched()):
        parts = symbolic.spatial.build_spatial_tree(bodies, (0, 0, -sp.Symbol("g")),
                                                    lazy=True)
        T1, U1 = parts["energies"]()
        T0, U0 = parts["energies_naive"]()
        psub = {s: params.get(s, 1.3) for s in (T0 + U0).free_symbols if s.name != "t"}
        for _ in range(3):
            sub = {q.diff(t): rng.uniform(-2, 2) for q in parts["q"]}
            sub.update({q: rng.uniform(-2, 2) for q in parts["q"]})
            for a, b in ((T1, T0), (U1, U0)):
                a, b = float(a.subs(sub).subs(psub)), float(b.subs(sub).subs(psub))
                assert abs(a - b) <= 1e-13 * max(abs(b), 1.0)


def test_planar_tree_as_spatial_tree():
    """A planar branched tree (revolute axes z, a prismatic joint in the plane) written as
    a spatial tree gives planar_tree's accelerations, mass matrix and energy."""
    x, a1, a2, a3 = dynamicsymbols("x a1 a2 a3")
    m0, m1, m2, m3, I1, I2, I3, l1, g = sp.symbols("m0 m1 m2 m3 I1 I2 I3 l1 g")
    params = {m0: 2.0, m1: 1.0, m2: 0.7, m3: 0.4, I1: 0.08, I2: 0.05, I3: 0.02, l1: 1.0,
              g: 9.81}
    planar = [Body("torso", None, "prismatic", x, axis=(0.6, 0.8), mass=m0),
              Body("arm1", "torso", "revolute", a1, at=(0.1, 0.2), mass=m1,
                   com=(l1 / 2, -0.05), inertia=I1),
              Body("arm2", "torso", "revolute", a2, at=(-0.1, 0.2), mass=m2,
                   com=(0.03, -0.4), inertia=I2),
              Body("hand", "arm1", "revolute", a3, at=(l1, 0), mass=m3, com=(0.2, 0.1),
                   inertia=I3)]

    def diag(Iz):       # the out-of-plane moments do not enter the planar motion
        return [[Iz * 0.6, 0, 0], [0, Iz * 0.7, 0], [0, 0, Iz]]
    spatial = [SpatialBody("torso", None, "prismatic", x, axis=(0.6, 0.8, 0), mass=m0),
               SpatialBody("arm1", "torso", "revolute", a1, at=(0.1, 0.2, 0), mass=m1,
                           com=(l1 / 2, -0.05, 0), inertia=diag(I1)),
               SpatialBody("arm2", "torso", "revolute", a2, at=(-0.1, 0.2, 0), mass=m2,
                           com=(0.03, -0.4, 0), inertia=diag(I2)),
               SpatialBody("hand", "arm1", "revolute", a3, at=(l1, 0, 0), mass=m3,
                           com=(0.2, 0.1, 0), inertia=diag(I3))]
    forces = {"arm2": -0.3 * a2.diff(t)}
    mp = planar_tree(planar, params, gravity=(0, -g), forces=forces, model_only=True)
    ms = spatial_tree(spatial, params, gravity=(0, -g, 0), forces=forces, model_only=True)
    rng = np.random.default_rng(4)
    for _ in range(4):
        q, v = rng.uniform(-2, 2, 4), rng.uniform(-2, 2, 4)
        assert rel(ms.call("accel", 0.0, q, v), mp.call("accel", 0.0, q, v)) <= 1e-12
        assert rel(ms.call("mass", 0.0, q), mp.call("mass", 0.0, q)) <= 1e-12
        assert abs(ms.call("energy", 0.0, q, v) - mp.call("energy", 0.0, q, v)) \
            <= 1e-12 * abs(mp.call("energy", 0.0, q, v))


def test_trajectories_match_lagrangian_system_and_energy_is_conserved():
    """The ABA right-hand side and the Cholesky right-hand side of lagrangian_system(T - U)
    give the same trajectory to 1e-10 (the double pendulum over several swings, the
    branched tree with forces); the double pendulum's energy is conserved."""
    bodies, params, q, g = double_pendulum()
    tree = spatial_tree(bodies, params, gravity=(0, 0, -g))
    parts = symbolic.spatial.build_spatial_tree(bodies, (0, 0, -g))
    ref = symbolic.lagrangian_system(parts["L"], parts["q"], params)
    y0 = [1.2, -0.7, 0.0, 0.5]
    kw = dict(method="DOP853", rtol=1e-13, atol=1e-13)
    r1 = conmech.solve_ivp(tree, (0, 8), y0, **kw)
    r2 = conmech.solve_ivp(ref, (0, 8), y0, **kw)
    assert r1.success and r2.success
    assert rel(r1.y[:, -1], r2.y[:, -1]) <= 1e-10
    model = symbolic.model_of(tree)
    E = [model.call("energy", 0.0, y[:2], y[2:]) for y in r1.y.T]
    assert np.max(np.abs(np.array(E) - E[0])) <= 1e-10 * abs(E[0])
    # the branched tree with springs, dampers and a time-dependent motor
    bodies, params, forces, g = branched()
    tree = spatial_tree(bodies, params, gravity=(0, 0, -g), forces=forces)
    parts = symbolic.spatial.build_spatial_tree(bodies, (0, 0, -g), forces)
    ref = symbolic.lagrangian_system(parts["L"], parts["q"], params, forces=parts["forces"])
    y0 = [0.1, 0.5, -0.4, 0.3, 0.0, 0.2, 0.0, -0.1]
    r1 = conmech.solve_ivp(tree, (0, 5), y0, **kw)
    r2 = conmech.solve_ivp(ref, (0, 5), y0, **kw)
    assert r1.success and r2.success
    assert rel(r1.y[:, -1], r2.y[:, -1]) <= 1e-10


def test_hanging_double_pendulum_is_a_centre():
    """The hanging equilibrium (the COMs below the joints, on the axes' normal planes) is a
    centre: purely imaginary eigenvalues; the upright one is unstable."""
    q1, q2 = dynamicsymbols("h1 h2")
    g = sp.Symbol("g")
    bodies = [SpatialBody("a", None, "revolute", q1, axis=(1, 0, 0), mass=1,
                          com=(0, 0, -1), inertia=[[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.02]]),
              SpatialBody("b", "a", "revolute", q2, axis=(0, 1, 0), at=(0, 0, -1), mass=1,
                          com=(0, 0, -1))]
    sysm = spatial_tree(bodies, {g: 9.81}, gravity=(0, 0, -g))
    from conmech import stability
    down = stability.equilibrium(sysm, [0, 0, 0, 0])
    assert down.kind == "centre"
    assert np.max(np.abs(down.eigenvalues.real)) <= 1e-10 * np.max(np.abs(down.eigenvalues))
    # decoupled at q = 0: the frequencies are closed forms
    # second link about y: (m l^2) th'' = -m g l th ; first about x: the whole (2 masses)
    # pendulum with the second link hanging: (0.1 + 1 + 4) th'' = -(1 + 2) g th
    om = np.sort(np.abs(down.eigenvalues.imag))[::2]
    ref = np.sort([np.sqrt(9.81), np.sqrt(3 * 9.81 / 5.1)])
    assert rel(om, ref) <= 1e-10
    up = stability.equilibrium(sysm, [np.pi, 0, 0, 0])
    assert up.kind == "unstable"


def test_zero_mass_at_run_time_is_a_failure_not_garbage():
    bodies, params, q, g = double_pendulum()
    sysm = spatial_tree(bodies, params, gravity=(0, 0, -g))
    model = symbolic.model_of(sysm)
    p = np.array(model.derived.param_values)
    p[model.derived.param_names.index("m2")] = 0.0
    a = model.call("accel", 0.0, np.array([0.3, 0.2]), np.array([0.0, 0.1]), params=p)
    assert not np.all(np.isfinite(a))
    r = conmech.solve_ivp(sysm.with_params(m2=0.0), (0, 1), [0.3, 0.2, 0, 0.1])
    assert not r.success and "not finite" in r.message


def test_bad_input():
    q1, q2 = dynamicsymbols("q1 q2")
    m, g = sp.symbols("m g")
    ok = SpatialBody("a", None, "revolute", q1, axis=(1, 0, 0), mass=m, com=(0, 0, -1))
    with pytest.raises(ValueError, match="not a unit vector"):
        spatial_tree([SpatialBody("a", None, "revolute", q1, axis=(1, 1, 0), mass=1,
                                  com=(0, 0, -1))], {})
    with pytest.raises(ValueError, match="axis is zero"):
        spatial_tree([SpatialBody("a", None, "revolute", q1, axis=(0, 0, 0), mass=1,
                                  com=(0, 0, -1))], {})
    with pytest.raises(ValueError, match="not symmetric"):
        spatial_tree([SpatialBody("a", None, "revolute", q1, mass=1,
                                  inertia=[[1, 0.1, 0], [0, 1, 0], [0, 0, 1]])], {})
    with pytest.raises(ValueError, match="not positive semi-definite"):
        spatial_tree([SpatialBody("a", None, "revolute", q1, mass=1,
                                  inertia=[[1, 0, 0], [0, -1, 0], [0, 0, 1]])], {})
    with pytest.raises(ValueError, match="triangle inequality"):
        spatial_tree([SpatialBody("a", None, "revolute", q1, mass=1,
                                  inertia=[[1, 0, 0], [0, 1, 0], [0, 0, 3]])], {})
    with pytest.raises(ValueError, match="not a rotation"):
        spatial_tree([SpatialBody("a", None, "revolute", q1, mass=1, com=(1, 0, 0),
                                  rot=[[1, 0, 0], [0, 1, 0], [0, 0, -1]])], {})
    with pytest.raises(ValueError, match="unknown parent"):
        spatial_tree([ok, SpatialBody("b", "nobody", "revolute", q2, mass=m)], {m: 1})
    with pytest.raises(ValueError, match="cycle"):
        spatial_tree([SpatialBody("a", "b", "revolute", q1, mass=m, com=(0, 1, 0)),
                      SpatialBody("b", "a", "revolute", q2, mass=m, com=(0, 1, 0))], {m: 1})
    with pytest.raises(ValueError, match="negative mass"):
        spatial_tree([ok], {m: -1})
    with pytest.raises(ValueError, match="leaf without mass"):
        spatial_tree([ok, SpatialBody("b", "a", "revolute", q2, at=(0, 0, -1))], {m: 1})
    with pytest.raises(ValueError, match="3 components"):
        spatial_tree([SpatialBody("a", None, "revolute", q1, axis=(1, 0), mass=1)], {})
    with pytest.raises(ValueError, match="3x3"):
        spatial_tree([SpatialBody("a", None, "revolute", q1, mass=1, inertia=[[1, 0]])], {})
    with pytest.raises(TypeError, match="rot must be a 3x3"):
        spatial_tree([SpatialBody("a", None, "revolute", q1, mass=1, com=(1, 0, 0), rot=0)],
                     {})
    with pytest.raises(ValueError, match="unknown joint"):
        spatial_tree([SpatialBody("a", None, "ball", q1, mass=1)], {})
    with pytest.raises(TypeError, match="SpatialBody"):
        spatial_tree([Body("a", None, "revolute", q1, mass=1)], {})
    with pytest.raises(ValueError, match="parameters only"):
        spatial_tree([SpatialBody("a", None, "revolute", q1, mass=1, com=(q2, 0, 0))], {})
    with pytest.raises(ValueError, match="'g' has no value|unknown symbol.*'g'"):
        spatial_tree([ok], {m: 1}, gravity=(0, 0, -g))


def test_emitted_module_uses_the_articulated_body_algorithm():
    """The standalone Fortran module of `python -m conmech.symbolic emit` (a model file
    returning derive_spatial_tree(...)): its right-hand side is the spatial ABA, no
    factorisation of M (compiling it is covered for planar trees by the user_tree
    example)."""
    from conmech.symbolic.emit_fortran import emit
    bodies, params, q, g = double_pendulum()
    d = symbolic.spatial.derive_spatial_tree(bodies, params, gravity=(0, 0, -g))
    src = emit(d, "sdp_sym", module="sdp_model")
    rhs = src[src.find("subroutine sdp_sym_rhs"):src.find("end subroutine sdp_sym_rhs")]
    assert rhs and "mass_cholesky" not in rhs
    assert rhs.count("sin(") == 2 and rhs.count("cos(") == 2
