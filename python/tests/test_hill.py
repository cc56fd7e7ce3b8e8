"""Hill's lunar problem and the stability layer through the Python API."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve
from scipy.special import mathieu_a, mathieu_b

import conmech
from conmech import hill, stability, systems


# ----------------------------------------------------------------------------- Hill

def test_perigee_constant_at_hills_m():
    orb = hill.variation_orbit(hill.M_HILL)
    assert abs(orb.c - hill.C_HILL) <= 1e-12
    assert orb.period == pytest.approx(2*np.pi, abs=0)
    assert orb.monodromy.shape == (4, 4)
    assert np.linalg.det(orb.monodromy) == pytest.approx(1.0, abs=1e-12)
    assert orb.stable and abs(orb.stability_index) < 1
    # non-trivial multipliers exp(+-2 pi i c), on the unit circle
    mu = orb.multipliers[np.argsort(-np.abs(orb.multipliers.imag))][:2]
    assert np.allclose(np.abs(mu), 1.0, atol=1e-12)
    assert np.allclose(np.sort(mu.imag), [-np.sin(2*np.pi*orb.c), np.sin(2*np.pi*orb.c)],
                       atol=1e-11)


def test_direct_full_period_agrees():
    a = hill.variation_orbit(hill.M_HILL)
    b = hill.variation_orbit(hill.M_HILL, full_period=True)
    assert abs(b.c - hill.C_HILL) <= 1e-12
    assert np.max(np.abs(a.monodromy - b.monodromy)) < 1e-10


def test_against_scipy_shooting():
    """An independent reference: SciPy's DOP853 on the variational equations + fsolve."""
    m = hill.M_HILL
    ref = _scipy_orbit(m)
    orb = hill.variation_orbit(m)
    assert np.allclose(orb.y0[[0, 3]], ref["u"], atol=1e-10)
    assert abs(orb.c - ref["c"]) < 1e-9


def test_transverse_hill_equation():
    orb = hill.variation_orbit(hill.M_HILL)
    tr = hill.transverse(orb, t=np.linspace(0, np.pi, 64, endpoint=False))
    assert abs(tr["c"] - hill.C_HILL) < 1e-11
    assert tr["half_trace"] == pytest.approx(orb.stability_index, abs=1e-11)
    assert np.linalg.det(tr["monodromy"]) == pytest.approx(1.0, abs=1e-11)
    # Phi has period pi: its samples into the general Hill's-equation solver
    res = stability.hill_equation(tr["phi"], np.pi)
    half_trace_2pi = 2*res.half_trace**2 - 1
    assert 1 + np.arccos(half_trace_2pi)/(2*np.pi) == pytest.approx(hill.C_HILL, abs=1e-9)


def test_family_continuation():
    ms = np.linspace(0.02, 0.13, 300)
    fam = hill.family(ms)
    assert np.all(fam.success)
    assert np.all(np.diff(fam.c) > 0)
    assert np.all(np.abs(fam.stability_index) < 1)
    one = hill.variation_orbit(ms[123])
    assert fam.c[123] == pytest.approx(one.c, abs=1e-13)
    # continuation: apart from the chunk starts, Newton needs at most 2 iterations
    assert np.mean(fam.iterations <= 2) > 0.95


def test_family_c_equals_single_orbits():
    """Issue 9: |c_family - c_single| <= 1e-13 (c from products of the quarter map, not
    from the trace of M, whose round-off floor was ~3e-12 at small m); c also agrees with
    single orbits computed with twice the steps (converged in the discretisation)."""
    ms = np.linspace(0.01, 0.15, 2000)
    fam = hill.family(ms)
    assert np.all(fam.success) and np.max(fam.residual) <= 1e-12
    for i in range(0, 2000, 97):
        assert abs(fam.c[i] - hill.variation_orbit(ms[i]).c) <= 1e-13
        assert abs(fam.c[i] - hill.variation_orbit(ms[i], nsteps=40).c) <= 1e-13
    # S = 1 - 8 s t agrees with the trace of the returned monodromy to its round-off
    tr = np.trace(fam.monodromy, axis1=1, axis2=2)
    assert np.max(np.abs(fam.stability_index - (tr - 2)/2)) < 1e-10


