"""The chain of N Cartesian pendulums (banded KKT path) from Python: projected runs stay
on the manifold to round-off and keep the energy; one link is the Cartesian pendulum."""
import numpy as np
import pytest

from conmech import constrained, systems


def test_chain_projected_run_round_off_and_energy():
    res = constrained.solve(systems.pendulum_chain_xy(N=24), (0, 2), rtol=1e-10, atol=1e-10)
    assert res.success and res.q.shape[0] == 48 and res.lam.shape[0] == 24
    assert res.res_pos.max() < 1e-13 and res.res_vel.max() < 1e-13
    assert abs(res.energy[-1] - res.energy[0]) < 1e-7 * abs(res.energy[0])


def test_one_link_is_the_pendulum():
    q0 = np.array([0.6, -0.8])
    v0 = np.zeros(2)
    a = constrained.solve(systems.pendulum_chain_xy(N=1, m=2.0, l=1.0), (0, 3), q0=q0, v0=v0,
                          rtol=1e-10, atol=1e-10, t_eval=[1.0, 2.0, 3.0])
    b = constrained.solve(systems.pendulum_xy(m=2.0, l=1.0), (0, 3), q0=q0, v0=v0,
                          rtol=1e-10, atol=1e-10, t_eval=[1.0, 2.0, 3.0])
    assert np.allclose(a.q, b.q, atol=1e-12) and np.allclose(a.lam, b.lam, atol=1e-10)


@pytest.mark.parametrize("n_links", [0, 2.5, "x"])
def test_bad_number_of_links(n_links):
    with pytest.raises(ValueError, match="whole number of links"):
        systems.pendulum_chain_xy(N=n_links)
