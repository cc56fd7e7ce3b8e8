"""Taylor's method generated from the model (conmech.symbolic.taylor, method "TAYLOR").

- the generated coefficients against sympy series of exact solutions (harmonic oscillator;
  Kepler via Kepler's equation solved order by order in sympy series) to round-off;
- one Kepler period (e = 0.9) against the exact solution; the dense output (the step's
  Taylor polynomial) between steps;
- energy over 1e4 Kepler periods: a random walk of round-off (Brouwer's law);
- compiled events: every zero of sin(50 t) + 0.9 on [0, 2] (32, several per step of the
  plain integration at rtol 1e-6) found to 1e-14;
- the variational system by the same recurrences: the STM agrees with DOP853's;
- batches: an ensemble member is its own solve_ivp run bit for bit;
- the recurrences written out for one order (what solve_ivp runs) give the loop version's
  coefficients bit for bit;
- quadruple precision: Arenstorf's orbit closes to 1e-25 (published period and initial
  velocity to 30 digits, Hairer-Norsett-Wanner I, II.0);
- clear errors for systems without Taylor code; a generalized system runs.
"""
import ctypes

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import conmech  # noqa: E402
from conmech import ensemble, stability, symbolic  # noqa: E402
from conmech.symbolic import taylor as T  # noqa: E402
from conmech.symbolic import taylor_quad  # noqa: E402

_P = ctypes.POINTER(ctypes.c_double)


def jet(system, y, order, t=0.0):
    """The generated coefficients y^[0..order] (rows: state components)."""
    tay = system.taylor
    fn = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_int, _P, _P)(
        conmech.compiled.function_address(tay["jet"]))
    w = np.zeros((tay["nw"], order + 1))
    w[:len(y), 0] = y
    p = np.ascontiguousarray(system.params if system.params.size else np.zeros(1))
    fn(t, order, w.ctypes.data_as(_P), p.ctypes.data_as(_P))
    return w[:len(y)]


@pytest.fixture(scope="module")
def kepler():
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    return symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])


@pytest.fixture(scope="module")
def arenstorf():
    x, y, u, w, mu = sp.symbols("x y u w mu")
    mup = 1 - mu
    d1 = ((x + mu)**2 + y**2)**sp.Rational(3, 2)
    d2 = ((x - mup)**2 + y**2)**sp.Rational(3, 2)
    f = [u, w, x + 2*w - mup*(x + mu)/d1 - mu*(x - mup)/d2,
         y - 2*u - mup*y/d1 - mu*y/d2]
    return symbolic.ode_system(f, [x, y, u, w], params={mu: 0.012277471})


def kepler_exact(z0, t):
    """The two-body solution (mu = 1, ellipse) at t by Kepler's equation (mpmath, 40 digits)."""
    import mpmath as mp
    with mp.workdps(40):
        x0 = [mp.mpf(z0[0]), mp.mpf(z0[1])]
        v0 = [mp.mpf(z0[2]), mp.mpf(z0[3])]
        r0 = mp.sqrt(x0[0]**2 + x0[1]**2)
        a = 1/(2/r0 - (v0[0]**2 + v0[1]**2))
        n = a**mp.mpf(-1.5)
        ec, es = 1 - r0/a, (x0[0]*v0[0] + x0[1]*v0[1])/mp.sqrt(a)
        ee = mp.sqrt(ec**2 + es**2)
        e0 = mp.atan2(es, ec)
        m = e0 - es + n*mp.mpf(t)
        big = m + ee*mp.sin(m)
        for _ in range(100):
            big -= (big - ee*mp.sin(big) - m)/(1 - ee*mp.cos(big))
        de = big - e0
        r = a*(1 - ee*mp.cos(big))
        f, g = 1 - a/r0*(1 - mp.cos(de)), mp.mpf(t) - (de - mp.sin(de))/n
        fd, gd = -mp.sqrt(a)/(r*r0)*mp.sin(de), 1 - a/r*(1 - mp.cos(de))
        return np.array([float(f*x0[i] + g*v0[i]) for i in range(2)]
                        + [float(fd*x0[i] + gd*v0[i]) for i in range(2)])


