"""Equilibria of constrained systems on their constraint manifold: Newton on
Q(q, 0) + G^T lambda = 0, phi(q) = 0; classification by the reduced linearisation on the
tangent space; Lagrange-Dirichlet from the potential restricted to the manifold."""
import numpy as np
import pytest

from conmech import constrained, stability, systems


def test_pendulum_xy_hanging_and_upright():
    """Hanging: a centre with the frequency sqrt(g/l); upright: a saddle (+-sqrt(g/l));
    the multiplier is the tension over l (m g/l); Lagrange-Dirichlet agrees."""
    g, l, m = 9.81, 2.0, 1.5
    s = systems.pendulum_xy(m=m, g=g, l=l)
    down = stability.constrained_equilibrium(s, [0.1, -1.9])
    assert np.allclose(down.q, [0, -l], atol=1e-12) and down.residual < 1e-12
    assert down.kind == "centre" and down.stable
    assert down.frequencies == pytest.approx([np.sqrt(g/l)], rel=1e-9)
    assert abs(down.lam[0]) == pytest.approx(m*g/l, rel=1e-10)
    assert down.lagrange_dirichlet is True
    # two independent routes to the reduced stiffness: forces vs the potential's Hessian
    assert np.allclose(down.hessian_reduced, down.stiffness_reduced, rtol=1e-6)
    up = stability.constrained_equilibrium(s, [0.2, 1.7])
    assert np.allclose(up.q, [0, l], atol=1e-12)
    assert up.kind == "unstable" and up.saddle and up.lagrange_dirichlet is False
    assert np.sort(up.eigenvalues.real) == pytest.approx([-np.sqrt(g/l), np.sqrt(g/l)],
                                                        rel=1e-9)


def test_double_pendulum_xy_four_equilibria():
    """Equal masses and lengths: four equilibria; the hanging one is the only stable one,
    with the normal-mode frequencies omega^2 = (g/l)(2 -+ sqrt 2) (Landau & Lifshitz,
    Mechanics, sec. 23, problem 1)."""
    g = 9.81
    s = systems.double_pendulum_xy(g=g)
    guesses = stability.grid([(-0.3, 0.3), (-1.2, 1.2), (-0.3, 0.3), (-2.2, 2.2)],
                             [2, 3, 2, 5])
    eqs = stability.constrained_equilibria(s, guesses)
    assert len(eqs) == 4
    stable = [e for e in eqs if e.stable]
    assert len(stable) == 1 and np.allclose(stable[0].q, [0, -1, 0, -2], atol=1e-12)
    assert stable[0].frequencies == pytest.approx(
        np.sqrt(g*np.array([2 - np.sqrt(2), 2 + np.sqrt(2)])), rel=1e-8)
    assert [e.lagrange_dirichlet for e in eqs] == [e.stable for e in eqs]


def _hoop(W, g=9.81, R=0.5, m=1.0):
    """Bead on a hoop spinning at W about the vertical, in the hoop's rotating plane
    q = [x, z] (x from the axis, z up), x^2 + z^2 = R^2: centrifugal m W^2 x and gravity
    (the Coriolis force is normal to the hoop); V = m g z - m W^2 x^2/2."""
    return constrained.ConstrainedSystem(
        2, mass=lambda t, q: m*np.eye(2),
        forces=lambda t, q, v: np.array([m*W*W*q[0], -m*g]),
        phi=lambda t, q: np.array([0.5*(q[0]**2 + q[1]**2 - R*R)]),
        jac=lambda t, q: np.array([[q[0], q[1]]]), n_hol=1,
        energy=lambda t, q, v: 0.5*m*(v @ v) + m*g*q[1] - 0.5*m*W*W*q[0]**2)


