"""Trees by the recursive algorithms (conmech.symbolic.recursive, the default of planar_tree
and spatial_tree) against the Lagrangian route (method="lagrangian": T and U expanded) on
the trees of the tree tests: mass matrix, forces, energy, accelerations, the Jacobian of
the forces and of the accelerations (no LAPACK: L^T D L with the tree's sparsity), to
1e-12; the pieces and loop forms of large trees against the straight-line form; what is
generated (entry points, one sine and cosine per joint, O(n) passes); a deterministic
source."""

import os
import subprocess
import sys

import numpy as np
import pytest

sp = pytest.importorskip("sympy")
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402

from conmech import compiled, solve_ivp, symbolic  # noqa: E402
from conmech.symbolic import Body, SpatialBody  # noqa: E402
import symbolic_seeds as seeds  # noqa: E402

t = dynamicsymbols._t


@pytest.fixture(scope="session", autouse=True)
def symbolic_cache(tmp_path_factory):
    """The test session's one compile cache (symbolic_seeds.use_test_cache)."""
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


rel = seeds.rel


def agree(m1, m2, n, rng, k=3, times=(0.0, 0.7)):
    """max relative difference of every entry point the two models share."""
    worst = 0.0
    for _ in range(k):
        q, v, a = rng.uniform(-2, 2, n), rng.uniform(-2, 2, n), rng.uniform(-2, 2, n)
        for t0 in times:
            for entry, args in (("mass", (q,)), ("forces", (q, v)), ("accel", (q, v)),
                                ("forces_jac", (q, v, a))):
                worst = max(worst, rel(m1.call(entry, t0, *args), m2.call(entry, t0, *args)))
            e1, e2 = m1.call("energy", t0, q, v), m2.call("energy", t0, q, v)
            worst = max(worst, abs(e1 - e2)/max(abs(e2), 1.0))
            acc, J = m1.call("accel_jac", t0, q, v)
            M = m2.call("mass", t0, q)
            ref_a = np.linalg.solve(M, m2.call("forces", t0, q, v))
            R = m2.call("forces_jac", t0, q, v, ref_a)
            worst = max(worst, rel(acc, ref_a), rel(J, np.linalg.solve(M, R)))
    return worst


def planar_branched():
    x, a1, a2, a3 = dynamicsymbols("x a1 a2 a3")
    m0, m1, m2, m3, I1, I2, l1, k, c, g = sp.symbols("m0 m1 m2 m3 I1 I2 l1 k c g")
    params = {m0: 2.0, m1: 1.0, m2: 0.7, m3: 0.4, I1: 0.08, I2: 0.05, l1: 1.0, k: 20.0,
              c: 0.3, g: 9.81}
    bodies = [Body("torso", None, "prismatic", x, axis=(0.6, 0.8), mass=m0),
              Body("arm1", "torso", "revolute", a1, at=(0.1, 0.2), mass=m1,
                   com=(l1/2, -0.05), inertia=I1),
              Body("arm2", "torso", "revolute", a2, at=(-0.1, 0.2), mass=m2,
                   com=(0.03, -0.4), inertia=I2),
              Body("hand", "arm1", "revolute", a3, at=(l1, 0), mass=m3, com=(0.2, 0.1))]
    forces = {"torso": -k*x - c*x.diff(t), a2: -c*a2.diff(t)*sp.cos(a1),
              a3: sp.sin(2*t) - c*(a3.diff(t) - a1.diff(t))}
    return bodies, params, forces, g


@pytest.mark.parametrize("coordinates", ["relative", "absolute"])
def test_planar_trees_agree_with_the_lagrangian_route(coordinates):
    """A chain of 4 rods and a branched tree with a prismatic root, springs, dampers
    depending on other coordinates and a time-dependent torque."""
    th = dynamicsymbols("th1:5")
    m, l, g, c = sp.symbols("m l g c")
    chain = [Body(f"r{i}", None if i == 0 else f"r{i - 1}", "revolute", th[i],
                  at=(0, 0) if i == 0 else (l, 0), mass=m*(1 + i/5), com=(l/2, 0.05*i),
                  inertia=m*l**2/12) for i in range(4)]
    cases = [(chain, {m: 1.0, l: 0.8, g: 9.81, c: 0.2}, {th[0]: -c*th[0].diff(t)}, g, 4),
             (*planar_branched(), 4)]
    for bodies, params, forces, g_, n in cases:
        kw = dict(gravity=(0, -g_), forces=forces, coordinates=coordinates, model_only=True)
        mr = symbolic.planar_tree(bodies, params, **kw)
        ml = symbolic.planar_tree(bodies, params, method="lagrangian", **kw)
        assert mr.source != ml.source
        assert agree(mr, ml, n, np.random.default_rng(n)) <= 1e-12