# ------------------------------------------------------------------ coefficients

def test_coefficients_harmonic_oscillator_are_the_exact_series():
    x, v, w2, t = sp.symbols("x v w2 t")
    osc = symbolic.ode_system([v, -w2*x], [x, v], params={w2: 2.25})
    x0, v0, om = 0.7, -0.4, sp.Rational(3, 2)
    exact = sp.Rational(7, 10)*sp.cos(om*t) + sp.Rational(-4, 10)/om*sp.sin(om*t)
    order = 24
    ser = sp.series(exact, t, 0, order + 1).removeO()
    want = np.array([float(ser.coeff(t, k)) for k in range(order + 1)])
    got = jet(osc, [x0, v0], order)
    assert np.max(np.abs(got[0] - want)) <= 4e-16*np.max(np.abs(want))
    # and v = x'
    assert np.allclose(got[1][:-1], want[1:]*np.arange(1, order + 1), rtol=0, atol=1e-15)


def test_coefficients_kepler_are_the_series_of_keplers_equation(kepler):
    # the orbit x = a (cos E - e), y = b sin E (a = 1, pericentre at t = 0) with E(t) from
    # E - e sin E = t, solved order by order in sympy series
    t = sp.Symbol("t")
    e = sp.Rational(1, 2)
    b = sp.sqrt(1 - e**2)
    order = 12
    cs = sp.symbols(f"c1:{order + 1}")
    big = sum(c*t**(k + 1) for k, c in enumerate(cs))
    sol = {}
    for k in range(1, order + 1):
        eq = sp.series((big - e*sp.sin(big)).subs(sol), t, 0, k + 1).removeO().coeff(t, k)
        eq -= 1 if k == 1 else 0
        sol[cs[k - 1]] = sp.nsimplify(sp.solve(eq, cs[k - 1])[0])
    bigs = big.subs(sol)
    xs = sp.series(sp.cos(bigs) - e, t, 0, order + 1).removeO()
    ys = sp.series(b*sp.sin(bigs), t, 0, order + 1).removeO()
    want = np.array([[float(s.coeff(t, k)) for k in range(order + 1)] for s in (xs, ys)])
    y0 = [0.5, 0.0, 0.0, float(sp.sqrt(3))]
    got = jet(kepler, y0, order)
    scale = np.max(np.abs(want), axis=1)
    assert np.all(np.max(np.abs(got[:2] - want), axis=1) <= 64*np.finfo(float).eps*scale)


def test_decomposition_shares_subexpressions_and_refuses_non_smooth(kepler):
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    d = symbolic.derive.derive_ode([u, v, -x/r3, -y/r3], [x, y, u, v])
    dec = T.decompose(list(d.f), d.coords, d.t, d.params)
    # x^2, y^2, their sum, one power (r^-3), two products: r^-3 is shared
    assert dec.counts() == {"sq": 2, "lin": 1, "pow": 1, "mul": 2}
    with pytest.raises(T.TaylorUnsupported, match="no Taylor recurrence"):
        T.decompose([sp.Abs(x)], [x], sp.Symbol("t"), [])
    bad = symbolic.ode_system([sp.Abs(x) - u, x], [x, u])
    assert bad.taylor is None
    with pytest.raises(ValueError, match="no Taylor"):
        conmech.solve_ivp(bad, (0, 1), [1.0, 0.0], method="TAYLOR")


# ------------------------------------------------------------------ integration

