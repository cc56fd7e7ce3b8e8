"""Pseudo-arclength continuation of periodic orbits and their special points.

The period-doubling, branch-point and Neimark-Sacker points against closed forms are
tested in Fortran (test/test_continuation.f90, a 7-dimensional normal form); here the
Python API on built-in and callback systems."""
import numpy as np
import pytest

from conmech import hill, stability, systems


def fold_cycle(t, y, p):
    """r' = r (p + r^2 - r^4), theta' = 1 + r^2: a fold of cycles at p = -1/4 (closed
    form: r^2 = 1/2, period 2 pi/(1 + 1/2) = 4 pi/3)."""
    r2 = y[0]**2 + y[1]**2
    g = p + r2 - r2*r2
    return [y[0]*g - y[1]*(1 + r2), y[1]*g + y[0]*(1 + r2)]


def test_hill_loss_of_stability_by_continuation():
    """The variation family continued in m by symmetric shooting (adaptive DOP853 on the
    variational equations): S crosses +1 at m = 0.195... (REFERENCE.md), located as a
    branch point; it agrees to 1e-10 with the fast path's own location (fixed-step,
    error-controlled, Illinois in m): two independent methods."""
    o = hill.variation_orbit(0.15)
    br = stability.continuation(systems.hill(m=0.15), o.y0, 2*np.pi, param="m",
                                free=[0, 3], targets=[0, 3], period_factor=4,
                                conservative=True, ds=0.01, ds_max=0.05, p_range=(0, 0.25),
                                rtol=1e-12, atol=1e-12)
    assert br.success and br.param == "m"
    assert np.allclose(br.period, 2*np.pi)
    bp = [s for s in br.special if s.kind == "branch point"]
    assert len(bp) == 1 and bp[0].kind == "S=+1"         # one event, both names
    assert bp[0].located and bp[0].residual < 1e-10
    assert 0.195 < bp[0].p < 0.196
    assert bp[0].stability_index == pytest.approx(1.0, abs=1e-9)
    ref = hill.locate_stability_change(0.19, 0.2)
    assert abs(bp[0].p - ref["m"]) < 1e-10
    # stable before, unstable after; S from the continuation = S of the fast path
    assert np.all(br.stable[br.p < bp[0].p - 1e-6]) and not np.any(br.stable[br.p > bp[0].p])
    fast = hill.variation_orbit(br.p[1], guess=br.y0[1, [0, 3]])
    assert br.stability_index[1] == pytest.approx(fast.stability_index, abs=1e-9)


def test_fold_on_a_callback_system():
    br = stability.continuation(fold_cycle, [1, 0], 3.0, p0=0.0, direction=-1, ds=0.05,
                                max_points=18, energy=lambda y, p: y[0]**2 + y[1]**2)
    assert br.success and len(br) == 18
    folds = [s for s in br.special if s.kind == "fold"]
    assert len(folds) == 1 and len(br.special) == 1
    f = folds[0]
    assert f.located and f.residual < 1e-9 and abs(f.test) < 1e-8
    assert f.p == pytest.approx(-0.25, abs=1e-9)
    assert np.sum(f.y0**2) == pytest.approx(0.5, abs=1e-5)
    assert f.period == pytest.approx(4*np.pi/3, abs=1e-5)
    # the branch turns: outer stable cycles, then inner unstable ones
    assert br.p[-1] > -0.25 and br.energy[-1] < 0.5 < br.energy[0]
    assert br.stable[0] and not br.stable[-1]


def test_builtin_limit_cycle_against_single_orbits():
    """Van der Pol's limit cycle continued in mu: every point is a periodic orbit of the
    built-in system (checked by independent shooting at the last point)."""
    br = stability.continuation(systems.vanderpol(1.0), [2.0, 0.0], 6.66, param="mu",
                                ds=0.1, ds_max=0.3, p_range=(0.5, 2.0), max_points=30)
    assert br.success and br.p[-1] >= 2.0
    assert not br.special and np.all(br.stable)
    one = stability.periodic_orbit(systems.vanderpol(br.p[-1]), br.y0[-1], br.period[-1])
    assert one.period == pytest.approx(br.period[-1], abs=1e-8)
    assert np.all(br.residual < 1e-8)


