"""Taylor's method for symbolic trees through their articulated-body code
(conmech.symbolic.taylor_tree: the chain of the articulated-body algorithm decomposed
definition by definition into elementary operations with Taylor recurrences).

- the generated coefficients of a small branched planar tree against the series of the
  solution computed independently: the accelerations M^-1 Q of the same tree's
  Lagrangian (sympy's Euler-Lagrange equations of its energies, not the articulated-body
  code), expanded along the solution by truncated power series in 40-digit arithmetic
  (mpmath), orders 0..8, to a few dozen round-offs;
- coefficients of an ode system whose decomposition sums symbolic coefficients of one
  column (as the chains of trees do): the exact series of a linear system;
- Taylor against DOP853, both at rtol 1e-13: a 3-link planar chain (absolute angles) and a
  branched tree with a prismatic joint, springs, dampers and a time-dependent torque agree
  to 1e-10; the same for the spatial route (three joints of the shipped arm, URDF);
- the energy of an undamped chain is conserved to the tolerance's level over about 50
  periods;
- the error at the end of a run falls with the tolerance (the order and step from the
  tolerance, as for ode systems): about in proportion, and below 100 times the tolerance;
- Stepper(method="TAYLOR") runs the steps of solve_ivp(method="TAYLOR"), bit for bit, and
  ensemble.solve(method="TAYLOR") each member's solve_ivp run (in SIMD lanes:
  test_taylor_tree_batch.py);
- a joint whose articulated inertia is not positive at run time (a zero mass at a leaf):
  a failed run whose message names the body; a tree with a non-smooth force is refused
  with the reason.
"""
import numpy as np
import pytest

sp = pytest.importorskip("sympy")
mpmath = pytest.importorskip("mpmath")
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402

import conmech  # noqa: E402
from conmech import symbolic  # noqa: E402
from conmech.ivp import ensemble  # noqa: E402
from conmech.ivp.taylor_generalized import first_order_view  # noqa: E402
from conmech.symbolic import Body, planar_tree  # noqa: E402
from conmech.symbolic.tree import derive_tree  # noqa: E402
from conmech.symbolic.urdf import data_path  # noqa: E402
import symbolic_seeds as seeds  # noqa: E402
import taylor_jets  # noqa: E402
from test_taylor_generalized import coefficients  # noqa: E402

t = dynamicsymbols._t


@pytest.fixture(scope="session", autouse=True)
def symbolic_cache(tmp_path_factory):
    """The test session's one compile cache (symbolic_seeds.use_test_cache)."""
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


def chain(N):
    """N point masses on massless rods, pinned at the origin, angles from the downward
    vertical (absolute)."""
    return taylor_jets.tree_chain_bodies(N)


def branched():
    """A torso on a horizontal prismatic slide (spring, damper), two arms with offsets and
    inertias, a hand on one arm driven by a torque that depends on t."""
    x, a1, a2, a3 = dynamicsymbols("x a1 a2 a3")
    m0, m1, m2, m3, I1, I2, I3, k, c, l1, l2, tau0, w = sp.symbols(
        "m0 m1 m2 m3 I1 I2 I3 k c l1 l2 tau0 w")
    g = sp.Symbol("g")
    bodies = [Body("torso", None, "prismatic", x, axis=(1, 0), mass=m0),
              Body("arm1", "torso", "revolute", a1, at=(0.1, 0.2), mass=m1,
                   com=(l1/2, -0.05), inertia=I1),
              Body("arm2", "torso", "revolute", a2, at=(-0.1, 0.2), mass=m2,
                   com=(0.03, -l2/2), inertia=I2),
              Body("hand", "arm1", "revolute", a3, at=(l1, 0), mass=m3, com=(0.2, 0.1),
                   inertia=I3)]
    params = {m0: 2.0, m1: 1.0, m2: 0.7, m3: 0.4, I1: 0.08, I2: 0.05, I3: 0.02, k: 3.0,
              c: 0.3, l1: 1.0, l2: 0.8, tau0: 0.5, w: 1.7, g: 9.81}
    forces = {"torso": -k*x - c*x.diff(t), "arm2": -c*a2.diff(t),
              a3: tau0*sp.sin(w*t) - c*(a3.diff(t) - a1.diff(t))}
    return bodies, params, forces, g


