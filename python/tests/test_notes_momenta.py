"""Generalized momenta, generalized forces, cyclic coordinates and first integrals of
symbolic Lagrangian systems, against the lecture notes' closed forms (the cart
pendulum's P = 2 x' + cos(theta) theta' and energy; the free particle's p_x, p_y,
the polar particle's angular momentum m r^2 theta' and radial force, the bead on the hoop's
Jacobi integral)."""
import numpy as np
import pytest
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

import conmech
from conmech import symbolic

t = dynamicsymbols._t


def _same(a, b):
    return sp.simplify(sp.sympify(a) - sp.sympify(b)) == 0


@pytest.fixture(scope="module")
def cart():
    x, th = dynamicsymbols("x theta")
    g = sp.Symbol("g")
    T = x.diff(t)**2 + sp.cos(th)*x.diff(t)*th.diff(t) + th.diff(t)**2/2
    return symbolic.lagrangian_system(T - g*sp.cos(th), [x, th], params={g: 9.81}), x, th


def test_cart_momentum_and_energy(cart):
    sysm, x, th = cart
    g = sp.Symbol("g")
    assert sysm.cyclic_coordinates == (0,)
    mo = sysm.momenta
    assert mo.cyclic_names == ("x",)
    # notes: P = 2 x' + cos(theta) theta' (the momentum conjugate to x)
    assert _same(mo.p[0], 2*x.diff(t) + sp.cos(th)*th.diff(t))
    assert _same(mo.p[1], sp.cos(th)*x.diff(t) + th.diff(t))
    # generalized forces dL/dq: dL/dx = 0, dL/dtheta = g sin - sin theta' x'
    assert mo.forces[0] == 0
    assert _same(mo.forces[1], g*sp.sin(th) - sp.sin(th)*x.diff(t)*th.diff(t))
    fi = sysm.first_integrals
    assert fi.names == ["energy", "p_x"]
    # notes: E = 1/2 [x' th'] [[2, cos], [cos, 1]] [x' th']^T + g cos(theta)
    E = (2*x.diff(t)**2 + 2*sp.cos(th)*x.diff(t)*th.diff(t) + th.diff(t)**2)/2 \
        + g*sp.cos(th)
    assert _same(fi.expressions[0], E)


def test_cart_integrals_along_solution(cart):
    sysm = cart[0]
    r = conmech.solve_ivp(sysm, (0, 20), [0.0, np.pi - 0.7, 0.3, 0.0], rtol=1e-12,
                          atol=1e-12)
    drift = sysm.first_integrals.check(r)
    assert drift["p_x"] <= 1e-10 and drift["energy"] <= 1e-9
    # the compiled P equals the notes' formula at every output point
    P = sysm.momenta.p_of(r.y)[0]
    assert np.max(np.abs(P - (2*r.y[2] + np.cos(r.y[1])*r.y[3]))) <= 1e-14
    # a solution that is not one (a wrong initial momentum half-way) shows a drift
    vals = sysm.first_integrals.along(r)
    assert vals.shape == (2, r.t.size)


def test_compiled_single_and_batch_agree(cart):
    sysm = cart[0]
    rng = np.random.default_rng(3)
    Y = rng.uniform(-2, 2, (4, 7))
    batch = sysm.momenta.p_of(Y, 0.0)
    for j in range(7):
        assert np.allclose(sysm.momenta.p_of(Y[:, j]), batch[:, j], rtol=0, atol=1e-15)
    L = sysm.momenta.lagrangian_of(Y)
    x0, th0, xd, thd = Y
    assert np.allclose(L, xd**2 + np.cos(th0)*xd*thd + thd**2/2 - 9.81*np.cos(th0),
                       rtol=0, atol=1e-13)
    F = sysm.momenta.forces_of(Y)
    assert np.allclose(F[1], 9.81*np.sin(th0) - np.sin(th0)*xd*thd, rtol=0, atol=1e-13)
    # a parameter copy evaluates with its own parameters
    heavy = sysm.with_params(g=1.0)
    assert heavy.cyclic_coordinates == (0,)
    assert np.allclose(heavy.momenta.lagrangian_of(Y), L + 8.81*np.cos(th0), atol=1e-13)


def test_free_particle_px_py_conserved():
    """Seed 001: L = m/2 (x'^2 + y'^2 + z'^2) - m g z, independent of x and y: p_x = m x'
    and p_y = m y' are conserved."""
    x, y, z = dynamicsymbols("x y z")
    m, g = sp.symbols("m g")
    L = m*(x.diff(t)**2 + y.diff(t)**2 + z.diff(t)**2)/2 - m*g*z
    s = symbolic.lagrangian_system(L, [x, y, z], params={m: 2.0, g: 9.81})
    assert s.cyclic_coordinates == (0, 1)
    mo = s.momenta
    assert _same(mo.p[0], m*x.diff(t)) and _same(mo.p[1], m*y.diff(t))
    assert _same(mo.forces[2], -m*g)
    r = conmech.solve_ivp(s, (0, 3), [0, 0, 10, 1.5, -0.5, 2.0], rtol=1e-12, atol=1e-12)
    d = s.first_integrals.check(r)
    assert set(d) == {"energy", "p_x", "p_y"}
    assert d["p_x"] <= 1e-12 and d["p_y"] <= 1e-12
    assert np.allclose(s.first_integrals.along(r)[1:, -1], [3.0, -1.0], atol=1e-12)


