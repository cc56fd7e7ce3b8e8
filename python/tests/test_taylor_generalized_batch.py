"""Ensembles of generalized systems M(t, q) q'' = Q in SIMD lanes
(conmech.symbolic.taylor_generalized_batch): ensemble.solve(method="TAYLOR") of a system
made by conmech.symbolic.lagrangian_system takes the batch route (the coefficients of the
first-order view computed for several members at once, the written-out Cholesky
factorisation and triangular solves per lane, the propagator of the ode systems' lanes).

- each member agrees with its own solve_ivp(method="TAYLOR") run (the first-order view's
  scalar Taylor stepper) and with the ensemble's member-by-member route, bit for bit (the
  lanes run the scalar routine's operations in its order), with the same step counts, and
  with DOP853 at a tight tolerance to ~1e-12: a simple pendulum (constant M), the double
  pendulum from its Lagrangian, and a driven spring pendulum with parameters, M(q) =
  diag(m, m r^2) and a time-dependent torque;
- 2, 4 and 8 lanes give the same bits;
- a member whose mass matrix is singular at its initial state fails on its own, with a
  message that names it and its mass matrix, the other members unaffected;
- at WRITE_OUT_MAX degrees of freedom (an 8-link pendulum chain, written out): its lanes'
  loops of thousands of references split to at most WIDE_REFS each, each member its own
  solve_ivp(method="TAYLOR") run bit for bit, 4 and 8 lanes the same bits;
- beyond WRITE_OUT_MAX degrees of freedom (M's factorisation in loops over per-lane
  arrays): nine pendulums on a cart (10 degrees of freedom, an arrow-shaped M whose
  Cholesky factor fills in) take the lanes route, each member its own solve_ivp(method=
  "TAYLOR") run bit for bit (and the member-by-member route's; its wide lanes' loops
  split into loops of at most WIDE_REFS references), 1 and 4 lanes the same bits, DOP853
  to ~1e-9; a member with a singular M among 9 degrees of freedom fails alone.
"""
import re

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import conmech  # noqa: E402
from conmech import ensemble, symbolic  # noqa: E402
from conmech.symbolic.pipeline import model_of  # noqa: E402
from conmech.symbolic.taylor_generalized import WRITE_OUT_MAX  # noqa: E402
from conmech.symbolic.taylor_generalized_batch import WIDE_REFS  # noqa: E402
from conmech.symbolic.taylor_library import taylor_source  # noqa: E402
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402
import taylor_jets  # noqa: E402
from taylor_jets import metronomes_on_a_cart, pendulum_chain  # noqa: E402

TOL = 1e-12


def simple_pendulum():
    t = dynamicsymbols._t
    q = dynamicsymbols("q")
    g, ell = sp.symbols("g ell")
    return symbolic.lagrangian_system(ell**2*q.diff(t)**2/2 + g*ell*sp.cos(q), [q],
                                      params={g: 9.81, ell: 1.5})


def driven_spring_pendulum():
    """A mass m on a spring (stiffness k, rest length l0) swinging in gravity, driven by
    the torque A cos(omega t): M(q) = diag(m, m r^2)."""
    t = dynamicsymbols._t
    r, th = dynamicsymbols("r th")
    m, g, k, l0, A, om = sp.symbols("m g k l0 A omega")
    T = m*(r.diff(t)**2 + r**2*th.diff(t)**2)/2
    U = -m*g*r*sp.cos(th) + k*(r - l0)**2/2
    return symbolic.lagrangian_system(T - U, [r, th], forces=[0, A*sp.cos(om*t)],
                                      params={m: 0.7, g: 9.81, k: 40.0, l0: 1.0, A: 0.3,
                                              om: 2.1})


def members(ndof, m, seed):
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(-1.0, 1.0, (m, ndof)),
                            rng.uniform(-0.5, 0.5, (m, ndof))])


@pytest.fixture(scope="module")
def systems():
    sp_ = simple_pendulum()
    dp = taylor_jets.double_pendulum()
    dr = driven_spring_pendulum()
    y_dr = members(2, 7, 3)
    y_dr[:, 0] += 1.5          # the spring's length r > 0
    return [(sp_, members(1, 7, 1), 5.0), (dp, members(2, 7, 2), 3.0), (dr, y_dr, 3.0)]


