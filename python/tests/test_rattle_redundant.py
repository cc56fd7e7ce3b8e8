"""The implicit and geometric methods on redundant constraints and singular configurations:
RATTLE solves its position and velocity constraints in the minimum-norm least-squares
sense when the constraint rows are dependent (the same motion as with the independent rows
alone, constraints at round-off, energy error bounded: IFToMM A04, Bricard's mechanism,
whose five loop equations have rank four everywhere); Radau IIA refuses dependent rows
before the first step with a message that names the method and the rank. The parallelogram
four-bar started in its flat (singular) configuration: see the cases below."""
import numpy as np
import pytest

from conmech import constrained

G = 9.81
Q0 = [np.sin(1.0), -np.cos(1.0)]


def pendulum(copies):
    """The Cartesian pendulum (m = l = 1) with its constraint written `copies` times,
    scaled differently (redundant rows: rank 1)."""
    return constrained.ConstrainedSystem(
        2, lambda t, q: np.eye(2), lambda t, q, v: [0.0, -G],
        phi=lambda t, q: [(k + 1) * 0.5 * (q[0] ** 2 + q[1] ** 2 - 1) for k in range(copies)],
        jac=lambda t, q: [[(k + 1) * q[0], (k + 1) * q[1]] for k in range(copies)],
        n_hol=copies)


def test_rattle_redundant_pendulum_is_the_pendulum():
    """The pendulum's constraint given twice and three times: RATTLE's grid values equal
    those with the single constraint (the minimum-norm corrections span the same
    direction), the constraints hold to round-off, the energy error stays bounded."""
    te = np.linspace(0, 20, 201)
    ref = constrained.solve(pendulum(1), (0, 20), Q0, [0, 0], method="RATTLE",
                            first_step=0.01, t_eval=te)
    assert ref.success
    for copies in (2, 3):
        r = constrained.solve(pendulum(copies), (0, 20), Q0, [0, 0], method="RATTLE",
                              first_step=0.01, t_eval=te)
        assert r.success, r.message
        assert r.rank == 1
        assert np.max(np.abs(r.q - ref.q)) <= 1e-11
        assert np.max(np.abs(r.v - ref.v)) <= 1e-10
        assert np.max(r.res_pos) <= 1e-13 and np.max(r.res_vel) <= 1e-13
        # the reaction C^T lambda is unique although lambda is not
        assert np.max(np.abs(r.reaction - ref.reaction)) <= 1e-8
        E = 0.5 * np.sum(r.v ** 2, axis=0) + G * r.q[1]
        assert np.max(np.abs(E - E[0])) <= 1e-3 * abs(E[0])


def test_radau_redundant_pendulum_is_the_pendulum():
    """Radau IIA (both DAE forms) on the pendulum's constraint given twice integrates an
    independent combination of the rows: the motion of the single constraint to the
    tolerance, every row satisfied, the minimum-norm multipliers of the full set (in the
    ratio 1 : 2 of the rows' scales) and the same reaction force."""
    te = np.linspace(0, 5, 51)
    for dae_index in (2, 3):
        ref = constrained.solve(pendulum(1), (0, 5), Q0, [0, 0], method="Radau",
                                dae_index=dae_index, rtol=1e-10, atol=1e-10, t_eval=te)
        r = constrained.solve(pendulum(2), (0, 5), Q0, [0, 0], method="Radau",
                              dae_index=dae_index, rtol=1e-10, atol=1e-10, t_eval=te)
        assert ref.success and r.success, r.message
        assert r.rank == 1
        assert np.max(np.abs(r.q - ref.q)) <= 1e-8
        assert np.max(r.res_pos) <= 1e-10
        assert np.max(np.abs(r.lam[1] - 2 * r.lam[0])) <= 1e-9 * np.max(np.abs(r.lam))
        assert np.max(np.abs(r.reaction - ref.reaction)) <= 1e-6


@pytest.fixture(scope="module")
def bricard():
    pytest.importorskip("sympy")
    import symbolic_seeds as seeds
    from conmech.benchmarks import iftomm
    import tempfile
    seeds.use_test_cache(tempfile.mkdtemp(prefix="conmech-rattle-redundant-"))
    return iftomm.a04_bricard("E")


def test_rattle_bricard(bricard):
    """IFToMM A04 (five loop equations of rank four on five joint angles, one degree of
    freedom) with RATTLE: constraints at round-off over 10 s, the energy error bounded and
    of the method's order two (a quarter when h halves), and the path of P3 that of
    projected DOP853 at rtol 1e-11 to O(h^2)."""
    from conmech.benchmarks import iftomm
    p = bricard
    te = np.linspace(0, 10, 41)
    ref = constrained.solve(p.system, p.t_span, p.q0, p.v0, rtol=1e-11, atol=1e-11,
                            t_eval=te)
    assert ref.success and ref.rank == 4
    dev, dE = [], []
    for h in (2e-3, 1e-3):
        r = constrained.solve(p.system, p.t_span, p.q0, p.v0, method="RATTLE",
                              first_step=h, t_eval=te)
        assert r.success, r.message
        assert r.rank == 4
        assert np.max(r.res_pos) <= 1e-12 and np.max(r.res_vel) <= 1e-12
        dev.append(np.max(np.abs(iftomm.a04_p3(r.q) - iftomm.a04_p3(ref.q))))
        dE.append(np.max(np.abs(r.energy - r.energy[0])))
    assert dev[1] <= 1e-3 and dE[1] <= 1e-3 * abs(ref.energy[0])
    assert 3.0 <= dev[0] / dev[1] <= 5.0, dev          # order two
    assert 3.0 <= dE[0] / dE[1] <= 5.0, dE