def test_one_period_kepler_and_dense_output(kepler):
    e = 0.9
    y0 = [1 - e, 0.0, 0.0, np.sqrt((1 + e)/(1 - e))]
    r = conmech.solve_ivp(kepler, (0, 2*np.pi), y0, method="TAYLOR", rtol=1e-12, atol=1e-12,
                          dense_output=True)
    # order 18 (Jorba and Zou's 15 raised by 3) and its longer steps: 54 steps, where
    # Jorba and Zou's order and step (heyoka's) take 73
    assert r.success and 45 < r.naccept < 65
    assert np.max(np.abs(r.y[:, -1] - kepler_exact(y0, 2*np.pi))) < 2e-10
    for tt in (0.3, 2.0, 3.14159, 6.2):
        assert np.max(np.abs(r.sol(tt) - kepler_exact(y0, tt))) < 2e-10


def test_energy_error_is_a_random_walk_of_round_off(kepler):
    e = 0.5
    y0 = [1 - e, 0.0, 0.0, np.sqrt((1 + e)/(1 - e))]
    periods = 10_000
    t_eval = 2*np.pi*np.array([10, 100, 1000, periods])
    r = conmech.solve_ivp(kepler, (0, 2*np.pi*periods), y0, method="TAYLOR", rtol=1e-16,
                          atol=1e-16, t_eval=t_eval, max_steps=10**7)
    assert r.success
    energy = 0.5*(r.y[2]**2 + r.y[3]**2) - 1/np.hypot(r.y[0], r.y[1])
    rel = np.abs(energy + 0.5)/0.5
    # Brouwer's law: ~ eps sqrt(steps) (378,000 steps: 1.4e-13), no linear drift
    assert rel[-1] <= 5*np.finfo(float).eps*np.sqrt(r.naccept)


def test_compiled_events_find_every_root(kepler):
    t = sp.Symbol("t")
    y0 = [0.5, 0.0, 0.0, np.sqrt(3.0)]
    ev = symbolic.event(kepler, sp.sin(50*t) + 0.9)
    th = np.arcsin(0.9)
    k = np.arange(20)
    exact = np.sort(np.r_[(np.pi + th + 2*np.pi*k)/50, (2*np.pi - th + 2*np.pi*k)/50])
    exact = exact[exact <= 2]
    assert exact.size == 32
    plain = conmech.solve_ivp(kepler, (0, 2), y0, method="TAYLOR", rtol=1e-6, atol=1e-6)
    per_step = [np.sum((exact > a) & (exact <= b)) for a, b in zip(plain.t[:-1], plain.t[1:])]
    assert max(per_step) >= 3          # the plain steps hold several roots each
    r = conmech.solve_ivp(kepler, (0, 2), y0, method="TAYLOR", rtol=1e-6, atol=1e-6,
                          events=[ev])
    assert r.success and r.t_events[0].size == 32
    assert np.max(np.abs(r.t_events[0] - exact)) <= 1e-14
    # the event state is the solution there; the event is a plain callable too
    assert abs(ev(r.t_events[0][3], r.y_events[0][3])) < 1e-13
    # direction and terminal: the 3rd rising crossing ends the run
    up = symbolic.event(kepler, sp.sin(50*t) + 0.9, terminal=3, direction=1)
    r = conmech.solve_ivp(kepler, (0, 2), y0, method="TAYLOR", rtol=1e-6, atol=1e-6,
                          events=[up])
    rising = np.sort((2*np.pi - th + 2*np.pi*k)/50)[:3]
    assert r.status == 1 and np.max(np.abs(r.t_events[0] - rising)) <= 1e-14
    assert r.t[-1] == r.t_events[0][-1]


