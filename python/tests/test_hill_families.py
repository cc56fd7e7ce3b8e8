"""Families of Hénon's classification of Hill's problem (Hénon 1969, A&A 1, 223), in his
units, continued by the general pseudo-arclength continuation, against published values:
A. B. Batkhin's data set of the families of symmetric periodic solutions of the plane
Hill problem (github.com/abbat06/Hill2D, files Libration/a/a.dat, Satellite/f/f.dat,
Satellite/README.md; columns x(0), p_y(0) = y'(0) + x(0), T, C = Gamma, stability
index), and closed forms of the linearisation at the Lagrange points."""
import numpy as np
import pytest

import conmech
from conmech import hill, hill_families as hf, stability


def _closure(y0, period):
    r = conmech.solve_ivp(hf.system(), (0, period), y0, method="VERNER98", rtol=1e-13,
                          atol=1e-13)
    return float(np.max(np.abs(r.y[:, -1] - y0)))


def _henon_potential(q):
    """V = -(3/2) x^2 - 1/r (Hénon's units; the rotating frame is omega = -1)."""
    x, y = q
    r = np.hypot(x, y)
    v = -1.5*x*x - 1.0/r
    g = np.array([-3*x + x/r**3, y/r**3])
    h = np.array([[-3 + 1/r**3 - 3*x*x/r**5, -3*x*y/r**5],
                  [-3*x*y/r**5, 1/r**3 - 3*y*y/r**5]])
    return v, g, h


def test_lyapunov_family_a_of_l1():
    """The orbits about L1 (Hénon's family a) tend, as the amplitude a -> 0, to the linear oscillation: period
    2 pi/sqrt(2 sqrt 7 - 1), Gamma = 3^(4/3), stability index cosh(lambda T) with
    lambda^2 = 1 + 2 sqrt 7 (closed forms of the linearisation at L2). The corrections
    start at a^2 (the energy above L1 is O(a^2)): a fit c0 + c2 a^2 + c3 a^3 through three
    amplitudes extrapolates to a = 0 with an O(a^4) error."""
    amps = np.array([1e-3, 2e-3, 3e-3])
    orbs = [hf.lyapunov_orbit(a) for a in amps]
    w = np.linalg.solve(np.stack([np.ones(3), amps**2, amps**3]), [1.0, 0.0, 0.0])
    T0 = w @ [o.period for o in orbs]
    G0 = w @ [hf.gamma(o.y0) for o in orbs]
    S0 = w @ [o.stability_index for o in orbs]
    o1 = orbs[1]
    assert T0 == pytest.approx(hf.PERIOD_L, abs=1e-8)    # at a = 1e-3 off by 5e-6
    assert G0 == pytest.approx(hf.GAMMA_L, abs=1e-8)     # at a = 1e-3 off by 3.5e-5
    lam = np.sqrt(1 + 2*np.sqrt(7))
    assert S0 == pytest.approx(np.cosh(lam*hf.PERIOD_L), rel=1e-7)
    # the mirror orbit about L2 (family c) has the same period
    assert hf.lyapunov_orbit(2e-3, side=-1).period == pytest.approx(o1.period, rel=1e-12)
    br = hf.family(o1, max_points=12, ds=0.02)
    assert br.success and len(br) == 12
    assert np.all(np.diff(br.energy) < 0)              # Gamma falls away from L1
    assert np.all(br.stability_index > 1)              # unstable (a saddle direction)
    k = len(br) - 1
    assert _closure(br.y0[k], br.p[k]) < 1e-9
    r = stability.transverse(_henon_potential, br.y0[k], br.p[k], omega=-1.0, rtol=1e-12)
    assert r["half_trace"] == pytest.approx(br.stability_index[k], rel=1e-7)
    # the published member at C = 4 (a.dat: x0 0.775219130, p_y0 0.156502880,
    # T 3.08230098, S 862.347092), reached along the continued family
    q = hf.orbit_at_gamma(hf.family(o1, max_points=40, ds=0.05), 4.0)
    assert q.y0[0] == pytest.approx(0.775219130, abs=1e-8)
    assert q.y0[3] + q.y0[0] == pytest.approx(0.156502880, abs=1e-8)
    assert q.period == pytest.approx(3.08230098, abs=1e-8)
    assert q.stability_index == pytest.approx(862.347092, rel=1e-8)


def test_family_g_loses_stability_where_the_variation_orbits_do():
    """Family g (direct satellites) continued from the Kepler limit in Hénon's units: S
    crosses +1 (located as a branch point) at the Hénon period T = 2 pi m* and at the
    Gamma of Hill's variation orbit at m* = 0.19510399668... located by the independent
    fast path in Hill's units (conmech.hill), and at the published C = 4.49998584 where
    family g' meets g (Hill2D, Satellite/README.md)."""
    o = hf.satellite_orbit(0.1, "g")
    assert o.period == pytest.approx(2*np.pi/(0.1**-1.5 - 1), rel=1e-2)
    br = hf.family(o, max_points=40)
    assert br.success
    bp = [s for s in br.special if s.kind == "branch point"]
    assert len(bp) == 1 and bp[0].kind == "S=+1"
    assert bp[0].located and bp[0].residual < 1e-9
    ref = hill.locate_stability_change(0.19, 0.2)
    assert bp[0].p == pytest.approx(2*np.pi*ref["m"], abs=1e-10)
    v = hill.variation_orbit(ref["m"])
    assert hf.gamma(bp[0].y0) == pytest.approx(hill.henon_gamma(ref["m"], v.jacobi),
                                               abs=1e-7)
    assert hf.gamma(bp[0].y0) == pytest.approx(4.49998584, abs=1e-8)
    assert np.all(br.stable[br.p < bp[0].p - 1e-6]) and not br.stable[-1]


