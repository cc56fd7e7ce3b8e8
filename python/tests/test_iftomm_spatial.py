"""IFToMM multibody benchmarks A04 (Bricard's mechanism) and A05 (the stiff flyball
governor). The library's reference solutions are published as plots and data files that
were not reachable, so each problem is checked against what its physics guarantees and
against a second, independent construction in conmech: Bricard's mechanism keeps its
energy and moves with one degree of freedom although its loop equations are as many as its
coordinates, and its point P3 follows the same path whether the loop is cut at E (one chain
of five rods) or at B (two chains, other coordinates and other loop equations); the
governor keeps its angular momentum about the shaft, and its slider height s(t) is the same
from the recursive derivation integrated by Radau IIA and from the Lagrangian derivation
integrated by DOP853."""
import numpy as np
import pytest

pytest.importorskip("sympy")
import conmech  # noqa: E402
from conmech import constrained  # noqa: E402
from conmech.benchmarks import iftomm  # noqa: E402
import symbolic_seeds as seeds  # noqa: E402


@pytest.fixture(scope="session", autouse=True)
def symbolic_cache(tmp_path_factory):
    """The test session's one compile cache (symbolic_seeds.use_test_cache)."""
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


def test_a04_bricard_one_dof_energy_and_two_cuts_agree():
    te = np.linspace(0, 10, 41)
    p3 = {}
    for cut in ("E", "B"):
        p = iftomm.a04_bricard(cut)
        r = constrained.solve(p.system, p.t_span, p.q0, p.v0, rtol=1e-10, atol=1e-10,
                              t_eval=te)
        assert r.success, r.message
        # five loop equations of rank four: one degree of freedom (Gruebler counts none)
        assert p.system.n_hol == 5 and r.rank == 4
        assert np.max(r.res_pos) <= 1e-10
        E = r.energy            # released at rest: E = U(0) = -3 m g L (the rods' centres)
        assert abs(E[0] + 3*9.81) <= 1e-12
        assert np.max(np.abs(E - E[0])) <= 1e-8*abs(E[0])
        p3[cut] = iftomm.a04_p3(r.q)
    assert np.allclose(p3["E"][:, 0], [1.0, -1.0, 0.0], atol=1e-15)
    # the mechanism really moves (P3 travels more than a metre) ...
    assert np.max(np.linalg.norm(p3["E"] - p3["E"][:, :1], axis=0)) > 1.0
    # ... and both spanning trees give the same path
    assert np.max(np.abs(p3["E"] - p3["B"])) <= 1e-7


def test_a05_governor_two_derivations_and_angular_momentum():
    te = np.linspace(0, 10, 401)
    s = {}
    for meth, integrator in (("recursive", "Radau"), ("lagrangian", "DOP853")):
        p = iftomm.a05_governor(meth)
        y0 = np.concatenate([p.q0, p.v0])
        r = conmech.solve_ivp(p.system, p.t_span, y0, method=integrator, rtol=1e-10,
                              atol=1e-10, t_eval=te)
        assert r.success, r.message
        s[meth] = r.y[1]
        fi = p.system.first_integrals
        assert fi.names == ["p_phi"]          # the dampers take the energy
        drift = fi.check(r)["p_phi"]
        assert drift <= 1e-8*abs(fi.values(y0)[0])
    assert np.max(np.abs(s["recursive"] - s["lagrangian"])) <= 1e-7
    # the balls fly out and lift the slider, which then oscillates between about 0.5 and
    # 0.74 m twice a second (the stiff couplers keep the mechanism close to one degree of
    # freedom, whose swing the dampers barely touch)
    x = s["recursive"]
    assert x[0] == 0.5 and np.max(x[:20]) > 0.7
    assert 0.49 < np.min(x) and np.max(x) < 0.75


def test_a04_joint_reaction_is_the_loop_equations_generalized_force():
    """joint_reactions on Bricard's mechanism (cut at E: rod5 to the ground by a revolute
    joint): the force and moment on rod5, in its frame, put back in the world and mapped
    through the five joints of its chain (virtual work omega_j . ((x - p_j) x F + M)),
    are the loop's generalized force G^T lambda of the compiled constraint Jacobian; the
    moment is normal to the joint axis."""
    from conmech import compiled, symbolic
    p = iftomm.a04_bricard("E")
    r = constrained.solve(p.system, (0, 2), p.q0, p.v0, rtol=1e-10, atol=1e-10,
                          t_eval=np.linspace(0, 2, 5))
    assert r.success, r.message
    (j,) = symbolic.joint_reactions(p.system, r).values()
    assert (j.kind, j.body_a, j.body_b) == ("revolute", "rod5", None)
    assert j.force.shape == (3, 5) and j.moment.shape == (3, 5)

    def rot(u, a):
        K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]], float)
        return np.eye(3) + np.sin(a)*K + (1 - np.cos(a))*K @ K
    axes = [(0, 1, 0), (0, 0, 1), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    steps = [(0, 0, 0), (1, 0, 0), (0, -1, 0), (0, 0, 1), (-1, 0, 0)]
    for k in range(r.t.size):
        q = r.q[:, k]
        R, pos, Rs, ps = np.eye(3), np.zeros(3), [], []
        for ax, st, qj in zip(axes, steps, q):
            pos = pos + R @ np.array(st, float)
            R = R @ rot(ax, qj)
            Rs.append(R)
            ps.append(pos)
        x = ps[-1] + Rs[-1] @ np.array([0.0, 1.0, 0.0])            # the joint E on rod5
        F, M = Rs[-1] @ j.force[:, k], Rs[-1] @ j.moment[:, k]
        Q = [(Rj @ np.array(ax, float)) @ (np.cross(x - pj, F) + M)
             for Rj, pj, ax in zip(Rs, ps, axes)]
        G = compiled.evaluate(p.system, r.t[k], q, r.v[:, k])["G"]
        ref = G.T @ r.lam[:, k]
        assert np.max(np.abs(Q - ref)) <= 1e-9*max(1.0, np.max(np.abs(ref)))
        assert abs(j.moment[:, k] @ np.array([1.0, 0.0, 0.0])) <= 1e-12*max(
            1.0, np.max(np.abs(j.moment[:, k])))