def test_event_of_a_state_variable(kepler):
    """Crossings of y = 0 (the apsides) of Kepler e = 0.9: half periods, and t0, where y
    is exactly zero (SciPy's rule, applied to compiled events as to a Python one)."""
    x, y = sp.symbols("x y")
    e = 0.9
    y0 = [1 - e, 0.0, 0.0, np.sqrt((1 + e)/(1 - e))]
    kw = dict(method="TAYLOR", rtol=1e-12, atol=1e-12)
    r = conmech.solve_ivp(kepler, (0, 3*np.pi + 0.1), y0, events=[symbolic.event(kepler, y)],
                          **kw)
    assert r.t_events[0][0] == 0.0 and np.array_equal(r.y_events[0][0], y0)
    assert np.allclose(r.t_events[0], [0.0, np.pi, 2*np.pi, 3*np.pi], rtol=0, atol=1e-9)
    p = conmech.solve_ivp(kepler, (0, 3*np.pi + 0.1), y0, events=[lambda t, s: s[1]], **kw)
    assert p.t_events[0].size == 4
    np.testing.assert_allclose(r.t_events[0], p.t_events[0], rtol=0, atol=1e-9)


def test_variational_taylor_agrees_with_dop853(arenstorf):
    y0 = [0.994, 0.0, 0.0, -2.00158510637908252240537862224]
    period = 17.0652165601579625588917206249
    y1, m1 = stability.stm(arenstorf, (0, period), y0, method="TAYLOR")
    y2, m2 = stability.stm(arenstorf, (0, period), y0)
    assert np.max(np.abs(y1 - y2)) < 1e-8
    assert np.max(np.abs(m1 - m2)) <= 1e-7*np.max(np.abs(m2))
    # the flow is divergence-free: det Phi = 1
    assert abs(np.linalg.det(m1) - 1) < 1e-6
    m3 = stability.monodromy(arenstorf, y0, period, method="TAYLOR")
    assert np.array_equal(m1, m3)