def jet(system, y, order, t0=0.0):
    view = first_order_view(system)
    tay = view.taylor
    return coefficients(conmech.compiled.function_address(tay["jet"]), tay["nw"],
                        view.params, y, order, t0)


# ------------------------------------------------------------------ coefficients

class _Series:
    """A truncated power series in mpmath numbers (coefficients 0..K)."""

    def __init__(self, c):
        self.c = list(c)

    @staticmethod
    def const(x, K):
        return _Series([mpmath.mpf(x)] + [mpmath.mpf(0)]*K)

    def __add__(self, o):
        return _Series([a + b for a, b in zip(self.c, o.c)])

    def __mul__(self, o):
        K = len(self.c)
        return _Series([mpmath.fsum(self.c[i]*o.c[k - i] for i in range(k + 1))
                        for k in range(K)])

    def inverse(self):
        """1/s from s * (1/s) = 1 solved order by order."""
        out = [1/self.c[0]]
        for k in range(1, len(self.c)):
            out.append(-mpmath.fsum(self.c[j]*out[k - j] for j in range(1, k + 1))/self.c[0])
        return _Series(out)

    def sincos(self):
        """sin and cos by the addition theorem: s = s0 + h, sin(h) and cos(h) from their
        power series in h (h has no constant term: h**j is O(t**j))."""
        K = len(self.c) - 1
        h = _Series([mpmath.mpf(0)] + self.c[1:])
        sh, ch = _Series.const(0, K), _Series.const(1, K)
        p = _Series.const(1, K)
        for j in range(1, K + 1):
            p = p*h
            term = _Series([x/mpmath.factorial(j) for x in p.c])
            if j % 2:
                sh = sh + _Series([x*(-1)**(j//2) for x in term.c])
            else:
                ch = ch + _Series([x*(-1)**(j//2) for x in term.c])
        s0, c0 = mpmath.sin(self.c[0]), mpmath.cos(self.c[0])
        sin = sh*_Series.const(c0, K) + ch*_Series.const(s0, K)
        cos = ch*_Series.const(c0, K) + sh*_Series.const(-s0, K)
        return sin, cos


def _evaluate(e, env, K):
    """The series of the sympy expression e with the symbols' series in env."""
    if e in env:
        return env[e]
    if e.is_Number:
        return _Series.const(mpmath.mpf(sp.Float(e, 45)), K)
    if e.is_Add:
        out = _evaluate(e.args[0], env, K)
        for a in e.args[1:]:
            out = out + _evaluate(a, env, K)
        return out
    if e.is_Mul:
        out = _evaluate(e.args[0], env, K)
        for a in e.args[1:]:
            out = out*_evaluate(a, env, K)
        return out
    if e.is_Pow and e.exp.is_Integer:
        b = _evaluate(e.base, env, K)
        if e.exp < 0:
            b = b.inverse()
        out = b
        for _ in range(abs(int(e.exp)) - 1):
            out = out*b
        return out
    if isinstance(e, (sp.sin, sp.cos)):
        s, c = _evaluate(e.args[0], env, K).sincos()
        return s if isinstance(e, sp.sin) else c
    raise NotImplementedError(str(e))


def series_of_the_solution(d, y0, K, t0=0.0):
    """The Taylor coefficients (orders 0..K) of [q; v] for M(q) q'' = Q(t, q, v) of the
    derived record d (with its parameter values), by Picard's iteration on truncated
    series: with q and v known to order k, the series of M and Q to order k give those of
    the accelerations a (M_0 a_m = Q_m - sum_{j=1..m} M_j a_{m-j}, m = 0..k, by mpmath's
    LU solve), then v^[k+1] = a_k/(k+1), q^[k+1] = v^[k]/(k+1)."""
    n = d.n
    vals = dict(zip(d.params, d.param_values))
    M = d.M.xreplace(vals)
    Q = d.Q.xreplace(vals)
    with mpmath.workdps(40):
        ys = [[mpmath.mpf(y)] + [mpmath.mpf(0)]*K for y in y0]
        tser = _Series([mpmath.mpf(t0), mpmath.mpf(1)] + [mpmath.mpf(0)]*(K - 1))
        for k in range(K):
            env = {s: _Series(ys[i]) for i, s in enumerate(list(d.coords) + list(d.speeds))}
            env[d.t] = tser
            Ms = [[_evaluate(M[i, j], env, K).c for j in range(n)] for i in range(n)]
            Qs = [_evaluate(Q[i], env, K).c for i in range(n)]
            M0 = mpmath.matrix([[Ms[i][j][0] for j in range(n)] for i in range(n)])
            a = []
            for m in range(k + 1):
                r = [Qs[i][m] - mpmath.fsum(Ms[i][l][j]*a[m - j][l] for j in range(1, m + 1)
                                            for l in range(n)) for i in range(n)]
                a.append(mpmath.lu_solve(M0, mpmath.matrix(r)))
            for i in range(n):
                ys[i][k + 1] = ys[n + i][k]/(k + 1)
                ys[n + i][k + 1] = a[k][i]/(k + 1)
        return np.array([[float(c) for c in y] for y in ys])


@pytest.mark.parametrize("coordinates", ["relative", "absolute"])
def test_coefficients_are_the_series_of_the_lagrangian_solution(coordinates):
    """Orders 0..8 of the branched tree (prismatic and revolute joints, forces in q, v and
    t) at a generic point: the generated recurrences of the articulated-body chain against
    the series of the solution of the tree's Lagrangian equations, to 64 round-offs of the
    coefficients' scale (each order's coefficients against their own size: they fall
    like the radius of convergence to the power k)."""
    bodies, params, forces, g = branched()
    system = planar_tree(bodies, params, gravity=(0, -g), forces=forces,
                         coordinates=coordinates)
    d = derive_tree(bodies, params, gravity=(0, -g), forces=forces,
                    coordinates=coordinates)
    y0 = [0.3, -0.4, 0.9, 0.25, 0.5, -0.7, 1.1, 0.2]
    K = 8
    t0 = 0.7
    ref = series_of_the_solution(d, y0, K, t0)
    got = jet(system, np.array(y0), K, t0)
    assert got.shape == ref.shape
    for k in range(K + 1):
        scale = np.max(np.abs(ref[:, k]))
        assert scale > 0
        err = np.max(np.abs(got[:, k] - ref[:, k]))
        assert err <= 64*np.finfo(float).eps*scale, (k, err/scale)


def test_coefficients_that_become_sums_print_as_factors():
    """A column reached by two terms with symbolic factors (p x + q (x + y): x's
    coefficient is p + q, as in the chains of definitions of trees) is one named constant
    in the generated code, not the text "p + q*x": the coefficients of the linear system
    y' = A y are A**k y0 / k!, exactly up to round-off."""
    import math
    x, y, p, q = sp.symbols("x_sum y_sum p_sum q_sum")
    system = symbolic.ode_system([p*x + q*(x + y), -x], [x, y], params={p: 0.3, q: -1.7})
    tay = system.taylor
    y0 = np.array([0.4, -1.1])
    got = coefficients(conmech.compiled.function_address(tay["jet"]), tay["nw"],
                       system.params, y0, 6)
    A = np.array([[0.3 - 1.7, -1.7], [-1.0, 0.0]])
    ref = np.array([np.linalg.matrix_power(A, k) @ y0/math.factorial(k) for k in range(7)]).T
    assert np.max(np.abs(got - ref)) <= 1e-15


# ------------------------------------------------------------------ trajectories

def _agree(system, y0, tf, n_check=None):
    """Taylor and DOP853 at rtol = atol = 1e-13: the largest difference at 9 times."""
    te = np.linspace(0, tf, 9)
    rt = conmech.solve_ivp(system, (0, tf), y0, method="TAYLOR", rtol=1e-13, atol=1e-13,
                           t_eval=te)
    rd = conmech.solve_ivp(system, (0, tf), y0, method="DOP853", rtol=1e-13, atol=1e-13,
                           t_eval=te)
    assert rt.success and rd.success, (rt.message, rd.message)
    # Taylor's steps are far longer than DOP853's (the order from the tolerance)
    assert rt.naccept < rd.naccept
    return np.max(np.abs(rt.y - rd.y))


def test_three_link_chain_agrees_with_dop853():
    bodies, params, g = chain(3)
    system = planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute")
    assert _agree(system, [1.2, 0.4, -0.5, 0.0, 0.3, -0.2], 10.0) <= 1e-10


@pytest.mark.parametrize("coordinates", ["relative", "absolute"])
def test_branched_tree_agrees_with_dop853(coordinates):
    bodies, params, forces, g = branched()
    system = planar_tree(bodies, params, gravity=(0, -g), forces=forces,
                         coordinates=coordinates)
    assert _agree(system, [0.3, -0.4, 0.9, 0.25, 0.5, -0.7, 1.1, 0.2], 8.0) <= 1e-10


def test_tree_derived_through_its_lagrangian_agrees_with_dop853():
    """method="lagrangian": the chain of the articulated-body algorithm kept on the
    derived record (d.aba), the same recurrences."""
    bodies, params, g = chain(3)
    system = planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute",
                         method="lagrangian")
    assert _agree(system, [1.2, 0.4, -0.5, 0.0, 0.3, -0.2], 5.0) <= 1e-10


def three_joint_arm():
    """The first three joints of the shipped seven-joint arm (URDF text: the links and
    joints beyond link3 dropped)."""
    import xml.etree.ElementTree as ET
    root = ET.parse(data_path("arm7.urdf")).getroot()
    keep = {"base", "link1", "link2", "link3"}
    for el in list(root):
        if el.tag == "link" and el.get("name") not in keep or \
                el.tag == "joint" and el.find("child").get("link") not in keep:
            root.remove(el)
    return ET.tostring(root, encoding="unicode")


def test_spatial_tree_from_urdf_agrees_with_dop853():
    """A spatial tree from URDF (three joints of the shipped arm, damping on): the
    spatial articulated-body algorithm's chain through the same route. (The whole
    seven-joint arm works the same way; its Taylor library takes minutes to compile.)"""
    system = symbolic.from_urdf(three_joint_arm())
    assert system.dimension == 6
    y0 = np.array([0.2, -0.4, 0.7, -0.5, 0.3, 0.5])
    assert _agree(system, y0, 3.0) <= 1e-10


def test_energy_is_conserved_over_a_long_run():
    """The undamped 3-link chain over ~50 periods of its slowest mode at rtol 1e-12: the
    energy T + U drifts by less than 1e-10 of its size (the local errors of an
    integrator with step control accumulate: no symplectic bound, a drift of the order of
    the tolerance times the number of steps)."""
    bodies, params, g = chain(3)
    system = planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute")
    model = symbolic.model_of(system)
    y0 = np.array([0.8, 0.3, -0.4, 0.0, 0.5, -0.3])
    r = conmech.solve_ivp(system, (0, 120.0), y0, method="TAYLOR", rtol=1e-12, atol=1e-12,
                          t_eval=np.linspace(0, 120.0, 241))
    assert r.success
    E = np.array([float(np.ravel(model.call("energy", 0.0, y[:3], y[3:]))[0])
                  for y in r.y.T])
    assert np.max(np.abs(E - E[0])) <= 1e-10*max(1.0, abs(E[0]))
    # and not trivially: Taylor at a loose tolerance drifts visibly more
    rl = conmech.solve_ivp(system, (0, 120.0), y0, method="TAYLOR", rtol=1e-6, atol=1e-6,
                           t_eval=np.linspace(0, 120.0, 241))
    El = np.array([float(np.ravel(model.call("energy", 0.0, y[:3], y[3:]))[0])
                   for y in rl.y.T])
    assert np.max(np.abs(El - El[0])) > 10*np.max(np.abs(E - E[0]))


def test_error_falls_with_the_tolerance():
    """The global error at t = 6 of the 3-link chain against a reference (Taylor and
    DOP853 at 3e-14, which agree to 1e-11): at tolerances 1e-7, 1e-9, 1e-11 the error
    falls about in proportion (log-log slope 0.6..1.6) and stays below 100 times the
    tolerance: the order and the step from the tolerance work for the tree's
    recurrences."""
    bodies, params, g = chain(3)
    system = planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute")
    y0 = [1.2, 0.4, -0.5, 0.0, 0.3, -0.2]
    ref = conmech.solve_ivp(system, (0, 6.0), y0, method="TAYLOR", rtol=3e-14,
                            atol=3e-14).y[:, -1]
    ref2 = conmech.solve_ivp(system, (0, 6.0), y0, method="DOP853", rtol=3e-14,
                             atol=3e-14).y[:, -1]
    assert np.max(np.abs(ref - ref2)) <= 1e-11
    tols = [1e-7, 1e-9, 1e-11]
    errs = []
    for tol in tols:
        r = conmech.solve_ivp(system, (0, 6.0), y0, method="TAYLOR", rtol=tol, atol=tol)
        assert r.success
        errs.append(np.max(np.abs(r.y[:, -1] - ref)))
    errs = np.array(errs)
    assert np.all(errs <= 100*np.array(tols)), errs
    slope = np.polyfit(np.log10(tols), np.log10(errs), 1)[0]
    assert 0.6 <= slope <= 1.6, (slope, errs)


# ------------------------------------------------------------------ step by step, ensembles

def test_stepper_takes_solve_ivps_steps():
    bodies, params, forces, g = branched()
    system = planar_tree(bodies, params, gravity=(0, -g), forces=forces)
    from test_taylor_generalized import _same_run
    s = _same_run(system, [0.3, -0.4, 0.9, 0.25, 0.5, -0.7, 1.1, 0.2], 3.0, 1e-11)
    assert s.naccept > 3


def test_ensemble_members_are_their_own_runs():
    bodies, params, g = chain(3)
    system = planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute")
    y0s = np.array([[1.2, 0.4, -0.5, 0.0, 0.3, -0.2], [0.2, -0.1, 0.6, 0.4, 0.0, 0.1]])
    ens = ensemble.solve(system, (0, 3.0), y0s, method="TAYLOR", rtol=1e-11, atol=1e-11)
    for i, y0 in enumerate(y0s):
        r = conmech.solve_ivp(system, (0, 3.0), y0, method="TAYLOR", rtol=1e-11,
                              atol=1e-11)
        assert ens.status[i] == 0 and np.array_equal(ens.y_final[i], r.y[:, -1])
        assert ens.naccept[i] == r.naccept


# ------------------------------------------------------------------ failures

def test_non_positive_articulated_inertia_is_a_failure_naming_the_joint():
    """A zero mass at the leaf of a chain of point masses (run-time parameter): the leaf's
    articulated inertia m l**2 is 0; the run fails at once and names the body."""
    bodies, params, g = chain(2)
    system = planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute")
    r = conmech.solve_ivp(system.with_params(m2=0.0), (0, 1), [0.3, 0.2, 0.0, 0.1],
                          method="TAYLOR")
    assert not r.success
    assert "articulated inertia of the joint of body 'link1'" in r.message
    assert "not positive definite" in r.message
    # and a good parameter value runs
    assert conmech.solve_ivp(system.with_params(m2=0.5), (0, 1), [0.3, 0.2, 0.0, 0.1],
                             method="TAYLOR").success


def test_non_smooth_force_is_refused_with_the_reason():
    bodies, params, g = chain(2)
    th = [b.q for b in bodies]
    system = planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute",
                         forces=[-sp.Abs(th[0]), 0])
    with pytest.raises(ValueError, match="no Taylor recurrences.*smooth functions"):
        conmech.solve_ivp(system, (0, 1), [0.3, 0.2, 0.0, 0.1], method="TAYLOR")
    assert conmech.solve_ivp(system, (0, 1), [0.3, 0.2, 0.0, 0.1], method="DOP853").success
