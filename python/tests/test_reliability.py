"""Reliability: no wrong result called success, every input validated, callbacks
of every kind handled alike (exception re-raised unchanged, no leak, clean messages).

The 13 cases of the issue are named regression tests here (test_case_*)."""
import math
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import conmech
from conmech import constrained, hill, stability, systems
from conmech._core.callback import Guard, as_result, message_text

G = 9.81


def harmonic(t, y):
    return [y[1], -y[0]]


def circle_system(jac=None, phi=None, n_hol=1):
    return constrained.ConstrainedSystem(
        2, mass=lambda t, q: np.eye(2), forces=lambda t, q, v: np.array([0.0, -G]),
        phi=phi or (lambda t, q: np.array([q[0]**2 + q[1]**2 - 1])), jac=jac, n_hol=n_hol)


# ----------------------------------------------------------------- the 13 cases
def test_case_01_rhs_returning_none_after_some_calls_raises():
    calls = [0]

    def f(t, y):
        calls[0] += 1
        return [y[1], -y[0]] if calls[0] <= 3 else None
    with pytest.raises(ValueError, match="fun returned None"):
        conmech.solve_ivp(f, (0, 1), [1.0, 0.0])


def test_case_01b_rhs_changing_shape_raises():
    calls = [0]

    def f(t, y):
        calls[0] += 1
        return [y[1], -y[0]] if calls[0] <= 5 else [y[1], -y[0], 0.0]
    with pytest.raises(ValueError, match=r"shape \(2,\)"):
        conmech.solve_ivp(f, (0, 1), [1.0, 0.0])
    with pytest.raises(ValueError, match="fun returned None"):   # 1-D: no constant solution
        conmech.solve_ivp(lambda t, y: None, (0, 1), [1.0])


def test_case_02_zero_constraint_jacobian_is_not_success():
    s = circle_system(jac=lambda t, q: np.zeros((1, 2)))
    try:
        r = constrained.solve(s, (0, 1), [0.6, -0.8], [0, 0])
    except ValueError as exc:
        assert "Jacobian" in str(exc)
    else:
        assert not r.success


def test_case_03_rank_deficient_constraint_jacobian_is_not_success():
    # the second row of the Jacobian is wrong (zero): x drifts and cannot be projected back
    s = circle_system(phi=lambda t, q: np.array([q @ q - 1, q[0] - 0.6]),
                      jac=lambda t, q: np.array([[2 * q[0], 2 * q[1]], [0.0, 0.0]]), n_hol=2)
    r = constrained.solve(s, (0, 1), [0.6, -0.8], [0, 0])
    assert not r.success and "projection" in r.message and "at t =" in r.message
    assert r.t[-1] < 1.0 and np.all(r.res_pos[:-1] <= 1e-12)   # stopped where it failed


def test_case_04_incompatible_constraints_are_not_success():
    s = circle_system(phi=lambda t, q: np.array([q @ q - 1, q @ q - 4]), n_hol=2)
    r = constrained.solve(s, (0, 1), [0.6, -0.8], [0, 0])
    assert not r.success and "inconsistent" in r.message


def test_case_05_variation_orbit_not_converged_raises():
    # Newton diverges there (the library says so), or, should it stop on a state that is
    # not periodic, the independent check of hill.py does
    with pytest.raises(RuntimeError, match="did not converge|diverged|not periodic"):
        hill.variation_orbit(1.0)
    orb = hill.variation_orbit(hill.M_HILL)         # the flagship still converges
    assert abs(orb.c - hill.C_HILL) < 1e-12


def test_case_06_family_wrong_orbit_is_not_success():
    fam = hill.family([1.0])
    assert not fam.success[0] and fam.status[0] < 0 and np.isnan(fam.c[0])
    fam = hill.family(np.linspace(0.05, 0.1, 6))
    assert fam.success.all()


@pytest.mark.parametrize("tol", [-1.0, float("nan"), float("inf"), 1.0])
def test_case_07_equilibrium_tolerance_validated(tol):
    with pytest.raises(ValueError, match="tol"):
        stability.equilibrium(systems.pendulum(), [0, 0], tol=tol)
    assert stability.equilibrium(systems.pendulum(), [0, 0]).kind == "centre"


