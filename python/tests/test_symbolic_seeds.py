"""Every seed system that conmech builds in, re-derived by conmech.symbolic from T, U and the
constraints as the lecture notes write them, against the hand-written built-in: M, Q (and
phi, G, gamma, A, b) to round-off at random states, trajectories (and multipliers) to 1e-10
relative over several periods. Also Hill's problem (formulas and rotating-frame Lagrangian),
the Arenstorf monodromy with the exact Jacobian, stability functions and events."""
import os
import zlib

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import conmech  # noqa: E402
from conmech import compiled, constrained, stability, symbolic  # noqa: E402
from conmech.systems import BuiltinSystem  # noqa: E402

import symbolic_seeds as seeds  # noqa: E402


@pytest.fixture(scope="session", autouse=True)
def symbolic_cache_seeds(tmp_path_factory):
    """The session's compile cache (shared with test_symbolic)."""
    d = os.environ.get("_CONMECH_TEST_CACHE")
    if not d:
        d = str(tmp_path_factory.getbasetemp() / "conmech_cache")
        os.environ["_CONMECH_TEST_CACHE"] = d
    os.environ["CONMECH_CACHE"] = d
    return d


rel = seeds.rel


def close(a, b, tol):
    """max |a - b| <= tol * max(|b|, 1)."""
    a, b = np.asarray(a), np.asarray(b)
    if a.size == 0 and b.size == 0:
        return True
    return np.max(np.abs(a - b)) <= tol * max(np.max(np.abs(b)), 1.0)


# ------------------------------------------------------------------ generalized coordinates

@pytest.mark.parametrize("name", sorted(seeds.GENERALIZED))
def test_generalized_seed_matches_builtin(name):
    P, make, q0, v0, tf = seeds.GENERALIZED[name]
    L, q = make()
    sym = symbolic.lagrangian_system(L, q, params=dict(P, **seeds.EXTRA.get(name, {})))
    built = BuiltinSystem(name, list(P.values()), tuple(P))
    n = len(q)
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    for _ in range(5):
        tt = rng.uniform(0, 3)
        # random states near the seed's configuration (springs not collapsed to r ~ 0,
        # where the round-off of d/r grows as 1/r)
        qq, vv = np.asarray(q0) + rng.uniform(-0.3, 0.3, n), rng.uniform(-1, 1, n)
        a, b = compiled.evaluate(sym, tt, qq, vv), compiled.evaluate(built, tt, qq, vv)
        assert close(a["M"], b["M"], 1e-14), (a["M"], b["M"])
        assert close(a["Q"], b["Q"], 2e-14), (a["Q"], b["Q"])
        if b["energy"] is not None and name not in ("bead_hoop",):
            assert abs(a["energy"] - b["energy"]) <= 1e-13 * max(abs(b["energy"]), 1.0)
        # first-order form: same f, and the symbolic Jacobian is exact
        fa, fb = compiled.evaluate(sym, tt, np.r_[qq, vv]), compiled.evaluate(built, tt,
                                                                              np.r_[qq, vv])
        assert fa["analytic"]
        assert close(fa["f"], fb["f"], 1e-13)
        assert close(fa["jac"], fb["jac"], 1e-6)      # the built-in's is a difference quotient
    if name == "bead_hoop":
        # the Jacobi integral T2 - T0 + U is the symbolic energy; the built-in's is the same
        e = compiled.evaluate(sym, 0.0, [0.3], [0.7])["energy"]
        R, w, g = P["R"], P["omega"], P["g"]
        assert abs(e - (0.5*R**2*(0.49 - w**2*np.sin(0.3)**2) - g*R*np.cos(0.3))) < 1e-13
    y0 = np.r_[q0, v0]
    kw = dict(method="DOP853", rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, tf, 41))
    ra, rb = conmech.solve_ivp(sym, (0, tf), y0, **kw), conmech.solve_ivp(built, (0, tf), y0,
                                                                          **kw)
    assert ra.success and rb.success
    assert rel(ra.y, rb.y) < 1e-10


# ------------------------------------------------------------------ excessive coordinates

@pytest.mark.parametrize("name", sorted(seeds.CONSTRAINED))
def test_constrained_seed_matches_builtin(name):
    P, make, tf = seeds.CONSTRAINED[name]
    spec = make()
    sym = symbolic.constrained_system(spec["T"], spec["U"], spec["q"],
                                      holonomic=spec.get("holonomic", ()),
                                      nonholonomic=spec.get("nonholonomic", ()), params=P)
    built = constrained.builtin(name, list(P.values()))
    n = len(spec["q"])
    assert symbolic.model_of(sym).derived.rheonomic == (name in ("pendulum_moving_xy", "yoyo"))
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    for _ in range(5):
        tt = rng.uniform(0, 3)
        qq, vv = rng.uniform(-1.5, 1.5, n), rng.uniform(-1, 1, n)
        a, b = compiled.evaluate(sym, tt, qq, vv), compiled.evaluate(built, tt, qq, vv)
        for k in ("M", "Q", "phi", "G", "gamma_h", "A", "b", "gamma_n"):
            assert close(a[k], b[k], 1e-14), (k, a[k], b[k])
        if b["energy"] is not None:
            assert abs(a["energy"] - b["energy"]) <= 1e-14 * max(abs(b["energy"]), 1.0)
    q0, v0 = built.initial_state()
    kw = dict(t_eval=np.linspace(0, tf, 41), rtol=1e-12, atol=1e-12)
    ra = constrained.solve(sym, (0, tf), q0, v0, **kw)
    rb = constrained.solve(built, (0, tf), q0, v0, **kw)
    assert ra.success and rb.success
    assert rel(ra.q, rb.q) < 1e-10 and rel(ra.v, rb.v) < 1e-10
    assert rel(ra.lam, rb.lam) < 1e-10


