"""Routh reduction against the lecture notes' closed forms: the cart pendulum's reduced
dynamics (1 - cos^2/2) theta'' + cos sin theta'^2/2 - g sin = 0, its integral E_red, its
linearisations z'' -+ 2 g z = 0, the reconstruction x(t) = -1/2 sin theta + C0 + C1 t
(the lecture notes); the bead on a freely spinning hoop, whose reduced (amended)
potential has the notes' stationary point cos(theta) = g/(R Omega^2)."""
import numpy as np
import pytest
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

import conmech
from conmech import stability, symbolic

t = dynamicsymbols._t
G = 9.81


def _same(a, b):
    return sp.simplify(sp.sympify(a) - sp.sympify(b)) == 0


@pytest.fixture(scope="module")
def cart():
    x, th = dynamicsymbols("x theta")
    g = sp.Symbol("g")
    T = x.diff(t)**2 + sp.cos(th)*x.diff(t)*th.diff(t) + th.diff(t)**2/2
    return symbolic.lagrangian_system(T - g*sp.cos(th), [x, th], params={g: G}), x, th


def test_reduced_cart_matches_the_notes(cart):
    s, x, th = cart
    g = sp.Symbol("g")
    red = symbolic.reduce(s, cyclic=[x], momenta={x: 0.0})
    r = red.reduction
    assert r.cyclic == ["x"] and r.remaining == ["theta"] and r.momentum_names == ["p_x"]
    assert _same(r.reduced_mass[0, 0], 1 - sp.cos(th)**2/2)
    # E_red = (1 - cos^2/2) theta'^2/2 + g cos theta (with P = 0)
    Ered = r.energy.subs(sp.Symbol("p_x"), 0)
    assert _same(Ered, (1 - sp.cos(th)**2/2)*th.diff(t)**2/2 + g*sp.cos(th))
    # the reduced accelerations are the notes' equation solved for theta''
    rng = np.random.default_rng(5)
    for _ in range(5):
        q, v = rng.uniform(-3, 3), rng.uniform(-3, 3)
        a = conmech.compiled.evaluate(red, 0.0, [q, v])["f"][1]
        want = (G*np.sin(q) - np.cos(q)*np.sin(q)*v**2/2)/(1 - np.cos(q)**2/2)
        assert abs(a - want) <= 1e-12*max(1, abs(want))
    # linearisations z'' - 2 g z = 0 at 0 and z'' + 2 g z = 0 at pi
    e0 = stability.equilibrium(red, [0.0, 0.0])
    ep = stability.equilibrium(red, [np.pi, 0.0])
    assert e0.kind == "unstable" and e0.saddle
    assert np.allclose(np.sort(e0.eigenvalues.real), [-np.sqrt(2*G), np.sqrt(2*G)],
                       rtol=0, atol=1e-10)
    assert ep.kind == "centre"
    assert np.allclose(np.sort(ep.eigenvalues.imag), [-np.sqrt(2*G), np.sqrt(2*G)],
                       rtol=0, atol=1e-10)


@pytest.mark.parametrize("P", [0.0, 0.37])
def test_reconstruction_and_closed_form(cart, P):
    """x(t) by quadrature on the reduced solution equals the full system's x(t) and the
    notes' x(t) = x0 + sin(theta0)/2 - sin(theta(t))/2 + P t/2."""
    s, x, th = cart
    red = symbolic.reduce(s, cyclic=[x], momenta={x: P})
    cf = red.reduction.closed_form["x"]
    want = sp.Symbol("p_x")*t/2 - sp.sin(th)/2 + sp.sin(sp.Symbol("theta0"))/2
    assert _same(cf, want)
    th0, thd0, x0 = np.pi - 0.7, 0.2, 0.5
    xd0 = (P - np.cos(th0)*thd0)/2              # P = 2 x' + cos(theta) theta'
    full = conmech.solve_ivp(s, (0, 10), [x0, th0, xd0, thd0], rtol=1e-12, atol=1e-12,
                             dense_output=True)
    rs = conmech.solve_ivp(red, (0, 10), [th0, thd0], method="DOP853", rtol=1e-12,
                           atol=1e-12, dense_output=True)
    tt = np.linspace(0, 10, 41)
    xr = red.reconstruct(rs, x0, tt)
    assert np.max(np.abs(rs.sol(tt)[0] - full.sol(tt)[1])) <= 1e-9
    assert np.max(np.abs(xr - full.sol(tt)[0])) <= 1e-9
    closed = x0 + np.sin(th0)/2 - np.sin(rs.sol(tt)[0])/2 + P*tt/2
    assert np.max(np.abs(xr - closed)) <= 1e-11
    # E_red is conserved along the reduced motion
    E = red.reduced_energy(rs.y, rs.t)
    assert np.ptp(E) <= 1e-10
    assert red.momenta_values == {"x": P}