@pytest.mark.parametrize("rtol", [1e300, 0.0, -1e-12, float("nan")])
def test_case_08_transverse_rtol_validated(rtol):
    orb = hill.variation_orbit(hill.M_HILL)
    with pytest.raises(ValueError, match="rtol"):
        hill.transverse(orb, rtol=rtol)


@pytest.mark.parametrize("call, name", [
    (lambda: constrained.solve("pendulum_xy", (0, 1), rtol=float("inf")), "rtol"),
    (lambda: constrained.solve("pendulum_xy", (0, 1), atol=float("inf")), "atol"),
    (lambda: constrained.solve("pendulum_xy", (0, 1), max_step=float("nan")), "max_step"),
    (lambda: constrained.solve("pendulum_xy", (0, 1), t_eval=[0.1, 0.1]), "t_eval"),
    (lambda: stability.stm(systems.harmonic(), (0, 1), [1.0, 0.0], atol=float("inf")),
     "atol"),
    (lambda: stability.stm(systems.harmonic(), (0, 1), [1.0, 0.0], rtol=float("inf")),
     "rtol"),
    (lambda: stability.periodic_orbit(systems.harmonic(), [1, 0], 6.0, max_iter=0),
     "max_iter"),
    (lambda: conmech.solve_ivp(harmonic, (0, 1), [1, 0], rtol=float("inf")), "rtol"),
    (lambda: conmech.solve_ivp(harmonic, (0, 1), [1, 0], atol=float("inf")), "atol"),
    (lambda: conmech.solve_ivp(harmonic, (0, 1), [1, 0], max_step=float("nan")), "max_step"),
    (lambda: conmech.solve_ivp(harmonic, (0, 1), [1, 0], t_eval=[0.5, 0.5]), "t_eval"),
    (lambda: stability.hill_equation(lambda t: 1.0, 2 * np.pi, rtol=float("inf")), "rtol"),
])
def test_case_09_tolerances_steps_counts_validated(call, name):
    with pytest.raises(ValueError, match=name):
        call()


@pytest.mark.parametrize("factory, kw, name", [
    (systems.pendulum, dict(l=0.0), "l"), (systems.kepler, dict(mu=-1.0), "mu"),
    (systems.kepler, dict(mu=0.0), "mu"), (systems.double_pendulum, dict(l2=0.0), "l2"),
    (systems.pendulum_xy, dict(l=0.0), "l"), (systems.rolling_disk, dict(R=0.0), "R"),
    (systems.arenstorf, dict(mu=1.5), "mu"), (systems.hill, dict(m=-0.1), "m"),
])
def test_case_10_singular_builtin_parameters_refused(factory, kw, name):
    with pytest.raises(ValueError, match=f"{name} of the system"):
        factory(**kw)


def test_case_11_hill_equation_with_a_million_constant_samples_is_fast():
    # Phi = 1: N'' + N = 0, the monodromy over 2 pi is the identity
    r = stability.hill_equation(np.ones(10**6), 2 * np.pi)
    np.testing.assert_allclose(r.monodromy, np.eye(2), atol=1e-9)
    # a band-limited Phi keeps its interpolant: Mathieu 1 + 0.2 cos t from 10^5 samples
    # against the callable
    t = np.arange(10**5) * 2 * np.pi / 10**5
    a = stability.hill_equation(1.2 + 0.2 * np.cos(t), 2 * np.pi)
    b = stability.hill_equation(lambda s: 1.2 + 0.2 * math.cos(s), 2 * np.pi)
    assert abs(a.half_trace - b.half_trace) < 1e-9


@pytest.mark.parametrize("y0", [[1e-150, 0.0], [5e149, 0.0], [1e300, 0.0]])
def test_case_12_huge_and_tiny_states_succeed_like_scipy(y0):
    for fun in (harmonic, systems.harmonic()):
        for method in ("RK45", "DOP853", "VERNER98"):
            r = conmech.solve_ivp(fun, (0, 10), y0, method=method)
            assert r.success, (method, r.message)
    if y0[0] > 1:     # relative accuracy where the states are far above atol
        r = conmech.solve_ivp(harmonic, (0, 10), y0, rtol=1e-8)
        np.testing.assert_allclose(r.y[:, -1] / y0[0], [np.cos(10), -np.sin(10)],
                                   atol=1e-6)