def test_orbit_unpacked_from_one_array():
    """variation_orbit's result is unpacked from the flat routine's one output array: its
    arrays must be the orbit's (the multipliers the eigenvalues of the monodromy, the
    monodromy symplectic-like with det 1 and trace 2 + 2 S, y0 on the x axis crossing it
    at right angles, the quarter-period state on the y axis), the counts plain ints and
    the scalars plain floats, as when they were returned one by one."""
    orb = hill.variation_orbit(hill.M_HILL)
    M = orb.monodromy
    assert M.shape == (4, 4) and M.flags.f_contiguous and M.dtype == np.float64
    assert orb.multipliers.shape == (4,) and orb.multipliers.dtype == np.complex128
    ev = np.linalg.eigvals(M)
    for mu in orb.multipliers:
        assert np.min(np.abs(ev - mu)) < 1e-6           # the Jordan pair at 1: ~sqrt(eps)
    assert abs(np.linalg.det(M) - 1.0) < 1e-10
    assert abs((np.trace(M) - 2.0)/2.0 - orb.stability_index) < 1e-10
    assert orb.y0.shape == (4,) and orb.y0[1] == 0.0 and orb.y0[2] == 0.0
    assert orb.quarter_state.shape == (4,) and abs(orb.quarter_state[0]) < 1e-12
    assert abs(orb.quarter_state[3]) < 1e-12
    for name in ("nsteps", "iterations", "nfev"):
        assert type(getattr(orb, name)) is int and getattr(orb, name) > 0
    for name in ("period", "jacobi", "stability_index", "c", "residual"):
        assert type(getattr(orb, name)) is float
    assert orb.period == 2.0*np.pi and orb.residual <= 1e-12
    # writing into one array of the orbit leaves the others alone
    y0, mono = orb.y0.copy(), M.copy()
    orb.quarter_state[:] = 7.0
    assert np.array_equal(orb.y0, y0) and np.array_equal(orb.monodromy, mono)
    # integers of NumPy types are accepted, floats and bools are not
    assert hill.variation_orbit(hill.M_HILL, nsteps=np.int32(20)).c == orb.c
    for bad in (20.0, True):
        with pytest.raises(TypeError, match="nsteps must be an integer"):
            hill.variation_orbit(hill.M_HILL, nsteps=bad)
        with pytest.raises(TypeError, match="max_nsteps must be an integer"):
            hill.variation_orbit(hill.M_HILL, max_nsteps=bad)
    # a failure's Fortran message travels in the same array
    with pytest.raises(RuntimeError, match="^hill_variation_orbit: Newton diverged$"):
        hill.variation_orbit(5.0)


def test_hill_bad_input():
    with pytest.raises(ValueError, match="m"):
        hill.variation_orbit(-0.1)
    with pytest.raises(ValueError, match="kappa"):
        hill.variation_orbit(0.08, kappa=0.0)
    with pytest.raises(TypeError):
        hill.variation_orbit("x")
    with pytest.raises(RuntimeError, match="converge"):
        hill.variation_orbit(hill.M_HILL, guess=(5.0, 5.0))
    with pytest.raises(RuntimeError, match="another periodic orbit"):
        hill.variation_orbit(hill.M_HILL, guess=(0.95, -0.95))
    with pytest.raises(ValueError):
        hill.family([])


def test_plots(tmp_path):
    mpl = pytest.importorskip("matplotlib")
    mpl.use("Agg")
    import matplotlib.pyplot as plt
    orb = hill.variation_orbit(hill.M_HILL)
    fig, axes = plt.subplots(1, 3, figsize=(12, 4))
    hill.plot_orbit(orb, axes[0])
    hill.plot_multipliers(orb, axes[1])
    hill.plot_family(hill.family(np.linspace(0.01, 0.15, 50)), axes[2])
    fig.savefig(tmp_path / "hill.png")
    plt.close(fig)
    assert (tmp_path / "hill.png").stat().st_size > 1000


# ------------------------------------------------------------------- Mathieu vs SciPy

@pytest.mark.parametrize("q", [0.5, 1.0, 3.0])
def test_mathieu_boundaries(q):
    """y'' + (a - 2 q cos 2t) y = 0: stable/unstable on either side of SciPy's
    characteristic values a_r(q), b_r(q); half trace +-1 on them."""
    def solve(a):
        return stability.hill_equation(lambda t: a - 2*q*np.cos(2*t), np.pi, rtol=1e-13)
    d = 1e-5
    cases = [(mathieu_a(0, q), 1, False, True), (mathieu_b(1, q), -1, True, False),
             (mathieu_a(1, q), -1, False, True), (mathieu_b(2, q), 1, True, False),
             (mathieu_a(2, q), 1, False, True)]
    for a, edge, below, above in cases:
        assert solve(a).half_trace == pytest.approx(edge, abs=1e-8)
        assert solve(a - d).stable is below
        assert solve(a + d).stable is above


