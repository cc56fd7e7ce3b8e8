"""Periodic orbits and their families with Taylor's method as the integrator of the state
and its STM (``integrator="TAYLOR"`` of stability.periodic_orbit / symmetric_orbit /
continuation: the variational system's own recurrences) against the default DOP853 route,
two independent integrations of the same equations:

- Arenstorf's orbit (planar restricted three-body problem) by symmetric single and
  multiple shooting: the same orbit (start, period) to the tolerances' level, the
  multipliers the same, and the Hamiltonian structure the multipliers must have
  (mu_min mu_max = 1, the trivial pair at 1) held at least as well as DOP853 holds it;
- an Earth-Moon L1 halo orbit of the spatial problem (three free unknowns);
- Van der Pol's limit cycle by general shooting (free period) and its family continued
  in mu, with the trivial multiplier at 1 along it;
- a generalized system M(q) q'' = Q (the double pendulum's in-phase normal mode) through
  its first-order view;
- the Lyapunov family of Duffing's oscillator q'' = -q - q^3 (a compiled system without
  parameters): its periods against the closed form T = 4 K(m)/sqrt(1 + A^2),
  m = A^2/(2 (1 + A^2)), A the amplitude from the energy;
- refusals: an unknown integrator, TAYLOR on a Python function.
"""
import numpy as np
import pytest

sp = pytest.importorskip("sympy")

from conmech import stability, symbolic  # noqa: E402
import taylor_jets  # noqa: E402
from symbolic_seeds import arenstorf_ode  # noqa: E402

ARENSTORF = ([0.994, 0.0, 0.0, -2.00158510637908252240537862224],
             17.0652165601579625588917206249)
HALO = ([0.8242000712223545, 0.0, 0.058201226424566974, 0.0, 0.16882862193947631, 0.0],
        2.763288917273153)


@pytest.fixture(scope="module")
def planar():
    f, state, mu = arenstorf_ode()
    return symbolic.ode_system(f, state, params={mu: 0.012277471})


@pytest.fixture(scope="module")
def spatial():
    x, y, z, u, v, w, mu = sp.symbols("x y z u v w mu")
    m1 = 1 - mu
    r1 = ((x + mu)**2 + y**2 + z**2)**sp.Rational(3, 2)
    r2 = ((x - m1)**2 + y**2 + z**2)**sp.Rational(3, 2)
    return symbolic.ode_system(
        [u, v, w, x + 2*v - m1*(x + mu)/r1 - mu*(x - m1)/r2, y - 2*u - m1*y/r1 - mu*y/r2,
         -m1*z/r1 - mu*z/r2], [x, y, z, u, v, w], params={mu: 0.012150585609624})


@pytest.fixture(scope="module")
def vdp():
    a, b, m = sp.symbols("a b m")
    return symbolic.ode_system([b, m*(1 - a**2)*b - a], [a, b], params={m: 1.0})


def structure(mu):
    """(max |mu - 1| over the trivial pair, |mu_min mu_max - 1|) of a conservative orbit's
    multipliers (moduli; the pair is a Jordan block, split by the error's square root)."""
    a = np.sort(np.abs(np.asarray(mu)))
    d = np.sort(np.abs(np.asarray(mu) - 1.0))
    return d[1], abs(a[0]*a[-1] - 1.0)


@pytest.mark.parametrize("method", ["single", "multiple"])
def test_arenstorf_orbit_by_taylor_agrees_and_keeps_the_structure(planar, method):
    kw = dict(free=[3], targets=[1, 2], period=ARENSTORF[1], free_time=True, method=method)
    d = stability.symmetric_orbit(planar, ARENSTORF[0], **kw)
    t = stability.symmetric_orbit(planar, ARENSTORF[0], integrator="TAYLOR", **kw)
    assert abs(t.period - d.period) < 1e-10
    assert np.max(np.abs(t.y0 - d.y0)) < 1e-10
    assert t.residual < 1e-9
    mt, md = np.sort_complex(t.multipliers), np.sort_complex(d.multipliers)
    # the unstable pair to its digits; the trivial pair within its sqrt(error) split
    assert abs(mt[-1] - md[-1]) < 1e-6*abs(md[-1])
    assert abs(mt[0] - md[0]) < 1e-6
    triv_t, recip_t = structure(mt)
    triv_d, recip_d = structure(md)
    assert recip_t < 1e-5 and triv_t < 1e-5
    # Taylor's expansions of Phi keep the symplectic structure no worse than DOP853's
    assert recip_t <= recip_d and triv_t <= triv_d