def test_case_13_stability_callback_exception_no_leak_and_unchanged():
    err = RuntimeError("boom")

    def f(t, y):
        raise err
    with pytest.raises(RuntimeError) as info:
        stability.stm(f, (0, 1), np.ones(2000))
    assert info.value is err            # the same object, re-raised unchanged


# ----------------------------------------------------------------- callbacks alike
def _raiser(exc):
    def f(*args):
        raise exc
    return f


def _after(k, good, bad):
    """good(*args) for the first k calls, then bad(*args)."""
    c = [0]

    def f(*args):
        c[0] += 1
        return good(*args) if c[0] <= k else bad(*args)
    return f


FAILURES = {
    "solve_ivp rhs raises": lambda: conmech.solve_ivp(
        _after(4, harmonic, _raiser(KeyError("k"))), (0, 1), [1.0, 0.0]),
    "solve_ivp rhs wrong length": lambda: conmech.solve_ivp(
        _after(4, harmonic, lambda t, y: [1.0]), (0, 1), [1.0, 0.0]),
    "solve_ivp rhs None": lambda: conmech.solve_ivp(
        _after(4, harmonic, lambda t, y: None), (0, 1), [1.0, 0.0]),
    "event raises": lambda: conmech.solve_ivp(
        harmonic, (0, 1), [1.0, 0.0], events=_after(3, lambda t, y: y[0],
                                                    _raiser(KeyError("e")))),
    "event wrong length": lambda: conmech.solve_ivp(
        harmonic, (0, 1), [1.0, 0.0], events=_after(3, lambda t, y: y[0],
                                                    lambda t, y: [1.0, 2.0])),
    "builtin event raises": lambda: conmech.solve_ivp(
        systems.harmonic(), (0, 1), [1.0, 0.0], events=_raiser(KeyError("b"))),
    "stm rhs raises": lambda: stability.stm(
        _after(3, harmonic, _raiser(KeyError("s"))), (0, 1), [1.0, 0.0]),
    "stm jac wrong shape": lambda: stability.stm(
        harmonic, (0, 1), [1.0, 0.0], jac=_after(2, lambda t, y: np.eye(2),
                                                  lambda t, y: np.eye(3))),
    "equilibrium rhs None": lambda: stability.equilibrium(
        _after(1, harmonic, lambda t, y: None), [0.0, 0.0]),
    "orbit rhs raises": lambda: stability.periodic_orbit(
        _after(5, harmonic, _raiser(KeyError("o"))), [1.0, 0.0], 6.3, fixed_period=True),
    "hill_equation phi raises": lambda: stability.hill_equation(
        _after(3, lambda t: 1.0, _raiser(KeyError("h"))), 2 * np.pi),
    "constrained mass wrong shape": lambda: constrained.solve(
        constrained.ConstrainedSystem(
            2, mass=_after(3, lambda t, q: np.eye(2), lambda t, q: np.eye(3)),
            forces=lambda t, q, v: np.array([0.0, -G]),
            phi=lambda t, q: np.array([q @ q - 1]), n_hol=1),
        (0, 1), [0.6, -0.8], [0, 0]),
    "constrained forces raises": lambda: constrained.solve(
        constrained.ConstrainedSystem(
            2, mass=lambda t, q: np.eye(2),
            forces=_after(3, lambda t, q, v: np.array([0.0, -G]), _raiser(KeyError("f"))),
            phi=lambda t, q: np.array([q @ q - 1]), n_hol=1),
        (0, 1), [0.6, -0.8], [0, 0]),
}


@pytest.mark.parametrize("name", sorted(FAILURES))
def test_every_callback_failure_is_a_clean_exception(name):
    with pytest.raises((KeyError, ValueError, TypeError)) as info:
        FAILURES[name]()
    text = str(info.value)
    assert text.isprintable()
    if info.type is not KeyError:
        assert "must return" in text or "returned None" in text


def _rss_kib():
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") // 1024


