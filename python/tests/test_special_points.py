"""Honest special points and the workflow of a continuation: every located point carries
its test-function value, the closure of its orbit by an independent integration and
`located`; a point the corrector cannot reach is "not located" (a computed orbit, never an
interpolated state); tighter tolerances never make a point worse; ranges end exactly on
their bounds; the first step leaves an equilibrium; the stability flag uses a round-off
aware tolerance."""
import numpy as np
import pytest

from conmech import hill, hill_families as hf, stability, systems


def fold_cycle(t, y, p):
    """r' = r (p + r^2 - r^4), theta' = 1 + r^2: a fold of cycles at p = -1/4 (closed
    form: r^2 = 1/2)."""
    r2 = y[0]**2 + y[1]**2
    g = p + r2 - r2*r2
    return [y[0]*g - y[1]*(1 + r2), y[1]*g + y[0]*(1 + r2)]


def _r2(y, p):
    return y[0]**2 + y[1]**2


def test_fold_located_with_its_test_value_and_closure():
    br = stability.continuation(fold_cycle, [1, 0], 3.0, p0=0.0, direction=-1, ds=0.05,
                                max_points=18)
    (f,) = br.special
    assert f.kind == "fold" and f.located and f.message == "located"
    assert f.p == pytest.approx(-0.25, abs=1e-10)
    assert abs(f.test) < 1e-8                  # the p-component of the tangent
    assert f.residual < 1e-9                   # |y(T) - y0| by an independent integration


def test_a_corrector_that_must_fail_gives_not_located():
    """The model cannot be evaluated within 1e-6 of the fold (it returns NaN there): the
    locator's trials fail as they approach it, and the special point says "not located":
    its orbit is the computed one nearest the sign change (outside the window, with its
    own test value and closure), never an interpolation."""
    def broken(t, y, p):
        return [np.nan, np.nan] if abs(p + 0.25) < 1e-6 else fold_cycle(t, y, p)
    br = stability.continuation(broken, [1, 0], 3.0, p0=0.0, direction=-1, ds=0.05,
                                max_points=18)
    assert br.success
    (f,) = br.special
    assert f.kind == "fold" and not f.located
    assert f.message.startswith("not located")
    assert abs(f.p + 0.25) >= 1e-6 and abs(f.test) > 0
    assert f.residual < 1e-9                    # a true orbit
    assert f.p_bracket[0] <= f.p <= f.p_bracket[1]


def test_hill_family_in_m_tight_tolerances_are_not_worse():
    """The acceptance check's case at three tolerance levels: m* to 1e-10 each time, the
    error never growing as rtol and locate_tol shrink."""
    m_star = 0.19510399668175
    o = hill.variation_orbit(0.15)
    errs = []
    for kw in ({}, {"rtol": 1e-12, "atol": 1e-12}, {"rtol": 1e-13, "atol": 1e-13,
                                                     "locate_tol": 1e-13}):
        br = stability.continuation(systems.hill(m=0.15), o.y0, 2*np.pi, param="m",
                                    free=[0, 3], targets=[0, 3], period_factor=4,
                                    conservative=True, p_range=(0, 0.25), **kw)
        (s,) = br.special
        assert s.located and s.residual < 1e-10
        errs.append(abs(s.p - m_star))
    assert errs[0] < 1e-10
    assert errs[1] <= max(errs[0], 1e-11) and errs[2] <= max(errs[1], 1e-11)


def test_ranges_end_exactly_on_their_bounds():
    """p_range, period_range and energy_range: the last point lies on the bound (its orbit
    computed there), none beyond."""
    br = stability.continuation(fold_cycle, [1, 0], 3.0, p0=0.0, direction=-1, ds=0.05,
                                max_points=40, p_range=(-0.2, 1))
    assert br.success and br.p[-1] == -0.2 and np.all(br.p >= -0.2)
    assert "reached p" in br.message
    br = stability.continuation(fold_cycle, [1, 0], 3.0, p0=0.0, direction=-1, ds=0.05,
                                max_points=40, period_range=(0, 4.3))
    assert br.period[-1] == pytest.approx(4.3, abs=1e-12) and np.all(br.period <= 4.3)
    br = stability.continuation(fold_cycle, [1, 0], 3.0, p0=0.0, direction=-1, ds=0.05,
                                max_points=40, energy=_r2, energy_range=(0.3, 2))
    assert br.energy[-1] == pytest.approx(0.3, abs=1e-10)
    assert np.all(br.energy >= 0.3 - 1e-10)
    assert "reached energy" in br.message
    # every point of the branch is an orbit: the end point's closure
    last = stability.periodic_orbit(lambda t, y: fold_cycle(t, y, br.p[-1]), br.y0[-1],
                                    br.period[-1])
    assert last.period == pytest.approx(br.period[-1], abs=1e-8)
    with pytest.raises(ValueError, match="energy_range needs energy"):
        stability.continuation(fold_cycle, [1, 0], 3.0, p0=0.0, energy_range=(0, 1))