def test_family_f_retrograde_satellites():
    """Family f (retrograde satellites): the period tends to 2 pi/(n + 1) in the Kepler
    limit (n = r^(-3/2); tidal corrections O(r^3)). From the published orbit at C = 4
    (f.dat: x0 0.204214888, p_y0 -2.22862633, T 0.53674099, S 0.851754132) the family is
    continued to Gamma < -1; its members at C = 0 and C = -1 equal the published ones,
    every orbit closes, and the family stays stable (|S| < 1) as Hénon (1969) found."""
    small = hf.satellite_orbit(0.02, "f")
    n = 0.02**-1.5
    assert small.period == pytest.approx(2*np.pi/(n + 1), rel=1e-4)
    x0, py0 = 0.204214888, -2.22862633
    o = stability.symmetric_orbit(hf.system(), [x0, 0, 0, py0 - x0], [3], [1, 2], 0.54,
                                  period_factor=2, free_time=True)
    assert o.period == pytest.approx(0.53674099, abs=1e-8)
    assert o.stability_index == pytest.approx(0.851754132, abs=1e-7)
    assert hf.gamma(o.y0) == pytest.approx(4.0, abs=1e-8)
    br = hf.family(o, max_points=60)
    assert br.success and br.energy[-1] < -1
    assert br.energy[0] == pytest.approx(4.0, abs=1e-8)
    assert np.all(np.abs(br.stability_index) < 1) and not br.special
    for k in (30, 59):
        assert _closure(br.y0[k], br.p[k]) < 1e-9
    for C, x0, py0, T, S in ((0.0, 0.659658383, -1.42296493, 2.52523443, -0.508086833),
                             (-1.0, 1.03399552, -1.44424671, 4.07953342, -0.645974036)):
        q = hf.orbit_at_gamma(br, C)
        assert q.y0[0] == pytest.approx(x0, abs=1e-8)
        assert q.y0[3] + q.y0[0] == pytest.approx(py0, abs=1e-8)
        assert q.period == pytest.approx(T, abs=1e-8)
        assert q.stability_index == pytest.approx(S, abs=1e-7)
    with pytest.raises(ValueError, match="kind"):
        hf.satellite_orbit(0.1, "h")
    with pytest.raises(ValueError, match="amplitude"):
        hf.lyapunov_orbit(0.0)
    with pytest.raises(ValueError, match="not reached"):
        hf.orbit_at_gamma(br, 50.0)


def test_family_g_prime_by_branch_switching():
    """At g's loss of stability (S = +1, Gamma = 4.49998584) the singly symmetric family
    g' branches off (Hill2D, Satellite/README.md: g' meets g there, is stable on
    C in (4.271428, 4.499986) and meets the two-orbit family Ha at C = 4.271428, i.e. its
    S passes -1 there). Branch switching in the conservative family (continued in the
    period): the new orbits are genuine, stable down to a period doubling located at the
    published Gamma, and are not family g's (other periods at the same Gamma)."""
    g = hf.family(hf.satellite_orbit(0.1, "g"), max_points=40)
    bp = [s for s in g.special if s.kind == "branch point"][0]
    gp = stability.switch_branch_point(hf.system(), g, bp, direction=-1, ds=0.02,
                                       ds_max=0.1, max_points=32,
                                       energy=lambda y, p: hf.gamma(y))
    assert gp.success and gp.kernel_ratio < 1e-4
    assert [s.kind for s in gp.special] == ["period doubling"]
    pd = gp.special[0]
    assert pd.located and pd.residual < 1e-9
    assert hf.gamma(pd.y0) == pytest.approx(4.271428, abs=1e-6)
    before = gp.p < pd.p
    assert np.all(np.abs(gp.stability_index[before]) < 1 + 1e-9)
    assert not np.all(np.abs(gp.stability_index[~before]) < 1)
    k = int(np.argmin(np.abs(gp.p - pd.p)))
    assert _closure(gp.y0[k], gp.p[k]) < 1e-9
    # family g at the same Gamma has a much shorter period
    tg = np.interp(-gp.energy[k], -g.energy, g.p)
    assert gp.p[k] - tg > 0.5


def test_published_orbit_of_family_g_by_orbit_at_gamma():
    """Family g at C = 4.34943072, past its loss of stability (Hill2D, Satellite/g/g.dat,
    row 466: x0 -0.295540401, p_y0 -1.93257001, T 1.35204787, S 1.20037665; the table
    lists the orbit at its left crossing of the x axis). Reached along the continued family
    by orbit_at_gamma at the left crossing (side=-1); at the right one (the default) the
    same orbit mirrored, x0 -> -x0."""
    g = hf.family(hf.satellite_orbit(0.1, "g"), max_points=40)
    q = hf.orbit_at_gamma(g, 4.34943072, side=-1)
    assert q.y0[0] == pytest.approx(-0.295540401, abs=1e-8)
    assert q.y0[3] + q.y0[0] == pytest.approx(-1.93257001, abs=1e-8)
    assert q.period == pytest.approx(1.35204787, abs=1e-8)
    assert q.stability_index == pytest.approx(1.20037665, abs=1e-7)
    r = hf.orbit_at_gamma(g, 4.34943072)
    assert r.y0[0] == pytest.approx(0.295540401, abs=1e-8)
    assert r.period == pytest.approx(q.period, abs=1e-10)
    with pytest.raises(ValueError, match="side"):
        hf.on_axis(q.y0, q.period, side=2)
