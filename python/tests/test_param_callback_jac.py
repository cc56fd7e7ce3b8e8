"""``jac=`` of a callable system in equilibrium_continuation and continuation: the exact
Jacobian is called, and the results agree with the closed forms (the Brusselator's Hopf
point b = 1 + a^2, omega = a) and with the finite-difference runs."""
import numpy as np
import pytest

from conmech import stability

A = 1.0


def bruss(t, y, b):
    x, z = y
    return np.array([A - (b + 1)*x + x*x*z, b*x - x*x*z])


def bruss_jac(t, y, b):
    x, z = y
    return np.array([[-(b + 1) + 2*x*z, x*x], [b - 2*x*z, -x*x]])


class Counted:
    def __init__(self, f):
        self.f, self.calls = f, 0

    def __call__(self, *a):
        self.calls += 1
        return self.f(*a)


def test_equilibrium_continuation_with_exact_jacobian_finds_the_brusselator_hopf():
    jac = Counted(bruss_jac)
    br = stability.equilibrium_continuation(bruss, [A, 1.5/A], p0=1.5, ds=0.05,
                                            max_points=40, p_range=(1.5, 2.5), jac=jac)
    assert jac.calls > 0
    hopf = [s for s in br.special if s.kind == "Hopf"]
    assert len(hopf) == 1 and hopf[0].located
    assert abs(hopf[0].p - (1 + A*A)) < 1e-10
    assert abs(hopf[0].omega - A) < 1e-9
    fd = stability.equilibrium_continuation(bruss, [A, 1.5/A], p0=1.5, ds=0.05,
                                            max_points=40, p_range=(1.5, 2.5))
    assert abs([s for s in fd.special if s.kind == "Hopf"][0].p - hopf[0].p) < 1e-9


def vdp(t, y, mu):
    return np.array([y[1], mu*(1 - y[0]**2)*y[1] - y[0]])


def vdp_jac(t, y, mu):
    return np.array([[0.0, 1.0], [-2*mu*y[0]*y[1] - 1, mu*(1 - y[0]**2)]])


def test_orbit_continuation_with_exact_jacobian_agrees_with_differences():
    jac = Counted(vdp_jac)
    a = stability.continuation(vdp, [2.0, 0.0], 6.66, p0=1.0, ds=0.05, max_points=6,
                               direction=1, jac=jac)
    b = stability.continuation(vdp, [2.0, 0.0], 6.66, p0=1.0, ds=0.05, max_points=6,
                               direction=1)
    assert jac.calls > 0
    assert len(a) == len(b) == 6
    assert np.max(np.abs(a.period - b.period)) < 1e-7
    # mu = 1: Van der Pol's period 6.663286859323130 (orbit_methods reference)
    assert abs(a.period[0] - 6.663286859323130) < 1e-8


def test_jac_bad_inputs():
    with pytest.raises(TypeError, match="jac"):
        stability.equilibrium_continuation(bruss, [A, 1.5], p0=1.5, jac=3)
    with pytest.raises(ValueError, match="jac must return"):
        stability.equilibrium_continuation(bruss, [A, 1.5], p0=1.5,
                                           jac=lambda t, y, p: np.eye(3))
    with pytest.raises(TypeError, match="jac"):
        stability.continuation(vdp, [2.0, 0.0], 6.66, p0=1.0, jac="no")
    from conmech import systems
    with pytest.raises(ValueError, match="jac"):
        stability.continuation(systems.vanderpol(1.0), [2.0, 0.0], 6.66, param=0,
                               jac=vdp_jac)