def spatial_arm(n):
    """A robot arm: axes z, y, x, y, x, z (a prismatic third joint), offsets, COM offsets,
    full inertia tensors with products of inertia, dampers."""
    qs = dynamicsymbols(f"j1:{n + 1}")
    g = sp.Symbol("g")
    rng = np.random.default_rng(5)
    axes = [(0, 0, 1), (0, 1, 0), (0, 0, 1), (1, 0, 0), (0, 1, 0), (1, 0, 0)]
    bodies = []
    for i in range(n):
        R, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        a_, b_, c_ = rng.uniform(0.05, 0.3, 3)
        I = R @ np.diag([b_*b_ + c_*c_, a_*a_ + c_*c_, a_*a_ + b_*b_]) @ R.T/12
        I = np.round((I + I.T)/2, 5)
        bodies.append(SpatialBody(
            f"link{i}", None if i == 0 else f"link{i - 1}",
            "prismatic" if i == 2 else "revolute", qs[i], axis=axes[i % 6],
            at=(0, 0, 0) if i == 0 else (0, sp.Rational(1, 10), sp.Rational(3, 10)),
            mass=sp.Rational(12 - i, 10),
            com=tuple(sp.Rational(str(round(x, 3))) for x in rng.normal(size=3)*0.1),
            inertia=[[sp.Rational(str(x)) for x in row] for row in I]))
    forces = {q: -sp.Rational(1, 10)*q.diff(t) for q in qs}
    return bodies, {g: 9.81}, forces, g


def spatial_branched():
    z, a1, a2, a3 = dynamicsymbols("z a1 a2 a3")
    m0, k, c, w, g = sp.symbols("m0 k c w g")
    ct, st = sp.Rational(3, 5), sp.Rational(4, 5)
    I3 = [[0.02, 0.001, 0], [0.001, 0.03, 0.002], [0, 0.002, 0.025]]
    bodies = [SpatialBody("torso", None, "prismatic", z, axis=(0, 0, 1), mass=m0,
                          inertia=I3),
              SpatialBody("arm1", "torso", "revolute", a1, axis=(0, 1, 0), at=(0.2, 0, 0.4),
                          mass=1.0, com=(0.3, 0, -0.05), inertia=I3),
              SpatialBody("arm2", "torso", "revolute", a2, axis=(1, 0, 0), at=(-0.2, 0, 0.4),
                          mass=0.7, com=(0, 0.05, -0.3), inertia=I3),
              SpatialBody("hand", "arm1", "revolute", a3, axis=(0, ct, st), at=(0.6, 0, 0),
                          rot=[[1, 0, 0], [0, ct, -st], [0, st, ct]], mass=0.4,
                          com=(0.1, 0.05, 0.02), inertia=I3)]
    params = {m0: 2.0, k: 30.0, c: 0.3, w: 1.7, g: 9.81}
    forces = {"torso": -k*z - c*z.diff(t), a3: sp.sin(w*t)*sp.cos(a2) - c*a3.diff(t)}
    return bodies, params, forces, g


def test_spatial_trees_agree_with_the_lagrangian_route():
    """A 4-joint arm (tilted inertia tensors, a prismatic joint, dampers) and a branched
    tree (a fixed joint rotation, a tilted axis, a spring, a torque in t and in another
    coordinate)."""
    for bodies, params, forces, g in (spatial_arm(4), spatial_branched()):
        kw = dict(gravity=(0, 0, -g), forces=forces, model_only=True)
        mr = symbolic.spatial_tree(bodies, params, **kw)
        ml = symbolic.spatial_tree(bodies, params, method="lagrangian", **kw)
        assert agree(mr, ml, len(bodies), np.random.default_rng(len(bodies))) <= 1e-12


def test_coordinates_in_any_order():
    """Bodies listed leaves first (the coordinates in an order that is not the tree's):
    the same system as the Lagrangian route, in the planar absolute and spatial cases."""
    bodies, params, forces, g = spatial_branched()
    kw = dict(gravity=(0, 0, -g), forces=forces, model_only=True)
    mr = symbolic.spatial_tree(bodies[::-1], params, **kw)
    ml = symbolic.spatial_tree(bodies[::-1], params, method="lagrangian", **kw)
    assert agree(mr, ml, 4, np.random.default_rng(8), k=2) <= 1e-12
    pb, pp, pf, pg = planar_branched()
    order = [pb[2], pb[3], pb[0], pb[1]]
    kw = dict(gravity=(0, -pg), forces=pf, coordinates="absolute", model_only=True)
    mr = symbolic.planar_tree(order, pp, **kw)
    ml = symbolic.planar_tree(order, pp, method="lagrangian", **kw)
    assert agree(mr, ml, 4, np.random.default_rng(9), k=2) <= 1e-12


