"""continuation(in_period=True) on a compiled system without parameters: the pendulum
theta'' = -sin(theta) (symbolic.ode_system, no params), its libration family continued in
the period, checked against the closed form T = 4 K(sin^2(theta0/2))."""
import numpy as np
import pytest
from scipy.special import ellipk

sympy = pytest.importorskip("sympy")

from conmech import stability, symbolic  # noqa: E402


def test_in_period_on_a_compiled_system_without_parameters():
    th, w = sympy.symbols("th w")
    pend = symbolic.ode_system([w, -sympy.sin(th)], [th, w])
    assert len(pend.params) == 0
    T0 = 4*ellipk(np.sin(0.25)**2)
    br = stability.continuation(pend, [0.5, 0.0], T0, in_period=True, conservative=True,
                                free=[0], targets=[1], max_points=6, ds=0.05)
    assert br.success and len(br) == 6 and br.param == "period"
    th0 = br.y0[:, 0]
    assert np.max(np.abs(4*ellipk(np.sin(th0/2)**2) - br.p)) < 1e-9
    assert np.ptp(th0) > 0.01
    # a parameter named for a system that has none is still refused
    with pytest.raises(ValueError, match="param"):
        stability.continuation(pend, [0.5, 0.0], T0, param=0, p0=1.0)