def test_radau_bricard(bricard):
    """Radau IIA on Bricard's mechanism (rank four of five rows all along the motion):
    both DAE forms follow projected DOP853's path of P3, every row of the full set holds,
    the energy is kept to the tolerance."""
    from conmech.benchmarks import iftomm
    p = bricard
    te = np.linspace(0, 10, 41)
    ref = constrained.solve(p.system, p.t_span, p.q0, p.v0, rtol=1e-11, atol=1e-11,
                            t_eval=te)
    for dae_index, tol_p3 in ((2, 1e-9), (3, 1e-8)):
        r = constrained.solve(p.system, p.t_span, p.q0, p.v0, method="Radau",
                              dae_index=dae_index, rtol=1e-10, atol=1e-10, t_eval=te)
        assert r.success, r.message
        assert r.rank == 4
        assert np.max(r.res_pos) <= 1e-10
        assert np.max(np.abs(iftomm.a04_p3(r.q) - iftomm.a04_p3(ref.q))) <= tol_p3
        assert np.max(np.abs(r.energy - r.energy[0])) <= 1e-8 * abs(r.energy[0])


def fourbar():
    pytest.importorskip("sympy")
    import symbolic_seeds as seeds
    import tempfile
    seeds.use_test_cache(tempfile.mkdtemp(prefix="conmech-rattle-redundant-"))
    from test_symbolic_loops import fourbar as build
    return build("absolute")[0]


def exact_parallelogram(th0, te):
    """The parallelogram of uniform rods (m = l = d = 1): phi'' = -(6/5) g cos phi."""
    from scipy.integrate import solve_ivp as sp_ivp
    return sp_ivp(lambda s, y: [y[1], -1.2 * G * np.cos(y[0])], (te[0], te[-1]),
                  [th0, 1.0], t_eval=te, method="DOP853", rtol=1e-13, atol=1e-13).y[0]


def test_rattle_parallelogram_through_singular_configurations():
    """The parallelogram four-bar started flat (rank 1 of 2) and started at phi = 0.3,
    with RATTLE: it passes its singular configurations again and again (phi = 0 and
    -pi), follows the exact one-degree-of-freedom motion to O(h^2), keeps the coupler
    horizontal and the constraints at round-off, the energy error bounded by O(h^2)."""
    mech = fourbar()
    te = np.linspace(0, 10, 201)
    for th0 in (0.0, 0.3):
        ref = exact_parallelogram(th0, te)
        errs = []
        for h in (2e-3, 1e-3):
            r = constrained.solve(mech, (0, 10), [th0, 0, th0], [1.0, 0, 1.0],
                                  method="RATTLE", first_step=h, t_eval=te)
            assert r.success, r.message
            assert r.rank == (1 if th0 == 0 else 2)
            assert np.max(r.res_pos) <= 1e-13 and np.max(r.res_vel) <= 1e-13
            assert np.max(np.abs(r.q[1])) <= 1e-10                # the coupler stays flat
            errs.append(max(np.max(np.abs(r.q[0] - ref)), np.max(np.abs(r.q[2] - ref))))
            E = r.energy
            assert np.max(np.abs(E - E[0])) <= 100 * h ** 2
        assert errs[1] <= 2e-5 and 3.5 <= errs[0] / errs[1] <= 4.5, errs


def test_radau_parallelogram_singular_configuration():
    """Radau IIA and the parallelogram: started flat it is refused before the first step
    (the rank grows a short way along the motion: a singular configuration); started at
    phi = 0.3 it follows the motion to the first flat crossing and stops there with a
    message that names the dependent constraints (a failure, not a wrong answer)."""
    mech = fourbar()
    calls = []

    def counting(t, q, v):
        calls.append(t)
        return q[0] - 5.0
    with pytest.raises(ValueError, match=r"Radau IIA cannot start from a singular "
                                         r"configuration.*rank is 1 of 2.*but 2"):
        constrained.solve(mech, (0, 10), [0.0, 0, 0], [1.0, 0, 1.0], method="Radau",
                          events=counting)
    assert all(t == 0.0 for t in calls)
    te = np.linspace(0, 10, 201)
    r = constrained.solve(mech, (0, 10), [0.3, 0, 0.3], [1.0, 0, 1.0], method="Radau",
                          rtol=1e-10, atol=1e-10, t_eval=te)
    assert not r.success and "dependent" in r.message and "singular" in r.message
    ref = exact_parallelogram(0.3, te)
    k = r.t.size
    assert 0.25 < r.t[-1] < 0.35                 # the first flat crossing (t ~ 0.32)
    assert np.max(np.abs(r.q[0] - ref[:k])) <= 1e-8
