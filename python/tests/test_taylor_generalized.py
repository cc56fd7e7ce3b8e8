"""Taylor's method for generalized systems M(q) q'' = Q (conmech.symbolic.taylor_generalized:
the entries of M and Q expanded by the recurrences, the accelerations by one Cholesky
factorisation of M_0 per step and a pair of triangular solves per order), and Taylor's
method step by step from Python (conmech.Stepper(method="TAYLOR")).

- the generated coefficients of a two-degree-of-freedom system with a configuration-dependent
  mass matrix (rational data, polynomial M and Q) against the exact series of the solution
  (Euler-Lagrange equations and their solution for the accelerations by sympy itself,
  expanded in exact rational arithmetic) to round-off, order by order: the expansion has
  the order it claims;
- the factorisation written out in scalars and in loops give the same coefficients;
- the lecture notes' cart pendulum and the double pendulum from their Lagrangians: Taylor
  against DOP853, both at rtol 1e-13, agree to 1e-10; the energy of the double pendulum is
  conserved to the tolerance's level over about 60 periods;
- a mass matrix singular at the initial point or along the solution: a failed run whose
  message names M (never non-finite or silent output);
- a non-smooth Lagrangian is refused with the reason (trees: test_taylor_tree.py);
- conmech.Stepper(method="TAYLOR"), ode and generalized systems, a fresh model whose Taylor
  library is still to be built: the steps, states and counts of solve_ivp's run, bit for
  bit, and the dense output of each step from its Taylor polynomial;
- ensemble.solve(method="TAYLOR") of a generalized system: each member its own run.
"""
from fractions import Fraction

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import conmech  # noqa: E402
from conmech import symbolic  # noqa: E402
from conmech.ivp.taylor_generalized import first_order_view  # noqa: E402
from conmech.symbolic import build  # noqa: E402
from conmech.symbolic.pipeline import model_of  # noqa: E402
from conmech.symbolic.printer import _names  # noqa: E402
from conmech.symbolic.taylor_generalized import (generalized_decomposition,  # noqa: E402
                                                 generalized_procedures)
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402
import taylor_jets  # noqa: E402
from taylor_jets import coefficients, module_source  # noqa: E402


def jet(system, y, order, t=0.0):
    view = first_order_view(system)
    tay = view.taylor
    return coefficients(conmech.compiled.function_address(tay["jet"]), tay["nw"],
                        view.params, y, order, t)


@pytest.fixture(scope="module")
def cart():
    return taylor_jets.cart_pendulum()


@pytest.fixture(scope="module")
def double_pendulum():
    return taylor_jets.double_pendulum()


# ------------------------------------------------------------------ coefficients

def _series_mul(a, b):
    return [sum(a[i]*b[k - i] for i in range(k + 1)) for k in range(len(a))]


def _series_of(poly, xs):
    """A polynomial (sympy Poly) at truncated power series xs (lists of Fractions)."""
    m = len(xs[0])
    out = [Fraction(0)]*m
    for exps, c in poly.terms():
        term = [Fraction(int(c.p), int(c.q))] + [Fraction(0)]*(m - 1)
        for x, e in zip(xs, exps):
            for _ in range(e):
                term = _series_mul(term, x)
        out = [u + v for u, v in zip(out, term)]
    return out


def exact_series(fractions, y0, order):
    """The Taylor coefficients (orders 0..order) of q and v for q'' = N_i/D_i(q, v) (each
    a pair of sympy Polys in (q, v)), exact in rational arithmetic: with q, v known to
    order k, the quotient's series to order k gives a_k, then v^[k+1] = a_k/(k + 1) and
    q^[k+1] = v^[k]/(k + 1)."""
    n = len(y0)//2
    ys = [[Fraction(y)] for y in y0]
    for k in range(order):
        a = []
        for num, den in fractions:
            nn, dd = _series_of(num, ys), _series_of(den, ys)
            c = []
            for m in range(k + 1):
                c.append((nn[m] - sum(dd[j]*c[m - j] for j in range(1, m + 1)))/dd[0])
            a.append(c[k])
        for i in range(n):
            ys[i].append(ys[n + i][k]/(k + 1))
            ys[n + i].append(a[i]/(k + 1))
        ys = [y + [Fraction(0)] for y in ys]
        ys = [y[:k + 2] for y in ys]
    return ys