def _batch_built(system):
    """Whether the model's batch library was built (the lanes route taken)."""
    parts = model_of(system).__dict__.get("_taylor_parts", {})
    return any(k.startswith("batch") and v[1] is not None for k, v in parts.items())


def _lanes_members_checked(system, y0s, tf, dop_tol, agree):
    """The lanes route's ensemble of `system`: built as a batch, each member bit-identical
    to the member-by-member route and to its own solve_ivp TAYLOR run (state and counts),
    and within `agree` (relative) of DOP853 at `dop_tol`. Returns the ensemble."""
    ens = ensemble.solve(system, (0, tf), y0s, method="TAYLOR", rtol=TOL, atol=TOL)
    assert ens.success and _batch_built(system)
    by_member = ensemble.solve(system, (0, tf), y0s, method="TAYLOR", rtol=TOL, atol=TOL,
                               progress=lambda done, total: None)
    assert np.array_equal(ens.y_final, by_member.y_final)
    assert np.array_equal(ens.nfev, by_member.nfev)
    for i, y0 in enumerate(y0s):
        r = conmech.solve_ivp(system, (0, tf), y0, method="TAYLOR", rtol=TOL, atol=TOL)
        assert r.success and ens.t_final[i] == tf
        assert np.array_equal(ens.y_final[i], r.y[:, -1])
        assert (ens.nfev[i], ens.naccept[i], ens.nreject[i]) == \
            (r.nfev, r.naccept, r.nreject)
        d = conmech.solve_ivp(system, (0, tf), y0, method="DOP853", rtol=dop_tol,
                              atol=dop_tol)
        scale = max(1.0, np.max(np.abs(d.y[:, -1])))
        assert np.max(np.abs(ens.y_final[i] - d.y[:, -1])) < agree*scale, system.name
    return ens


def test_members_are_their_own_taylor_runs_and_agree_with_dop853(systems):
    for system, y0s, tf in systems:
        _lanes_members_checked(system, y0s, tf, 3e-14, 1e-11)


def test_lanes_give_the_same_bits(systems):
    system, y0s, tf = systems[1]
    runs = [ensemble.solve(system, (0, tf), y0s, method="TAYLOR", rtol=TOL, atol=TOL,
                           lanes=k) for k in (2, 4, 8)]
    for r in runs[1:]:
        assert np.array_equal(r.y_final, runs[0].y_final)
        assert np.array_equal(r.nfev, runs[0].nfev)
    paths = model_of(system).taylor_paths
    assert len({paths.get(k) for k in ("batch2", "batch4", "batch8")} - {None}) >= 2


def test_a_singular_mass_matrix_fails_its_member_only():
    """M = q^2, singular at q = 0: the member starting there fails (a non-finite
    expansion), with its index and its mass matrix in the message; the others are their
    solve_ivp runs. The member-by-member route fails it with the same code."""
    t = dynamicsymbols._t
    q = dynamicsymbols("q")
    system = symbolic.lagrangian_system(q**2*q.diff(t)**2/2 + q**2/2, [q])
    y0s = np.array([[1.0, 0.3], [0.9, -0.2], [0.0, 1.0], [1.2, 0.1], [0.7, 0.0]])
    ens = ensemble.solve(system, (0, 1.0), y0s, method="TAYLOR", rtol=TOL, atol=TOL,
                         lanes=2)
    assert _batch_built(system)
    assert not ens.success and list(ens.status) == [0, 0, -1, 0, 0]
    assert "1 of 5 members failed; the first, member 2: non-finite" in ens.message
    assert "mass matrix" in ens.message and "not positive definite" in ens.message
    assert np.all(np.isfinite(ens.y_final)) and ens.t_final[2] == 0.0
    for i in (0, 1, 3, 4):
        r = conmech.solve_ivp(system, (0, 1.0), y0s[i], method="TAYLOR", rtol=TOL, atol=TOL)
        assert np.array_equal(ens.y_final[i], r.y[:, -1]) and ens.naccept[i] == r.naccept
    by_member = ensemble.solve(system, (0, 1.0), y0s, method="TAYLOR", rtol=TOL, atol=TOL,
                               progress=lambda done, total: None)
    assert np.array_equal(by_member.codes, ens.codes)


