"""Normal modes and Lyapunov families of conservative systems (stability.normal_modes,
stability.lyapunov_family): frequencies against closed forms, the small-amplitude period
2 pi/omega_k to 1e-8, the energy of every system, and bad input."""
import numpy as np
import pytest
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from conmech import compiled, solve_ivp, stability, symbolic, systems

G = 9.81


def _period_limit(fam):
    """The period of the family extrapolated to zero amplitude from its two start orbits
    (amplitudes a and 2a: T(a) = T0 + c a^2 + O(a^4), Richardson)."""
    (_, ta, _), (_, tb, _) = fam.start
    return (4*ta - tb)/3


def _check_orbits(system, fam, ks, tol=1e-8):
    """Every orbit ks of the family closes after its period (independent integration)."""
    for k in ks:
        r = solve_ivp(system, (0, fam.period[k]), fam.y0[k], method="DOP853", rtol=1e-12,
                      atol=1e-12)
        assert np.max(np.abs(r.y[:, -1] - fam.y0[k])) < tol


def test_double_pendulum_modes_and_families():
    """The double pendulum (m = l = 1): omega^2 = (g/l)(2 -+ sqrt 2) (closed form); the
    families of both modes start at 2 pi/omega_k to 1e-8, are periodic, carry the energy
    (T + U of the system) and leave the equilibrium (the energy grows)."""
    s = systems.double_pendulum()
    nm = stability.normal_modes(s, [0, 0])
    w2 = G*np.array([2 - np.sqrt(2), 2 + np.sqrt(2)])
    assert np.allclose(nm.omega**2, w2, rtol=1e-10)
    assert nm.hyperbolic == 0 and nm.resonant == ["", ""]
    for k in (0, 1):
        fam = stability.lyapunov_family(s, [0, 0], mode=k, max_points=25)
        assert fam.success and fam.mode == k and fam.param == "period"
        assert abs(_period_limit(fam) - 2*np.pi/np.sqrt(w2[k])) < 1e-8
        assert fam.energy_equilibrium == pytest.approx(-3*G)
        assert np.allclose(fam.energy, s.energy(fam.y0), atol=1e-12)
        assert np.all(np.diff(fam.energy) > 0)
        _check_orbits(s, fam, [0, len(fam) - 1])


def _double_spring_pendulum():
    """Seed 001's double spring pendulum from its T and U: polar coordinates (l1, th1,
    l2, th2), equal masses m and springs k of rest length l0."""
    t = dynamicsymbols._t
    l1, th1, l2, th2 = dynamicsymbols("l1 theta1 l2 theta2")
    m, k, l0, g = sp.symbols("m k l0 g")
    x1, y1 = l1*sp.sin(th1), -l1*sp.cos(th1)
    x2, y2 = x1 + l2*sp.sin(th2), y1 - l2*sp.cos(th2)
    T = m/2*(x1.diff(t)**2 + y1.diff(t)**2) + m/2*(x2.diff(t)**2 + y2.diff(t)**2)
    U = m*g*(y1 + y2) + k/2*((l1 - l0)**2 + (l2 - l0)**2)
    return symbolic.lagrangian_system(T - U, [l1, th1, l2, th2],
                                      params={m: 1.0, k: 40.0, l0: 1.0, g: G})


