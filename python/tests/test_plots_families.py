"""Plots of families (stability.plots): the round-off-aware stability decision, the asinh
stability axis, the log-radius multiplier view with the unit circle kept, grouped labels
of special points, and orbits in configuration space."""
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402

from conmech import cr3bp, stability, systems  # noqa: E402


@pytest.fixture(scope="module")
def pendulum_family():
    return stability.lyapunov_family(systems.double_pendulum(), [0, 0], mode=0,
                                     max_points=30)


@pytest.fixture(scope="module")
def l1_family():
    return cr3bp.lyapunov_family(cr3bp.MU_EARTH_MOON, "L1", "planar", max_points=80,
                                 ds=0.02, ds_max=0.1)


def test_stable_orbits_roundoff(pendulum_family):
    """The double pendulum's slow family near the equilibrium is stable (the non-trivial
    pair on the unit circle, |S| < 1); its computed non-trivial multipliers exceed 1 by
    round-off (~1e-11), and the trivial pair (a Jordan block; the periodic QR algorithm
    with the flow direction deflated keeps it within ~1e-9 of 1): stable_orbits calls
    every orbit stable within the branch's tolerance (and shows it), while a zero
    tolerance calls some unstable."""
    fam = pendulum_family
    assert np.all(np.abs(fam.stability_index) < 1)
    nontriv = np.array([np.sort(np.abs(m))[[0, -1]] for m in fam.multipliers])
    excess = np.array([np.max(np.abs(m[np.argsort(np.abs(m - 1))[2:]])) - 1
                       for m in fam.multipliers])
    assert np.max(excess) > 0 and np.max(excess) < 1e-9
    assert np.max(nontriv) < 1 + 1e-9           # the trivial pair kept together
    st, tau = stability.stable_orbits(fam)
    assert st.all() and np.array_equal(tau, fam.stable_tol) and np.all(tau >= 1e-9)
    assert np.array_equal(st, fam.stable)
    st0, _ = stability.stable_orbits(fam, tol=0.0)
    assert not st0.all()
    with pytest.raises(TypeError):
        stability.stable_orbits(np.zeros(3))


def test_plot_branch_axes(pendulum_family, l1_family):
    """x = energy or period; the stability index of the L1 family (~2e3) on an asinh
    axis; the legend shows the stability tolerance; a linear axis for the pendulum's
    period."""
    fig, axes = plt.subplots(1, 3)
    ax = stability.plot_branch(l1_family, axes[0], x="energy")
    assert ax.get_yscale() == "asinh" and ax.get_xlabel() == "energy"
    ax = stability.plot_branch(pendulum_family, axes[1], x="energy", y="period")
    assert ax.get_yscale() == "linear"
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(lab.startswith("stable (|mu| <= 1 + ") for lab in labels)
    ax = stability.plot_branch(l1_family, axes[2], x="period")
    assert ax.get_xlabel() == "period"
    with pytest.raises(ValueError, match="x must be"):
        stability.plot_branch(l1_family, x="nonsense")
    plt.close("all")


def test_special_point_labels_grouped():
    """Special points closer than 4 % of the axes share one label ('2-4'); each one is
    listed in the legend with its value."""
    def fun(t, s, p):
        x, y, z = s
        r2 = x*x + y*y
        return [x*(1 - r2) - y, y*(1 - r2) + x, (p - 2.0)*z - z**3]
    br = stability.continuation(fun, [1, 0, 0], 6.3, p0=1.5, ds=0.1, p_range=(0, 2.4))
    assert any(s.kind == "branch point" for s in br.special)
    # three copies of the same point: one label for all
    br.special = [br.special[0]]*3
    fig, ax = plt.subplots()
    stability.plot_branch(br, ax)
    texts = [c.get_text() for c in ax.texts]
    assert texts == ["1-3"]
    assert sum(t.get_text().startswith(("1:", "2:", "3:"))
               for t in ax.get_legend().get_texts()) == 3
    plt.close(fig)


def test_plot_multipliers_log_view(l1_family):
    """The log-radius view: |mu| = 1 is drawn at radius 1, |mu| = r at 2^asinh(log10 r),
    the aspect is equal; the largest multiplier (~2e3) stays in view."""
    fig, ax = plt.subplots()
    stability.plot_multipliers(l1_family, ax, color="energy")
    pts = ax.collections[0].get_offsets()
    mu = l1_family.multipliers.ravel()
    rad = np.hypot(pts[:, 0], pts[:, 1])
    assert np.allclose(rad, 2.0**np.arcsinh(np.log10(np.abs(mu))), rtol=1e-12)
    assert ax.get_aspect() == 1.0
    assert np.max(rad) < 6
    # the unit circle line has radius 1
    circle = [ln for ln in ax.lines if ln.get_linestyle() == "-"][0]
    assert np.allclose(np.hypot(*circle.get_data()), 1.0)
    stability.plot_multipliers(l1_family, ax, view="linear")
    with pytest.raises(ValueError, match="view"):
        stability.plot_multipliers(l1_family, ax, view="polar")
    plt.close(fig)


def test_plot_orbits(pendulum_family, l1_family):
    """The orbits in configuration space coloured by the energy: a LineCollection of the
    requested orbits (2-D), or 3-D curves; each closes (first = last point)."""
    fig, ax = plt.subplots()
    stability.plot_orbits(systems.double_pendulum(), pendulum_family, ax, n_orbits=5,
                          color="energy")
    lc = [c for c in ax.collections if isinstance(c, LineCollection)][0]
    segs = lc.get_segments()
    assert len(segs) == 5
    assert all(np.allclose(s[0], s[-1], atol=1e-7) for s in segs)
    fig = plt.figure()
    ax3 = fig.add_subplot(111, projection="3d")
    stability.plot_orbits(systems.cr3bp(cr3bp.MU_EARTH_MOON), l1_family, ax3,
                          coords=(0, 1, 2), n_orbits=4, colorbar=False, label="planar")
    assert len(ax3.lines) == 4
    with pytest.raises(ValueError, match="coords"):
        stability.plot_orbits(systems.double_pendulum(), pendulum_family, coords=(0,))
    plt.close("all")


def test_plot_equilibrium_branch():
    """A branch of equilibria: Hopf point marked, stable part solid."""
    def bru(t, y, b):
        return [2 - (b + 1)*y[0] + y[0]**2*y[1], b*y[0] - y[0]**2*y[1]]
    br = stability.equilibrium_continuation(bru, [2, 0.5], p0=1.0, ds=0.1, p_range=(0, 8))
    fig, ax = plt.subplots()
    stability.plot_branch(br, ax, y=1)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("Hopf" in lab for lab in labels)
    plt.close(fig)
