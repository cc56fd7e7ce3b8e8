"""conmech.symbolic: derivation, generated Fortran (evaluated through ctypes against sympy's
own values), the compile cache (hits, two processes at once, failures), bad input."""
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

sp = pytest.importorskip("sympy")
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402

from conmech import symbolic  # noqa: E402
from conmech.symbolic import build  # noqa: E402
import symbolic_seeds as seeds  # noqa: E402

t = dynamicsymbols._t


@pytest.fixture(scope="session", autouse=True)
def symbolic_cache(tmp_path_factory):
    """The test session's one compile cache (symbolic_seeds.use_test_cache)."""
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


arenstorf_formulas = seeds.arenstorf_ode


def cart_lagrangian():
    x, th = dynamicsymbols("x theta")
    M, m, l, g = sp.symbols("M m l g", positive=True)
    T = sp.Rational(1, 2)*(M + m)*x.diff(t)**2 + m*l*sp.cos(th)*x.diff(t)*th.diff(t) \
        + sp.Rational(1, 2)*m*l**2*th.diff(t)**2
    U = m*g*l*sp.cos(th)
    return T, U, [x, th], dict(M=1.3, m=0.7, l=0.9, g=9.81)


rel = seeds.rel


# ------------------------------------------------------------------ generated code values

def test_ode_rhs_and_jacobian_match_sympy():
    f, y, mu = arenstorf_formulas()
    mod = symbolic.ode_system(f, y, params={mu: 0.012277471}, model_only=True)
    F = sp.lambdify(y, sp.Matrix(f).subs(mu, 0.012277471))
    J = sp.lambdify(y, sp.Matrix(f).subs(mu, 0.012277471).jacobian(y))
    rng = np.random.default_rng(1)
    for _ in range(20):
        s = rng.uniform(-1.5, 1.5, 4)
        assert rel(mod.call("rhs", 0.0, s), np.ravel(F(*s))) < 1e-14
        assert rel(mod.call("jac", 0.0, s), np.array(J(*s), float)) < 1e-14
    # the generated code has one sqrt per distance and no real-valued power (the Taylor
    # routines that follow have their own tests)
    src = mod.source.split("subroutine conmech_taylor(")[0]
    assert src.count("sqrt(") == 6       # 2 each in rhs, jac and jac_prod
    assert "**(" not in mod.source and "d0" not in mod.source


def test_lagrangian_mass_forces_jacobian_energy():
    T, U, q, P = cart_lagrangian()
    mod = symbolic.lagrangian_system(T - U, q, params=P, model_only=True)
    Mc, m, l, g = P["M"], P["m"], P["l"], P["g"]
    rng = np.random.default_rng(2)
    for _ in range(10):
        qq, vv, aa = rng.normal(size=2), rng.normal(size=2), rng.normal(size=2)
        c, s = np.cos(qq[1]), np.sin(qq[1])
        Mm = np.array([[Mc + m, m*l*c], [m*l*c, m*l*l]])
        Q = np.array([m*l*s*vv[1]**2, m*g*l*s])
        assert rel(mod.call("mass", 0.0, qq), Mm) < 1e-15
        assert rel(mod.call("forces", 0.0, qq, vv), Q) < 1e-15
        E = 0.5*(vv @ Mm @ vv) + m*g*l*c
        assert abs(mod.call("energy", 0.0, qq, vv) - E) < 1e-14*abs(E) + 1e-15
        # R = [dQ/dq - d(M a)/dq, dQ/dv] against central differences of Q - M a
        R = mod.call("forces_jac", 0.0, qq, vv, aa)
        h = 1e-6

        def res(qx, vx):
            return mod.call("forces", 0.0, qx, vx) - mod.call("mass", 0.0, qx) @ aa
        for j in range(2):
            e = np.zeros(2)
            e[j] = h
            dq = (res(qq + e, vv) - res(qq - e, vv))/(2*h)
            dv = (res(qq, vv + e) - res(qq, vv - e))/(2*h)
            assert np.allclose(R[:, j], dq, atol=1e-8)
            assert np.allclose(R[:, 2 + j], dv, atol=1e-8)


