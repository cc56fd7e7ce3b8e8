"""conmech.symbolic: the structured forces and Jacobian (sparse dM/dq, collected
coefficients) and the sines and cosines of sums by angle addition agree with the expanded
Euler-Lagrange derivation (two independent derivations of the same system), and the code of
a chain needs 2n trigonometric calls, not n^2."""
import re

import numpy as np
import pytest

sp = pytest.importorskip("sympy")
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402

from conmech import symbolic  # noqa: E402
import symbolic_seeds as seeds  # noqa: E402
from conmech.symbolic.codegen import trig_split  # noqa: E402
from conmech.symbolic.derive import derive_lagrangian  # noqa: E402

t = dynamicsymbols._t


@pytest.fixture(scope="module", autouse=True)
def symbolic_cache(tmp_path_factory):
    """The test session's one compile cache (symbolic_seeds.use_test_cache)."""
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


def shaken_chain(n):
    """n links, support shaken horizontally (explicit t, terms linear in the velocities),
    a spring on the first angle, viscous damping (generalized forces)."""
    q = dynamicsymbols(f"th1:{n + 1}")
    m = sp.symbols(f"m1:{n + 1}")
    ln = sp.symbols(f"l1:{n + 1}")
    g, A, w, k, c = sp.symbols("g A w k c")
    x, y = A*sp.sin(w*t), sp.Integer(0)
    T = U = 0
    for i in range(n):
        x, y = x + ln[i]*sp.sin(q[i]), y - ln[i]*sp.cos(q[i])
        T += m[i]*(x.diff(t)**2 + y.diff(t)**2)/2
        U += m[i]*g*y
    U += k*q[0]**2/2
    params = {**{s: 1.0 + 0.1*i for i, s in enumerate(m)},
              **{s: 0.8 + 0.05*i for i, s in enumerate(ln)},
              g: 9.81, A: 0.3, w: 2.5, k: 0.7, c: 0.05}
    forces = [-c*qi.diff(t) for qi in q]
    return T - U, q, params, forces


def test_structured_forces_and_jacobian_equal_the_expanded_derivation():
    n = 3
    L, q, params, forces = shaken_chain(n)
    d = derive_lagrangian(L, q, params, forces)
    assert d.struct is not None
    mod = symbolic.compile_model(d)
    # the expanded Q and R (Euler-Lagrange written out, computed when read)
    args = [d.t] + list(d.coords) + list(d.speeds) + list(d.accels) + list(d.params)
    fQ = sp.lambdify(args, d.Q, modules="numpy")
    fR = sp.lambdify(args, d.R, modules="numpy")
    fM = sp.lambdify(args, d.M, modules="numpy")
    rng = np.random.default_rng(7)
    p = np.array(d.param_values)
    for _ in range(10):
        tt = rng.uniform(0, 3)
        qq, vv, aa = rng.uniform(-2, 2, n), rng.normal(size=n), rng.normal(size=n)
        vals = [tt, *qq, *vv, *aa, *p]
        Q = np.ravel(fQ(*vals))
        R = np.array(fR(*vals), float)
        Mx = np.array(fM(*vals), float)
        assert np.max(np.abs(mod.call("mass", tt, qq) - Mx)) < 1e-14*np.max(np.abs(Mx))
        assert np.max(np.abs(mod.call("forces", tt, qq, vv) - Q)) < 1e-13*np.max(np.abs(Q))
        Rc = mod.call("forces_jac", tt, qq, vv, aa)
        assert np.max(np.abs(Rc - R)) < 1e-13*np.max(np.abs(R))
    # the expanded form compiled on its own gives the same functions
    d2 = derive_lagrangian(L, q, params, forces, structured=False)
    assert d2.struct is None
    mod2 = symbolic.compile_model(d2)
    qq, vv, aa = rng.uniform(-2, 2, n), rng.normal(size=n), rng.normal(size=n)
    for entry, a in (("forces", (qq, vv)), ("forces_jac", (qq, vv, aa))):
        x, y = mod.call(entry, 0.4, *a), mod2.call(entry, 0.4, *a)
        assert np.max(np.abs(x - y)) < 1e-13*np.max(np.abs(y))