@pytest.mark.skipif(not os.path.exists("/proc/self/statm"), reason="needs /proc")
def test_callback_failures_leak_no_memory():
    """Each failure kind 300 times with a 200-dimensional state: a leaked call would lose
    the solver's arrays (the stages alone are 200 x 7 doubles, 11 KiB; with the other
    work arrays, results and f2py copies > 30 KiB), so a leak would grow the resident
    memory by > 9 MiB; it must stay flat (< 3 MiB, allocator noise)."""
    n = 200
    y0 = np.ones(n)

    def rhs(t, y):
        return -y

    kinds = {
        "rhs raises": lambda: conmech.solve_ivp(_after(3, rhs, _raiser(KeyError())),
                                                (0, 1), y0),
        "rhs wrong length": lambda: conmech.solve_ivp(_after(3, rhs, lambda t, y: y[:3]),
                                                      (0, 1), y0),
        "event wrong length": lambda: conmech.solve_ivp(
            rhs, (0, 1), y0, events=lambda t, y: y[:2]),
        "stm raises": lambda: stability.stm(_after(4, rhs, _raiser(KeyError())),
                                            (0, 1), y0[:8]),
    }
    for name, call in kinds.items():
        for _ in range(30):                 # warm-up: allocator pools, caches
            with pytest.raises((KeyError, ValueError)):
                call()
        before = _rss_kib()
        for _ in range(300):
            with pytest.raises((KeyError, ValueError)):
                call()
        grow = _rss_kib() - before
        assert grow < 3072, f"{name}: resident memory grew by {grow} KiB over 300 calls"


def test_no_f2py_conversion_message_on_stderr():
    """A wrong-length return used to make f2py print 'rv_cb_arr is NULL' (and leak)."""
    code = textwrap.dedent("""
        import numpy as np, conmech
        for _ in range(3):
            try:
                conmech.solve_ivp(lambda t, y: [1.0], (0, 1), [1.0, 0.0])
            except ValueError:
                pass
            try:
                conmech.solve_ivp(lambda t, y: -y, (0, 1), [1.0], events=lambda t, y: [1, 2])
            except ValueError:
                pass
        print("done")
    """)
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 0 and p.stdout.strip() == "done"
    assert "NULL" not in p.stderr and "Traceback" not in p.stderr


def test_guard_and_result_checks():
    g = Guard()
    cb = g.wrap(lambda t, y: [1.0, 2.0], 2, (2,), "fun")
    np.testing.assert_array_equal(cb(0.0, np.zeros(2)), [1.0, 2.0])
    bad = g.wrap(lambda t, y: 1j, 2, (1,), "fun")
    assert np.isnan(bad(0.0, np.zeros(1))).all() and isinstance(g.error, TypeError)
    assert np.isnan(cb(0.0, np.zeros(2))).all()       # NaN after a failure, not called
    with pytest.raises(TypeError, match="complex"):
        g.check()
    g.check()                                          # cleared
    assert as_result(3.0, (1,), "f").shape == (1,)
    with pytest.raises(ValueError):
        as_result(np.ones((2, 2)), (4,), "f")
    assert message_text(b"bad \xff input\x00junk") == "bad ? input"
    assert message_text(np.frombuffer(b"ok  ", dtype="S4")) == "ok"


def test_hill_family_marks_only_wrong_orbits():
    ms = np.array([0.06, 0.08, 1.0])
    fam = hill.family(ms)
    assert fam.success.tolist() == [True, True, False]
    assert np.all(np.abs(fam.c[:2] - 1.07) < 0.02)


# ----------------------------------------------------------------- jac= for Python systems
ARENSTORF_MU = 0.012277471
ARENSTORF_Y0 = [0.994, 0.0, 0.0, -2.00158510637908252240537862224]
ARENSTORF_T = 17.0652165601579625588917206249


def _arenstorf(t, y):
    mu, mup = ARENSTORF_MU, 1 - ARENSTORF_MU
    x, yy, vx, vy = y
    d1 = ((x + mu)**2 + yy**2)**1.5
    d2 = ((x - mup)**2 + yy**2)**1.5
    return np.array([vx, vy, x + 2*vy - mup*(x + mu)/d1 - mu*(x - mup)/d2,
                     yy - 2*vx - mup*yy/d1 - mu*yy/d2])


