"""Hamilton's principle along computed motions (the lecture notes): the action
S = integral of L dt by quadrature on the dense output, its first variation (zero on a
motion, for variations with fixed ends), its second variation (closed forms for the
harmonic oscillator; the sign change at the conjugate point T = pi/omega)."""
import numpy as np
import pytest
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

import conmech
from conmech import symbolic

t = dynamicsymbols._t
ts = sp.Symbol("t")
G = 9.81


@pytest.fixture(scope="module")
def pendulum():
    th = dynamicsymbols("theta")
    m, l, g = sp.symbols("m l g")
    L = m*l**2*th.diff(t)**2/2 + m*g*l*sp.cos(th)
    return symbolic.lagrangian_system(L, [th], params={m: 1.3, l: 0.8, g: G})


@pytest.fixture(scope="module")
def oscillator():
    q = dynamicsymbols("q")
    w = sp.Symbol("w")
    return symbolic.lagrangian_system(q.diff(t)**2/2 - w**2*q**2/2, [q], params={w: 1.0})


class _Path:
    """A path given by a dense callable (for paths that are not motions)."""

    def __init__(self, t, f, ts_):
        self.t = t
        self.sol = f
        self.sol.ts = ts_
        self.y = f(t)


def _sol(system, y0, T):
    return conmech.solve_ivp(system, (0, T), y0, method="DOP853", rtol=1e-13, atol=1e-13,
                             dense_output=True)


def test_action_of_the_harmonic_oscillator(oscillator):
    """q = A cos t: S = integral (A^2 sin^2 - A^2 cos^2)/2 dt = -A^2 sin(2T)/4."""
    A, T = 0.7, 2.3
    sol = _sol(oscillator, [A, 0.0], T)
    S = symbolic.action(oscillator, sol)
    assert abs(S - (-A**2*np.sin(2*T)/4)) <= 1e-12
    # over a sub-interval
    S2 = symbolic.action(oscillator, sol, t_span=(0.5, 1.5))
    want = -A**2*(np.sin(3.0) - np.sin(1.0))/4
    assert abs(S2 - want) <= 1e-12


def test_pendulum_action_is_stationary(pendulum):
    """The first variation vanishes along the computed motion for variations with fixed
    ends, to the integration tolerance; along a path that is not a motion it does not."""
    T = 3.0
    sol = _sol(pendulum, [1.2, 0.0], T)
    variations = [[sp.sin(k*sp.pi*ts/T)] for k in (1, 2, 3)] + \
        [[ts*(T - ts)*sp.cos(ts)]]
    ok, out = symbolic.check_stationary(pendulum, sol, variations, tol=1e-9)
    assert ok, [v.relative for v in out]
    assert all(abs(v.virtual_work) == 0.0 for v in out)
    assert all(v.scale > 1.0 for v in out)
    # a callable variation (derivative by differences) gives the same
    v = symbolic.first_variation(pendulum, sol,
                                 lambda tt: np.sin(np.pi*np.asarray(tt)/T)[None, :])
    assert v.relative <= 1e-9
    # a path that is not a motion: the motion plus eps*sin(pi t/T) (same ends)
    eps = 1e-3

    def f(tt):
        y = np.asarray(sol.sol(tt), dtype=float)
        tt = np.asarray(tt, dtype=float)
        return y + eps*np.array([np.sin(np.pi*tt/T), np.pi/T*np.cos(np.pi*tt/T)])
    path = _Path(sol.t, f, sol.sol.ts)
    bad = symbolic.first_variation(pendulum, path, [sp.sin(sp.pi*ts/T)])
    assert bad.relative > 1e-5


def test_action_expansion_is_the_second_variation(oscillator):
    """For a quadratic Lagrangian S(q + eps eta) = S(q) + eps^2 d2S[eta]/2 exactly (the
    first variation vanishes on the motion)."""
    T, A = 2.0, 0.5
    sol = _sol(oscillator, [A, 0.3], T)
    eta = [sp.sin(sp.pi*ts/T)*(1 + ts)]
    d2 = symbolic.second_variation(oscillator, sol, eta)
    eps = 0.1
    fe = sp.lambdify(ts, eta[0])
    fd = sp.lambdify(ts, sp.diff(eta[0], ts))

    def f(tt):
        tt = np.asarray(tt, dtype=float)
        return np.asarray(sol.sol(tt), dtype=float) + eps*np.array([fe(tt), fd(tt)])
    S0 = symbolic.action(oscillator, sol)
    S1 = symbolic.action(oscillator, _Path(sol.t, f, sol.sol.ts))
    assert abs((S1 - S0) - eps**2*d2/2) <= 1e-12


@pytest.mark.parametrize("T", [2.0, 4.0])
def test_second_variation_sign_at_the_conjugate_point(oscillator, T):
    """d2S[sin(pi t/T)] = (T/2)((pi/T)^2 - w^2): positive before the conjugate point
    T = pi/w (a minimum of the action), negative after it (a saddle)."""
    sol = _sol(oscillator, [0.2, 0.1], T)
    v = symbolic.first_variation(oscillator, sol, [sp.sin(sp.pi*ts/T)], second=True)
    want = T/2*((np.pi/T)**2 - 1.0)
    assert abs(v.second - want) <= 1e-12
    assert (v.second > 0) == (T < np.pi)


def test_lagrange_dalembert_with_a_damper():
    """With a non-conservative force Q the first variation is minus its virtual work."""
    q = dynamicsymbols("q")
    c = sp.Symbol("c")
    s = symbolic.lagrangian_system(q.diff(t)**2/2 - q**2/2, [q], params={c: 0.4},
                                   forces=[-c*q.diff(t)])
    T = 3.0
    sol = _sol(s, [1.0, 0.0], T)
    v = symbolic.first_variation(s, sol, [sp.sin(sp.pi*ts/T)])
    assert abs(v.delta_S) > 1e-2 and v.relative <= 1e-9
    assert abs(v.delta_S + v.virtual_work) <= 1e-9*v.scale


def test_bad_input(pendulum):
    T = 2.0
    sol = _sol(pendulum, [0.5, 0.0], T)
    with pytest.raises(ValueError, match="vanish at both ends"):
        symbolic.first_variation(pendulum, sol, [sp.cos(ts)])
    nodense = conmech.solve_ivp(pendulum, (0, T), [0.5, 0.0])
    with pytest.raises(ValueError, match="dense output"):
        symbolic.action(pendulum, nodense)
    with pytest.raises(ValueError, match="outside"):
        symbolic.action(pendulum, sol, t_span=(0, 3))
    with pytest.raises(TypeError, match="variation"):
        symbolic.first_variation(pendulum, sol, 3.0)
    with pytest.raises(ValueError, match="t only"):
        symbolic.first_variation(pendulum, sol, [sp.sin(sp.Symbol("s"))])