def test_bad_input_and_failures():
    with pytest.raises(ValueError, match="param"):
        stability.continuation(systems.vanderpol(1.0), [2, 0], 6.6, param="nope")
    with pytest.raises(ValueError, match="p0"):
        stability.continuation(fold_cycle, [1, 0], 3.0)
    with pytest.raises(ValueError, match="period"):
        stability.continuation(fold_cycle, [1, 0], -3.0, p0=0.0)
    with pytest.raises(TypeError):
        stability.continuation("vanderpol", [2, 0], 6.6, p0=1.0)
    # a degenerate start: the harmonic oscillator's orbits are not isolated
    with pytest.raises(RuntimeError, match="isolated"):
        stability.continuation(systems.harmonic(1.0), [1, 0], 2*np.pi, param="omega")

    # the model breaks down below p = -0.1: the branch so far, and the parameter value
    def broken(t, y, p):
        return fold_cycle(t, y, p) if p >= -0.1 else [np.nan, np.nan]
    br = stability.continuation(broken, [1, 0], 3.0, p0=0.0, direction=-1, ds=0.05,
                                max_points=30)
    assert not br.success and len(br) >= 2
    assert "stopped at p = -" in br.message
    assert -0.1 - 1e-6 <= br.p[-1] < -0.09


# ------------------------------------------------------- transverse linearisation (2 DOF)

def _henon_heiles(t, s):
    x, y, vx, vy = s
    return [vx, vy, -(x + 2*x*y), -(y + x*x - y*y)]


def _hh_potential(q):
    """Henon and Heiles (1964): V = (x^2 + y^2)/2 + x^2 y - y^3/3."""
    x, y = q
    return (0.5*(x*x + y*y) + x*x*y - y**3/3, [x + 2*x*y, y + x*x - y*y],
            [[1 + 2*y, 2*x], [2*x, 1 - 2*y]])


def test_transverse_henon_heiles_loop_orbit():
    """A loop orbit (symmetric about the y axis, period fixed at 1.97 pi, E ~ 0.05): the
    2 x 2 multipliers of N'' + Phi N = 0 are the non-trivial ones of the 4 x 4 monodromy."""
    o = stability.symmetric_orbit(_henon_heiles, [0, 0.2, 0.25, 0], [1, 2], [0, 3],
                                  1.97*np.pi, period_factor=2, rtol=1e-13, atol=1e-13)
    assert abs(o.y0[2]) > 0.1                        # a loop, not the line orbit
    r = stability.transverse(_hh_potential, o.y0, o.period, rtol=1e-13,
                             t=np.linspace(0, o.period, 9))
    assert r["closure"] < 1e-11
    assert r["half_trace"] == pytest.approx(r["stability_index4"], abs=1e-12)
    assert r["det"] == pytest.approx(1.0, abs=1e-12)
    mu4 = np.linalg.eigvals(r["monodromy4"])
    nontrivial = mu4[np.argsort(np.abs(mu4 - 1))][2:]
    assert np.allclose(np.sort_complex(nontrivial), np.sort_complex(r["multipliers"]),
                       atol=1e-10)
    # Phi has the orbit's symmetry: Phi(t) = Phi(T - t)
    assert np.allclose(r["phi"], r["phi"][::-1], atol=1e-9)
    with pytest.raises(ValueError):
        stability.transverse(_hh_potential, [0, 0.2, 0.25], o.period)


def test_transverse_general_equals_hill():
    """Hill's problem as V = -F, omega = -m: the general construction gives the perigee
    constant's half trace (the fast path's S by symmetry) to 1e-12."""
    m = hill.M_HILL
    orb = hill.variation_orbit(m)

    def pot(q):
        x, y = q
        r = np.hypot(x, y)
        v = -(1/r + 1.5*m*m*x*x)
        g = [x/r**3 - 3*m*m*x, y/r**3]
        h = [[1/r**3 - 3*x*x/r**5 - 3*m*m, -3*x*y/r**5], [-3*x*y/r**5, 1/r**3 - 3*y*y/r**5]]
        return v, g, h
    r = stability.transverse(pot, orb.y0, orb.period, omega=-m, rtol=1e-14)
    assert r["half_trace"] == pytest.approx(orb.stability_index, abs=1e-12)
    assert 1 + np.arccos(r["half_trace"])/(2*np.pi) == pytest.approx(hill.C_HILL, abs=1e-12)


# --------------------------------------------------------------------- equilibria

def test_equilibria_of_the_pendulum_from_a_grid():
    eqs = stability.equilibria(systems.pendulum(g=9.81, l=1.0),
                               stability.grid([(-4, 4), (-1, 1)], [9, 3]))
    assert [round(e.y[0], 12) for e in eqs] == [round(-np.pi, 12), 0.0, round(np.pi, 12)]
    kinds = [e.kind for e in eqs]
    assert kinds == ["unstable", "centre", "unstable"] and eqs[0].saddle
    assert np.max(eqs[1].eigenvalues.imag) == pytest.approx(np.sqrt(9.81), abs=1e-10)


