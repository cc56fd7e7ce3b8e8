"""Equilibria with Jordan structure and in families (the lecture notes' cart pendulum: lines of
equilibria in x; 'any of the downward equilibria is unstable as well' because x drifts,
while the reduced dynamics has a centre at theta = pi)."""
import numpy as np
import pytest
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from conmech import stability, symbolic, systems

t = dynamicsymbols._t
G = 9.81


@pytest.fixture(scope="module")
def cart():
    x, th = dynamicsymbols("x theta")
    g = sp.Symbol("g")
    T = x.diff(t)**2 + sp.cos(th)*x.diff(t)*th.diff(t) + th.diff(t)**2/2
    return symbolic.lagrangian_system(T - g*sp.cos(th), [x, th], params={g: G})


def test_cart_hanging_drifts_and_is_a_reduced_centre(cart):
    e = stability.equilibrium(cart, [0.4, np.pi, 0.0, 0.0])
    assert e.kind == "unstable (secular drift along x)" and not e.stable
    assert e.zero_multiplicity == 2 and e.largest_block == 2 and e.family_dim == 1
    assert np.allclose(np.abs(e.family[:, 0]), [1, 0, 0, 0], atol=1e-12)
    assert e.drift_names == ["x"] and np.allclose(e.drift[:, 0], [1, 0, 0, 0], atol=1e-12)
    # relative to P = 2 x' + cos theta' and the family: z'' + 2 g z = 0, a centre, and the
    # reduced energy has a strict minimum (the notes' "centre at theta = pi")
    rel = e.relative
    assert rel.kind == "centre" and rel.integrals == ["energy", "p_x"]
    assert np.allclose(np.sort(rel.eigenvalues.imag), [-np.sqrt(2*G), np.sqrt(2*G)],
                       rtol=0, atol=1e-10)
    assert np.max(np.abs(rel.eigenvalues.real)) <= 1e-12
    assert rel.lagrange_dirichlet is True


def test_cart_upright(cart):
    e = stability.equilibrium(cart, [0.0, 0.0, 0.0, 0.0])
    assert e.kind == "unstable" and e.saddle and e.drift_names == ["x"]
    rel = e.relative
    assert rel.kind == "unstable" and rel.saddle and rel.lagrange_dirichlet is False
    assert np.allclose(np.sort(rel.eigenvalues.real), [-np.sqrt(2*G), np.sqrt(2*G)],
                       rtol=0, atol=1e-10)


def test_nonlinear_drift_confirms_instability(cart):
    """The linear drift is real: a momentum P = 2 eps (however small) from the hanging
    equilibrium gives the steady motion x = eps t, theta = pi."""
    import conmech
    eps = 1e-6
    r = conmech.solve_ivp(cart, (0, 1e4), [0.0, np.pi, eps, 0.0], rtol=1e-12, atol=1e-14)
    assert abs(r.y[0, -1] - eps*1e4) <= 1e-9 and abs(r.y[1, -1] - np.pi) <= 1e-9


def test_find_equilibrium_and_equilibria_on_the_lines(cart):
    e = stability.find_equilibrium(cart, [1.7, np.pi - 0.4, 0.2, -0.1])
    assert abs(e.y[1] - np.pi) <= 1e-12 and e.family_dim == 1
    eqs = stability.equilibria(cart, stability.grid([(-2, 2), (-1, 4), (0, 0), (0, 0)],
                                                    [5, 6, 1, 1]))
    assert len(eqs) == 2                              # two lines, each reported once
    assert sorted(round(float(q.y[1]), 9) for q in eqs) == [0.0, round(np.pi, 9)]
    assert all(q.family_dim == 1 for q in eqs)


def test_builtin_cart_and_integrals_given_as_callables():
    """The built-in cart (finite-difference Jacobian, named coordinates) and the momentum
    given by hand as a first integral."""
    c = systems.cart_pendulum()
    e = stability.equilibrium(c, [0.0, np.pi, 0.0, 0.0],
                              integrals=[lambda y: 2*y[2] + np.cos(y[1])*y[3]])
    assert e.kind == "unstable (secular drift along x)" and e.family_dim == 1
    assert e.relative.kind == "centre" and e.relative.lagrange_dirichlet is None
    assert np.allclose(np.abs(e.relative.eigenvalues.imag), np.sqrt(2*G), atol=1e-7)
    assert stability.equilibrium(c, [0.0, np.pi, 0.0, 0.0]).relative is None
    with pytest.raises(ValueError, match="does not conserve"):
        stability.equilibrium(c, [0.0, np.pi, 0.0, 0.0], integrals=[lambda y: y[1] + y[3]])