def test_a_mass_matrix_singular_along_the_way_fails_its_member_only():
    """M = q^2 with no force: from q = 1, v = -1 the solution q = sqrt(1 - 2 t) reaches
    the singularity q = 0 at t = 1/2 with an infinite velocity; that member stops just
    before, as its solve_ivp run does (the same steps), the others reach the end."""
    t = dynamicsymbols._t
    q = dynamicsymbols("q")
    system = symbolic.lagrangian_system(q**2*q.diff(t)**2/2, [q])
    y0s = np.array([[1.0, 0.3], [1.0, -1.0], [0.8, 0.1]])
    ens = ensemble.solve(system, (0, 1.0), y0s, method="TAYLOR", rtol=1e-10, atol=1e-10,
                         lanes=2)
    assert list(ens.status) == [0, -1, 0] and "member 1" in ens.message
    assert "mass matrix" in ens.message and np.all(np.isfinite(ens.y_final))
    r = conmech.solve_ivp(system, (0, 1.0), y0s[1], method="TAYLOR", rtol=1e-10, atol=1e-10)
    assert not r.success and 0.45 < ens.t_final[1] < 0.5 + 1e-9
    assert ens.t_final[1] == r.t[-1] and np.array_equal(ens.y_final[1], r.y[:, -1])
    assert ens.nfev[1] == r.nfev
    # the others: q^2 = q0^2 + 2 q0 v0 t exactly
    for i in (0, 2):
        q0, v0 = y0s[i]
        assert abs(ens.y_final[i, 0] - np.sqrt(q0**2 + 2*q0*v0)) < 1e-9


def _lane_loop_refs(src):
    """The references to per-lane values, w(l, ...) and x(l), of each lanes' loop."""
    refs, cur = [], None
    for x in src.splitlines():
        s = x.strip()
        if s == "do l = 1, nl":
            cur = 0
        elif cur is not None and s == "end do":
            refs.append(cur)
            cur = None
        elif cur is not None:
            cur += len(re.findall(r"\(l[,)]", x))
    return refs


def test_written_out_at_its_largest_splits_wide_loops_and_gives_each_member_its_own_run():
    """An 8-link pendulum chain (M full, written out): the order-0, history-sum and
    recurrence loops over the lanes (851, 1008 and 1990 references unsplit) split to at
    most WIDE_REFS references, for 4 and 8 lanes; each member its own solve_ivp run."""
    system = pendulum_chain(WRITE_OUT_MAX)
    d = model_of(system).derived
    assert d.n == WRITE_OUT_MAX
    for part in ("batch4", "batch8"):
        src, _, why = taylor_source(d, part)
        assert why is None and "lm(" not in src and "cl8_7(nl)" in src
        assert max(_lane_loop_refs(src)) <= WIDE_REFS
    rng = np.random.default_rng(13)
    y0s = np.column_stack([rng.uniform(-0.3, 0.3, (5, 8)), rng.uniform(-0.2, 0.2, (5, 8))])
    ens = _lanes_members_checked(system, y0s, 1.0, 1e-13, 1e-9)
    assert np.min(np.abs(ens.y_final - y0s)) > 1e-6
    runs = [ensemble.solve(system, (0, 1.0), y0s, method="TAYLOR", rtol=TOL, atol=TOL,
                           lanes=k) for k in (4, 8)]
    assert np.array_equal(runs[0].y_final, runs[1].y_final)
    assert np.array_equal(runs[0].nfev, runs[1].nfev)
    assert np.array_equal(runs[0].y_final, ens.y_final)


@pytest.fixture(scope="module")
def metronomes():
    """Nine pendulums on a cart on a spring (10 degrees of freedom), 6 members."""
    system = metronomes_on_a_cart(9)
    rng = np.random.default_rng(11)
    y0s = np.column_stack([rng.uniform(-0.3, 0.3, (6, 10)), rng.uniform(-0.4, 0.4, (6, 10))])
    return system, y0s, 2.0