def test_double_spring_pendulum_from_T_and_U():
    """Seed 001's double spring pendulum: the hanging equilibrium l1 = l0 + 2 m g/k,
    l2 = l0 + m g/k; the stretching frequencies omega^2 = (k/m)(3 -+ sqrt 5)/2 and the
    swinging ones omega^2 = g [L1 + L2 -+ sqrt(L1^2 + L2^2)]/(L1 L2) (closed forms of the
    linearisation); the energy of the symbolic system is callable (= T + U); the slowest
    mode's family starts at 2 pi/omega_0 to 1e-8."""
    dsp = _double_spring_pendulum()
    L1, L2 = 1 + 2*G/40, 1 + G/40
    q_eq = [L1, 0, L2, 0]
    y_eq = np.array(q_eq + [0.0]*4)
    # U at rest: -m g (2 L1 + L2) + k/2 ((L1 - l0)^2 + (L2 - l0)^2)
    assert dsp.energy(y_eq) == pytest.approx(-G*(2*L1 + L2) + 20*((L1 - 1)**2 + (L2 - 1)**2),
                                             abs=1e-12)
    nm = stability.normal_modes(dsp, q_eq)
    swing = G*np.array([L1 + L2 - np.hypot(L1, L2), L1 + L2 + np.hypot(L1, L2)])/(L1*L2)
    stretch = 40*np.array([3 - np.sqrt(5), 3 + np.sqrt(5)])/2
    assert np.allclose(nm.omega**2, np.sort(np.concatenate([swing, stretch])), rtol=1e-10)
    assert all(r == "" for r in nm.resonant)
    fam = stability.lyapunov_family(dsp, q_eq, mode=0, max_points=20)
    assert abs(_period_limit(fam) - 2*np.pi/np.sqrt(swing[0])) < 1e-8
    assert np.allclose(fam.energy, dsp.energy(fam.y0), atol=1e-12)
    _check_orbits(dsp, fam, [len(fam) - 1])


def test_callable_coupled_oscillators():
    """Two anharmonic oscillators coupled by a spring, as a callable fun(t, y) with its
    energy: V = x^2/2 + 2 y^2 + (x - y)^2/2 + x^4/4 + y^4/4, so omega^2 are the eigenvalues
    of [[2, -1], [-1, 5]] (closed form (7 -+ sqrt 13)/2); both families start at 2 pi/omega
    to 1e-8 (finite-difference Jacobian in the continuation)."""
    def f(t, s):
        x, y, u, v = s
        return [u, v, -x - (x - y) - x**3, -4*y + (x - y) - y**3]

    def energy(s):
        x, y, u, v = s
        return 0.5*(u*u + v*v) + 0.5*x*x + 2*y*y + 0.5*(x - y)**2 + 0.25*(x**4 + y**4)

    def jac(t, s):
        x, y = s[0], s[1]
        return [[0, 0, 1, 0], [0, 0, 0, 1], [-2 - 3*x*x, 1, 0, 0], [1, -5 - 3*y*y, 0, 0]]
    w2 = np.array([7 - np.sqrt(13), 7 + np.sqrt(13)])/2
    for k in (0, 1):
        fam = stability.lyapunov_family(f, [0, 0, 0, 0], mode=k, energy=energy, jac=jac,
                                        max_points=10)
        assert abs(_period_limit(fam) - 2*np.pi/np.sqrt(w2[k])) < 1e-8
        assert np.allclose(fam.energy, [energy(y) for y in fam.y0])
    with pytest.raises(ValueError, match="energy"):
        stability.lyapunov_family(f, [0, 0, 0, 0], mode=0)


