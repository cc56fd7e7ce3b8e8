"""conmech.symbolic.planar_tree: the articulated-body accelerations (conmech_accel) against
M^-1 Q of the same tree's Lagrangian, trajectories against lagrangian_system of the same
T and U, run-time parameters, a stability function, bad input."""

import numpy as np
import pytest

sp = pytest.importorskip("sympy")
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402

import conmech  # noqa: E402
from conmech import compiled, symbolic  # noqa: E402
from conmech.symbolic import Body, planar_tree  # noqa: E402
import symbolic_seeds as seeds  # noqa: E402
import taylor_jets  # noqa: E402

t = dynamicsymbols._t


@pytest.fixture(scope="session", autouse=True)
def symbolic_cache(tmp_path_factory):
    """The test session's one compile cache (symbolic_seeds.use_test_cache)."""
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


rel = seeds.rel


def chain(N, absolute):
    """N point masses on massless rods, pinned at the origin (PyDy's chain: angles from the
    downward vertical; absolute angles, or each relative to the previous link, as the
    caller builds the tree): taylor_jets.tree_chain_bodies, with its symbols."""
    bodies, params, g = taylor_jets.tree_chain_bodies(N)
    return bodies, params, dynamicsymbols(f"th1:{N + 1}"), (
        sp.symbols(f"m1:{N + 1}"), sp.symbols(f"l1:{N + 1}"), g)


def accel_vs_lagrangian(model, n, rng, k=4, t0=0.37):
    worst = 0.0
    for _ in range(k):
        q, v = rng.uniform(-2.5, 2.5, n), rng.uniform(-2, 2, n)
        a = model.call("accel", t0, q, v)
        ref = np.linalg.solve(model.call("mass", t0, q), model.call("forces", t0, q, v))
        worst = max(worst, rel(a, ref))
    return worst


@pytest.mark.parametrize("absolute", [True, False])
@pytest.mark.parametrize("N", [2, 5])
def test_chain_accel_matches_lagrangian(N, absolute):
    bodies, params, th, (m, l, g) = chain(N, absolute)
    model = planar_tree(bodies, params, gravity=(0, -g),
                        coordinates="absolute" if absolute else "relative", model_only=True)
    assert "accel" in model.addresses
    assert accel_vs_lagrangian(model, N, np.random.default_rng(N)) <= 1e-12
    # the accelerations do not factorise a matrix: one sin/cos per joint, O(N) code
    src = model.source[model.source.find("subroutine conmech_accel"):]
    src = src[:src.find("end subroutine")]
    assert src.count("sin(") == N and src.count("cos(") == N


def test_absolute_chain_is_the_textbook_chain():
    """The absolute-angle chain's M and Q agree with lagrangian_system of the notes' T, U."""
    N = 3
    bodies, params, th, (m, l, g) = chain(N, True)
    qd = [x.diff(t) for x in th]
    T = U = 0
    for i in range(N):
        T += sum(m[i:]) * l[i]**2 * qd[i]**2 / 2
        U -= sum(m[i:]) * g * l[i] * sp.cos(th[i])
        for j in range(i + 1, N):
            T += sum(m[j:]) * l[i] * l[j] * sp.cos(th[i] - th[j]) * qd[i] * qd[j]
    ref = symbolic.lagrangian_system(T - U, th, params, model_only=True)
    tree = planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute",
                       model_only=True)
    rng = np.random.default_rng(3)
    for _ in range(3):
        q, v = rng.uniform(-2, 2, N), rng.uniform(-2, 2, N)
        a_ref = np.linalg.solve(ref.call("mass", 0.0, q), ref.call("forces", 0.0, q, v))
        assert rel(tree.call("accel", 0.0, q, v), a_ref) <= 1e-12