def test_batch_members_are_their_own_runs(kepler):
    m = 9                              # two full batches of 4 and one of 1
    e = np.linspace(0.1, 0.7, m)
    y0 = np.column_stack([1 - e, 0*e, 0*e, np.sqrt((1 + e)/(1 - e))])
    res = ensemble.solve(kepler, (0, 3.0), y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
    assert res.success
    for i in range(m):
        r = conmech.solve_ivp(kepler, (0, 3.0), y0[i], method="TAYLOR", rtol=1e-12,
                              atol=1e-12)
        assert np.array_equal(r.y[:, -1], res.y_final[i])
        assert r.naccept == res.naccept[i]
    two = ensemble.solve(kepler, (0, 3.0), y0, method="TAYLOR", rtol=1e-12, atol=1e-12,
                         threads=2)
    assert np.array_equal(two.y_final, res.y_final)


def test_quadruple_precision_arenstorf_closes(arenstorf):
    y0 = ["0.994", "0", "0", "-2.00158510637908252240537862224"]
    period = "17.0652165601579625588917206249"
    r = taylor_quad.reference(arenstorf, (0, period), y0, tol=1e-30,
                              params={"mu": "0.012277471"})
    assert r.success and r.order == 36
    from decimal import Decimal
    closure = max(abs(Decimal(a) - Decimal(b)) for a, b in zip(r.y_str, y0))
    assert closure < Decimal("1e-25")
    # a double-precision run's error measured against it
    d = conmech.solve_ivp(arenstorf, (0, float(period)), [float(v) for v in y0],
                          method="TAYLOR", rtol=1e-14, atol=1e-14)
    err = np.max(np.abs(d.y[:, -1] - r.y_float))
    assert 1e-14 < err < 1e-8


def test_methods_without_taylor_code_are_refused():
    def f(t, y):
        return [y[1], -y[0]]
    with pytest.raises(ValueError, match="no Taylor"):
        conmech.solve_ivp(f, (0, 1), [1.0, 0.0], method="TAYLOR")
    with pytest.raises(ValueError, match="no Taylor"):
        conmech.solve_ivp(conmech.systems.kepler(), (0, 1), [0.5, 0, 0, 1.7], method="TAYLOR")
    with pytest.raises(ValueError, match="TAYLOR"):
        stability.stm(f, (0, 1), [1.0, 0.0], method="TAYLOR")


def test_generalized_system_runs_through_its_accelerations():
    """A Lagrangian system's accelerations come from a linear solve with M(q), expanded
    order by order (conmech.symbolic.taylor_generalized; test_taylor_generalized.py): the
    pendulum agrees with DOP853."""
    t = sp.Symbol("t")
    a = sp.Function("a")(t)
    pend = symbolic.lagrangian_system(sp.Rational(1, 2)*sp.diff(a, t)**2 + sp.cos(a), [a])
    r = conmech.solve_ivp(pend, (0, 1), [0.5, 0.0], method="TAYLOR", rtol=1e-12, atol=1e-12)
    d = conmech.solve_ivp(pend, (0, 1), [0.5, 0.0], method="DOP853", rtol=1e-12, atol=1e-12)
    assert r.success and d.success and np.max(np.abs(r.y[:, -1] - d.y[:, -1])) < 1e-10


def test_emitted_kepler_module_is_regenerated_identically():
    """test/taylor_kepler_model.f90 (used by the Fortran test test_taylor) is the emitted
    module of example/models/kepler.py."""
    from pathlib import Path
    from conmech.symbolic.__main__ import emit_file
    root = Path(__file__).resolve().parents[2]
    out = root / "test" / "taylor_kepler_model.f90"
    src, name, module = emit_file(root / "example" / "models" / "kepler.py", out)
    assert (name, module) == ("kepler_sym", "taylor_kepler_model")
    assert src == out.read_text()
    assert "procedure :: taylor_jet => kepler_sym_taylor_jet" in src


def test_written_out_recurrences_are_the_loops_bit_for_bit(arenstorf):
    """solve_ivp runs the recurrences written out for its order (no loops): the same
    coefficients, to the last bit, as the loop version (and so the same steps as the
    batch routine), for powers, quotients and sine/cosine pairs."""
    from conmech.ivp.taylor import taylor_order, with_fixed_order
    a, b, p, q = sp.symbols("a b p q")
    dd = a - b
    den = 3 - sp.cos(2*dd)
    pend = symbolic.ode_system(
        [p, q, (-3*sp.sin(a) - sp.sin(a - 2*b) - 2*sp.sin(dd)*(q**2 + p**2*sp.cos(dd)))/den,
         2*sp.sin(dd)*(2*p**2 + 2*sp.cos(a) + q**2*sp.cos(dd))/den], [a, b, p, q])
    for system, y in ((arenstorf, [0.994, 0.01, 0.02, -2.0]), (pend, [1.2, -0.4, 0.3, 0.1])):
        for tol in (1e-6, 1e-12):
            order = taylor_order(tol)
            fixed = with_fixed_order(system, tol, tol)
            assert fixed.taylor["order"] == order and fixed is not system
            assert with_fixed_order(system, tol, tol) is fixed      # kept with the model
            tay = fixed.taylor
            fn = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_int, _P, _P)(
                conmech.compiled.function_address(tay["jet_fixed"]))
            w = np.zeros((tay["nw"], order + 1))
            w[:4, 0] = y
            pr = np.ascontiguousarray(system.params if system.params.size else np.zeros(1))
            fn(0.0, order, w.ctypes.data_as(_P), pr.ctypes.data_as(_P))
            loop = jet(system, y, order)
            assert np.all(np.isfinite(loop)) and np.array_equal(w[:4], loop)
        # the same functions without the model behind them: solve_ivp runs the loop version
        plain = conmech.compiled.ode_system(
            4, int(system.spec[5]), jac=int(system.spec[6]), params=tuple(system.params),
            taylor={"jet": int(system.spec[18]), "nw": int(system.spec[19])})
        assert with_fixed_order(plain, 1e-12, 1e-12) is plain
        r1 = conmech.solve_ivp(system, (0, 2.0), y, method="TAYLOR", rtol=1e-12, atol=1e-12)
        r2 = conmech.solve_ivp(plain, (0, 2.0), y, method="TAYLOR", rtol=1e-12, atol=1e-12)
        assert r1.success and r1.naccept == r2.naccept and np.array_equal(r1.y, r2.y)