def test_hill_equation_samples_and_bad_input():
    q, a = 2.0, 3.0
    f = stability.hill_equation(lambda t: a - 2*q*np.cos(2*t), np.pi)
    t = np.arange(32)*np.pi/32
    s = stability.hill_equation(a - 2*q*np.cos(2*t), np.pi)
    assert np.allclose(f.monodromy, s.monodromy, atol=1e-9)
    with pytest.raises(ValueError):
        stability.hill_equation([1.0, 2.0], np.pi)
    with pytest.raises(ValueError):
        stability.hill_equation(lambda t: 1.0, -1.0)


# ------------------------------------------------------------------------- stability

def test_equilibria():
    g = 9.81
    e = stability.equilibrium(systems.pendulum(g=g), [0, 0])
    assert e.kind == "centre" and e.analytic
    assert np.max(e.eigenvalues.imag) == pytest.approx(np.sqrt(g), abs=1e-12)
    e = stability.equilibrium(systems.pendulum(g=g), [np.pi, 0])
    assert e.kind == "unstable" and e.saddle

    def cart(t, y):   # reduced cart-pendulum dynamics (the lecture notes)
        th, w = y
        return [w, (g*np.sin(th) - 0.5*np.cos(th)*np.sin(th)*w**2)/(1 - 0.5*np.cos(th)**2)]
    up = stability.equilibrium(cart, [0, 0])
    down = stability.equilibrium(cart, [np.pi, 0])
    assert up.kind == "unstable" and not up.analytic
    assert np.max(up.eigenvalues.real) == pytest.approx(np.sqrt(2*g), rel=1e-8)
    assert down.kind == "centre"
    assert np.max(down.eigenvalues.imag) == pytest.approx(np.sqrt(2*g), rel=1e-8)
    xe = (1/(3*hill.M_HILL**2))**(1/3)
    e = stability.equilibrium(systems.hill(), [xe, 0, 0, 0])
    assert e.kind == "unstable" and e.saddle and e.residual < 1e-12


def test_lagrange_dirichlet():
    ok, w = stability.lagrange_dirichlet([[2.0, 0.5], [0.5, 1.0]])
    assert ok and np.all(w > 0)
    ok, w = stability.lagrange_dirichlet([[-2.0, 0.5], [0.5, 1.0]])
    assert not ok
    with pytest.raises(ValueError):
        stability.lagrange_dirichlet([[1.0, 1.0], [0.0, 1.0]])


def test_periodic_orbits_builtin_and_callback():
    vdp = stability.periodic_orbit(systems.vanderpol(1.0), [2, 0], 6.5)
    assert vdp.period == pytest.approx(6.663286859323130, abs=1e-9)
    cb = stability.periodic_orbit(lambda t, y: [y[1], (1 - y[0]**2)*y[1] - y[0]], [2, 0], 6.5)
    assert cb.period == pytest.approx(vdp.period, abs=1e-8)
    assert np.min(np.abs(vdp.multipliers)) < 0.01
    sym = stability.symmetric_orbit(systems.hill(), [0.95, 0, 0, 0.95], [0, 3], [0, 3],
                                    2*np.pi, period_factor=4)
    assert 1 + np.arccos(sym.stability_index)/(2*np.pi) == pytest.approx(hill.C_HILL,
                                                                         abs=1e-10)
    with pytest.raises(RuntimeError, match="singular"):
        stability.periodic_orbit(systems.harmonic(), [1, 0], 2*np.pi, fixed_period=True)
    with pytest.raises(ValueError):
        stability.periodic_orbit(systems.harmonic(), [1, 0, 0], 2*np.pi)
    with pytest.raises(ValueError):
        stability.symmetric_orbit(systems.hill(), [1, 0, 0, 1], [7], [0], 1.0)