@pytest.mark.parametrize("method", ["single", "multiple"])
def test_halo_orbit_by_taylor(spatial, method):
    kw = dict(free=[0, 4], targets=[1, 3, 5], period=HALO[1], free_time=True, method=method)
    d = stability.symmetric_orbit(spatial, HALO[0], **kw)
    t = stability.symmetric_orbit(spatial, HALO[0], integrator="taylor", **kw)
    assert abs(t.period - d.period) < 1e-11
    assert np.max(np.abs(t.y0 - d.y0)) < 1e-11
    mt, md = np.sort_complex(t.multipliers), np.sort_complex(d.multipliers)
    assert np.max(np.abs(mt - md)/np.maximum(1.0, np.abs(md))) < 1e-9
    assert abs(mt[-1]) > 1e3                    # the unstable halo: a real check of digits
    triv, recip = structure(mt)
    assert triv < 1e-9 and recip < 1e-9


def test_limit_cycle_and_its_family_by_taylor(vdp):
    d = stability.periodic_orbit(vdp, [2.0, 0.0], 6.66)
    t = stability.periodic_orbit(vdp, [2.0, 0.0], 6.66, integrator="TAYLOR")
    assert abs(t.period - 6.663286859323) < 1e-11          # Van der Pol, mu = 1
    assert abs(t.period - d.period) < 1e-11
    assert np.min(np.abs(t.multipliers - 1.0)) < 1e-11
    kw = dict(param="m", p_range=(1.0, 2.0), max_points=60)
    bd = stability.continuation(vdp, [2.0, 0.0], 6.66, **kw)
    bt = stability.continuation(vdp, [2.0, 0.0], 6.66, integrator="TAYLOR", **kw)
    assert bt.success and bt.p[-1] == 2.0
    assert abs(bt.period[-1] - bd.period[-1]) < 1e-10
    assert np.max(np.abs(bt.y0[-1] - bd.y0[-1])) < 1e-10
    triv = [np.min(np.abs(np.asarray(m) - 1.0)) for m in bt.multipliers]
    assert max(triv) < 1e-8          # the branch at its default rtol = atol = 1e-11


def test_normal_mode_of_a_generalized_system_by_taylor():
    """The double pendulum M(q) q'' = Q through its first-order view: the in-phase normal
    mode found by either integrator, the same orbit and multipliers."""
    system = taylor_jets.double_pendulum()
    a0 = 0.3
    period = 2*np.pi/np.sqrt(9.81*(2 - np.sqrt(2)))
    kw = dict(free=[1], targets=[2, 3], period=period, free_time=True)
    d = stability.symmetric_orbit(system, [a0, np.sqrt(2)*a0, 0.0, 0.0], **kw)
    t = stability.symmetric_orbit(system, [a0, np.sqrt(2)*a0, 0.0, 0.0], integrator="TAYLOR",
                                  **kw)
    assert abs(t.period - d.period) < 1e-10
    assert np.max(np.abs(t.y0 - d.y0)) < 1e-10
    mt, md = np.sort_complex(t.multipliers), np.sort_complex(d.multipliers)
    assert np.max(np.abs(mt - md)) < 1e-5


def test_duffing_family_by_taylor_against_the_closed_form():
    special = pytest.importorskip("scipy.special")
    q, v = sp.symbols("q v")
    duffing = symbolic.ode_system([v, -q - q**3], [q, v])

    def energy(y):
        return 0.5*y[1]**2 + 0.5*y[0]**2 + 0.25*y[0]**4
    fam = stability.lyapunov_family(duffing, [0.0], energy=energy, max_points=30,
                                    integrator="TAYLOR")
    e = np.array([energy(y) for y in fam.y0])
    a2 = np.sqrt(1.0 + 4.0*e) - 1.0
    assert fam.success and a2.max() > 1.0        # well into the nonlinear range
    exact = 4.0*special.ellipk(a2/(2.0*(1.0 + a2)))/np.sqrt(1.0 + a2)
    assert np.max(np.abs(np.asarray(fam.period) - exact)) < 1e-11


def test_refusals(vdp):
    with pytest.raises(ValueError, match="integrator must be 'DOP853' or 'TAYLOR'"):
        stability.periodic_orbit(vdp, [2.0, 0.0], 6.66, integrator="RK45")
    with pytest.raises(ValueError, match="integrator must be"):
        stability.continuation(vdp, [2.0, 0.0], 6.66, param="m", integrator=3)

    def f(t, y):
        return [y[1], (1 - y[0]**2)*y[1] - y[0]]
    with pytest.raises(ValueError, match="needs a compiled system"):
        stability.periodic_orbit(f, [2.0, 0.0], 6.66, integrator="TAYLOR")
