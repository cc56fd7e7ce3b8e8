"""The transverse linearisation of periodic orbits of any system
(conmech.stability.transverse_linearisation): its multipliers against the non-trivial ones
of the full monodromy (built-in, symbolic, constrained, Python systems), Hill's
coefficient Phi(t) against the planar construction (stability.transverse, hill.transverse),
the periodic frame and A_perp(t), and bad input."""
import numpy as np
import pytest
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from conmech import compiled, hill, stability, symbolic, systems

G = 9.81


@pytest.fixture(scope="module")
def dp_orbit():
    """The built-in double pendulum's slow normal-mode orbit through th1 = 0.6 at rest."""
    s = systems.double_pendulum()
    w = np.sqrt(G*(2 - np.sqrt(2)))
    o = stability.symmetric_orbit(s, [0.6, np.sqrt(2)*0.6, 0, 0], free=[1], targets=[2, 3],
                                  period=2*np.pi/w, period_factor=2, free_time=True,
                                  rtol=1e-12, atol=1e-12)
    return s, o


def _match(a, b):
    return float(np.max(np.abs(np.sort_complex(np.asarray(a)) - np.sort_complex(np.asarray(b)))))


def test_double_pendulum_multipliers_equal_the_full_monodromy(dp_orbit):
    s, o = dp_orbit
    tl = stability.transverse_linearisation(s, o)
    assert tl.dimension == 2 and tl.reduced and tl.kind == "generalized"
    full = stability.monodromy(s, o.y0, o.period, rtol=1e-13, atol=1e-13)
    nt = stability.nontrivial_multipliers(full, 2)
    assert _match(tl.multipliers, nt) <= 1e-10
    assert tl.agreement <= 1e-10                       # against its own full monodromy
    assert np.allclose(np.abs(tl.multipliers), 1, atol=1e-10)   # an elliptic orbit
    # without the energy: 2n - 1 = 3 coordinates, the third multiplier is the energy's 1
    t3 = stability.transverse_linearisation(s, o, energy="none")
    assert t3.dimension == 3 and not t3.reduced
    extra = t3.multipliers[np.argmin(np.abs(t3.multipliers - 1))]
    assert abs(extra - 1) <= 1e-9
    assert _match(np.delete(t3.multipliers, np.argmin(np.abs(t3.multipliers - 1))),
                  tl.multipliers) <= 1e-10


def test_periodic_frame_and_coefficient_matrix(dp_orbit):
    """Q(t) is orthonormal, normal to f and to grad H, periodic; A_perp(t) =
    Q^T J Q - Q^T Q' (Q' by central differences of the returned frame, J the system's
    Jacobian) and A_perp(T) = A_perp(0)."""
    s, o = dp_orbit
    T = o.period
    h = 1e-5*T
    base = np.array([0.0, 0.13, 0.31, 0.5, 0.77, 0.93])*T + 2*h
    t = np.sort(np.concatenate([base - h, base, base + h, [0.0, T]]))
    tl = stability.transverse_linearisation(s, o, t=t, rtol=1e-13, atol=1e-13)
    q = tl.frame
    for i in range(t.size):
        assert np.allclose(q[i].T @ q[i], np.eye(2), atol=1e-11)
        f = compiled.evaluate(s, 0.0, tl.states[i])["f"]
        assert np.max(np.abs(f @ q[i]))/np.linalg.norm(f) <= 1e-11
    i0, iT = np.argmin(t), np.argmax(t)
    assert np.allclose(q[iT], q[i0], atol=1e-10)
    assert np.allclose(tl.A[iT], tl.A[i0], atol=1e-9)
    for tb in base:
        i = int(np.argmin(np.abs(t - tb)))
        dq = (q[i + 1] - q[i - 1])/(t[i + 1] - t[i - 1])
        jac = compiled.evaluate(s, 0.0, tl.states[i])["jac"]
        a = q[i].T @ jac @ q[i] - q[i].T @ dq
        assert np.max(np.abs(a - tl.A[i])) <= 1e-6*np.max(np.abs(tl.A[i]))


