"""Simple branch points of equilibrium families (stability.equilibrium_branch_points) and
the switch onto the crossing branch, against closed forms: Lorenz's pitchfork at r = 1
(the origin and the pair C+- x = y = +-sqrt(beta (r - 1)), z = r - 1) and a transcritical
crossing x = 0 / x = p."""
import numpy as np
import pytest

from conmech import stability

SIGMA, BETA = 10.0, 8.0/3.0


def lorenz(t, y, r):
    x, yy, z = y
    return np.array([SIGMA*(yy - x), x*(r - z) - yy, x*yy - BETA*z])


def lorenz_jac(t, y, r):
    x, yy, z = y
    return np.array([[-SIGMA, SIGMA, 0.0], [r - z, -1.0, -x], [yy, x, -BETA]])


@pytest.mark.parametrize("jac", [None, lorenz_jac])
def test_lorenz_pitchfork_located_and_switched(jac):
    br = stability.equilibrium_continuation(lorenz, [0.0, 0.0, 0.0], p0=0.5, ds=0.07,
                                            max_points=15)
    assert br.success and br.p[0] < 1 < br.p[-1]
    bps = stability.equilibrium_branch_points(lorenz, br, jac=jac)
    assert len(bps) == 1
    bp = bps[0]
    assert bp.kind == "branch point" and bp.located
    assert abs(bp.p - 1.0) < 1e-10
    assert bp.residual < 1e-12 and abs(bp.test) < 1e-8
    # a fold is not a branch point: the origin's branch has no fold either
    assert not any(s.kind == "fold" for s in br.special)
    new = stability.switch_equilibrium_branch(lorenz, br, bp, jac=jac, ds=0.05,
                                              max_points=10)
    assert new.success and len(new) == 10
    x, y, z = new.y.T
    assert np.max(np.abs(x - y)) < 1e-10
    assert np.max(np.abs(x**2 - BETA*(new.p - 1.0))) < 1e-10
    assert np.max(np.abs(z - (new.p - 1.0))) < 1e-10
    assert np.all(np.abs(x) > 1e-3)           # off the origin's branch
    other = stability.switch_equilibrium_branch(lorenz, br, bp, side=-1, ds=0.05,
                                                max_points=5)
    assert np.sign(other.y[0, 0]) == -np.sign(new.y[0, 0])     # the mirror branch C-


def transcritical(t, y, p):
    x, w = y
    return np.array([x*(p - x), -2.0*w + x*x])


def test_transcritical_crossing_switches_to_x_equal_p():
    br = stability.equilibrium_continuation(transcritical, [0.0, 0.0], p0=-0.3, ds=0.05,
                                            max_points=14)
    bps = stability.equilibrium_branch_points(transcritical, br)
    assert len(bps) == 1 and bps[0].located and abs(bps[0].p) < 1e-10
    new = stability.switch_equilibrium_branch(transcritical, br, bps[0], ds=0.05,
                                              max_points=8)
    x, w = new.y.T
    assert np.max(np.abs(x - new.p)) < 1e-10
    assert np.max(np.abs(w - x**2/2)) < 1e-10


def test_fold_is_not_a_branch_point():
    """x' = p - x^2: a fold at p = 0, no crossing branch; tau keeps its sign."""
    br = stability.equilibrium_continuation(lambda t, y, p: np.array([p - y[0]**2]),
                                            [0.5], p0=0.25, direction=-1, ds=0.05,
                                            max_points=30)
    assert any(s.kind == "fold" for s in br.special)
    assert stability.equilibrium_branch_points(lambda t, y, p: np.array([p - y[0]**2]),
                                               br) == []


def test_bad_inputs():
    br = stability.equilibrium_continuation(lorenz, [0.0, 0.0, 0.0], p0=0.5, ds=0.07,
                                            max_points=15)
    with pytest.raises(TypeError, match="branch"):
        stability.equilibrium_branch_points(lorenz, "not a branch")
    with pytest.raises(TypeError, match="jac"):
        stability.equilibrium_branch_points(lorenz, br, jac=3)
    with pytest.raises(ValueError, match="jac must return"):
        stability.equilibrium_branch_points(lorenz, br, jac=lambda t, y, p: np.eye(2))
    bp = stability.equilibrium_branch_points(lorenz, br)[0]
    with pytest.raises(ValueError, match="point"):
        stability.switch_equilibrium_branch(lorenz, br, br.special[0] if br.special
                                            else "x")
    with pytest.raises(ValueError, match="side"):
        stability.switch_equilibrium_branch(lorenz, br, bp, side=0)
    with pytest.raises(ValueError, match="direction"):
        stability.switch_equilibrium_branch(lorenz, br, bp, direction=1)


def test_bead_on_a_rotating_hoop_builtin():
    """Built-in bead_hoop (theta from the bottom, hoop spun at omega): the bottom loses
    stability in a pitchfork at omega^2 = g/R, where the pair cos(theta) = g/(R omega^2)
    is born (e.g. Strogatz, Nonlinear Dynamics and Chaos, sect. 3.5)."""
    from conmech import systems
    s = systems.bead_hoop(R=1.0, omega=2.5, g=9.81)
    br = stability.equilibrium_continuation(s, [0.0, 0.0], "omega", ds=0.1, max_points=15)
    bps = stability.equilibrium_branch_points(s, br)
    assert len(bps) == 1 and bps[0].located
    assert abs(bps[0].p - np.sqrt(9.81)) < 1e-10
    assert abs(bps[0].test) < 1e-8
    new = stability.switch_equilibrium_branch(s, br, bps[0], ds=0.05, max_points=8)
    assert new.success and np.all(np.abs(new.y[:, 0]) > 1e-3)
    assert np.max(np.abs(np.cos(new.y[:, 0]) - 9.81/new.p**2)) < 1e-12
    with pytest.raises(ValueError, match="jac"):
        stability.equilibrium_branch_points(s, br, jac=lambda t, y, p: np.eye(2))