def test_stm_and_floquet():
    y1, phi = stability.stm(systems.harmonic(2.0), (0, 1.3), [1, 0])
    assert phi[0, 1] == pytest.approx(np.sin(2.6)/2, abs=1e-10)
    _, phi2 = stability.stm(lambda t, y: [y[1], -4*y[0]], (0, 1.3), [1, 0])
    assert np.allclose(phi, phi2, atol=1e-8)
    orb = hill.variation_orbit(hill.M_HILL)
    m = stability.monodromy(systems.hill(), orb.y0, 2*np.pi, rtol=1e-13, atol=1e-13)
    fl = stability.floquet(m, 2*np.pi)
    assert fl["stability_index"] == pytest.approx(orb.stability_index, abs=1e-10)


def test_package_exports():
    assert conmech.hill is hill and conmech.stability is stability


# -------------------------------------------------------------------- SciPy reference

def _scipy_orbit(m, kappa=1.0, rtol=1e-13, atol=1e-13, u0=None):
    """Variation orbit and c with SciPy only: DOP853 on state + STM, fsolve."""
    def rhs(t, z):
        x, y, vx, vy = z[:4]
        r2 = x*x + y*y
        r3 = r2*np.sqrt(r2)
        r5 = r3*r2
        fxx = kappa*(3*x*x/r5 - 1/r3) + 3*m*m
        fxy = 3*kappa*x*y/r5
        fyy = kappa*(3*y*y/r5 - 1/r3)
        a = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [fxx, fxy, 0, 2*m], [fxy, fyy, -2*m, 0]])
        p = z[4:].reshape(4, 4)
        return np.concatenate([[vx, vy, 2*m*vy - kappa*x/r3 + 3*m*m*x,
                                -2*m*vx - kappa*y/r3], (a @ p).ravel()])

    def flow(u, t1):
        z0 = np.concatenate([[u[0], 0, 0, u[1]], np.eye(4).ravel()])
        return solve_ivp(rhs, (0, t1), z0, method="DOP853", rtol=rtol, atol=atol).y[:, -1]

    def resid(u):
        z = flow(u, np.pi/2)
        return [z[0], z[3]]

    def jac(u):
        p = flow(u, np.pi/2)[4:].reshape(4, 4)
        return [[p[0, 0], p[0, 3]], [p[3, 0], p[3, 3]]]

    if u0 is None:
        u0 = [(1 + m)**(-2/3), (1 + m)**(-2/3)]
    u = fsolve(resid, u0, fprime=jac, xtol=1e-14)
    mono = flow(u, 2*np.pi)[4:].reshape(4, 4)
    s = 0.5*(np.trace(mono) - 2)
    return {"u": u, "c": 1 + np.arccos(s)/(2*np.pi), "monodromy": mono}


def test_family_threads_give_the_same_orbits():
    """The extension is built with OpenMP: the family with 1 and 2 threads agrees."""
    import json
    import os
    import subprocess
    import sys
    code = ("import json, numpy as np, conmech; "
            "f = conmech.hill.family(np.linspace(0.01, 0.15, 400)); "
            "print(json.dumps([f.c.tolist(), f.stability_index.tolist()]))")
    out = {}
    for nt in ("1", "2"):
        env = dict(os.environ, OMP_NUM_THREADS=nt)
        r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                           text=True, check=True, cwd="/")
        out[nt] = np.array(json.loads(r.stdout))
    assert out["1"].shape == (2, 400) and np.all(np.isfinite(out["1"]))
    # fixed chunks (chunk_size) independent of the thread count: bit for bit the same
    assert np.array_equal(out["1"], out["2"])


# ------------------------------------------------ honest accuracy along the family

def _true_closure(m, y0):
    """Independent check: the closure |(x, y')(T/4)| by conmech's adaptive Verner 9(8) at
    rtol = atol = 1e-14 (another method than the fixed-step DOP853 of the orbit solver)."""
    s = conmech.solve_ivp(systems.hill(m=m), (0, np.pi/2), y0, method="VERNER98",
                          rtol=1e-14, atol=1e-14)
    return float(np.hypot(s.y[0, -1], s.y[3, -1]))


@pytest.fixture(scope="module")
def long_family():
    return hill.family(np.linspace(0.01, 0.72, 360))


def test_true_closure_along_the_family(long_family):
    fam = long_family
    assert np.all(fam.success)
    assert np.max(fam.residual) <= 1e-12          # the reported (true) closure
    assert fam.nsteps[-1] > 20                     # the error control raised the step count
    for i in (100, 200, 270, 359):                 # m ~ 0.21, 0.41, 0.54, 0.72
        assert _true_closure(fam.ms[i], fam.y0[i]) <= 1e-11
    # the fixed 20 steps of before are rejected, not reported as success
    with pytest.raises(RuntimeError, match="closure"):
        hill.variation_orbit(fam.ms[359], guess=fam.y0[359, [0, 3]], max_nsteps=20)