def test_run_time_parameters_no_recompile():
    T, U, q, P = cart_lagrangian()
    mod = symbolic.lagrangian_system(T - U, q, params=P, model_only=True)
    names = mod.derived.param_names
    assert names == ["M", "m", "l", "g"]
    p2 = mod.derived.values(m=2.0)
    assert p2 == [1.3, 2.0, 0.9, 9.81]
    qq = np.array([0.1, 0.4])
    Mm = mod.call("mass", 0.0, qq, params=p2)
    assert abs(Mm[1, 1] - 2.0*0.9**2) < 1e-15 and abs(Mm[0, 0] - 3.3) < 1e-15
    with pytest.raises(ValueError, match="unknown parameter 'mass'"):
        mod.derived.values(mass=1.0)
    # the same source compiles to the same cached library
    mod2 = symbolic.lagrangian_system(T - U, q, params=dict(P, m=2.0), model_only=True)
    assert mod2.path == mod.path and mod2.cache_hit


def test_rational_coefficients_are_real_literals():
    x, v = sp.symbols("x v")
    f = [v, sp.Rational(1, 3)*x - sp.Rational(7, 2)*x**2 + sp.pi*v/2]
    mod = symbolic.ode_system(f, [x, v], model_only=True)
    out = mod.call("rhs", 0.0, [1.0, 1.0])
    assert abs(out[1] - (1/3 - 3.5 + np.pi/2)) < 1e-15


def test_constrained_moving_pendulum_terms():
    """phi, G, phi_t, gamma_h of the rheonomic pendulum against the closed forms of
    conmech_systems_constrained (pendulum_moving_xy)."""
    x, y = dynamicsymbols("x y")
    m, g, l, a, b, w = sp.symbols("m g l a b w")
    s = a*t**2/2 + b*sp.sin(w*t)
    T = m*(x.diff(t)**2 + y.diff(t)**2)/2
    P = dict(m=1.1, g=9.81, l=0.8, a=0.3, b=0.1, w=3.0)
    mod = symbolic.constrained_system(T, m*g*y, [x, y],
                                      holonomic=[((x - s)**2 + y**2 - l**2)/2],
                                      params=P, model_only=True)
    assert mod.derived.rheonomic and mod.derived.n_hol == 1
    rng = np.random.default_rng(3)
    for _ in range(5):
        tt = rng.uniform(0, 5)
        q, v = rng.normal(size=2), rng.normal(size=2)
        S = P["a"]*tt**2/2 + P["b"]*np.sin(P["w"]*tt)
        Sd = P["a"]*tt + P["b"]*P["w"]*np.cos(P["w"]*tt)
        Sdd = P["a"] - P["b"]*P["w"]**2*np.sin(P["w"]*tt)
        assert rel(mod.call("phi", tt, q), [0.5*((q[0] - S)**2 + q[1]**2 - P["l"]**2)]) < 1e-14
        assert rel(mod.call("phi_jac", tt, q), [[q[0] - S, q[1]]]) < 1e-14
        assert rel(mod.call("phi_t", tt, q), [-(q[0] - S)*Sd]) < 1e-14
        gam = -((v[0] - Sd)**2 + v[1]**2 - (q[0] - S)*Sdd)
        assert rel(mod.call("phi_gamma", tt, q, v), [gam]) < 1e-13
        assert rel(mod.call("mass", tt, q), P["m"]*np.eye(2)) < 1e-15
        assert rel(mod.call("forces", tt, q, v), [0, -P["m"]*P["g"]]) < 1e-15


def test_nonholonomic_matrix_and_gamma():
    xs, ys, th = dynamicsymbols("x y theta")
    m, I = sp.symbols("m I")
    T = m*(xs.diff(t)**2 + ys.diff(t)**2)/2 + I*th.diff(t)**2/2
    mod = symbolic.constrained_system(
        T, 0, [xs, ys, th],
        nonholonomic=[-sp.sin(th)*xs.diff(t) + sp.cos(th)*ys.diff(t) + 0.5*sp.cos(t)],
        params={m: 1.0, I: 0.5}, model_only=True)
    d = mod.derived
    assert (d.n_hol, d.n_nh) == (0, 1)
    q, v, tt = np.array([0.2, 0.1, 0.7]), np.array([0.3, -0.2, 1.1]), 0.4
    A, b = mod.call("nh_matrix", tt, q)
    assert rel(A, [[-np.sin(0.7), np.cos(0.7), 0.0]]) < 1e-15
    assert rel(b, [0.5*np.cos(tt)]) < 1e-15
    gam = v[2]*(np.cos(0.7)*v[0] + np.sin(0.7)*v[1]) + 0.5*np.sin(tt)
    assert rel(mod.call("nh_gamma", tt, q, v), [gam]) < 1e-14