def test_coefficients_are_the_series_of_the_exact_solution():
    """M(q) = [[1 + q2^2, q1], [q1, 2]], U = (q1^2 + q2^2)/2 + q1 q2^2 / 3: every entry of
    M but one varies, the forces hold velocity products; with rational data the exact
    series has rational coefficients. The Euler-Lagrange equations are sympy's own
    (euler_equations), the accelerations its solve of them (a rational function of q, v),
    expanded along the solution in exact rational arithmetic."""
    from sympy.calculus.euler import euler_equations
    t = sp.Symbol("t")
    q1, q2 = sp.Function("q1")(t), sp.Function("q2")(t)
    M = sp.Matrix([[1 + q2**2, q1], [q1, 2]])
    qd = sp.Matrix([q1.diff(t), q2.diff(t)])
    L = (qd.T*M*qd)[0]/2 - (q1**2 + q2**2)/2 - q1*q2**2/3
    system = symbolic.lagrangian_system(L, [q1, q2])
    # the exact ODE: sympy's Euler-Lagrange equations solved for the accelerations
    eqs = euler_equations(L, [q1, q2], t)
    Q1, Q2, V1, V2, A1, A2 = sp.symbols("Q1 Q2 V1 V2 A1 A2")
    plain = [(q1.diff(t, 2), A1), (q2.diff(t, 2), A2), (q1.diff(t), V1),
             (q2.diff(t), V2), (q1, Q1), (q2, Q2)]      # derivatives first
    lhs = [e.lhs.subs(plain) for e in eqs]
    sol = sp.solve(lhs, [A1, A2], dict=True)[0]
    fracs = []
    for A in (A1, A2):
        num, den = sp.fraction(sp.together(sol[A]))
        fracs.append((sp.Poly(num, Q1, Q2, V1, V2), sp.Poly(den, Q1, Q2, V1, V2)))
    y0 = [Fraction(1, 2), Fraction(-1, 3), Fraction(1, 5), Fraction(3, 4)]
    order = 12
    want = np.array([[float(c) for c in row] for row in exact_series(fracs, y0, order)])
    got = jet(system, [float(v) for v in y0], order)
    for k in range(order + 1):
        scale = np.max(np.abs(want[:, k]))
        assert np.max(np.abs(got[:, k] - want[:, k])) <= 64*np.finfo(float).eps*scale, k
    # a genuine order-12 expansion: no order vanishes
    assert np.all(np.max(np.abs(want), axis=0) > 1e-8)


def test_factorisation_in_loops_gives_the_written_out_coefficients(cart):
    """Beyond WRITE_OUT_MAX degrees of freedom the Cholesky factorisation and the solves
    run in loops over a local array: the same coefficients (to round-off) as the scalars."""
    d = model_of(cart).derived
    g, why = generalized_decomposition(d)
    assert why is None
    lines = generalized_procedures(g, _names(d), write_out=False, npar=len(d.params))
    src = module_source("conmech_tgen_loop_form", lines)
    assert "do jj = 1, 2" in src
    path, _ = build.compile_source(src, None, ["taylor", "taylor_info", "taylor_rhs"])
    lib, addr = build.load(path, ["taylor", "taylor_info", "taylor_rhs"])
    y = [0.3, np.pi - 0.7, -0.2, 0.5]
    loops = coefficients(addr["taylor"], g.ncol, cart.params, y, 16)
    written = jet(cart, y, 16)
    assert np.all(np.isfinite(written))
    assert np.allclose(loops, written, rtol=1e-13, atol=1e-13*np.max(np.abs(written)))


# ------------------------------------------------------------------ integration