def test_momentum_is_a_runtime_parameter(cart):
    s, x, th = cart
    red = symbolic.reduce(s, cyclic=["x"], momenta={"x": 0.0})
    red2 = red.with_params(p_x=0.8)
    assert red2.momenta_values == {"x": 0.8}
    assert np.isclose(red2.cyclic_velocity(np.array([0.3, 0.0]))[0], 0.4, atol=1e-15)
    assert red2.reduction is red.reduction


def test_reduced_system_runs_everywhere(cart):
    """The reduced system runs in shooting and continuation: the swing about theta = pi
    (period found by symmetric shooting) has both multipliers 1, and its reconstruction
    with P = 0 closes the full motion (x(T) = x(0))."""
    s, x, th = cart
    red = symbolic.reduce(s, cyclic=[x])
    w = np.sqrt(2*G)
    orb = stability.symmetric_orbit(red, [np.pi - 0.5, 0.0], free=[0], targets=[1],
                                    period=1.02*2*np.pi/w)
    assert np.allclose(orb.multipliers, 1.0, atol=1e-6)
    amp = np.pi - orb.y0[0]
    # the full system from the reconstructed state is periodic with the same period
    full = conmech.solve_ivp(s, (0, orb.period), [0.0, orb.y0[0], 0.0, 0.0], rtol=1e-12,
                             atol=1e-12)
    assert np.max(np.abs(full.y[:, -1] - [0.0, orb.y0[0], 0.0, 0.0])) <= 1e-8
    # the period from the reduced energy E_red = g cos(theta0):
    # T = 2 integral over [theta0, 2 pi - theta0] of sqrt((1 - cos^2/2)/(2 (E - g cos))) dtheta
    from scipy.integrate import quad
    a, b = orb.y0[0], 2*np.pi - orb.y0[0]

    def r(u):                       # u / sin(u/2), regular at 0
        return 2.0 if u == 0 else u/np.sin(u/2)

    def f(q):                       # E - g cos q = 2 g sin((q - a)/2) sin((b - q)/2)
        return np.sqrt((1 - np.cos(q)**2/2)*r(q - a)*r(b - q)/(4*G))
    half, _ = quad(f, a, b, weight="alg", wvar=(-0.5, -0.5), epsabs=1e-13, epsrel=1e-13)
    assert amp > 0.1 and abs(2*half - orb.period) <= 1e-8*orb.period
    # continuation in g at a fixed period (a conservative family): the amplitude changes
    br = stability.continuation(red, orb.y0, orb.period, param="g", free=[0], targets=[1],
                                conservative=True, ds=0.05, max_points=6)
    assert br.success and len(br.p) >= 4
    assert np.ptp(br.p) > 0.1 and np.ptp(br.y0[:, 0]) > 1e-3


