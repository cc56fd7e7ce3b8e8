"""The spatial circular restricted three-body problem (systems.cr3bp, conmech.cr3bp):
libration points against a 30-digit computation, the exact Jacobian, the Lyapunov and halo
families about L1 and L2, and the halo bifurcations against an independent computation and
the published values."""
import mpmath
import numpy as np
import pytest
from scipy.integrate import solve_ivp as scipy_solve_ivp
from scipy.optimize import brentq, fsolve

from conmech import compiled, cr3bp, solve_ivp, stability, systems

MU = cr3bp.MU_EARTH_MOON


def _libration_mp(mu, k):
    """L_k (k = 1, 2, 3) as a root of Omega_x(x, 0, 0) at 30 digits (mpmath)."""
    with mpmath.workdps(30):      # the caller's precision is left as it was
        mu = mpmath.mpf(mu)

        def ox(x):
            d1, d2 = x + mu, x - 1 + mu
            return x - (1 - mu)*d1/abs(d1)**3 - mu*d2/abs(d2)**3
        guess = {1: 1 - mu - (mu/3)**(mpmath.mpf(1)/3), 2: 1 - mu + (mu/3)**(mpmath.mpf(1)/3),
                 3: -1 - 5*mu/12}[k]
        x = mpmath.findroot(ox, guess)
        r1, r2 = abs(x + mu), abs(x - 1 + mu)
        return x, x*x + 2*((1 - mu)/r1 + mu/r2)


@pytest.mark.parametrize("mu", [MU, 0.5, 1e-6, 0.2])
def test_libration_points(mu):
    """L1..L3 and their Jacobi constants to 1e-13 against mpmath's 30-digit roots of
    Omega_x; L4, L5 at the equilateral apexes with C = 3 - mu (1 - mu); every point is an
    equilibrium of the built-in system (f = 0 to round-off)."""
    lp = cr3bp.libration_points(mu)
    for k in (1, 2, 3):
        x, c = _libration_mp(mu, k)
        assert abs(lp.positions[k - 1, 0] - float(x)) < 1e-13
        assert abs(lp.jacobi[k - 1] - float(c)) < 1e-13
    assert np.allclose(lp["L4"], [0.5 - mu, np.sqrt(3)/2, 0], atol=1e-15)
    assert lp.jacobi[3] == pytest.approx(3 - mu*(1 - mu), abs=1e-13)
    s = systems.cr3bp(mu)
    for name in ("L1", "L2", "L3", "L4", "L5"):
        f = compiled.evaluate(s, 0.0, lp.state(name))["f"]
        assert np.max(np.abs(f)) < 1e-13
    # the values Doedel et al. (2007) and Szebehely (1967) tabulate for the Earth-Moon
    # system, to their digits
    if mu == MU:
        assert lp["L1"][0] == pytest.approx(0.83691513, abs=5e-8)
        assert lp["L2"][0] == pytest.approx(1.15568217, abs=5e-8)


def test_jacobian_exact_and_jacobi_conserved():
    """The analytic Jacobian against central differences, and C constant along an orbit."""
    s = systems.cr3bp(MU)
    y = np.array([0.8, 0.05, 0.03, 0.01, 0.2, -0.05])
    ev = compiled.evaluate(s, 0.0, y)
    assert ev["analytic"]
    h = 1e-6
    fd = np.column_stack([(compiled.evaluate(s, 0, y + h*e)["f"] -
                           compiled.evaluate(s, 0, y - h*e)["f"])/(2*h) for e in np.eye(6)])
    assert np.allclose(ev["jac"], fd, atol=1e-8)
    r = solve_ivp(s, (0, 10), y, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=[0, 5, 10])
    c = s.energy(r.y.T)
    assert np.ptp(c) < 1e-10


def _vertical_half_trace(mu, x0, vy0, half_t):
    """Independent route (SciPy only): the planar orbit through (x0, 0) with x' = 0
    corrected by fsolve on y(T/2) = x'(T/2) = 0, then the vertical variational equation
    z'' = Omega_zz(t) z integrated over the full period with SciPy's DOP853: its half
    trace, and the orbit's Jacobi constant."""
    def rhs(t, s):
        x, y, u, v = s[:4]
        r1 = np.sqrt((x + mu)**2 + y*y)
        r2 = np.sqrt((x - 1 + mu)**2 + y*y)
        a1, a2 = (1 - mu)/r1**3, mu/r2**3
        ozz = -a1 - a2
        z = s[4:].reshape(2, 2)
        dz = np.array([z[1], ozz*z[0]])
        return np.concatenate([[u, v, x - a1*(x + mu) - a2*(x - 1 + mu) + 2*v,
                                y - a1*y - a2*y - 2*u], dz.ravel()])

    def shoot(w, t_end):
        s0 = np.concatenate([[x0, 0, 0, w[0]], np.eye(2).ravel()])
        return scipy_solve_ivp(rhs, (0, t_end), s0, method="DOP853", rtol=1e-13,
                               atol=1e-13).y[:, -1]
    sol = fsolve(lambda w: shoot(w, w[1])[[1, 2]], [vy0, half_t], xtol=1e-13)
    end = shoot(sol, 2*sol[1])
    z = end[4:].reshape(2, 2)
    x, vy = x0, sol[0]
    r1, r2 = abs(x + mu), abs(x - 1 + mu)
    c = x*x + 2*((1 - mu)/r1 + mu/r2) - vy*vy
    return 0.5*(z[0, 0] + z[1, 1]), c, sol