def test_bead_on_hoop_equilibria_and_lagrange_dirichlet():
    """REFERENCE.md: off-axis equilibria cos th* = g/(R W^2) when W^2 > g/R, oscillating
    at W sin th*; th = 0 is then unstable."""
    g, R, W = 9.81, 1.0, 5.0
    sys = systems.bead_hoop(m=1.0, R=R, omega=W, g=g)
    eqs = stability.equilibria(sys, stability.grid([(-3, 3), (0, 0)], [13, 1]))
    th = np.arccos(g/(R*W**2))
    ys = np.array([e.y[0] for e in eqs])
    for target in (-th, 0.0, th):
        assert np.min(np.abs(ys - target)) < 1e-10
    off = [e for e in eqs if abs(abs(e.y[0]) - th) < 1e-10]
    assert all(e.kind == "centre" for e in off)
    assert np.max(off[0].eigenvalues.imag) == pytest.approx(W*np.sin(th), rel=1e-9)
    assert [e for e in eqs if abs(e.y[0]) < 1e-10][0].kind == "unstable"

    # the effective potential in the rotating frame: V = -m g R cos th - m R^2 W^2 sin^2/2
    def V(q):
        return -g*R*np.cos(q[0]) - 0.5*R**2*W**2*np.sin(q[0])**2
    ok, w, H = stability.lagrange_dirichlet_potential(V, [th])
    exact = (R*W*np.sin(th))**2     # V''(th*) = m R^2 W^2 sin^2 th*
    assert ok and H[0, 0] == pytest.approx(exact, rel=1e-7)
    ok0, w0, _ = stability.lagrange_dirichlet_potential(V, [0.0])
    assert not ok0 and w0[0] < 0
    ok2, _, H2 = stability.lagrange_dirichlet_potential(
        V, [th], hessian=lambda q: [[R**2*W**2*np.sin(q[0])**2]])
    assert ok2 and H2[0, 0] == pytest.approx(exact, rel=1e-14)


def test_equilibria_callback_and_failures():
    m = hill.M_HILL
    xe = (1/(3*m*m))**(1/3)

    def hill_rhs(t, s):
        x, y, vx, vy = s
        r3 = np.hypot(x, y)**3
        return [vx, vy, 2*m*vy - x/r3 + 3*m*m*x, -2*m*vx - y/r3]
    eqs = stability.equilibria(hill_rhs, [[xe*1.1, 0.1, 0, 0], [-xe*0.9, 0, 0, 0],
                                          [xe*0.95, -0.05, 0, 0]])
    assert len(eqs) == 2
    assert eqs[0].y[0] == pytest.approx(-xe, rel=1e-10) and eqs[1].y[0] == pytest.approx(xe)
    assert all(e.kind == "unstable" and e.saddle for e in eqs)
    with pytest.raises(RuntimeError):
        stability.find_equilibrium(lambda t, y: [1.0, y[1]], [0.0, 0.0])
    with pytest.raises(ValueError):
        stability.equilibria(hill_rhs, [])


def test_plots(tmp_path):
    mpl = pytest.importorskip("matplotlib")
    mpl.use("Agg")
    import matplotlib.pyplot as plt
    br = stability.continuation(fold_cycle, [1, 0], 3.0, p0=0.0, direction=-1, ds=0.08,
                                max_points=10)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    stability.plot_branch(br, axes[0], y="period")
    stability.plot_multipliers(br, axes[1])
    fig.savefig(tmp_path / "branch.png")
    plt.close(fig)
    assert (tmp_path / "branch.png").stat().st_size > 1000


# ------------------------------------------------------------------ the family program

