"""Branch switching at a branch point and Neimark-Sacker points from Python.

Closed forms by construction (normal forms on the cycle x = cos t, y = sin t, period
2 pi, multipliers known exactly): Kuznetsov, Elements of Applied Bifurcation Theory
(2004), sec. 3.4 (pitchfork normal form z' = a z - z^3) and sec. 4.6 / 10.2
(Neimark-Sacker: a complex pair exp(2 pi (p - 3) +- 2 pi i alpha) through |mu| = 1)."""
import numpy as np
import pytest

import conmech
from conmech import stability


def pitchfork_cycle(t, s, p):
    """The cycle x^2 + y^2 = 1 and z' = (p - 2) z - z^3 (symmetric under z -> -z): the
    z-multiplier exp(2 pi (p - 2)) passes +1 at p = 2, where the orbits with
    z^2 = p - 2 (z = const) branch off (a symmetry-breaking pitchfork)."""
    x, y, z = s
    r2 = x*x + y*y
    return [x*(1 - r2) - y, y*(1 - r2) + x, (p - 2.0)*z - z**3]


def _closure(fun, y0, period, p):
    r = conmech.solve_ivp(lambda t, s: fun(t, s, p), (0, period), y0, method="VERNER98",
                          rtol=1e-13, atol=1e-13)
    return float(np.max(np.abs(r.y[:, -1] - y0)))


def test_branch_point_switching_pitchfork():
    br = stability.continuation(pitchfork_cycle, [1, 0, 0], 6.3, p0=1.5, ds=0.1,
                                ds_max=0.2, p_range=(0, 2.4), rtol=1e-11, atol=1e-11)
    assert br.success
    bps = [s for s in br.special if s.kind == "branch point"]
    assert len(bps) == 1 and bps[0].p == pytest.approx(2.0, abs=1e-8)
    assert bps[0].located and bps[0].residual < 1e-8
    # on the old (symmetric) branch z stays 0
    assert np.max(np.abs(br.y0[:, 2])) < 1e-12
    new = stability.switch_branch_point(pitchfork_cycle, br, bps[0], ds=0.05, ds_max=0.1,
                                        max_points=6, rtol=1e-11, atol=1e-11)
    assert new.success and len(new) == 6
    assert new.kernel_ratio < 1e-4
    p, z = new.p[1:], new.y0[1:, 2]
    assert np.all(p > 2) and np.all(z > 0)             # the new branch, not the old one
    assert np.allclose(z**2, p - 2, atol=1e-9)         # closed form
    assert np.allclose(new.period, 2*np.pi, atol=1e-9)
    for k in (1, 5):                                   # genuine orbits: true closure
        assert _closure(pitchfork_cycle, new.y0[k], new.period[k], new.p[k]) < 1e-9
    # the new orbits are stable (z-multiplier exp(-4 pi (p - 2))), the old ones past 2 not
    mu = new.multipliers[-1]
    assert np.min(np.abs(mu - np.exp(-4*np.pi*(new.p[-1] - 2)))) < 1e-6
    assert np.all(new.stable[1:]) and not br.stable[-1]
    mirror = stability.switch_branch_point(pitchfork_cycle, br, bps[0], direction=-1,
                                           ds=0.05, max_points=3)
    assert mirror.success and mirror.y0[-1, 2] < -0.05
    with pytest.raises(ValueError, match="branch point"):
        stability.switch_branch_point(pitchfork_cycle, br, br, ds=0.05)
    with pytest.raises(ValueError, match="not an option"):
        stability.switch_branch_point(pitchfork_cycle, br, bps[0], free=[0])


def transcritical_cycle(t, s, p):
    """The cycle, coupled to z (x' gets 0.3 z x: the period changes along the new branch),
    and z' = (p - 2) z - z^2: the branches z = 0 and z = p - 2 cross transversally at
    p = 2 (a transcritical branch point; closed form by construction)."""
    x, y, z = s
    r2 = x*x + y*y
    return [x*(1 - r2) - y + 0.3*z*x, y*(1 - r2) + x, (p - 2.0)*z - z*z]


def test_branch_point_switching_transcritical():
    """Both sides of the second branch z = p - 2 (not orthogonal to the first in (z, p)):
    every new orbit on it, p moving both ways from 2, periods off 2 pi."""
    br = stability.continuation(transcritical_cycle, [1, 0, 0], 6.3, p0=1.5, ds=0.1,
                                ds_max=0.2, p_range=(0, 2.4))
    bp = [s for s in br.special if s.kind == "branch point"]
    assert len(bp) == 1 and bp[0].p == pytest.approx(2.0, abs=1e-8)
    assert bp[0].located and bp[0].residual < 1e-8
    for d in (1, -1):
        new = stability.switch_branch_point(transcritical_cycle, br, bp[0], direction=d,
                                            ds=0.05, max_points=5)
        assert new.success and new.kernel_ratio < 1e-4
        assert np.allclose(new.y0[:, 2], new.p - 2, atol=1e-10)
        assert d*(new.p[-1] - 2) > 0.1 and abs(new.period[-1] - 2*np.pi) > 1e-3
        assert _closure(transcritical_cycle, new.y0[-1], new.period[-1], new.p[-1]) < 1e-9


def ns_cycle(t, s, p, alpha=0.4472135954999579):
    """The cycle and v' = (p - 3 + i alpha) v - |v|^2 v: the pair exp(2 pi (p - 3))
    exp(+-2 pi i alpha) leaves the unit circle at p = 3 (Neimark-Sacker); the radial
    multiplier exp(-4 pi) stays inside."""
    x, y, u, w = s
    r2 = x*x + y*y
    q2 = u*u + w*w
    return [x*(1 - r2) - y, y*(1 - r2) + x, (p - 3)*u - alpha*w - q2*u,
            (p - 3)*w + alpha*u - q2*w]


def test_neimark_sacker_from_python():
    br = stability.continuation(ns_cycle, [1, 0, 0, 0], 6.3, p0=2.6, ds=0.1, ds_max=0.2,
                                p_range=(0, 3.4), rtol=1e-11, atol=1e-11)
    assert br.success
    assert [s.kind for s in br.special] == ["Neimark-Sacker"]
    ns = br.special[0]
    assert ns.located and ns.residual < 1e-8
    assert ns.p == pytest.approx(3.0, abs=1e-8)
    mu = ns.multipliers
    pair = mu[np.abs(mu.imag) > 1e-3]
    assert pair.size == 2 and np.allclose(np.abs(pair), 1.0, atol=1e-7)
    expected = np.exp(2j*np.pi*0.4472135954999579*np.array([1, -1]))
    assert all(np.min(np.abs(expected - m)) < 1e-7 for m in pair)
    assert np.all(br.stable[br.p < 3 - 1e-6]) and not np.any(br.stable[br.p > 3 + 1e-6])