def test_taylor_agrees_with_dop853(cart, double_pendulum):
    for system, y0 in ((cart, [0.0, np.pi - 0.7, 0.3, 0.0]),
                       (double_pendulum, [1.2, -0.4, 0.3, 0.1])):
        r = conmech.solve_ivp(system, (0, 10), y0, method="TAYLOR", rtol=1e-13, atol=1e-13)
        d = conmech.solve_ivp(system, (0, 10), y0, method="DOP853", rtol=1e-13, atol=1e-13)
        assert r.success and d.success
        assert np.max(np.abs(r.y[:, -1] - d.y[:, -1])) < 1e-10
        assert r.nfev == r.naccept + r.nreject + 1          # one expansion per step
        # the first-order view runs with the system's current parameters
        r2 = conmech.solve_ivp(system, (0, 2), y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
        g = system.with_params(g=4.0)
        rg = conmech.solve_ivp(g, (0, 2), y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
        dg = conmech.solve_ivp(g, (0, 2), y0, method="DOP853", rtol=1e-12, atol=1e-12)
        assert np.max(np.abs(rg.y[:, -1] - dg.y[:, -1])) < 1e-9
        assert np.max(np.abs(rg.y[:, -1] - r2.y[:, -1])) > 1e-2


def test_energy_is_conserved_to_the_tolerance(double_pendulum):
    """About 60 periods of the double pendulum's small oscillations: the energy (a first
    integral of the Lagrangian) drifts by no more than the tolerance's level."""
    y0 = [0.3, -0.2, 0.0, 0.1]
    r = conmech.solve_ivp(double_pendulum, (0, 150), y0, method="TAYLOR", rtol=1e-12,
                          atol=1e-12, dense_output=True)
    assert r.success
    drift = double_pendulum.first_integrals.check(r, relative=True)["energy"]
    assert drift < 1e-10
    # the dense output (each step's Taylor polynomial) between the steps
    tm = 0.5*(r.t[:-1] + r.t[1:])[:50]
    d = conmech.solve_ivp(double_pendulum, (0, float(tm[-1])), y0, method="DOP853",
                          rtol=1e-13, atol=1e-13, t_eval=tm)
    assert np.max(np.abs(r.sol(tm) - d.y)) < 1e-9


def test_singular_mass_matrix_is_reported():
    """M = q^2: singular at q = 0. From q = 0 the run fails at once; from q = 1, v = -1
    the solution q = sqrt(1 - 2 t) reaches q = 0 at t = 1/2 with an infinite velocity:
    the run fails before, its output finite, and the message names the mass matrix."""
    t = dynamicsymbols._t
    q = dynamicsymbols("q")
    system = symbolic.lagrangian_system(q**2*q.diff(t)**2/2, [q])
    r = conmech.solve_ivp(system, (0, 1), [0.0, 1.0], method="TAYLOR", rtol=1e-10,
                          atol=1e-10)
    assert not r.success and r.status == -1
    assert "not finite" in r.message and "not positive definite" in r.message
    r = conmech.solve_ivp(system, (0, 1), [1.0, -1.0], method="TAYLOR", rtol=1e-10,
                          atol=1e-10)
    assert not r.success and "mass matrix" in r.message and "smallest eigenvalue" in r.message
    # the last accepted point at the singularity, to the accuracy of its time
    assert 0.45 < r.t[-1] < 0.5 + 1e-9 and np.all(np.isfinite(r.y))
    # away from the singularity the solution is the exact one
    away = r.t < 0.45
    assert np.max(np.abs(r.y[0, away] - np.sqrt(1 - 2*r.t[away]))) < 1e-8


def test_non_smooth_lagrangian_is_refused_with_the_reason():
    t = dynamicsymbols._t
    q = dynamicsymbols("q")
    system = symbolic.lagrangian_system(q.diff(t)**2/2 - sp.Abs(q), [q])
    with pytest.raises(ValueError, match="M\\(q\\) q'' = Q has no Taylor recurrences"):
        conmech.solve_ivp(system, (0, 1), [0.5, 0.0], method="TAYLOR")
    assert conmech.solve_ivp(system, (0, 1), [0.5, 0.0], method="DOP853").success


# ------------------------------------------------------------------ step by step

def _same_run(system, y0, tf, tol):
    """Stepper(method="TAYLOR") against solve_ivp(method="TAYLOR"): bit for bit."""
    r = conmech.solve_ivp(system, (0, tf), y0, method="TAYLOR", rtol=tol, atol=tol,
                          dense_output=True)
    s = conmech.Stepper(system, 0.0, y0, tf, method="TAYLOR", rtol=tol, atol=tol)
    ts, ys = [s.t], [s.y]
    while s.status == "running":
        assert s.step() is None
        ts.append(s.t)
        ys.append(s.y)
        sol = s.dense_output()
        tm = np.linspace(s.t_old, s.t, 5)[1:-1]      # inside the step: its polynomial
        assert np.array_equal(sol(s.t_old), ys[-2]) and \
            np.max(np.abs(sol(s.t) - s.y)) <= 1e-14*max(1.0, np.max(np.abs(s.y)))
        assert np.allclose(sol(tm), r.sol(tm), rtol=1e-15, atol=1e-15)
    assert s.status == "finished" and r.success
    assert np.array_equal(np.array(ts), r.t)
    assert np.array_equal(np.array(ys).T, r.y)
    assert (s.nfev, s.naccept, s.nreject) == (r.nfev, r.naccept, r.nreject)
    return s


def test_stepper_takes_solve_ivps_steps_on_a_fresh_model():
    """A model made here: its Taylor library is not built when the stepper is made (the
    stepper builds it, as solve_ivp does)."""
    x, v, kappa = sp.symbols("x v kappa_tgen_stepper")
    system = symbolic.ode_system([v, -sp.sin(x) - kappa*v*x**2], [x, v],
                                 params={kappa: 0.125})
    assert system.taylor_pending
    s = _same_run(system, [1.1, 0.2], 6.0, 1e-11)
    assert not system.taylor_pending and s.naccept > 5


def test_stepper_on_a_generalized_system(cart):
    _same_run(cart, [0.0, np.pi - 0.7, 0.3, 0.0], 4.0, 1e-12)


def test_stepper_refuses_a_system_without_taylor_code():
    def f(t, y):
        return [y[1], -y[0]]
    with pytest.raises(ValueError, match="no Taylor coefficients"):
        conmech.Stepper(f, 0.0, [1.0, 0.0], 1.0, method="TAYLOR")
    with pytest.raises(ValueError, match="no Taylor coefficients"):
        conmech.Stepper(conmech.systems.kepler(), 0.0, [0.5, 0, 0, 1.7], 1.0,
                        method="TAYLOR")


def test_ensemble_members_are_their_own_runs(cart):
    """ensemble.solve(method="TAYLOR") of a generalized system runs its first-order view
    in SIMD lanes (test_taylor_generalized_batch.py): each member is its solve_ivp run,
    bit for bit."""
    from conmech import ensemble
    y0s = np.array([[0.0, np.pi - 0.7, 0.3, 0.0], [0.1, 2.0, -0.2, 0.4]])
    ens = ensemble.solve(cart, (0, 3.0), y0s, method="TAYLOR", rtol=1e-11, atol=1e-11)
    for i, y0 in enumerate(y0s):
        r = conmech.solve_ivp(cart, (0, 3.0), y0, method="TAYLOR", rtol=1e-11, atol=1e-11)
        assert ens.status[i] == 0 and np.array_equal(ens.y_final[i], r.y[:, -1])
        assert ens.naccept[i] == r.naccept


def test_small_rtol_warns_once_at_the_callers_line(double_pendulum):
    """rtol below 100 eps, as a number (the fast entry) or an array (the full path): one
    UserWarning, pointing at the caller, as for an ode system."""
    import warnings
    y0 = [0.1, 0.2, 0.0, 0.0]
    for rtol in (1e-16, np.full(4, 1e-16)):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            r = conmech.solve_ivp(double_pendulum, (0, 1), y0, method="TAYLOR", rtol=rtol,
                                  atol=1e-16)
        assert r.success
        assert [w.filename for w in caught] == [__file__]
        assert "rtol" in str(caught[0].message)