def test_family_program_resumes(tmp_path):
    """`fpm run family`: Hill's variation orbits continued in m past the loss of stability
    (branch point at m = 0.195...), interrupted after 5 points and resumed."""
    import shutil
    import subprocess
    from pathlib import Path
    if shutil.which("fpm") is None:
        pytest.fail("fpm is not on PATH: run the tests through scripts/test.sh")
    root = Path(__file__).resolve().parents[2]
    out, sp = tmp_path / "b.csv", tmp_path / "s.csv"
    args = ["fpm", "run", "family", "--", "--system", "hill", "--params", "0.15,1",
            "--param", "1", "--y0", "0.8,0,0,1", "--period", str(2*np.pi), "--free", "1,4",
            "--targets", "1,4", "--period-factor", "4", "--conservative", "--p-max", "0.25",
            "--ds", "0.005", "--ds-max", "0.01", "--out", str(out), "--special", str(sp)]
    r = subprocess.run(args + ["--max-points", "5"], cwd=root, capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stderr
    first = np.loadtxt(out, delimiter=",", skiprows=1)
    assert first.shape[0] == 5 and first[-1, 1] < 0.195
    r = subprocess.run(args + ["--max-points", "12"], cwd=root, capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stderr
    assert "resuming after 5 points" in r.stdout
    rows = np.loadtxt(out, delimiter=",", skiprows=1)
    assert np.array_equal(rows[:5], first) and rows[-1, 1] > 0.195
    assert np.all(np.diff(rows[:, 0]) == 1)
    lines = sp.read_text().splitlines()
    assert len(lines) == 2 and lines[1].startswith("branch point")
    assert abs(float(lines[1].split(",")[2]) - 0.19510399668) < 1e-9
    bad = subprocess.run(["fpm", "run", "family", "--", "--system", "nope", "--y0", "1",
                          "--period", "1"], cwd=root, capture_output=True, text=True)
    assert bad.returncode == 2 and "unknown --system" in bad.stderr


def _moebius(t, s, p):
    """The cycle x = cos t, y = sin t with (u, w) turning by half the angle (a Moebius band):
    in the half-angle frame xi' = diag(p - 1, -1) xi - |xi|^2 xi, so the multiplier
    -exp(2 pi (p - 1)) passes -1 at p = 1 and the doubled orbit (period 4 pi) has
    u^2 + w^2 = p - 1 (closed forms by construction)."""
    x, y, u, w = s
    r2 = x*x + y*y
    r = np.sqrt(r2)
    c, sn = x/r, y/r
    a, b = p - 1.0, -1.0
    q2 = u*u + w*w
    return [x*(1 - r2) - y, y*(1 - r2) + x,
            -0.5*w + 0.5*(a + b)*u + 0.5*(a - b)*(c*u + sn*w) - q2*u,
            0.5*u + 0.5*(a + b)*w + 0.5*(a - b)*(sn*u - c*w) - q2*w]


def test_period_doubling_and_branch_switching():
    br = stability.continuation(_moebius, [1, 0, 0, 0], 6.3, p0=0.7, ds=0.2, ds_max=0.3,
                                p_range=(0, 1.3), rtol=1e-10, atol=1e-10, locate_tol=1e-10)
    assert br.success and [s.kind for s in br.special] == ["period doubling"]
    pd = br.special[0]
    assert pd.located and pd.residual < 1e-8
    assert pd.p == pytest.approx(1.0, abs=1e-8)
    assert np.min(np.abs(pd.multipliers + 1)) < 1e-7
    b2 = stability.switch_period_doubling(_moebius, pd, ds=0.05, max_points=4, rtol=1e-10,
                                          atol=1e-10)
    assert b2.success and len(b2) == 4
    assert np.allclose(b2.period, 4*np.pi, atol=1e-9)
    assert np.all(b2.p[1:] > 1)
    assert np.allclose(b2.y0[:, 2]**2 + b2.y0[:, 3]**2, b2.p - 1, atol=1e-9)
    with pytest.raises(ValueError, match="period doubling"):
        stability.switch_period_doubling(_moebius, br)


def test_tolerances_checked():
    orb = hill.variation_orbit(hill.M_HILL)
    with pytest.raises((ValueError, RuntimeError), match="rtol"):
        hill.transverse(orb, rtol=1e300)
    with pytest.raises(ValueError, match="rtol"):
        stability.transverse(_hh_potential, [0, 0.2, 0.25, 0], 6.2, rtol=2.0)
    with pytest.raises(ValueError, match="rtol"):
        stability.continuation(fold_cycle, [1, 0], 3.0, p0=0.0, rtol=5.0)


def test_conservative_family_in_the_period():
    """Henon-Heiles loop orbits continued along their family (no parameter: the period is
    the continued quantity, the energy a function of the point): every point is a periodic
    orbit (independent closure check with Verner 9(8)), the energy changes monotonically,
    and the transverse linearisation gives each point's stability index."""
    import conmech
    o = stability.symmetric_orbit(_henon_heiles, [0, 0.2, 0.25, 0], [1, 2], [0, 3],
                                  1.97*np.pi, period_factor=2, rtol=1e-12, atol=1e-12)

    def energy(s, p):
        return _hh_potential(s[:2])[0] + 0.5*(s[2]**2 + s[3]**2)
    br = stability.continuation(_henon_heiles, o.y0, o.period, in_period=True,
                                conservative=True, direction=-1, ds=0.05, max_points=6,
                                energy=energy)
    assert br.success and br.param == "period" and len(br) == 6
    assert np.all(np.diff(br.p) < 0) and np.all(np.diff(br.energy) > 0)
    for y0, T in zip(br.y0[::2], br.p[::2]):
        s = conmech.solve_ivp(_henon_heiles, (0, T), y0, method="VERNER98", rtol=1e-13,
                              atol=1e-13)
        assert np.max(np.abs(s.y[:, -1] - y0)) < 1e-9
    r = stability.transverse(_hh_potential, br.y0[-1], br.p[-1], rtol=1e-13)
    assert r["half_trace"] == pytest.approx(br.stability_index[-1], abs=1e-8)