def test_constrained_double_pendulum_in_excessive_coordinates(dp_orbit):
    """The same motion in Cartesian coordinates with two rod constraints: 8 states, 4
    constraint normals, the energy: 8 - 1 - 4 - 1 = 2 transverse coordinates, the same
    multipliers as in angles."""
    s, o = dp_orbit
    a, b, va, vb = o.y0
    q = [np.sin(a), -np.cos(a), np.sin(a) + np.sin(b), -np.cos(a) - np.cos(b)]
    v = [np.cos(a)*va, np.sin(a)*va, np.cos(a)*va + np.cos(b)*vb, np.sin(a)*va + np.sin(b)*vb]
    c = systems.double_pendulum_xy()
    tl = stability.transverse_linearisation(c, (np.r_[q, v], o.period))
    assert tl.kind == "constrained" and tl.dimension == 2 and tl.reduced
    assert tl.agreement <= 1e-10
    ref = stability.transverse_linearisation(s, o)
    assert _match(tl.multipliers, ref.multipliers) <= 1e-10
    # the 6 trivial multipliers of the index-1 form are 1 (flow, energy, constraints)
    assert np.sort(np.abs(tl.full_multipliers - 1))[5] <= 1e-3
    with pytest.raises(ValueError, match="constraint"):       # y0 off the constraints
        stability.transverse_linearisation(c, (np.r_[q, v] + [0.1, 0, 0, 0, 0, 0, 0, 0],
                                               o.period), rtol=1e-6, atol=1e-6)


@pytest.fixture(scope="module")
def triple():
    t = dynamicsymbols._t  # noqa: F841
    th = dynamicsymbols("th1:4")
    m, l, g = sp.symbols("m l g")
    links = [symbolic.Body(f"link{i}", None if i == 0 else f"link{i - 1}", "revolute", th[i],
                           at=(0, 0) if i == 0 else (0, -l), mass=m, com=(0, -l))
             for i in range(3)]
    return symbolic.planar_tree(links, {m: 1.0, l: 1.0, g: G}, gravity=(0, -g),
                                coordinates="absolute")


def test_three_degrees_of_freedom_symbolic(triple):
    """A triple pendulum (symbolic planar tree, exact Jacobian): its slowest normal-mode
    orbit at amplitude 0.4; 2n - 2 = 4 transverse multipliers = the full ones."""
    jac = compiled.evaluate(triple, 0.0, np.zeros(6))["jac"]
    lam, vec = np.linalg.eig(jac)
    i = int(np.argmin(np.abs(lam.imag)))
    w = abs(lam[i].imag)
    mode = vec[:3, i].real/np.max(np.abs(vec[:3, i].real))
    y0 = np.r_[0.4*mode, 0, 0, 0]
    o = stability.symmetric_orbit(triple, y0, free=[1, 2], targets=[3, 4, 5], period=2*np.pi/w,
                                  period_factor=2, free_time=True)
    tl = stability.transverse_linearisation(triple, o)
    assert tl.dimension == 4 and tl.reduced
    full = stability.monodromy(triple, o.y0, o.period, rtol=1e-13, atol=1e-13)
    assert _match(tl.multipliers, stability.nontrivial_multipliers(full, 4)) <= 1e-10
    assert tl.agreement <= 1e-10


def test_four_degrees_of_freedom_builtin():
    """The built-in double spring pendulum (4 DOF, no analytic Jacobian: sixth-order
    differences inside the construction): 6 transverse multipliers."""
    d = systems.double_spring_pendulum()
    ye = stability.find_equilibrium(d, [0, -1.25, 0, -2.5, 0, 0, 0, 0]).y
    jac = compiled.evaluate(d, 0.0, ye)["jac"]
    lam, vec = np.linalg.eig(jac)
    i = int(np.argmin(np.abs(lam.imag - np.min(np.abs(lam.imag)))))
    u = vec[:4, i]
    u = u/u[int(np.argmax(np.abs(u)))]       # the mode shape is real up to a complex phase
    mode = u.real/np.max(np.abs(u.real))
    o = stability.symmetric_orbit(d, ye + np.r_[0.15*mode, 0, 0, 0, 0], free=[1, 2, 3],
                                  targets=[4, 5, 6, 7], period=2*np.pi/abs(lam[i].imag),
                                  period_factor=2, free_time=True)
    tl = stability.transverse_linearisation(d, o)
    assert tl.dimension == 6 and tl.reduced
    assert tl.agreement <= 1e-10
    assert np.allclose(np.abs(tl.multipliers), 1, atol=1e-9)