def chain_textbook(n):
    q = dynamicsymbols(f"th1:{n + 1}")
    qd = [qi.diff(t) for qi in q]
    g = sp.Symbol("g")
    T = U = 0
    for i in range(n):
        T += (n - i)*qd[i]**2/2
        U -= (n - i)*g*sp.cos(q[i])
        for j in range(i + 1, n):
            T += (n - j)*sp.cos(q[i] - q[j])*qd[i]*qd[j]
    return T - U, q, {g: 9.81}


def test_chain_code_needs_2n_trigonometric_calls():
    n = 6
    L, q, params = chain_textbook(n)
    mod = symbolic.lagrangian_system(L, q, params, model_only=True)
    src = mod.source
    for name in ("conmech_mass", "conmech_forces", "conmech_forces_jac"):
        body = src[src.index(f"subroutine {name}("):src.index(f"end subroutine {name}")]
        calls = re.findall(r"\b(sin|cos)\(", body)
        assert len(calls) <= 2*n, (name, len(calls))     # n(n - 1)/2 cos(th_i - th_j) before
    # forces: O(n^2) work: each dM entry enters once per force component it touches
    st = mod.derived.struct
    assert len(st["dM"]) == n*(n - 1)
    assert sum(len(terms) for terms in st["quad"]) == n*(n - 1)
    # energy conserved along a motion (checks M and Q together)
    import conmech
    y0 = np.concatenate([np.linspace(0.9, 0.3, n), np.zeros(n)])
    sysm = symbolic.pipeline._system(mod)
    r = conmech.solve_ivp(sysm, (0, 3), y0, rtol=1e-12, atol=1e-12)
    assert r.success
    e = [mod.call("energy", 0.0, r.y[:n, k], r.y[n:, k]) for k in (0, -1)]
    assert abs(e[1] - e[0]) < 1e-9*abs(e[0])


def test_trig_split_values_and_no_gain_case():
    a, b, c = sp.symbols("a b c", real=True)
    exprs = [sp.sin(a - b) + sp.cos(a + b + c), sp.cos(b - c)*sp.sin(a), sp.sin(c)]
    new, defs = trig_split(exprs)
    assert defs and len(defs) > 0
    # evaluate definitions in order, then the rewritten expressions
    vals = {a: 0.7, b: -1.3, c: 2.9}
    env = dict(vals)
    for s_, e in defs:
        env[s_] = float(e.xreplace(env).evalf())
    for e_old, e_new in zip(exprs, new):
        assert abs(float(e_new.xreplace(env)) - float(e_old.xreplace(vals))) < 1e-15
    # one sum of two terms that appear nowhere else: no gain, unchanged
    same, none = trig_split([sp.cos(a - b)])
    assert none == [] and same == [sp.cos(a - b)]


def test_time_dependent_mass_and_gyroscopic_terms_match_the_expanded_form():
    """M depends on t and q, terms linear in the velocities depend on t and q (a particle in
    a frame turning at a varying rate, with a pulsating mass and a pendulum on it)."""
    x, y, th = dynamicsymbols("x y th")
    m, w, e, g, ln = sp.symbols("m w e g l")
    mt = m*(1 + e*sp.sin(t))
    om = w*(1 + e*sp.cos(2*t))
    vx, vy = x.diff(t) - om*y, y.diff(t) + om*x
    px, py = x + ln*sp.sin(th), y - ln*sp.cos(th)
    T = mt*(vx**2 + vy**2)/2 + m*(px.diff(t)**2 + py.diff(t)**2)/2
    U = m*g*py + (x**2 + y**2)/2
    params = {m: 1.3, w: 0.7, e: 0.2, g: 9.81, ln: 0.8}
    d = derive_lagrangian(T - U, [x, y, th], params)
    assert d.struct is not None and d.struct["QL"][0].has(d.t)
    mod = symbolic.compile_model(d)
    args = [d.t] + list(d.coords) + list(d.speeds) + list(d.accels) + list(d.params)
    fQ = sp.lambdify(args, d.Q, modules="numpy")
    fR = sp.lambdify(args, d.R, modules="numpy")
    rng = np.random.default_rng(3)
    p = np.array(d.param_values)
    for _ in range(10):
        tt = rng.uniform(0, 3)
        qq, vv, aa = rng.uniform(-2, 2, 3), rng.normal(size=3), rng.normal(size=3)
        vals = [tt, *qq, *vv, *aa, *p]
        Q = np.ravel(fQ(*vals))
        R = np.array(fR(*vals), float)
        assert np.max(np.abs(mod.call("forces", tt, qq, vv) - Q)) < 1e-13*np.max(np.abs(Q))
        Rc = mod.call("forces_jac", tt, qq, vv, aa)
        assert np.max(np.abs(Rc - R)) < 1e-13*np.max(np.abs(R))