def test_plain_symbols_with_velocities():
    th, w = sp.symbols("theta omega")
    m, g, l = sp.symbols("m g l")
    L = m*l**2*w**2/2 + m*g*l*sp.cos(th)
    mod = symbolic.lagrangian_system(L, [th], velocities=[w], params=dict(m=1, g=9.81, l=2),
                                     model_only=True)
    assert rel(mod.call("forces", 0.0, [0.3], [0.0]), [-9.81*2*np.sin(0.3)]) < 1e-15
    with pytest.raises(ValueError, match="velocities"):
        symbolic.lagrangian_system(L, [th], params=dict(m=1, g=9.81, l=2))


# ------------------------------------------------------------------ cache

def test_cache_hit_loads_without_compiling(symbolic_cache):
    f, y, mu = arenstorf_formulas()
    a = symbolic.ode_system(f, y, params={mu: 0.1}, model_only=True)
    b = symbolic.ode_system(f, y, params={mu: 0.1}, model_only=True)
    assert b.cache_hit and b.path == a.path
    # the derivation is cached too: the second construction runs no sympy derivation
    assert b.times["derive"] == 0.0 and "derived_cache" in b.times
    assert b.derived.param_values == [0.1]
    c = symbolic.ode_system(f, y, params={"mu": 0.2}, model_only=True)
    assert c.path == a.path and c.derived.param_values == [0.2]
    # a corrupt derivation-cache entry is ignored (derived again, then rewritten)
    entries = [e for e in os.listdir(symbolic_cache) if e.endswith(".derived.pickle")]
    for e in entries:
        with open(os.path.join(symbolic_cache, e), "wb") as fh:
            fh.write(b"not a pickle")
    d = symbolic.ode_system(f, y, params={mu: 0.1}, model_only=True)
    assert d.times["derive"] > 0 and d.path == a.path
    e = symbolic.ode_system(f, y, params={mu: 0.1}, model_only=True)
    assert e.times["derive"] == 0.0
    assert os.path.dirname(b.path) == symbolic_cache
    assert os.path.basename(b.path) == f"conmech_{build.library_path(b.source)[1]}.so"
    # the key changes with the flags
    assert build.library_path(b.source, ["-O2", "-fPIC", "-shared"])[0] != b.path