def branched():
    """A branched tree of rigid bodies: a torso on a prismatic slide (horizontal, with a
    spring and a damper), two arms (COM offsets, inertias) on it, a forearm on one arm with
    a motor torque that depends on time, a damper on the other arm."""
    x, a1, a2, a3 = dynamicsymbols("x a1 a2 a3")
    m0, m1, m2, m3, I1, I2, I3, k, c, l1, l2, tau0, w = sp.symbols(
        "m0 m1 m2 m3 I1 I2 I3 k c l1 l2 tau0 w")
    g = sp.Symbol("g")
    bodies = [Body("torso", None, "prismatic", x, axis=(1, 0), mass=m0),
              Body("arm1", "torso", "revolute", a1, at=(0.1, 0.2), mass=m1,
                   com=(l1 / 2, -0.05), inertia=I1),
              Body("arm2", "torso", "revolute", a2, at=(-0.1, 0.2), mass=m2,
                   com=(0.03, -l2 / 2), inertia=I2),
              Body("hand", "arm1", "revolute", a3, at=(l1, 0), mass=m3, com=(0.2, 0.1),
                   inertia=I3)]
    params = {m0: 2.0, m1: 1.0, m2: 0.7, m3: 0.4, I1: 0.08, I2: 0.05, I3: 0.02, k: 3.0,
              c: 0.3, l1: 1.0, l2: 0.8, tau0: 0.5, w: 1.7, g: 9.81}
    forces = {"torso": -k * x - c * x.diff(t), "arm2": -c * a2.diff(t),
              a3: tau0 * sp.sin(w * t) - c * (a3.diff(t) - a1.diff(t))}
    return bodies, params, forces, (g,)


@pytest.mark.parametrize("coordinates", ["relative", "absolute"])
def test_branched_tree_with_prismatic_joint_and_forces(coordinates):
    bodies, params, forces, (g,) = branched()
    model = planar_tree(bodies, params, gravity=(0, -g), forces=forces,
                        coordinates=coordinates, model_only=True)
    rng = np.random.default_rng(7)
    for t0 in (0.0, 0.9, 2.3):       # the motor torque depends on t
        assert accel_vs_lagrangian(model, 4, rng, k=2, t0=t0) <= 1e-12


def test_trajectory_matches_lagrangian_system_of_the_same_energies():
    """Several periods of the branched tree and of the absolute chain: the ABA right-hand
    side and the Cholesky right-hand side of lagrangian_system(T - U) give the same
    trajectory to 1e-10."""
    bodies, params, forces, (g,) = branched()
    tree = planar_tree(bodies, params, gravity=(0, -g), forces=forces)
    parts = symbolic.tree.build_tree(bodies, (0, -g), forces)
    ref = symbolic.lagrangian_system(parts["L"], parts["q"], params, forces=parts["forces"])
    y0 = [0.1, 0.5, -0.4, 0.3, 0.0, 0.2, 0.0, -0.1]
    kw = dict(method="DOP853", rtol=1e-13, atol=1e-13)
    r1 = conmech.solve_ivp(tree, (0, 8), y0, **kw)
    r2 = conmech.solve_ivp(ref, (0, 8), y0, **kw)
    assert r1.success and r2.success
    assert rel(r1.y[:, -1], r2.y[:, -1]) <= 1e-10
    bodies, params, th, (m, l, g) = chain(3, True)
    tree = planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute")
    parts = symbolic.tree.build_tree(bodies, (0, -g), coordinates="absolute")
    ref = symbolic.lagrangian_system(parts["L"], parts["q"], params)
    y0 = [0.5, 0.3, 0.1, 0, 0, 0]
    r1 = conmech.solve_ivp(tree, (0, 10), y0, **kw)
    r2 = conmech.solve_ivp(ref, (0, 10), y0, **kw)
    assert r1.success and r2.success
    assert rel(r1.y[:, -1], r2.y[:, -1]) <= 1e-10