def test_python_systems():
    """x'' = -x^3: a Jordan block and no family (the linearisation drifts, the nonlinear
    system is a stable oscillator: the kind speaks of the linearisation); a free particle:
    a 2-D family and drift along x and y; x' = v, v' = -v: an attracting line."""
    e = stability.equilibrium(lambda t, y: [y[1], -y[0]**3], [0.0, 0.0])
    assert e.kind == "unstable (secular drift along y[0])" and e.family_dim == 0
    free = stability.equilibrium(lambda t, y: [y[2], y[3], 0.0, 0.0], [1.0, 2.0, 0.0, 0.0])
    assert free.family_dim == 2 and free.largest_block == 2 and len(free.drift_names) == 2
    assert free.kind.startswith("unstable (secular drift along")
    line = stability.equilibrium(lambda t, y: [y[1], -y[1]], [3.0, 0.0])
    assert line.kind.startswith("stable (on an attracting family of equilibria of dimension 1")
    assert line.stable
    sq = stability.equilibrium(lambda t, y: [y[0]**2], [0.0])
    assert sq.kind == "degenerate" and sq.family_dim == 0


def test_semisimple_double_frequency_is_a_centre():
    """Two equal uncoupled oscillators: +-i twice, semisimple: a centre (was degenerate);
    a resonant Jordan block at +-i: secular growth."""
    e = stability.equilibrium(lambda t, y: [y[2], y[3], -y[0], -y[1]], [0, 0, 0, 0])
    assert e.kind == "centre" and e.largest_block == 1
    r = stability.equilibrium(lambda t, y: [y[1] + y[2], -y[0] + y[3], y[3], -y[2]],
                              [0, 0, 0, 0])
    assert r.kind.startswith("unstable (secular growth") and abs(r.secular_frequency - 1) < 1e-6


def test_readme_example_wording():
    """The README's cart (M = 1.3, m = 0.7, l = 0.9): upright unstable (a saddle, x drifts),
    hanging unstable by the drift of x, a centre relative to the momentum."""
    x, th = dynamicsymbols("x theta")
    M, m, l, g = sp.symbols("M m l g")
    T = (M + m)*x.diff(t)**2/2 + m*l*sp.cos(th)*x.diff(t)*th.diff(t) + m*l**2*th.diff(t)**2/2
    cart = symbolic.lagrangian_system(T - m*g*l*sp.cos(th), [x, th],
                                      params={M: 1.3, m: 0.7, l: 0.9, g: 9.81})
    up = stability.equilibrium(cart, [0.0, 0.0, 0.0, 0.0])
    down = stability.equilibrium(cart, [0.0, np.pi, 0.0, 0.0])
    assert up.kind == "unstable" and up.saddle
    assert down.kind == "unstable (secular drift along x)"
    assert down.relative.kind == "centre"
    w = np.sqrt(9.81*(1.3 + 0.7)/(1.3*0.9))
    assert np.allclose(np.abs(down.relative.eigenvalues.imag), w, atol=1e-10)


def test_curved_family_of_a_symmetry():
    """A particle in the 'Mexican hat' V = (x^2 + y^2 - 1)^2/4: a circle of equilibria (the
    rotational symmetry), found with its dimension; along the circle the particle drifts
    (a Jordan block); relative to the angular momentum x y' - y x' (and the circle) it is a
    centre with the radial frequency sqrt(V''(1)) = sqrt(2)."""
    def f(t, s):
        x, y, vx, vy = s
        c = x*x + y*y - 1.0
        return [vx, vy, -c*x, -c*y]
    a = 0.7
    y0 = [np.cos(a), np.sin(a), 0.0, 0.0]
    e = stability.equilibrium(f, y0, integrals=[lambda s: s[0]*s[3] - s[1]*s[2]])
    assert e.family_dim == 1
    assert abs(abs(e.family[:, 0] @ [-np.sin(a), np.cos(a), 0, 0]) - 1) <= 1e-6
    assert e.kind.startswith("unstable (secular drift along")
    assert e.relative.kind == "centre"
    assert np.allclose(np.abs(e.relative.eigenvalues.imag), np.sqrt(2), atol=1e-6)
    # Newton from off the circle lands on it
    r = stability.find_equilibrium(f, [1.3, 0.4, 0.1, 0.0])
    assert abs(np.hypot(r.y[0], r.y[1]) - 1) <= 1e-12 and r.family_dim == 1