def _hh(t, s):
    x, y, vx, vy = s
    return [vx, vy, -(x + 2*x*y), -(y + x*x - y*y)]


def _hh_jac(t, s):
    x, y, vx, vy = s
    return [[0, 0, 1, 0], [0, 0, 0, 1], [-(1 + 2*y), -2*x, 0, 0], [-2*x, -(1 - 2*y), 0, 0]]


def _hh_pot(q):
    x, y = q
    return (0.5*(x*x + y*y) + x*x*y - y**3/3, [x + 2*x*y, y + x*x - y*y],
            [[1 + 2*y, 2*x], [2*x, 1 - 2*y]])


def _phi_planar(pot, omega, s):
    """Hill's Phi = n^T V'' n + 3 (turn - omega)^2 + omega^2 at the state s."""
    v = s[2:]
    sp_ = np.linalg.norm(v)
    n = np.array([-v[1], v[0]])/sp_
    _, g, h = pot(s[:2])
    turn = -n @ np.asarray(g)/sp_ + 2*omega
    return n @ np.asarray(h) @ n + 3*(turn - omega)**2 + omega**2


def test_henon_heiles_phi_equals_the_planar_construction():
    """Henon-Heiles loop orbit (a Python system with its Jacobian and energy gradient):
    psi = 0 and phi = Hill's Phi(t) of stability.transverse, to 1e-12."""
    o = stability.symmetric_orbit(_hh, [0, 0.2, 0.25, 0], [1, 2], [0, 3], 1.97*np.pi,
                                  period_factor=2, rtol=1e-13, atol=1e-13, jac=_hh_jac)
    t = np.linspace(0, o.period, 17)
    tl = stability.transverse_linearisation(
        _hh, o, t=t, jac=_hh_jac, rtol=1e-13, atol=1e-13,
        energy_gradient=lambda s: [s[0] + 2*s[0]*s[1], s[1] + s[0]**2 - s[1]**2, s[2], s[3]])
    r = stability.transverse(_hh_pot, o.y0, o.period, rtol=1e-13, t=t)
    assert np.max(np.abs(tl.hill_psi)) <= 1e-12
    phi_here = np.array([_phi_planar(_hh_pot, 0.0, s) for s in tl.states])
    assert np.max(np.abs(tl.hill_phi - phi_here)) <= 1e-12*np.max(np.abs(phi_here))
    assert np.max(np.abs(tl.hill_phi - r["phi"])) <= 1e-12*np.max(np.abs(r["phi"]))
    assert _match(tl.multipliers, r["multipliers"]) <= 1e-12
    assert tl.agreement <= 1e-12


def _hill_pot(m):
    def pot(q):
        x, y = q
        r = np.hypot(x, y)
        return (-(1/r + 1.5*m*m*x*x), [x/r**3 - 3*m*m*x, y/r**3],
                [[1/r**3 - 3*x*x/r**5 - 3*m*m, -3*x*y/r**5], [-3*x*y/r**5, 1/r**3 - 3*y*y/r**5]])
    return pot


def test_hill_variation_orbit_phi_and_stability_index():
    """Hill's problem, built-in (its Jacobi integral removes the energy): Phi(t) of
    hill.transverse and the orbit's stability index (half the trace) to 1e-12."""
    m = hill.M_HILL
    orb = hill.variation_orbit(m)
    t = np.linspace(0, orb.period, 9)
    tl = stability.transverse_linearisation(systems.hill(m=m), (orb.y0, orb.period), t=t,
                                            rtol=1e-13, atol=1e-13)
    assert tl.reduced and tl.dimension == 2
    ref = hill.transverse(orb, t=t)
    assert np.max(np.abs(tl.hill_phi - ref["phi"])) <= 1e-12*np.max(np.abs(ref["phi"]))
    # at the same states the two formulas agree to round-off
    phi_here = np.array([_phi_planar(_hill_pot(m), -m, s) for s in tl.states])
    assert np.max(np.abs(tl.hill_phi - phi_here)) <= 1e-13*np.max(np.abs(phi_here))
    assert np.max(np.abs(tl.hill_psi)) <= 1e-12
    assert 0.5*np.trace(tl.monodromy) == pytest.approx(orb.stability_index, abs=1e-12)
    assert tl.agreement <= 1e-12