def test_bead_on_spinning_hoop_against_closed_forms():
    """The lecture notes: the off-axis equilibria cos th* = g/(R W^2) exist when
    W^2 > g/R and oscillate at W sin th*; the bottom is stable iff W^2 < g/R (then with
    the frequency sqrt(g/R - W^2))."""
    g, R = 9.81, 0.5
    slow = _hoop(3.0, g, R)
    bottom = stability.constrained_equilibrium(slow, [0.05, -0.45])
    assert np.allclose(bottom.q, [0, -R], atol=1e-12) and bottom.stable
    assert bottom.frequencies == pytest.approx([np.sqrt(g/R - 9.0)], rel=1e-8)
    W = 6.0
    fast = _hoop(W, g, R)
    th = np.arccos(g/(R*W*W))
    side = stability.constrained_equilibrium(fast, [0.4, -0.3])
    assert np.allclose(side.q, [R*np.sin(th), -R*np.cos(th)], atol=1e-12)
    assert side.kind == "centre" and side.frequencies == pytest.approx([W*np.sin(th)],
                                                                       rel=1e-8)
    assert side.lagrange_dirichlet is True
    bottom = stability.constrained_equilibrium(fast, [0.01, -0.49])
    assert np.allclose(bottom.q, [0, -R], atol=1e-12)
    assert not bottom.stable and bottom.lagrange_dirichlet is False
    found = stability.constrained_equilibria(
        fast, [[R*np.cos(a), R*np.sin(a)] for a in np.linspace(0, 2*np.pi, 13)[:-1]])
    assert len(found) == 4          # top, bottom, two off-axis
    assert sum(e.stable for e in found) == 2


def test_constrained_equilibrium_bad_input():
    with pytest.raises(ValueError, match="non-holonomic"):
        stability.constrained_equilibrium(systems.skate(), [0, 0, 0])
    with pytest.raises(ValueError, match="rheonomic"):
        stability.constrained_equilibrium(systems.pendulum_moving_xy(), [0, -1])
    with pytest.raises(ValueError, match="coordinates"):
        stability.constrained_equilibrium(systems.pendulum_xy(), [0, -1, 0])
    with pytest.raises(TypeError, match="constrained system"):
        stability.constrained_equilibrium(systems.pendulum(), [0, 0])
    with pytest.raises(ValueError, match="finite"):
        stability.constrained_equilibrium(systems.pendulum_xy(), [np.nan, -1])
    # a system without an equilibrium (the Atwood machine with unequal masses accelerates)
    with pytest.raises(RuntimeError, match="Newton|singular"):
        stability.constrained_equilibrium(systems.atwood_xy(), [1.0, 1.0])


def test_compiled_constrained_pendulum():
    """A pendulum derived and compiled by conmech.symbolic: the same equilibria and
    frequency sqrt(g/l) as the built-in; a rheonomic compiled system is rejected."""
    sp = pytest.importorskip("sympy")
    from sympy.physics.mechanics import dynamicsymbols
    from conmech import symbolic
    t = sp.Symbol("t")
    x, y = dynamicsymbols("x y")
    m, g, l = sp.symbols("m g l")
    T = m*(x.diff(t)**2 + y.diff(t)**2)/2
    sys_ = symbolic.constrained_system(T, m*g*y, [x, y],
                                       holonomic=[(x**2 + y**2 - l**2)/2],
                                       params=dict(m=1.0, g=9.81, l=0.5))
    e = stability.constrained_equilibrium(sys_, [0.05, -0.4])
    assert np.allclose(e.q, [0, -0.5], atol=1e-12) and e.kind == "centre"
    assert e.frequencies == pytest.approx([np.sqrt(9.81/0.5)], rel=1e-9)
    assert e.lagrange_dirichlet is True
    s = sp.sin(t)/10
    moving = symbolic.constrained_system(T, m*g*y, [x, y],
                                         holonomic=[((x - s)**2 + y**2 - l**2)/2],
                                         params=dict(m=1.0, g=9.81, l=0.5))
    with pytest.raises(ValueError, match="rheonomic"):
        stability.constrained_equilibrium(moving, [0.05, -0.4])
