"""Periodic orbits on a constraint manifold (stability.constrained_orbits): closed forms
(the pendulum's period 4 sqrt(l/g) K(sin^2(theta0/2)), the conical pendulum's
2 pi sqrt(l cos(alpha)/g)) and the same motions in generalized coordinates."""
import numpy as np
import pytest
from scipy.special import ellipk

from conmech import constrained, stability, systems

G, L = 9.81, 1.0


def pendulum_period(th0, g=G, l=L):
    """Exact period of the planar pendulum of amplitude th0 (K of parameter m = k^2)."""
    return 4.0*np.sqrt(l/g)*ellipk(np.sin(th0/2)**2)


def brake_state(th0):
    return np.array([L*np.sin(th0), -L*np.cos(th0)]), np.zeros(2)


@pytest.mark.parametrize("method", ["single", "multiple", "collocation"])
def test_pendulum_xy_amplitude_of_a_period_is_the_elliptic_integral(method):
    th0 = 1.0
    T = pendulum_period(th0)
    q0, v0 = brake_state(0.9)
    # released from rest at x0 (free), at rest again (x' = 0, index n + 0) at T/2
    o = stability.constrained_symmetric_orbit(systems.pendulum_xy(g=G, l=L), q0, v0,
                                              free=[0], targets=[2], period=T,
                                              method=method, intervals=24,
                                              independent=[0])
    assert abs(o.q0[0] - L*np.sin(th0)) < 1e-10
    assert abs(o.q0[1] + L*np.cos(th0)) < 1e-10
    assert o.manifold_residual < 1e-13
    assert o.constrained_residual < 1e-8
    assert o.removed_trivial == 2
    assert o.multipliers.size == 2                 # the motion on the manifold only
    assert np.max(np.abs(o.multipliers - 1.0)) < 1e-6
    assert list(o.chart.independent) == [0]


def test_pendulum_xy_agrees_with_the_angle_coordinate():
    T = pendulum_period(1.2)
    q0, v0 = brake_state(1.0)
    o = stability.constrained_symmetric_orbit(systems.pendulum_xy(g=G, l=L), q0, v0,
                                              free=[0], targets=[2], period=T,
                                              q_ref=[0.0, -L])
    a = stability.symmetric_orbit(systems.pendulum_angle(g=G, l=L), [1.0, 0.0], [0], [1], T)
    assert abs(np.arcsin(o.q0[0]/L) - a.y0[0]) < 1e-10
    assert abs(a.y0[0] - 1.2) < 1e-10


def test_double_pendulum_xy_brake_orbit_matches_generalized_coordinates():
    """A nonlinear normal mode (brake orbit of the in-phase mode) of the Cartesian double
    pendulum and of the double pendulum in absolute angles: same period, same shape, same
    non-trivial multipliers (they do not depend on the coordinates)."""
    th1 = 0.3
    # angles: th1 fixed, th2 and the half period free, at rest again at T/2
    w1 = np.sqrt((2 - np.sqrt(2))*G/L)
    a = stability.symmetric_orbit(systems.double_pendulum(g=G), [th1, np.sqrt(2)*th1, 0, 0],
                                  free=[1], targets=[2, 3], period=2*np.pi/w1,
                                  free_time=True)
    x1, y1 = L*np.sin(th1), -L*np.cos(th1)
    th2 = 1.3*th1
    q0 = np.array([x1, y1, x1 + L*np.sin(th2), y1 - L*np.cos(th2)])
    o = stability.constrained_symmetric_orbit(systems.double_pendulum_xy(g=G), q0,
                                              np.zeros(4), free=[2], targets=[4, 6],
                                              period=2*np.pi/w1, free_time=True,
                                              independent=[0, 2])
    assert abs(o.period - a.period) < 1e-9*a.period
    assert abs(np.arcsin((o.q0[2] - o.q0[0])/L) - a.y0[1]) < 1e-9
    assert o.multipliers.size == 4 and o.removed_trivial == 4
    key = np.argsort(np.angle(o.multipliers))
    ka = np.argsort(np.angle(a.multipliers))
    assert np.max(np.abs(o.multipliers[key] - a.multipliers[ka])) < 1e-7
    # a genuinely non-trivial pair: not both at 1
    assert np.max(np.abs(o.multipliers - 1.0)) > 1e-2


def spherical_pendulum():
    """A point mass on a sphere from Python callables, q = [x, y, z]."""
    return constrained.ConstrainedSystem(
        3, mass=lambda t, q: np.eye(3), forces=lambda t, q, v: np.array([0, 0, -G]),
        phi=lambda t, q: np.array([0.5*(q @ q - L**2)]),
        jac=lambda t, q: q.reshape(1, 3), gamma=lambda t, q, v: np.array([-(v @ v)]),
        n_hol=1)


def test_conical_pendulum_period_and_speed():
    alpha = 0.7
    r, h = L*np.sin(alpha), L*np.cos(alpha)
    omega = np.sqrt(G/h)
    q0 = np.array([r, 0.0, -h])
    v0 = np.array([0.0, 0.9*omega*r, 0.0])
    # x fixed at r; the speed y' and the half period free; y = x' = 0 at T/2
    o = stability.constrained_symmetric_orbit(spherical_pendulum(), q0, v0, free=[4],
                                              targets=[1, 3], period=2*np.pi/omega,
                                              free_time=True)
    assert abs(o.period - 2*np.pi*np.sqrt(h/G)) < 1e-10
    assert abs(o.v0[1] - omega*r) < 1e-9
    assert o.multipliers.size == 4
    assert o.constrained_residual < 1e-8


def test_libration_family_in_the_period():
    q0, v0 = brake_state(0.5)
    br = stability.constrained_continuation(systems.pendulum_xy(g=G, l=L), q0, v0,
                                            pendulum_period(0.5), free=[0], targets=[2],
                                            max_points=8, ds=0.05, ds_max=0.05,
                                            independent=[0])
    assert len(br) == 8 and br.branch.success
    th = np.arcsin(br.q0[:, 0]/L)
    assert np.max(np.abs(pendulum_period(th) - br.branch.p)) < 1e-9
    assert np.ptp(br.branch.p) > 0.05


def test_bad_inputs_are_named():
    pxy = systems.pendulum_xy()
    q0, v0 = brake_state(0.5)
    with pytest.raises(ValueError, match="dependent coordinate"):
        stability.constrained_symmetric_orbit(pxy, q0, v0, free=[1], targets=[2], period=2.0)
    with pytest.raises(ValueError, match="not on the constraint manifold"):
        stability.constrained_periodic_orbit(pxy, q0 + 0.1, v0, 2.0)
    with pytest.raises(ValueError, match="non-holonomic"):
        stability.constrained_periodic_orbit("skate", np.zeros(3), np.zeros(3), 2.0)
    with pytest.raises(ValueError, match="rheonomic"):
        stability.constrained_periodic_orbit("pendulum_moving_xy", q0, v0, 2.0)
    with pytest.raises(ValueError, match="independent"):
        stability.ManifoldChart(pxy, q0, independent=[0, 1])
    with pytest.raises(ValueError, match="range"):
        stability.constrained_symmetric_orbit(pxy, q0, v0, free=[7], targets=[2], period=2.0)
    with pytest.raises(TypeError, match="constrained system"):
        stability.constrained_periodic_orbit(systems.pendulum(), q0, v0, 2.0)
    with pytest.raises(ValueError, match="in_period"):
        stability.constrained_continuation(pxy, q0, v0, 2.0, param=0)