def test_van_der_pol_multiplier_by_liouville():
    """A limit cycle (non-conservative, 1 transverse coordinate): the multiplier is
    exp(int_0^T div f dt) = exp(int mu (1 - x^2) dt) (Liouville), the integral by
    Simpson's rule on the returned orbit samples."""
    mu = 1.0
    s = systems.vanderpol(mu=mu)
    o = stability.periodic_orbit(s, [2.0, 0.0], 6.66)
    t = np.linspace(0, o.period, 4001)
    tl = stability.transverse_linearisation(s, o, t=t)
    assert tl.dimension == 1 and not tl.reduced
    from scipy.integrate import simpson
    div = simpson(mu*(1 - tl.states[:, 0]**2), x=t)
    assert tl.multipliers[0].real == pytest.approx(np.exp(div), rel=1e-9)
    assert tl.agreement <= 1e-10


def test_rtol_is_honoured(dp_orbit):
    s, o = dp_orbit
    loose = stability.transverse_linearisation(s, o, rtol=1e-8, atol=1e-8)
    tight = stability.transverse_linearisation(s, o, rtol=1e-13, atol=1e-13)
    assert tight.nfev > 2*loose.nfev
    assert 1e-14 < _match(loose.multipliers, tight.multipliers) < 1e-5


def test_bad_input(dp_orbit):
    s, o = dp_orbit
    with pytest.raises(ValueError, match="not periodic"):
        stability.transverse_linearisation(s, (o.y0, 0.9*o.period))
    with pytest.raises(ValueError, match="vanishes"):
        stability.transverse_linearisation(s, ([0, 0, 0, 0], 1.0))
    with pytest.raises(ValueError, match="components"):
        stability.transverse_linearisation(s, ([0.6, 0.8, 0], o.period))
    with pytest.raises(ValueError, match="energy"):
        stability.transverse_linearisation(s, o, energy="maybe")
    with pytest.raises(ValueError, match="rtol"):
        stability.transverse_linearisation(s, o, rtol=0)
    with pytest.raises(TypeError, match="orbit"):
        stability.transverse_linearisation(s, 3.0)
    with pytest.raises(ValueError, match="no energy"):       # required, but none given
        stability.transverse_linearisation(_hh, ([0, 0.2, 0.25, 0], 6.0), energy="required",
                                           rtol=1e-6, atol=1e-6)


def test_symbolic_constrained_system_and_rheonomic_refused(dp_orbit):
    """The Cartesian double pendulum from conmech.symbolic.constrained_system (compiled,
    excessive coordinates): k = 2 and the multipliers in angles; a rheonomic constraint
    (a moving suspension) has no periodic orbits in this sense: refused."""
    t = dynamicsymbols._t
    x1, y1, x2, y2 = dynamicsymbols("x1 y1 x2 y2")
    g = sp.Symbol("g")
    T = (x1.diff(t)**2 + y1.diff(t)**2 + x2.diff(t)**2 + y2.diff(t)**2)/2
    c = symbolic.constrained_system(T, g*(y1 + y2), [x1, y1, x2, y2],
                                    holonomic=[(x1**2 + y1**2 - 1)/2,
                                               ((x2 - x1)**2 + (y2 - y1)**2 - 1)/2],
                                    params={g: G})
    s, o = dp_orbit
    a, b, va, vb = o.y0
    q = [np.sin(a), -np.cos(a), np.sin(a) + np.sin(b), -np.cos(a) - np.cos(b)]
    v = [np.cos(a)*va, np.sin(a)*va, np.cos(a)*va + np.cos(b)*vb, np.sin(a)*va + np.sin(b)*vb]
    tl = stability.transverse_linearisation(c, (np.r_[q, v], o.period))
    assert tl.kind == "constrained" and tl.dimension == 2 and tl.agreement <= 1e-10
    ref = stability.transverse_linearisation(s, o)
    assert _match(tl.multipliers, ref.multipliers) <= 1e-10
    x, y = dynamicsymbols("x y")
    w = sp.Symbol("w")
    moving = symbolic.constrained_system((x.diff(t)**2 + y.diff(t)**2)/2, g*y, [x, y],
                                         holonomic=[((x - 0.1*sp.sin(w*t))**2 + y**2 - 1)/2],
                                         params={g: G, w: 3.0})
    with pytest.raises(ValueError, match="rheonomic"):
        stability.transverse_linearisation(moving, ([0, -1, 0.3, 0], 2.0))