def test_the_jacobian_of_the_compiled_system_uses_accel_jac():
    """The first-order system's Jacobian comes from accel_jac (d a/d[q, v] directly, no
    factorisation of M): equal to it bit for bit, and to the Lagrangian route's M^-1 R."""
    bodies, params, forces, g = spatial_branched()
    sysr = symbolic.spatial_tree(bodies, params, gravity=(0, 0, -g), forces=forces)
    sysl = symbolic.spatial_tree(bodies, params, gravity=(0, 0, -g), forces=forces,
                                 method="lagrangian")
    model = symbolic.model_of(sysr)
    y = np.random.default_rng(1).uniform(-1, 1, 8)
    ev = compiled.evaluate(sysr, 0.4, y)
    a, J = model.call("accel_jac", 0.4, y[:4], y[4:])
    assert ev["analytic"]
    assert np.array_equal(ev["jac"][4:], J) and np.array_equal(ev["f"][4:], a)
    assert rel(ev["jac"], compiled.evaluate(sysl, 0.4, y)["jac"]) <= 1e-12


def test_large_tree_forms_agree(monkeypatch):
    """The pair loops (trees above STRAIGHT_MAX bodies) and the passes split into pieces
    (with the crossing values in an array) give the straight-line results."""
    from conmech.symbolic import tree_fortran
    from conmech.symbolic.recursive import derive_recursive
    for bodies, params, forces, g in (spatial_arm(5), spatial_branched()):
        parts = symbolic.spatial.build_spatial_tree(bodies, (0, 0, -g), forces, lazy=True)
        d = derive_recursive(parts, params, planar=False)
        with monkeypatch.context() as mp:
            mp.setattr(tree_fortran, "CHUNK", 10**6)
            m0 = symbolic.compile_model(d)
        with monkeypatch.context() as mp:
            mp.setattr(tree_fortran, "STRAIGHT_MAX", 2)
            mp.setattr(tree_fortran, "CHUNK_LARGE", 40)
            m1 = symbolic.compile_model(d)
        assert "subroutine tree_vel_3(" in m1.source and "do while (j > 0)" in m1.source
        assert "subroutine tree_vel_3(" not in m0.source
        assert agree(m1, m0, len(bodies), np.random.default_rng(3), k=2) <= 1e-13


def passes(src):
    """Statements of the straight-line passes (position, velocity, accelerations)."""
    count, inside = 0, False
    for line in src.splitlines():
        s = line.strip()
        if s.startswith("subroutine tree_pos") or s.startswith("subroutine tree_vel") \
                or s.startswith("subroutine tree_aba"):
            inside = True
        elif s.startswith("end subroutine"):
            inside = False
        elif inside and " = " in s and not s.startswith("real("):
            count += 1
    return count


def test_what_is_generated():
    """Entry points by need (no Jacobian entries with jacobian=False, no accelerations or
    Jacobian for a constrained loop system), one sine and cosine per revolute joint in
    the accelerations, straight-line passes linear in the number of bodies."""
    def chain(n, **kw):
        th = dynamicsymbols(f"c1:{n + 1}")
        bodies = [SpatialBody(f"b{i}", None if i == 0 else f"b{i - 1}", "revolute", th[i],
                              axis=(0, 1, 0) if i % 2 else (1, 0, 0), at=(0, 0, -0.5),
                              mass=1, com=(0, 0, -0.5),
                              inertia=[[0.02, 0, 0], [0, 0.02, 0], [0, 0, 0.001]])
                  for i in range(n)]
        return symbolic.spatial_tree(bodies, {}, gravity=(0, 0, -9.81), model_only=True, **kw)
    m4, m8, m12 = chain(4), chain(8), chain(12)
    assert set(m4.addresses) == {"mass", "forces", "mass_forces", "accel", "forces_jac",
                                 "accel_jac", "energy"}
    d1 = passes(m8.source) - passes(m4.source)
    d2 = passes(m12.source) - passes(m8.source)
    assert abs(d2 - d1) <= 0.05*d1           # four more bodies cost the same: O(n)
    acc = m8.source[m8.source.find("subroutine conmech_accel("):]
    acc = acc[:acc.find("end subroutine")]
    assert acc.count("sin(") == 8 and acc.count("cos(") == 8
    aba = m8.source[m8.source.find("subroutine tree_aba("):]
    assert "sin(" not in aba[:aba.find("end subroutine")]
    mj = chain(4, jacobian=False)
    assert set(mj.addresses) == {"mass", "forces", "mass_forces", "accel", "energy"}
    assert "tree_did" not in mj.source and "if (deriv)" not in mj.source
    assert "lapack" not in m8.source.lower() and "dpotrf" not in m8.source