@pytest.mark.parametrize("point,published", [("L1", 3.1743), ("L2", 3.1520)])
def test_halo_bifurcation(point, published):
    """The halo bifurcation of the Earth-Moon planar Lyapunov family: the continuation
    locates a branch point there; halo_bifurcation refines it (regula falsi on y1'(T/2)
    of the vertical variational equation, symmetric shooting); an independent computation
    (SciPy's fsolve and DOP853, the full-period vertical half-trace through 1, Brent's
    method) agrees to 1e-9 in the Jacobi constant; the published values: C ~ 3.1743 (L1)
    and ~ 3.1520 (L2) (Howell 1984; Doedel et al. 2007, IJBC 17, to their digits)."""
    pl = cr3bp.lyapunov_family(MU, point, "planar", max_points=150, ds=0.02, ds_max=0.1)
    # the first branch point along the family (further out, other families branch off)
    bps = sorted((s for s in pl.special if s.kind == "branch point"), key=lambda s: s.index)
    assert bps
    hb = cr3bp.halo_bifurcation(MU, point, pl)
    assert hb.located and hb.residual < 1e-11
    assert abs(hb.vertical) < 1e-12 and abs(hb.half_trace - 1) < 1e-12
    # the continuation's own branch point, from the eigenvalues of the 6 x 6 monodromy
    assert abs(cr3bp.jacobi(bps[0].y0, MU) - hb.jacobi) < 1e-7

    def g(x0):
        ht, _, _ = _vertical_half_trace(MU, x0, hb.y0[4], hb.period/2)
        return ht - 1.0
    x_ind = brentq(g, hb.x0 - 2e-4, hb.x0 + 2e-4, xtol=1e-15, rtol=1e-15)
    _, c_ind, _ = _vertical_half_trace(MU, x_ind, hb.y0[4], hb.period/2)
    assert abs(c_ind - hb.jacobi) < 1e-9
    assert abs(hb.jacobi - published) < 5e-4


def test_halo_and_vertical_families():
    """The northern and southern L1 halo families by branch switching: every orbit
    periodic (independent integration), z grows from 0, the two families mirror each
    other (z -> -z), C decreases from the bifurcation's; the stability index of the
    vertical pair starts at 1 (the bifurcation) and the other is the large planar one.
    The vertical Lyapunov family starts at 2 pi/omega_v."""
    s = systems.cr3bp(MU)
    pl = cr3bp.lyapunov_family(MU, "L1", "planar", max_points=150, ds=0.02, ds_max=0.1)
    north = cr3bp.halo_family(MU, pl, direction=1, max_points=40, ds=0.01, ds_max=0.05)
    south = cr3bp.halo_family(MU, pl, direction=-1, max_points=40, ds=0.01, ds_max=0.05)
    assert north.success and south.success
    zmax = np.max(np.abs(north.y0[:, 2]))
    assert north.y0[1, 2] > 0 > south.y0[1, 2] and zmax > 0.01
    assert np.allclose(north.y0[:, [0, 1, 3, 4]], south.y0[:, [0, 1, 3, 4]], atol=1e-9)
    assert np.allclose(north.y0[:, [2, 5]], -south.y0[:, [2, 5]], atol=1e-9)
    assert np.all(np.diff(north.energy) < 0)
    for k in (5, len(north) - 1):
        r = solve_ivp(s, (0, north.period[k]), north.y0[k], method="DOP853", rtol=1e-12,
                      atol=1e-12)
        assert np.max(np.abs(r.y[:, -1] - north.y0[k])) < 1e-8
    nu = cr3bp.stability_indices(north)
    assert abs(nu[0, 0] - 1) < 1e-3 and nu[0, 1] > 100
    vert = cr3bp.lyapunov_family(MU, "L1", "vertical", max_points=10)
    nm = stability.normal_modes(s, cr3bp.libration_points(MU).state("L1"))
    (_, ta, _), (_, tb, _) = vert.start
    assert abs((4*ta - tb)/3 - 2*np.pi/nm.omega[0]) < 1e-8
    assert np.max(np.abs(vert.y0[-1, [2, 5]])) > 1e-3


def test_bad_input():
    with pytest.raises(ValueError, match="mu"):
        cr3bp.libration_points(0.7)
    with pytest.raises(ValueError, match="mu"):
        systems.cr3bp(mu=-0.1)
    with pytest.raises(ValueError, match="point"):
        cr3bp.lyapunov_family(MU, "L6")
    with pytest.raises(ValueError, match="collinear"):
        cr3bp.lyapunov_family(MU, "L4")
    with pytest.raises(ValueError, match="kind"):
        cr3bp.lyapunov_family(MU, "L1", "halo")
    vert = cr3bp.lyapunov_family(MU, "L1", "vertical", max_points=5)
    with pytest.raises(ValueError, match="no branch point"):
        cr3bp.halo_bifurcation(MU, "L1", vert)