def sub_hopf(t, s, p):
    """r' = r (-p - r^2), theta' = 1: cycles r^2 = -p for p < 0, born at the equilibrium
    at p = 0."""
    x, y = s
    g = -p - x*x - y*y
    return [x*g - y, y*g + x]


def test_the_default_direction_leaves_an_equilibrium():
    """Started at a small cycle (r = 0.1, p = -0.01), the default first step goes to
    smaller p, where the cycle grows, instead of into the equilibrium at p = 0 (where the
    branch would turn and report a 'fold' at the equilibrium); direction=+1 is obeyed."""
    br = stability.continuation(sub_hopf, [0.1, 0.0], 2*np.pi, p0=-0.01, ds=0.02,
                                max_points=10)
    assert br.direction == -1 and np.all(np.diff(br.p) < 0) and not br.special
    assert np.all(np.diff(np.hypot(br.y0[:, 0], br.y0[:, 1])) > 0)
    forced = stability.continuation(sub_hopf, [0.1, 0.0], 2*np.pi, p0=-0.01, ds=0.02,
                                    max_points=10, direction=1)
    assert forced.direction == 1 and forced.p[1] > forced.p[0]
    assert [s.kind for s in forced.special] == ["fold"]     # the equilibrium
    assert abs(forced.special[0].p) < 1e-8


def test_small_conservative_orbits_are_stable_within_round_off():
    """A 2-DOF conservative system (V = x^2/2 + y^2 + x^2 y/2 + y^3/3) continued along its
    family of y-axis orbits without declaring it conservative (as a new user would): the second
    trivial multiplier is a simple eigenvalue after the flow direction's deflation, within
    1e-9 of 1, every small orbit is stable with the reported tolerance, and every multiplier
    lies within that tolerance of the unit disk."""
    def two(t, s):
        x, y, vx, vy = s
        return [vx, vy, -x - x*y, -2*y - 0.5*x*x - y*y]
    o = stability.symmetric_orbit(two, [0, 0.05, 0, 0], [0], [2, 3], np.pi*np.sqrt(2),
                                  free_time=True)
    br = stability.continuation(two, o.y0, o.period, in_period=True, ds=0.01,
                                max_points=12)
    assert np.min(np.abs(br.y0[:, 1])) > 0.04           # orbits, not the equilibrium
    assert br.success and np.all(br.stable)
    assert np.all((br.stable_tol >= 1e-9) & (br.stable_tol < 1e-5))
    assert np.all(np.abs(br.multipliers) <= 1 + br.stable_tol[:, None])
    near_one = np.sort(np.abs(br.multipliers - 1), axis=1)[:, :2]
    assert np.all(near_one < 1e-9)


def test_henon_family_g_branch_point_default_and_tight():
    """Hénon's family g loses stability (S = +1, a genuine branch point of the general
    shooting equations: family g' crosses there) at the Hénon period 2 pi m*, m* of Hill's
    variation family (conmech.hill's independent fast path): located to 1e-10 at default
    settings and not worse at rtol 1e-13, labelled both 'branch point' and 'S=+1'."""
    ref = 2*np.pi*hill.locate_stability_change(0.19, 0.2)["m"]
    errs = []
    for kw in ({}, {"rtol": 1e-13}):
        g = hf.family(hf.satellite_orbit(0.1, "g"), max_points=40, **kw)
        (bp,) = g.special
        assert bp.kind == "branch point" and bp.kind == "S=+1"
        assert bp.located and bp.residual < 1e-9
        assert bp.stability_index == pytest.approx(1.0, abs=1e-9)
        errs.append(abs(bp.p - ref))
    assert errs[0] < 1e-10 and errs[1] <= max(errs[0], 1e-11)