def test_with_params_does_not_recompile():
    bodies, params, th, (m, l, g) = chain(2, False)
    sysm = planar_tree(bodies, params, gravity=(0, -g))
    model = symbolic.model_of(sysm)
    heavy = sysm.with_params(m2=3.0, g=1.62)
    assert symbolic.model_of(heavy) is model       # same library, same code
    p = np.array([heavy.parameters[k] for k in model.derived.param_names])
    rng = np.random.default_rng(11)
    q, v = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2)
    a = model.call("accel", 0.0, q, v, params=p)
    ref = np.linalg.solve(model.call("mass", 0.0, q, params=p),
                          model.call("forces", 0.0, q, v, params=p))
    assert rel(a, ref) <= 1e-12
    a0 = model.call("accel", 0.0, q, v)
    assert rel(a, a0) > 1e-3                        # the new values are used
    # and the integration uses them: compiled system with and without accel agree
    y0 = [0.4, -0.2, 0.0, 0.1]
    r1 = conmech.solve_ivp(heavy, (0, 3), y0, rtol=1e-12, atol=1e-12)
    d = model.addresses
    plain = compiled.generalized_system(2, d["mass"], d["forces"], d["forces_jac"],
                                        params=heavy.parameters, keep=model)
    r2 = conmech.solve_ivp(plain, (0, 3), y0, rtol=1e-12, atol=1e-12)
    assert rel(r1.y[:, -1], r2.y[:, -1]) <= 1e-9


def test_equilibria_of_a_tree_double_pendulum():
    """Relative angles, m = l = 1: the hanging equilibrium is a centre with the closed-form
    frequencies omega^2 = (g/l)(2 -+ sqrt 2); the upright one is unstable."""
    th = dynamicsymbols("p1 p2")
    g = sp.Symbol("g")
    bodies = [Body("a", None, "revolute", th[0], mass=1, com=(0, -1)),
              Body("b", "a", "revolute", th[1], at=(0, -1), mass=1, com=(0, -1))]
    sysm = planar_tree(bodies, {g: 9.81}, gravity=(0, -g))
    from conmech import stability
    down = stability.equilibrium(sysm, [0, 0, 0, 0])
    assert down.kind == "centre" and down.analytic
    om = np.sort(np.abs(down.eigenvalues.imag))[::2]
    assert rel(om, np.sqrt(9.81 * np.array([2 - np.sqrt(2), 2 + np.sqrt(2)]))) <= 1e-10
    up = stability.equilibrium(sysm, [np.pi, 0, 0, 0])
    assert up.kind == "unstable"


def test_zero_mass_at_run_time_is_a_failure_not_garbage():
    bodies, params, th, (m, l, g) = chain(2, True)
    sysm = planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute")
    model = symbolic.model_of(sysm)
    p = np.array(model.derived.param_values)
    p[model.derived.param_names.index("m2")] = 0.0
    a = model.call("accel", 0.0, np.array([0.3, 0.2]), np.array([0.0, 0.1]), params=p)
    assert not np.all(np.isfinite(a))
    r = conmech.solve_ivp(sysm.with_params(m2=0.0), (0, 1), [0.3, 0.2, 0, 0.1])
    assert not r.success and "not finite" in r.message


def test_bad_input():
    th1, th2 = dynamicsymbols("th1 th2")
    m, g, k = sp.symbols("m g k")
    ok = Body("a", None, "revolute", th1, mass=m, com=(0, -1))
    with pytest.raises(ValueError, match="unknown parent"):
        planar_tree([ok, Body("b", "nobody", "revolute", th2, mass=m)], {m: 1})
    with pytest.raises(ValueError, match="cycle"):
        planar_tree([Body("a", "b", "revolute", th1, mass=m, com=(0, 1)),
                     Body("b", "a", "revolute", th2, mass=m, com=(0, 1))], {m: 1})
    with pytest.raises(ValueError, match="leaf"):
        planar_tree([ok, Body("b", "a", "revolute", th2, at=(0, -1), mass=0)], {m: 1})
    with pytest.raises(ValueError, match="unknown symbol.*'k'"):
        planar_tree([ok], {m: 1, g: 9.81}, gravity=(0, -g), forces=[-k * th1])
    with pytest.raises(ValueError, match="'g' has no value|unknown symbol.*'g'"):
        planar_tree([ok], {m: 1}, gravity=(0, -g))
    with pytest.raises(ValueError, match="unknown joint"):
        planar_tree([Body("a", None, "ball", th1, mass=1)], {})
    with pytest.raises(TypeError, match="dynamicsymbol"):
        planar_tree([Body("a", None, "revolute", sp.Symbol("x"), mass=1, com=(1, 0))], {})
    with pytest.raises(ValueError, match="given twice"):
        planar_tree([ok, ok], {m: 1})
    with pytest.raises(ValueError, match="coordinates must be"):
        planar_tree([ok], {m: 1}, coordinates="polar")
    with pytest.raises(ValueError, match="forces has 2 components"):
        planar_tree([ok], {m: 1}, forces=[0, 0])
    with pytest.raises(ValueError, match="parameters only"):
        planar_tree([Body("a", None, "revolute", th1, mass=1, com=(th2, 0))], {})
    with pytest.raises(TypeError, match="Body"):
        planar_tree([("a", None)], {})