# ------------------------------------------------------------------ Hill's problem

def test_hill_formulas_and_rotating_lagrangian_match_builtin():
    m, kappa = 0.080848933808312, 1.0
    built = conmech.systems.hill(m=m, kappa=kappa)
    f, y = seeds.hill_ode()
    ode = symbolic.ode_system(f, y, params=dict(m=m, kappa=kappa))
    L, q = seeds.hill_lagrangian()
    lag = symbolic.lagrangian_system(L, q, params=dict(m=m, kappa=kappa))
    rng = np.random.default_rng(7)
    for _ in range(5):
        s = np.r_[rng.uniform(0.3, 1.0, 2), rng.uniform(-1, 1, 2)]
        b = compiled.evaluate(built, 0.0, s)
        for sys_ in (ode, lag):
            a = compiled.evaluate(sys_, 0.0, s)
            assert a["analytic"]
            assert close(a["f"], b["f"], 1e-14)
            assert close(a["jac"], b["jac"], 1e-14)
    y0 = [0.3, 0.0, 0.0, 1.5]
    kw = dict(rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, 6, 31))
    rb = conmech.solve_ivp(built, (0, 6), y0, **kw)
    for sys_ in (ode, lag):
        ra = conmech.solve_ivp(sys_, (0, 6), y0, **kw)
        assert ra.success and rel(ra.y, rb.y) < 1e-10


# ------------------------------------------------------------------ stability, events

def arenstorf():
    f, y, mu = seeds.arenstorf_ode()
    return symbolic.ode_system(f, y, params={mu: 0.012277471})


def arenstorf_numpy(mu=0.012277471):
    """Hand-written right-hand side and analytic Jacobian (independent of sympy)."""
    mp = 1.0 - mu

    def f_and_jac(s):
        x, y, u, v = s
        dx1, dx2 = x + mu, x - mp
        r1, r2 = np.hypot(dx1, y), np.hypot(dx2, y)
        a1, a2 = mp/r1**3, mu/r2**3
        b1, b2 = 3*mp/r1**5, 3*mu/r2**5
        f = np.array([u, v, x + 2*v - a1*dx1 - a2*dx2, y - 2*u - a1*y - a2*y])
        J = np.zeros((4, 4))
        J[0, 2] = J[1, 3] = 1.0
        J[2, 0] = 1 - a1 - a2 + b1*dx1**2 + b2*dx2**2
        J[2, 1] = J[3, 0] = b1*dx1*y + b2*dx2*y
        J[3, 1] = 1 - a1 - a2 + (b1 + b2)*y**2
        J[2, 3], J[3, 2] = 2.0, -2.0
        return f, J
    return f_and_jac


def test_arenstorf_monodromy_exact_jacobian():
    """Monodromy through the exact symbolic Jacobian vs DOP853 at rtol 1e-13 on the 20
    variational equations with a hand-written analytic Jacobian: <= 1e-8 relative (the
    finite-difference path reaches only ~1.5e-6)."""
    T = 17.0652165601579625588917206249
    y0 = np.array([0.994, 0.0, 0.0, -2.00158510637908252240537862224])
    sys_ = arenstorf()
    fj = arenstorf_numpy()
    s = np.r_[0.5, 0.3, 0.1, -0.2]
    e = compiled.evaluate(sys_, 0.0, s)
    f, J = fj(s)
    assert e["analytic"] and close(e["f"], f, 1e-14) and close(e["jac"], J, 1e-14)

    def rhs(t, z):
        f, J = fj(z[:4])
        return np.r_[f, (J @ z[4:].reshape(4, 4)).ravel()]
    r = conmech.solve_ivp(rhs, (0, T), np.r_[y0, np.eye(4).ravel()], method="DOP853",
                          rtol=1e-13, atol=1e-13)
    assert r.success
    ref = r.y[4:, -1].reshape(4, 4)
    mono = stability.monodromy(sys_, y0, T, rtol=1e-13, atol=1e-13)
    assert rel(mono, ref) <= 1e-8


def cart_symbolic(**P):
    L, q = seeds.cart_pendulum()
    return symbolic.lagrangian_system(L, q, params=P)