def test_beyond_written_out_the_lanes_route_gives_each_member_its_own_run(metronomes):
    system, y0s, tf = metronomes
    assert model_of(system).derived.n == 10 > WRITE_OUT_MAX
    src, _, why = taylor_source(model_of(system).derived, "batch4")
    assert why is None and "do jj = 1, 10" in src and "lm(nl, 10, 10)" in src
    # its wide lanes' loops split (one of 271 references here) to WIDE_REFS at most
    assert max(_lane_loop_refs(src)) <= WIDE_REFS
    ens = _lanes_members_checked(system, y0s, tf, 1e-13, 1e-9)
    for i, y0 in enumerate(y0s):
        # a genuine motion: every pendulum and the cart move
        assert np.min(np.abs(ens.y_final[i] - y0)) > 1e-6


def test_beyond_written_out_one_and_four_lanes_give_the_same_bits(metronomes):
    system, y0s, tf = metronomes
    runs = [ensemble.solve(system, (0, tf), y0s, method="TAYLOR", rtol=TOL, atol=TOL,
                           lanes=k) for k in (1, 4)]
    assert np.array_equal(runs[0].y_final, runs[1].y_final)
    assert np.array_equal(runs[0].nfev, runs[1].nfev)
    paths = model_of(system).taylor_paths
    # two libraries (4 lanes: "batch" when that is the machine's width)
    assert paths.get("batch1") is not None
    assert paths.get("batch4", paths.get("batch")) not in (None, paths["batch1"])


def test_beyond_written_out_a_singular_mass_matrix_fails_its_member_only():
    """Eight oscillators with M_ii = 1 + x_i^2/4 and a ninth coordinate z with M = z^2
    (singular at z = 0): the member starting at z = 0 fails on its own, the others are
    their solve_ivp runs."""
    n = WRITE_OUT_MAX + 1
    t = dynamicsymbols._t
    qs = dynamicsymbols(" ".join(f"x{i}" for i in range(n)))
    L = sum((1 + qs[i]**2/4)*qs[i].diff(t)**2/2 - qs[i]**2/2 for i in range(n - 1))
    z = qs[-1]
    L += z**2*z.diff(t)**2/2 + z**2/2
    system = symbolic.lagrangian_system(L, qs, jacobian=False)
    y0s = members(n, 4, 5)
    y0s[:, n - 1] = [1.0, 0.9, 0.0, 1.2]
    y0s[:, 2*n - 1] = [0.3, -0.2, 1.0, 0.1]
    ens = ensemble.solve(system, (0, 1.0), y0s, method="TAYLOR", rtol=1e-10, atol=1e-10,
                         lanes=2)
    assert _batch_built(system)
    assert not ens.success and list(ens.status) == [0, 0, -1, 0]
    assert "1 of 4 members failed; the first, member 2: non-finite" in ens.message
    assert "mass matrix" in ens.message and "not positive definite" in ens.message
    assert np.all(np.isfinite(ens.y_final)) and ens.t_final[2] == 0.0
    for i in (0, 1, 3):
        r = conmech.solve_ivp(system, (0, 1.0), y0s[i], method="TAYLOR", rtol=1e-10,
                              atol=1e-10)
        assert np.array_equal(ens.y_final[i], r.y[:, -1]) and ens.naccept[i] == r.naccept


def test_shared_parameters_given_to_the_call_are_used(systems):
    """params given to the call for every member (one row or scalars) are the members'
    parameters on the lanes route too, for a generalized system and an ode system."""
    system, y0s, tf = systems[2]
    ens = ensemble.solve(system, (0, 1.0), y0s[:3], params={"k": 25.0, "A": 0.5},
                         method="TAYLOR", rtol=TOL, atol=TOL)
    other = system.with_params(k=25.0, A=0.5)
    for i in range(3):
        r = conmech.solve_ivp(other, (0, 1.0), y0s[i], method="TAYLOR", rtol=TOL, atol=TOL)
        assert np.array_equal(ens.y_final[i], r.y[:, -1])
    x, v, c = sp.symbols("x v c_gbatch")
    osc = symbolic.ode_system([v, -c*sp.sin(x)], [x, v], params={c: 1.0})
    y0 = np.array([[1.0, 0.0], [0.5, 0.2]])
    ens = ensemble.solve(osc, (0, 2.0), y0, params=[4.0], method="TAYLOR", rtol=TOL,
                         atol=TOL)
    for i in range(2):
        r = conmech.solve_ivp(osc.with_params(c_gbatch=4.0), (0, 2.0), y0[i],
                              method="TAYLOR", rtol=TOL, atol=TOL)
        assert np.array_equal(ens.y_final[i], r.y[:, -1])