# ------------------------------------------------------------------ standalone Fortran
def test_emitted_tree_module_is_committed_and_agrees_with_the_compiled_system():
    """`python -m conmech.symbolic emit` of a tree: the committed module is regenerated
    identically, its right-hand side is the articulated-body algorithm (no Cholesky), and
    the fpm example that runs it agrees with planar_tree from Python and with the Cholesky
    path of the same module's M and Q."""
    import importlib.util
    import re
    import shutil
    import subprocess
    from pathlib import Path
    from conmech.symbolic.__main__ import emit_file
    root = Path(__file__).resolve().parents[2]
    out = root / "example" / "tree_chain_model.f90"
    src, name, module = emit_file(root / "example" / "models" / "tree_chain.py", out)
    assert (name, module) == ("tree_chain_sym", "tree_chain_model")
    assert src == out.read_text(), f"{out} is stale: re-run the emit command in its header"
    rhs = src[src.find("subroutine tree_chain_sym_rhs"):
              src.find("end subroutine tree_chain_sym_rhs")]
    assert "mass_cholesky" not in rhs and rhs.count("sin(") == 3
    if shutil.which("fpm") is None:
        pytest.fail("fpm is not on PATH: run the tests through scripts/test.sh")
    r = subprocess.run(["fpm", "run", "--example", "user_tree"], cwd=root,
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stdout + r.stderr

    def value(label, k=1):
        m = re.search(re.escape(label) + r"\s*((?:[-+0-9.E]+\s*){%d})" % k, r.stdout)
        assert m, (label, r.stdout)
        return [float(s) for s in m.group(1).split()]
    y_fortran = np.array(value("y(5):", 6))
    assert value("energy drift:")[0] < 1e-10
    assert value("articulated-body vs Cholesky:")[0] < 1e-10
    spec = importlib.util.spec_from_file_location("_tree_chain_model",
                                                  root / "example" / "models" / "tree_chain.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    bodies, params, gravity, coordinates = mod.inputs()
    sysm = planar_tree(bodies, params, gravity=gravity, coordinates=coordinates)
    rc = conmech.solve_ivp(sysm, (0, 5), [0.9, 0.6, 0.3, 0.0, 0.5, -0.4], method="DOP853",
                           rtol=1e-12, atol=1e-12)
    assert rc.success
    assert np.max(np.abs(y_fortran - rc.y[:, -1])) < 1e-10


def test_model_library_of_a_tree_exports_accel(tmp_path):
    """save_model writes conmech_accel into the model library; load_model uses it (spec
    slot 17) and integrates like the system it was saved from."""
    bodies, params, th, (m, l, g) = chain(3, True)
    sysm = planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute")
    path = symbolic.save_model(sysm.with_params(g=3.7), tmp_path / "libtree.so")
    lib = compiled.load_model(path)
    assert lib.spec[16] != 0 and lib.parameters["g"] == 3.7
    y0 = [0.5, 0.3, 0.1, 0.0, 0.2, 0.0]
    r1 = conmech.solve_ivp(lib, (0, 4), y0, method="DOP853", rtol=1e-12, atol=1e-12)
    r2 = conmech.solve_ivp(sysm.with_params(g=3.7), (0, 4), y0, method="DOP853",
                           rtol=1e-12, atol=1e-12)
    assert r1.success and r2.success
    assert rel(r1.y[:, -1], r2.y[:, -1]) <= 1e-13