def test_no_false_success_far_out():
    """m = 1: the cold start is far from the orbit. Either a clear failure, or an orbit
    whose independently checked closure meets the tolerance (never a wrong success)."""
    try:
        orb = hill.variation_orbit(1.0)
    except RuntimeError as exc:
        assert any(w in str(exc) for w in ("converge", "diverge", "closure", "another"))
    else:
        assert _true_closure(1.0, orb.y0) <= 1e-11
    fam = hill.family([1.0])
    if fam.status[0] == 0:
        assert _true_closure(1.0, fam.y0[0]) <= 1e-11
    else:
        assert np.isnan(fam.c[0])


def test_loss_of_stability_located(long_family):
    """S crosses +1 at m = 0.195... (REFERENCE.md): located to 1e-10 in m."""
    sp = [p for p in long_family.special if p["kind"] == "S=+1"]
    assert len(sp) == 1
    m_star = sp[0]["m"]
    assert 0.195 < m_star < 0.196
    assert sp[0]["residual"] <= 1e-12
    guess = sp[0]["y0"][[0, 3]]
    below = hill.variation_orbit(m_star - 1e-10, guess=guess)
    above = hill.variation_orbit(m_star + 1e-10, guess=guess)
    assert below.stability_index < 1 < above.stability_index
    assert below.stable and not above.stable and np.isnan(above.c)
    # the same point from the library function on its own bracket
    p = hill.locate_stability_change(0.19, 0.2)
    assert abs(p["m"] - m_star) < 1e-10


def test_cusp_orbit_region(long_family):
    """x'(T/4) -> 0: the cusp orbit of maximum lunation (Hill 1878, m ~ 0.56) is reached
    with the true closure error reported."""
    from scipy.optimize import brentq
    fam = long_family
    vx = fam.quarter_state[:, 2]
    i = int(np.nonzero(vx[:-1]*vx[1:] < 0)[0][0])
    assert 0.5 < fam.ms[i] < 0.6

    def f(m):
        return hill.variation_orbit(m, guess=fam.y0[i, [0, 3]]).quarter_state[2]
    m_cusp = brentq(f, fam.ms[i], fam.ms[i + 1], xtol=1e-12)
    orb = hill.variation_orbit(m_cusp, guess=fam.y0[i, [0, 3]])
    assert 0.55 < m_cusp < 0.57
    assert abs(orb.quarter_state[2]) < 1e-9
    assert orb.residual <= 1e-12 and _true_closure(m_cusp, orb.y0) <= 1e-11


def test_family_bitwise_independent_of_threads_and_matches_single_orbits():
    fam = hill.family(np.linspace(0.05, 0.15, 300), chunk_size=64)
    for i in (0, 77, 150, 299):
        one = hill.variation_orbit(fam.ms[i])
        assert abs(fam.c[i] - one.c) <= 1e-13
        assert abs(fam.y0[i, 0] - one.y0[0]) <= 1e-14


def test_henon_units():
    """Henon's form x'' - 2 y' = 3 x - x/r^3, y'' + 2 x' = -y/r^3: the converted variation
    orbit is periodic with period 2 pi m there, and Gamma = 3 x^2 + 2/r - v^2 of the
    converted state equals -I m^(-2/3)."""
    m = 0.3
    fam = hill.family(np.linspace(0.1, m, 60))
    y0 = fam.y0[-1]
    yh = hill.to_henon(m, y0)
    assert np.allclose(hill.from_henon(m, yh), y0, rtol=1e-15, atol=0)
    x, y, vx, vy = yh
    gamma = 3*x*x + 2/np.hypot(x, y) - vx*vx - vy*vy
    assert gamma == pytest.approx(hill.henon_gamma(m, fam.jacobi[-1]), rel=1e-13)

    def henon(t, s):
        x, y, vx, vy = s
        r3 = np.hypot(x, y)**3
        return [vx, vy, 2*vy + 3*x - x/r3, -2*vx - y/r3]
    sol = conmech.solve_ivp(henon, (0, 2*np.pi*m), yh, method="VERNER98", rtol=1e-13,
                            atol=1e-13)
    assert np.max(np.abs(sol.y[:, -1] - yh)) < 1e-9