def test_equilibria_stm_and_periodic_orbit_of_a_symbolic_system():
    P = dict(M=1.3, m=0.7, l=0.9, g=9.81)
    sym = cart_symbolic(**P)
    built = conmech.systems.cart_pendulum(**P)
    # upright (theta = 0) is a saddle, hanging (theta = pi) a centre, as for the built-in
    for th in (0.0, np.pi):
        ea = stability.equilibrium(sym, [0.0, th, 0.0, 0.0])
        eb = stability.equilibrium(built, [0.0, th, 0.0, 0.0])
        assert ea.kind == eb.kind
        assert close(np.sort_complex(ea.eigenvalues), np.sort_complex(eb.eigenvalues), 1e-7)
    # the linearisation at the hanging position: omega^2 = g (M + m)/(M l)
    w = np.sqrt(P["g"]*(P["M"] + P["m"])/(P["M"]*P["l"]))
    e = stability.equilibrium(sym, [0.0, np.pi, 0.0, 0.0])
    assert abs(np.max(np.abs(np.imag(e.eigenvalues))) - w) < 1e-8*w
    # state transition matrix: symbolic (exact Jacobian) vs built-in
    y0 = [0.0, np.pi - 0.5, 0.0, 0.0]
    ya, pa = stability.stm(sym, (0, 2.0), y0, rtol=1e-12, atol=1e-12)
    yb, pb = stability.stm(built, (0, 2.0), y0, rtol=1e-12, atol=1e-12)
    assert rel(ya, yb) < 1e-10 and rel(pa, pb) < 1e-7
    # a symmetric periodic swing (velocities zero at t = 0 and at half the period) of a
    # period 2 % longer than the linear one: the amplitude is the unknown
    period = 1.02*2*np.pi/w
    oa = stability.symmetric_orbit(sym, y0, free=[1], targets=[3], period=period)
    ob = stability.symmetric_orbit(built, y0, free=[1], targets=[3], period=period)
    assert abs(oa.y0[1] - ob.y0[1]) < 1e-9 and oa.residual < 1e-9
    # conservative, with the cart's translation: all four multipliers at 1
    assert np.max(np.abs(oa.multipliers - 1.0)) < 1e-4
    assert rel(oa.monodromy, ob.monodromy) < 1e-6
    # with_params: a heavier bob, no recompilation, the frequency follows
    sym2 = sym.with_params(m=2.0)
    e2 = stability.equilibrium(sym2, [0.0, np.pi, 0.0, 0.0])
    w2 = np.sqrt(P["g"]*(P["M"] + 2.0)/(P["M"]*P["l"]))
    assert abs(np.max(np.abs(np.imag(e2.eigenvalues))) - w2) < 1e-8*w2
    assert symbolic.model_of(sym2) is symbolic.model_of(sym)


def test_events_on_a_symbolic_system():
    """Bottom passages of the pendulum at T/4 and 3T/4 (closed-form period)."""
    import math
    L, q = seeds.pendulum_angle()
    sym = symbolic.lagrangian_system(L, q, params=dict(m=1.0, g=9.81, l=1.0))
    th0 = 1.0
    k = math.sin(th0/2)
    a, b = 1.0, math.sqrt(1 - k*k)
    for _ in range(40):
        a, b = (a + b)/2, math.sqrt(a*b)
    period = 4*math.sqrt(1/9.81)*math.pi/(2*a)

    def bottom(t, y):
        return y[0]
    r = conmech.solve_ivp(sym, (0, period), [th0, 0.0], events=bottom, rtol=1e-12,
                          atol=1e-12)
    assert r.success
    te = np.asarray(r.t_events[0])
    assert te.size == 2
    assert np.max(np.abs(te - [period/4, 3*period/4])) < 1e-9


def test_periodic_orbit_limit_cycle_of_a_symbolic_ode():
    """Van der Pol's limit cycle by Newton shooting (periodic_orbit, free period) on the
    formulas vs the built-in: same period and multipliers; the nontrivial multiplier is
    exp(integral of the divergence) < 1 (stable), the other is 1."""
    x, v, mu = sp.symbols("x v mu")
    sym = symbolic.ode_system([v, mu*(1 - x**2)*v - x], [x, v], params={mu: 1.0})
    built = conmech.systems.vanderpol(mu=1.0)
    guess = [2.0, 0.0]
    oa = stability.periodic_orbit(sym, guess, 6.66)
    ob = stability.periodic_orbit(built, guess, 6.66)
    assert abs(oa.period - 6.663286859323130) < 1e-8          # Van der Pol, mu = 1
    assert abs(oa.period - ob.period) < 1e-10
    ma = np.sort(np.abs(oa.multipliers))
    mb = np.sort(np.abs(ob.multipliers))
    assert abs(ma[1] - 1.0) < 1e-7 and ma[0] < 0.1
    assert abs(ma[0] - mb[0]) < 1e-7