def test_free_hoop_reduced_potential():
    """A bead on a hoop that spins freely about the vertical (hoop inertia I): the spin
    angle phi is cyclic; Routh's amended potential is -m g R cos(theta) +
    mu^2/(2 (I + m R^2 sin^2 theta)), and its off-axis critical point is the notes'
    cos(theta*) = g/(R Omega^2) with Omega the spin rate there. For a heavy hoop the
    amended potential tends to the driven hoop's -m g R cos - m R^2 Omega^2 sin^2/2 and
    the oscillation about theta* to Omega sin(theta*) (REFERENCE.md)."""
    th, ph = dynamicsymbols("theta phi")
    m, R, g, I = sp.symbols("m R g I")
    L = I*ph.diff(t)**2/2 + m*R**2*(th.diff(t)**2 + sp.sin(th)**2*ph.diff(t)**2)/2 \
        + m*g*R*sp.cos(th)
    Iv, W = 50.0, 5.0
    mu = (Iv + np.sin(0.8)**2)*W          # near a spin W at theta ~ 0.8
    s = symbolic.lagrangian_system(L, [th, ph], params={m: 1.0, R: 1.0, g: G, I: Iv})
    assert s.cyclic_coordinates == (1,)
    red = symbolic.reduce(s, cyclic=[ph], momenta={ph: mu})
    p = sp.Symbol("p_phi")
    want = -m*g*R*sp.cos(th) + p**2/(2*(I + m*R**2*sp.sin(th)**2))
    assert _same(red.reduction.amended_potential, want)
    e = stability.find_equilibrium(red, [0.8, 0.0])
    ths = e.y[0]
    Omega = mu/(Iv + np.sin(ths)**2)
    assert abs(np.cos(ths) - G/Omega**2) <= 1e-12
    assert e.kind == "centre"
    freq = np.max(e.eigenvalues.imag)
    # heavy hoop: the frequency tends to Omega sin(theta*) as I grows (O(1/I))
    assert abs(freq - Omega*np.sin(ths)) <= 5.0/Iv*Omega
    heavy = red.with_params(I=1e6, p_phi=(1e6 + np.sin(ths)**2)*Omega)
    eh = stability.find_equilibrium(heavy, [ths, 0.0])
    Oh = (1e6 + np.sin(ths)**2)*Omega/(1e6 + np.sin(eh.y[0])**2)
    assert abs(np.max(eh.eigenvalues.imag) - Oh*np.sin(eh.y[0])) <= 1e-4


def test_bad_input(cart):
    s, x, th = cart
    with pytest.raises(ValueError, match="'theta' is not a cyclic coordinate"):
        symbolic.reduce(s, cyclic=[th])
    with pytest.raises(ValueError, match="not a coordinate"):
        symbolic.reduce(s, cyclic=["y"])
    with pytest.raises(ValueError, match="momenta\\['x'\\].*not finite"):
        symbolic.reduce(s, cyclic=[x], momenta={x: np.inf})
    with pytest.raises(ValueError, match="not among the cyclic"):
        symbolic.reduce(s, cyclic=[x], momenta={th: 1.0})
    with pytest.raises(TypeError, match="momenta"):
        symbolic.reduce(s, cyclic=[x], momenta=[1.0])
    # a damper on x: L does not depend on x but the momentum is not conserved
    c = sp.Symbol("c")
    T = x.diff(t)**2 + sp.cos(th)*x.diff(t)*th.diff(t) + th.diff(t)**2/2
    damped = symbolic.lagrangian_system(T - 9.81*sp.cos(th), [x, th], params={c: 0.2},
                                        forces=[-c*x.diff(t), 0])
    with pytest.raises(ValueError, match="non-conservative force .* acts on it"):
        symbolic.reduce(damped, cyclic=[x])
    with pytest.raises(ValueError, match="no cyclic coordinate"):
        symbolic.reduce(damped)


def test_momentum_singular_reduced_energy():
    """The polar particle with p_theta /= 0: the amended potential p^2/(2 m r^2) is
    singular at r = 0; evaluating there is an error naming the momentum."""
    r_, th = dynamicsymbols("r theta")
    m = sp.Symbol("m")
    s = symbolic.lagrangian_system(m*(r_.diff(t)**2 + r_**2*th.diff(t)**2)/2 + 1/r_,
                                   [r_, th], params={m: 1.0})
    red = symbolic.reduce(s, cyclic=[th], momenta={th: 0.5})
    assert _same(red.reduction.singular, m*r_**2)
    with pytest.raises(ValueError, match="p_theta|theta = 0.5"):
        red.reduced_energy(np.array([0.0, 0.1]))
    assert np.isfinite(red.reduced_energy(np.array([1.0, 0.1])))
    # Kepler: the reduced radial motion conserves E_red and reconstructs theta(t)
    sol_r = conmech.solve_ivp(red, (0, 5), [1.0, 0.0], rtol=1e-12, atol=1e-12,
                              dense_output=True)
    full = conmech.solve_ivp(s, (0, 5), [1.0, 0.0, 0.0, 0.5], rtol=1e-12, atol=1e-12,
                             dense_output=True)
    tt = np.linspace(0, 5, 11)
    assert np.max(np.abs(red.reconstruct(sol_r, 0.0, tt) - full.sol(tt)[1])) <= 1e-9