def test_bad_input():
    s = systems.double_pendulum()
    with pytest.raises(ValueError, match="not an equilibrium"):
        stability.lyapunov_family(s, [0.3, 0], mode=0)
    with pytest.raises(ValueError, match="not an elliptic mode"):
        stability.lyapunov_family(s, [0, 0], mode=2)
    # the upright pendulum: a saddle, no elliptic mode
    with pytest.raises(ValueError, match="not an elliptic mode"):
        stability.lyapunov_family(systems.pendulum(), [np.pi], mode=0)
    # two identical oscillators: a 1:1 resonance

    def f(t, y):
        return [y[2], y[3], -y[0] - y[0]**3, -y[1] - y[1]**3]
    with pytest.raises(ValueError, match="resonant"):
        stability.lyapunov_family(f, [0, 0, 0, 0], mode=0, energy=lambda y: 0.0)
    # 1:2 resonance: omega_1 = 2 omega_0

    def g(t, y):
        return [y[2], y[3], -y[0] + y[0]*y[1], -4*y[1] + y[0]**2/2]
    with pytest.raises(ValueError, match="resonant"):
        stability.lyapunov_family(g, [0, 0, 0, 0], mode=0, energy=lambda y: 0.0)
    with pytest.raises(TypeError, match="mode"):
        stability.lyapunov_family(s, [0, 0], mode=0.5)
    with pytest.raises(ValueError, match="configuration"):
        stability.lyapunov_family(s, [0, 0, 0], mode=0)
    # a compiled first-order system defines no energy: it must be given
    x, v = sp.symbols("x v")
    duff = symbolic.ode_system([v, -x - x**3], [x, v])
    with pytest.raises(ValueError, match="no energy"):
        stability.lyapunov_family(duff, [0, 0], mode=0)
    fam = stability.lyapunov_family(duff, [0, 0], mode=0, max_points=3,
                                    energy=lambda y: 0.5*y[1]**2 + 0.5*y[0]**2 + 0.25*y[0]**4)
    assert abs(_period_limit(fam) - 2*np.pi) < 1e-8
    with pytest.raises(ValueError, match="in_period"):
        stability.lyapunov_family(s, [0, 0], mode=0, in_period=True)
    # a linear system: isochronous, no continuation in the period
    with pytest.raises(ValueError, match="does not change"):
        stability.lyapunov_family(systems.harmonic(), [0.0], mode=0)


def test_energy_of_every_system():
    """system.energy(y): closed forms for the built-ins, T + U of a symbolic Lagrangian
    system, the Jacobi constants; ValueError for systems without one."""
    y = np.array([0.3, -0.7])
    assert systems.harmonic(omega=2.0).energy(y) == pytest.approx(0.5*(0.49 + 4*0.09))
    assert systems.pendulum(g=9.0, l=2.0).energy(y) == pytest.approx(0.245 - 4.5*np.cos(0.3))
    ky = np.array([0.6, 0.8, -0.3, 0.9])
    assert systems.kepler(mu=2.0).energy(ky) == pytest.approx(0.45 - 2.0)
    mu = 0.1
    s6 = np.array([0.5, 0.2, 0.1, 0.3, -0.2, 0.05])
    r1 = np.sqrt((0.5 + mu)**2 + 0.04 + 0.01)
    r2 = np.sqrt((0.5 - 1 + mu)**2 + 0.04 + 0.01)
    cj = 0.25 + 0.04 + 2*((1 - mu)/r1 + mu/r2) - (0.09 + 0.04 + 0.0025)
    assert systems.cr3bp(mu=mu).energy(s6) == pytest.approx(cj, abs=1e-14)
    s4 = s6[[0, 1, 3, 4]]
    assert systems.arenstorf(mu=mu).energy(s4) == pytest.approx(
        systems.cr3bp(mu=mu).energy([0.5, 0.2, 0, 0.3, -0.2, 0]), abs=1e-14)
    h4 = np.array([0.3, 0.1, 0.2, -0.4])
    hs = systems.hill_spatial(m=0.1)
    assert hs.energy([0.3, 0.1, 0.0, 0.2, -0.4, 0.0]) == pytest.approx(
        systems.hill(m=0.1).energy(h4), abs=1e-14)
    # the double pendulum: T + U (m = l = 1), at rest U = -g (2 cos th1 + cos th2)
    assert systems.double_pendulum().energy([0.1, 0.2, 0, 0]) == pytest.approx(
        -G*(2*np.cos(0.1) + np.cos(0.2)))
    assert systems.double_pendulum().energy(np.zeros((3, 4))).shape == (3,)
    for s in (systems.vanderpol(), systems.pendulum_moving()):
        if s.name == "vanderpol":
            with pytest.raises(ValueError, match="vanderpol"):
                s.energy([0.1, 0.2])
            assert not s.has_energy
    with pytest.raises(ValueError, match="components"):
        systems.kepler().energy([1, 2, 3])
    # a compiled first-order system has none
    x, v = sp.symbols("x v")
    osc = symbolic.ode_system([v, -x], [x, v])
    assert isinstance(osc, compiled.CompiledSystem)
    with pytest.raises(ValueError, match="no energy"):
        osc.energy([1.0, 0.0])