def test_derivation_cache_hit_reads_the_expressions_only_when_used():
    L, q, params = chain_textbook(5)
    first = symbolic.lagrangian_system(L, q, params, model_only=True)
    again = symbolic.lagrangian_system(L, q, params, model_only=True)
    assert again.times["derive"] == 0.0 and "derived_cache" in again.times
    d = again.derived
    assert "_heavy" in d.__dict__ and "M" not in d.__dict__     # not unpickled yet
    qq, vv = np.linspace(0.1, 0.9, 5), np.linspace(-1, 1, 5)
    np.testing.assert_array_equal(again.call("forces", 0.0, qq, vv),
                                  first.call("forces", 0.0, qq, vv))
    assert d.M == first.derived.M and len(d.struct["dM"]) == 20     # read back on use
    assert "_heavy" not in d.__dict__


def test_mass_forces_in_one_call_equals_the_separate_calls():
    """conmech_mass_forces (one common-subexpression elimination over M and Q, used by the
    right-hand side) gives the same M and Q as conmech_mass and conmech_forces, has no more
    trigonometric calls than either alone, and the integration with it equals the one
    through the separate calls (the old path, mass_forces absent) to round-off."""
    import conmech
    from conmech import compiled
    n = 4
    L, q, params, forces = shaken_chain(n)
    mod = symbolic.lagrangian_system(L, q, params, forces, model_only=True)
    assert "mass_forces" in mod.addresses
    src = mod.source
    body = src[src.index("subroutine conmech_mass_forces("):
               src.index("end subroutine conmech_mass_forces")]
    assert len(re.findall(r"\b(sin|cos)\(", body)) <= 2*n + 2   # + sin, cos of w t
    rng = np.random.default_rng(3)
    for _ in range(10):
        tt, qq, vv = rng.uniform(0, 3), rng.uniform(-2, 2, n), rng.normal(size=n)
        Mb, Qb = mod.call("mass_forces", tt, qq, vv)
        Ms, Qs = mod.call("mass", tt, qq), mod.call("forces", tt, qq, vv)
        assert np.max(np.abs(Mb - Ms)) <= 1e-15*np.max(np.abs(Ms))
        assert np.max(np.abs(Qb - Qs)) <= 1e-14*np.max(np.abs(Qs))
    y0 = np.concatenate([np.linspace(0.9, 0.3, n), np.zeros(n)])
    both = symbolic.pipeline._system(mod)
    d, a = mod.derived, mod.addresses
    sep = compiled.generalized_system(n, a["mass"], a["forces"], params=tuple(d.param_values),
                                      param_names=tuple(d.param_names), keep=mod)
    kw = dict(method="DOP853", rtol=1e-10, atol=1e-10)
    r1 = conmech.solve_ivp(both, (0, 2), y0, **kw)
    r2 = conmech.solve_ivp(sep, (0, 2), y0, **kw)
    assert r1.success and r2.success and r1.nfev == r2.nfev
    assert np.max(np.abs(r1.y[:, -1] - r2.y[:, -1])) < 1e-12
    # a NULL mass_forces address is the old path; a bad one is refused like the others
    with pytest.raises((TypeError, ValueError)):
        compiled.generalized_system(n, a["mass"], a["forces"], mass_forces="x",
                                    params=tuple(d.param_values),
                                    param_names=tuple(d.param_names))