def test_cache_directory_default_respects_xdg(monkeypatch, tmp_path):
    monkeypatch.delenv("CONMECH_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert build.cache_dir() == str(tmp_path / "conmech")
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert build.cache_dir() == str(tmp_path / "home" / ".cache" / "conmech")


def test_two_processes_build_the_same_system_at_once(tmp_path):
    """Two processes compile the same new system into an empty cache concurrently: both
    get a loadable library at the same path, no temporary file is left behind."""
    cache = tmp_path / "race"
    script = textwrap.dedent("""
        import sys, numpy as np, sympy as sp
        from conmech import symbolic
        x, v, k = sp.symbols("x v k")
        mod = symbolic.ode_system([v, -k*x - x**3/7], [x, v], params={k: 2.0},
                                  model_only=True)
        out = mod.call("rhs", 0.0, [1.0, 0.5])
        assert abs(out[1] - (-2.0 - 1/7)) < 1e-15
        print(mod.path, mod.cache_hit)
    """)
    env = dict(os.environ, CONMECH_CACHE=str(cache))
    procs = [subprocess.Popen([sys.executable, "-c", script], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for _ in range(2)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert all(p.returncode == 0 for p in procs), [o[1] for o in outs]
    paths = {o[0].split()[0] for o in outs}
    assert len(paths) == 1
    files = sorted(os.listdir(cache))
    assert len([f for f in files if f.endswith(".so")]) == 1
    assert not [f for f in files if f.startswith(".build")]


def test_missing_compiler_is_a_clear_error(monkeypatch, tmp_path):
    monkeypatch.setenv("CONMECH_CACHE", str(tmp_path))
    monkeypatch.setenv("CONMECH_FC", "gfortran-not-installed-here")
    x, v = sp.symbols("x v")
    with pytest.raises(symbolic.CompileError, match=r"gfortran.*apt-get install gfortran"):
        symbolic.ode_system([v, -x], [x, v], model_only=True)
    assert os.listdir(tmp_path) == []


def test_compile_error_reports_the_message_and_leaves_no_entry(monkeypatch, tmp_path):
    monkeypatch.setenv("CONMECH_CACHE", str(tmp_path))
    with pytest.raises(symbolic.CompileError, match="Error"):
        build.compile_source("module broken\n  this is not fortran\nend module broken\n")
    assert [f for f in os.listdir(tmp_path)] == []


# ------------------------------------------------------------------ bad input

def test_unknown_symbol_is_named():
    x, v, k, c = sp.symbols("x v k c")
    with pytest.raises(ValueError, match="unknown symbol.*'c'"):
        symbolic.ode_system([v, -k*x - c*v], [x, v], params={k: 1.0})


def test_parameter_without_value_is_named():
    x, v, k = sp.symbols("x v k")
    with pytest.raises(ValueError, match="parameter 'k' has no value"):
        symbolic.ode_system([v, -k*x], [x, v], params={k: None})
    with pytest.raises(ValueError, match="parameter 'k' has no value"):
        symbolic.ode_system([v, -k*x], [x, v], params=[k])
    with pytest.raises(ValueError, match="parameter 'k'.*numeric"):
        symbolic.ode_system([v, -k*x], [x, v], params={"k": "one"})


def test_coordinates_that_do_not_match():
    x, y = dynamicsymbols("x y")
    m = sp.Symbol("m")
    L = m*(x.diff(t)**2 + y.diff(t)**2)/2
    with pytest.raises(ValueError, match="not one of the coordinates|not a coordinate"):
        symbolic.lagrangian_system(L, [x], params={m: 1.0})
    with pytest.raises(ValueError, match="f has 1 components for 2"):
        symbolic.ode_system([x], sp.symbols("a b"))
    with pytest.raises(ValueError, match="given twice"):
        symbolic.lagrangian_system(L, [x, x], params={m: 1.0})
    with pytest.raises(TypeError, match="neither a sympy Symbol nor a dynamicsymbol"):
        symbolic.lagrangian_system(L, [x + y], params={m: 1.0})
    with pytest.raises(ValueError, match="'m' is a coordinate"):
        symbolic.ode_system([sp.Symbol("m")], [sp.Symbol("m")], params={"m": 1.0})


def test_singular_mass_matrix_at_construction():
    x, y = dynamicsymbols("x y")
    m = sp.Symbol("m")
    # both coordinates move together: T depends on x' + y' only, det M = 0 identically
    L = m*(x.diff(t) + y.diff(t))**2/2 - m*x**2/2
    with pytest.raises(ValueError, match="singular"):
        symbolic.lagrangian_system(L, [x, y], params={m: 1.0})
    # a coordinate without kinetic energy
    with pytest.raises(ValueError, match="singular"):
        symbolic.constrained_system(m*x.diff(t)**2/2, 0, [x, y], params={m: 1.0})


def test_velocity_dependent_mass_and_nonlinear_pfaffian_are_rejected():
    x, y = dynamicsymbols("x y")
    with pytest.raises(ValueError, match="depends on the velocities"):
        symbolic.lagrangian_system(x.diff(t)**4/12 + y.diff(t)**2/2, [x, y])
    with pytest.raises(ValueError, match="not linear in the velocities"):
        symbolic.constrained_system((x.diff(t)**2 + y.diff(t)**2)/2, 0, [x, y],
                                    nonholonomic=[x.diff(t)**2 - y.diff(t)])
    with pytest.raises(ValueError, match="holonomic constraint 0 depends on the velocities"):
        symbolic.constrained_system((x.diff(t)**2 + y.diff(t)**2)/2, 0, [x, y],
                                    holonomic=[x.diff(t) - y])


def test_mass_matrix_singular_at_run_time_is_a_failure_not_a_crash():
    """M = x^2 vanishes at x = 0, reached at t = 1/2 from x = 1, x' = -1 (x x' = -1):
    the integration stops with success=False at that time, with a message."""
    import conmech
    x = dynamicsymbols("x")
    sysm = symbolic.lagrangian_system(x**2*x.diff(t)**2/2, [x], simplify=False)
    r = conmech.solve_ivp(sysm, (0, 5), [1.0, -1.0])
    assert not r.success and r.message
    assert abs(r.t[-1] - 0.5) < 1e-3


def test_nonconservative_forces_enter_q_and_the_exact_jacobian():
    """Damped pendulum m l^2 th'' = -m g l sin th - c th': the force is in Q, dQ/dv = -c in
    R, and the energy decays at the rate -c th'^2 along the solution."""
    import conmech
    th = dynamicsymbols("theta")
    m, g, l, c = sp.symbols("m g l c")
    L = m*l**2*th.diff(t)**2/2 + m*g*l*sp.cos(th)
    P = dict(m=1.0, g=9.81, l=1.0, c=0.3)
    sysm = symbolic.lagrangian_system(L, [th], params=P, forces=[-c*th.diff(t)])
    mod = symbolic.model_of(sysm)
    assert rel(mod.call("forces", 0.0, [0.4], [1.5]), [-9.81*np.sin(0.4) - 0.3*1.5]) < 1e-15
    R = mod.call("forces_jac", 0.0, [0.4], [1.5], [0.0])
    assert rel(R, [[-9.81*np.cos(0.4), -0.3]]) < 1e-15
    r = conmech.solve_ivp(sysm, (0, 4), [1.0, 0.0], rtol=1e-11, atol=1e-11,
                          t_eval=np.linspace(0, 4, 401), dense_output=False)
    E = np.array([mod.call("energy", 0.0, [a], [b]) for a, b in r.y.T])
    dE = np.gradient(E, r.t)
    assert np.max(np.abs(dE[5:-5] + 0.3*r.y[1, 5:-5]**2)) < 1e-3
    # with_params: no damping, the energy is conserved (same library)
    r0 = conmech.solve_ivp(sysm.with_params(c=0.0), (0, 4), [1.0, 0.0], rtol=1e-11,
                           atol=1e-11)
    E0 = [mod.call("energy", 0.0, [a], [b], params=[1.0, 9.81, 1.0, 0.0]) for a, b in r0.y.T]
    assert np.max(np.abs(np.array(E0) - E0[0])) < 1e-9


def test_constrained_with_params_changes_the_multiplier():
    """Cartesian pendulum at rest at the bottom: lambda = m/l^2 (y g - v^2) = -m g / l (seed
    000, phi = (x^2+y^2-l^2)/2), and with_params(m=2) doubles it without recompiling."""
    import conmech
    x, y = dynamicsymbols("x y")
    m, g, l = sp.symbols("m g l")
    sysm = symbolic.constrained_system(m*(x.diff(t)**2 + y.diff(t)**2)/2, m*g*y, [x, y],
                                       holonomic=[(x**2 + y**2 - l**2)/2],
                                       params=dict(m=1.0, g=9.81, l=1.5))
    for mass in (1.0, 2.0):
        s = sysm.with_params(m=mass)
        r = conmech.constrained.solve(s, (0, 1), [0.0, -1.5], [0.0, 0.0], rtol=1e-12,
                                      atol=1e-12)
        assert r.success
        assert np.max(np.abs(r.lam[0] + mass*9.81/1.5)) < 1e-10
        assert symbolic.model_of(s) is symbolic.model_of(sysm)


def test_elementary_and_piecewise_functions_compile_exactly():
    """abs, exp, log, tanh, atan2, Piecewise, Max, sign, Heaviside, asin, cube roots and
    real powers: generated values and Jacobians equal sympy's (the Jacobian of sign /
    Heaviside is taken away from the jump)."""
    x, v = sp.symbols("x v", real=True)
    f = [sp.Abs(x)*sp.exp(-v) + sp.log(1 + x**2),
         sp.tanh(v) + sp.atan2(v, x) + sp.Piecewise((x, x > 0), (x**2, True)) + sp.Max(x, v)
         + sp.sign(x) + sp.asin(x/5) + sp.cbrt(x**2 + 1) + (x**2 + 1)**0.7 + sp.Heaviside(v)]
    mod = symbolic.ode_system(f, [x, v], model_only=True)
    F = sp.lambdify([x, v], f)
    J = sp.lambdify([x, v], sp.Matrix(f).jacobian([x, v]).replace(sp.DiracDelta,
                                                                   lambda *a: 0))
    for s in ([0.5, 0.3], [1.2, -0.4], [-0.5, 0.7], [-1.3, -0.2]):
        assert np.max(np.abs(mod.call("rhs", 0.0, s) - np.array(F(*s)))) < 1e-14
        assert np.max(np.abs(mod.call("jac", 0.0, s) - np.array(J(*s), float))) < 1e-14


def test_unsupported_function_is_a_clear_error():
    x, v = sp.symbols("x v")
    with pytest.raises(ValueError, match="cannot generate Fortran for"):
        symbolic.ode_system([v, sp.gamma(x)], [x, v])


def test_symbol_with_a_coordinate_name_and_equation_constraints():
    x, y = dynamicsymbols("x y")
    m, l = sp.symbols("m l")
    T = m*(x.diff(t)**2 + y.diff(t)**2)/2
    with pytest.raises(ValueError, match="has the name of a coordinate"):
        symbolic.lagrangian_system(T - sp.Symbol("x")**2, [x, y], params={m: 1.0})
    # a holonomic constraint may be written as an equation lhs == rhs
    mod = symbolic.constrained_system(T, 0, [x, y], holonomic=[sp.Eq(x**2 + y**2, l**2)],
                                      params={m: 1.0, l: 2.0}, model_only=True)
    assert rel(mod.call("phi", 0.0, [1.0, 1.0]), [-2.0]) < 1e-15


def test_without_exact_jacobian():
    """jacobian=False: no forces_jac entry; the system integrates the same (the Jacobian
    then comes from differences)."""
    import conmech
    import conmech
    from conmech import compiled
    T, U, q, P = cart_lagrangian()
    a = symbolic.lagrangian_system(T - U, q, params=P)
    b = symbolic.lagrangian_system(T - U, q, params=P, jacobian=False)
    assert "forces_jac" not in symbolic.model_of(b).addresses
    y = [0.1, 2.5, 0.3, -0.2]
    assert compiled.evaluate(a, 0.0, y)["analytic"] and not compiled.evaluate(b, 0.0,
                                                                               y)["analytic"]
    kw = dict(rtol=1e-11, atol=1e-11, t_eval=[0.0, 1.0, 2.0])
    ra, rb = conmech.solve_ivp(a, (0, 2), y, **kw), conmech.solve_ivp(b, (0, 2), y, **kw)
    assert rel(ra.y, rb.y) < 1e-12


def test_singular_mass_of_a_large_system_is_seen_on_the_compiled_code():
    """Nine coordinates, the last one without kinetic energy: M is singular everywhere."""
    q = dynamicsymbols("q1:10")
    T = sum(qi.diff(t)**2 for qi in q[:-1])/2
    with pytest.raises(ValueError, match="singular"):
        symbolic.lagrangian_system(T - sum(qi**2 for qi in q)/2, list(q))


def test_model_call_checks_its_arguments():
    T, U, q, P = cart_lagrangian()
    mod = symbolic.lagrangian_system(T - U, q, params=P, model_only=True)
    with pytest.raises(ValueError, match="takes t and 2 array"):
        mod.call("forces", 0.0, [0.1, 0.2])
    with pytest.raises(ValueError, match="params must have 4 values"):
        mod.call("mass", 0.0, [0.1, 0.2], params=[1.0])
    with pytest.raises(ValueError, match="shape"):
        mod.call("mass", 0.0, [0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match="no entry point 'rhs'"):
        mod.call("rhs", 0.0, [0.1, 0.2])


def test_stale_build_directories_of_killed_processes_are_removed(monkeypatch, tmp_path):
    monkeypatch.setenv("CONMECH_CACHE", str(tmp_path))
    old, fresh = tmp_path / ".build-old-x", tmp_path / ".build-new-y"
    old.mkdir()
    fresh.mkdir()
    os.utime(old, (0, 0))
    x, v = sp.symbols("x v")
    symbolic.ode_system([v, -x/3], [x, v], model_only=True)
    assert not old.exists() and fresh.exists()     # a build in progress is left alone


def test_save_model_runs_in_python_and_sweep(tmp_path):
    """A symbolic system saved as a model library loads with compiled.load_model (its
    parameters as defaults) and runs in the sweep program like the built-in it equals."""
    import subprocess
    import conmech
    from conmech import compiled
    x, v, w = sp.symbols("x v omega")
    osc = symbolic.ode_system([v, -w**2*x], [x, v], params={w: 2.0})
    path = symbolic.save_model(osc.with_params(omega=3.0), tmp_path / "libosc.so")
    m = compiled.load_model(path)
    assert m.kind == "ode" and m.parameters == {"omega": 3.0}
    r = conmech.solve_ivp(m, (0, 1), [1.0, 0.0], rtol=1e-12, atol=1e-12)
    assert r.success and abs(r.y[0, -1] - np.cos(3.0)) < 1e-10
    exe = subprocess.run(["fpm", "run", "sweep", "--runner", "echo"], capture_output=True,
                         text=True, check=True).stdout.strip().splitlines()[-1]
    out = {}
    for name, sysargs in (("model", ["--model", str(path)]),
                          ("builtin", ["--system", "harmonic", "--params", "3"])):
        out[name] = tmp_path / f"{name}.csv"
        p = subprocess.run([exe, *sysargs, "--y0", "1,0", "--vary", "y0:1", "--from", "0.5",
                            "--to", "1.5", "--count", "3", "--t-end", "1", "--rtol", "1e-12",
                            "--atol", "1e-12", "--quiet", "--out", str(out[name])],
                           capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
    a = np.genfromtxt(out["model"], delimiter=",", skip_header=1)
    b = np.genfromtxt(out["builtin"], delimiter=",", skip_header=1)
    assert a.shape == b.shape == (3, b.shape[1])
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-14)


def test_continuation_of_a_symbolic_system_matches_the_builtin():
    """Pseudo-arclength continuation runs on a compiled (symbolic) system, its parameter set
    in place in the compiled parameter array: Van der Pol's limit cycle continued in mu
    gives the same branch as the built-in system (periods at the same mu to 1e-8)."""
    from conmech import stability, systems
    x, v, mu = sp.symbols("x v mu")
    vdp = symbolic.ode_system([v, mu*(1 - x**2)*v - x], [x, v], params={mu: 1.0})
    kw = dict(param="mu", ds=0.1, ds_max=0.3, p_range=(0.5, 2.0), max_points=30)
    a = stability.continuation(vdp, [2.0, 0.0], 6.66, **kw)
    b = stability.continuation(systems.vanderpol(1.0), [2.0, 0.0], 6.66, **kw)
    assert a.success and b.success and a.p[-1] >= 2.0
    # the same branch: the period as a function of mu agrees where both have points
    pa = np.interp(b.p, a.p, a.period)
    inside = (b.p >= a.p.min()) & (b.p <= a.p.max())
    assert inside.sum() >= 5
    assert np.abs(pa[inside] - b.period[inside]).max() < 1e-3     # interpolation error
    one = stability.periodic_orbit(vdp.with_params(mu=float(a.p[-1])), a.y0[-1], a.period[-1])
    assert one.period == pytest.approx(a.period[-1], abs=1e-8)
    ref = stability.periodic_orbit(systems.vanderpol(float(a.p[-1])), a.y0[-1], a.period[-1])
    assert ref.period == pytest.approx(a.period[-1], abs=1e-8)