def _arenstorf_jac(t, y):
    mu, mup = ARENSTORF_MU, 1 - ARENSTORF_MU
    x, yy = y[0], y[1]
    jm = np.zeros((4, 4))
    jm[0, 2] = jm[1, 3] = 1.0
    jm[2, 3], jm[3, 2] = 2.0, -2.0
    jm[2, 0] = jm[3, 1] = 1.0
    for m, dx in ((mup, x + mu), (mu, x - mup)):
        r2 = dx*dx + yy*yy
        r3, r5 = r2**1.5, r2**2.5
        jm[2, 0] += m*(3*dx*dx/r5 - 1/r3)
        jm[2, 1] += m*3*dx*yy/r5
        jm[3, 0] += m*3*dx*yy/r5
        jm[3, 1] += m*(3*yy*yy/r5 - 1/r3)
    return jm


def test_stm_with_python_jac_is_exact_arenstorf():
    """Arenstorf's monodromy with an exact Python Jacobian to <= 1e-8 relative (finite
    differences give ~1.5e-6), against an independent tight reference: Verner 9(8) at
    1e-13 on the variational equations written out in Python."""
    def var(t, z):
        p = z[4:].reshape(4, 4, order="F")
        return np.concatenate([_arenstorf(t, z[:4]),
                               (_arenstorf_jac(t, z[:4]) @ p).ravel(order="F")])
    z0 = np.concatenate([ARENSTORF_Y0, np.eye(4).ravel()])
    r = conmech.solve_ivp(var, (0, ARENSTORF_T), z0, method="VERNER98", rtol=1e-13,
                          atol=1e-13)
    ref = r.y[4:, -1].reshape(4, 4, order="F")
    y1, mono, info = stability.stm(_arenstorf, (0, ARENSTORF_T), ARENSTORF_Y0,
                                   jac=_arenstorf_jac, full_output=True)
    rel = np.max(np.abs(mono - ref)) / np.max(np.abs(ref))
    assert rel <= 1e-8, rel
    # one Jacobian per right-hand side of the variational equations, none by differences
    assert info["njev"] > 0 and info["njev"] == info["nfev"]
    np.testing.assert_allclose(stability.monodromy(_arenstorf, ARENSTORF_Y0, ARENSTORF_T,
                                                   jac=_arenstorf_jac), mono, rtol=0,
                               atol=0)


def test_jac_in_equilibrium_and_orbits():
    # pendulum: the exact Jacobian at the bottom, njev counted; a wrong-shaped jac is a
    # clean ValueError; a built-in refuses jac
    f = lambda t, y: [y[1], -np.sin(y[0])]  # noqa: E731
    jac = lambda t, y: [[0.0, 1.0], [-np.cos(y[0]), 0.0]]  # noqa: E731
    e = stability.equilibrium(f, [0.0, 0.0], jac=jac)
    assert e.kind == "centre" and e.njev >= 1 and e.analytic
    np.testing.assert_array_equal(e.jacobian, [[0.0, 1.0], [-1.0, 0.0]])
    with pytest.raises(ValueError, match="jac"):
        stability.equilibrium(f, [0.0, 0.0], jac=lambda t, y: np.eye(3))
    with pytest.raises(TypeError, match="built-in"):
        stability.stm(systems.pendulum(), (0, 1), [0.1, 0.0], jac=jac)
    # harmonic oscillator: period 2 pi, multipliers 1 (with and without jac agree)
    h = lambda t, y: [y[1], -y[0]]  # noqa: E731
    hj = lambda t, y: [[0.0, 1.0], [-1.0, 0.0]]  # noqa: E731
    a = stability.symmetric_orbit(h, [1.0, 0.0], free=[0], targets=[1], period=6.0,
                                  free_time=True, jac=hj)
    assert abs(a.period - 2*np.pi) < 1e-10 and a.njev > 0
    np.testing.assert_allclose(a.monodromy, np.eye(2), atol=1e-9)


def test_orbit_residual_is_the_true_one():
    """Newton's own test used the residual before its last step; the result carries the
    residual of the returned orbit from a fresh integration (SciPy's agrees)."""
    from scipy.integrate import solve_ivp as scipy_solve_ivp
    vdp = lambda t, y: [y[1], (1 - y[0]**2)*y[1] - y[0]]  # noqa: E731
    o = stability.periodic_orbit(vdp, [2.0, 0.0], 6.5)
    r = scipy_solve_ivp(vdp, (0, o.period), o.y0, method="DOP853", rtol=1e-12, atol=1e-12)
    true = np.max(np.abs(r.y[:, -1] - o.y0))
    assert o.residual <= 1e-8 and true <= 1e-8
    assert abs(o.residual - true) <= 1e-9