def test_source_is_deterministic(tmp_path):
    """Two processes generate the same module (the compile cache is keyed by it)."""
    code = ("import hashlib, sympy as sp\n"
            "from conmech.symbolic.recursive import derive_recursive\n"
            "from conmech.symbolic.tree_fortran import generate_tree\n"
            "from conmech import symbolic\n"
            "import test_symbolic_recursive as T\n"
            "b, p, f, g = T.spatial_branched()\n"
            "parts = symbolic.spatial.build_spatial_tree(b, (0, 0, -g), f, lazy=True)\n"
            "d = derive_recursive(parts, p, planar=False)\n"
            "print(hashlib.sha256(generate_tree(d)[0].encode()).hexdigest())\n")
    env = dict(os.environ, PYTHONPATH=os.path.dirname(__file__), PYTHONHASHSEED="random")
    out = [subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, check=True).stdout for _ in range(2)]
    assert out[0] == out[1] and len(out[0].strip()) == 64


def test_cache_hit_skips_derivation_and_compilation():
    bodies, params, forces, g = spatial_branched()
    kw = dict(gravity=(0, 0, -g), forces=forces, model_only=True)
    symbolic.spatial_tree(bodies, params, **kw)
    again = symbolic.spatial_tree(bodies, params, **kw)
    assert again.cache_hit and again.times["derive"] == 0.0 and "derived_cache" in again.times


def test_radau_runs_on_the_exact_jacobian():
    """Radau IIA on a recursive tree (its Jacobian from accel_jac) follows DOP853."""
    from conmech import solve_ivp
    bodies, params, forces, g = spatial_branched()
    sysm = symbolic.spatial_tree(bodies, params, gravity=(0, 0, -g), forces=forces)
    y0 = [0.1, 0.5, -0.4, 0.3, 0.0, 0.2, 0.0, -0.1]
    r1 = solve_ivp(sysm, (0, 2), y0, method="Radau", rtol=1e-10, atol=1e-10)
    r2 = solve_ivp(sysm, (0, 2), y0, method="DOP853", rtol=1e-12, atol=1e-12)
    assert r1.success and r2.success and r1.njev > 0
    assert np.max(np.abs(r1.y[:, -1] - r2.y[:, -1])) <= 1e-7


def test_lagrangian_of_a_recursive_tree():
    """The Lagrangian a recursive tree rebuilds on request (for momenta and cyclic
    coordinates) equals the Lagrangian route's at a sample state; the joint about the
    vertical is cyclic and its momentum is conserved along a computed motion."""
    q1, q2 = dynamicsymbols("q1 q2")
    m, l, g = sp.symbols("m l g")
    bodies = [SpatialBody("a", None, "revolute", q1, axis=(0, 0, 1), mass=m, com=(l, 0, 0),
                          inertia=[[0.1, 0, 0], [0, 0.2, 0], [0, 0, 0.3]]),
              SpatialBody("b", "a", "revolute", q2, axis=(0, 1, 0), at=(l, 0, 0), mass=m,
                          com=(0, 0, -l))]
    vals = {"q1": 0.3, "q2": 0.7, "q1_d": 1.1, "q2_d": -0.4, "m": 1.3, "l": 0.9, "g": 9.81}
    out, systems = [], []
    for method in ("recursive", "lagrangian"):
        s = symbolic.spatial_tree(bodies, {m: 1, l: 1, g: 9.81}, gravity=(0, 0, -g),
                                  method=method)
        L = symbolic.model_of(s).derived.lagrangian
        out.append(float(L.subs({x: vals[x.name.lstrip("_")] for x in L.free_symbols})))
        assert s.cyclic_coordinates == (0,)
        systems.append(s)
    assert abs(out[0] - out[1]) <= 1e-12*abs(out[1])
    tree = systems[0]
    r = solve_ivp(tree, (0, 5), [0.0, 0.5, 1.0, 0.0], rtol=1e-12, atol=1e-12)
    assert tree.first_integrals.check(r)["p_q1"] <= 1e-10