def test_polar_particle_angular_momentum():
    """Seed 001: L = m/2 (r'^2 + r^2 theta'^2) - U(r): theta is cyclic, p_theta = m r^2
    theta' (the angular momentum) is conserved; the radial generalized force is
    m r theta'^2 - dU/dr."""
    r_, th = dynamicsymbols("r theta")
    m, mu = sp.symbols("m mu")
    U = -mu*m/r_
    s = symbolic.lagrangian_system(m*(r_.diff(t)**2 + r_**2*th.diff(t)**2)/2 - U, [r_, th],
                                   params={m: 1.5, mu: 1.0})
    assert s.cyclic_coordinates == (1,)
    mo = s.momenta
    assert _same(mo.p[1], m*r_**2*th.diff(t))
    assert _same(mo.forces[0], m*r_*th.diff(t)**2 - sp.diff(U, r_))
    sol = conmech.solve_ivp(s, (0, 30), [1.0, 0.0, 0.1, 0.9], rtol=1e-12, atol=1e-12)
    d = s.first_integrals.check(sol)
    assert d["p_theta"] <= 1e-11
    # the compiled angular momentum equals m r^2 theta' along the orbit
    pth = s.momenta.p_of(sol.y)[1]
    assert np.max(np.abs(pth - 1.5*sol.y[0]**2*sol.y[3])) <= 1e-13


def test_hoop_jacobi_integral():
    """Seed 001's bead on a spinning hoop: L = m R^2 (theta'^2 + w^2 sin^2)/2 + m g R cos:
    no cyclic coordinate; the conserved energy is the Jacobi integral
    m R^2 theta'^2/2 - m R^2 w^2 sin^2/2 - m g R cos (its potential part is the reduced,
    effective potential whose critical points are the notes' stationary points)."""
    th = dynamicsymbols("theta")
    m, R, w, g = sp.symbols("m R w g")
    L = m*R**2*(th.diff(t)**2 + w**2*sp.sin(th)**2)/2 + m*g*R*sp.cos(th)
    s = symbolic.lagrangian_system(L, [th], params={m: 1.0, R: 1.0, w: 5.0, g: 9.81})
    assert s.cyclic_coordinates == ()
    fi = s.first_integrals
    assert fi.names == ["energy"]
    Veff = -m*R**2*w**2*sp.sin(th)**2/2 - m*g*R*sp.cos(th)
    assert _same(fi.expressions[0], m*R**2*th.diff(t)**2/2 + Veff)
    # stationary points of V_eff: cos(theta) = g/(w^2 R) (stable) and sin(theta) = 0
    crit = sp.solve(sp.diff(Veff.subs(th, sp.Symbol("q")), sp.Symbol("q")), sp.Symbol("q"))
    assert any(_same(sp.cos(c), g/(w**2*R)) for c in crit)
    sol = conmech.solve_ivp(s, (0, 10), [0.5, 0.0], rtol=1e-12, atol=1e-12)
    assert fi.check(sol)["energy"] <= 1e-10


def test_force_makes_a_coordinate_ignorable_not_cyclic():
    """A damper on x: L does not depend on x, but the momentum is not conserved."""
    x, th = dynamicsymbols("x theta")
    c = sp.Symbol("c")
    T = x.diff(t)**2 + sp.cos(th)*x.diff(t)*th.diff(t) + th.diff(t)**2/2
    s = symbolic.lagrangian_system(T - 9.81*sp.cos(th), [x, th], params={c: 0.3},
                                   forces=[-c*x.diff(t), 0])
    assert s.cyclic_coordinates == ()
    mo = s.momenta
    assert mo.ignorable == (0,) and mo.cyclic == ()
    assert s.first_integrals.names == []     # no energy with a damper, no momentum


def test_not_a_symbolic_lagrangian_system():
    with pytest.raises(TypeError, match="conmech.symbolic"):
        symbolic.momenta(conmech.systems.cart_pendulum())
    ode = symbolic.ode_system([sp.Symbol("v"), -sp.Symbol("x")],
                              [sp.Symbol("x"), sp.Symbol("v")])
    with pytest.raises(TypeError):
        symbolic.momenta(ode)


def test_planar_tree_cart_pole():
    """A cart-pole described as bodies (a prismatic cart, a revolute pole): the cart's
    coordinate is cyclic, its momentum conserved, and the reduction and the equilibrium
    structure work on the tree as on the Lagrangian."""
    from conmech import stability
    x, th = dynamicsymbols("x theta")
    M, m, l, g = sp.symbols("M m l g")
    bodies = [symbolic.Body("cart", None, "prismatic", x, axis=(1, 0), mass=M),
              symbolic.Body("pole", "cart", "revolute", th, mass=m, com=(0, l))]
    tree = symbolic.planar_tree(bodies, {M: 1.0, m: 1.0, l: 1.0, g: 9.81}, gravity=(0, -g))
    assert tree.cyclic_coordinates == (0,)
    r = conmech.solve_ivp(tree, (0, 10), [0.0, 0.3, 0.2, 0.0], rtol=1e-12, atol=1e-12)
    assert tree.first_integrals.check(r)["p_x"] <= 1e-10
    red = symbolic.reduce(tree, cyclic=[x])
    e = stability.equilibrium(red, [np.pi, 0.0])
    assert e.kind == "centre"
    assert np.allclose(np.abs(e.eigenvalues.imag), np.sqrt(2*9.81), atol=1e-10)
    full = stability.equilibrium(tree, [0.0, np.pi, 0.0, 0.0])
    assert full.kind == "unstable (secular drift along x)" and full.relative.kind == "centre"
