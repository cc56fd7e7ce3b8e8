"""Continuation of equilibria (conmech_equilibrium_continuation): folds and Hopf points
against closed forms, the first Lyapunov coefficient against an exact evaluation of
Kuznetsov's formula and against the amplitude of the born cycles, the periodic branch born
at a Hopf point, a degenerate Hopf point and bad input."""
import numpy as np
import pytest
import sympy as sp

from conmech import solve_ivp, stability, symbolic

A = 2.0     # the Brusselator's a: Hopf at b = 1 + a^2 = 5, omega = a


def bru(t, y, b):
    x, u = y
    return [A - (b + 1)*x + x*x*u, b*x - x*x*u]


@pytest.fixture(scope="module")
def bru_symbolic():
    x, u, a, b = sp.symbols("x u a b")
    return symbolic.ode_system([a - (b + 1)*x + x**2*u, b*x - x**2*u], [x, u],
                               params={a: A, b: 1.0})


def test_brusselator_hopf_exact_jacobian(bru_symbolic):
    """Hopf at b = 1 + a^2 with omega = a (Kuznetsov 2004, Example 3.1; REFERENCE.md),
    located to 1e-10 by the corrector on the compiled system (exact Jacobian); every point
    is the equilibrium (a, b/a); the branch ends exactly on p_max."""
    br = stability.equilibrium_continuation(bru_symbolic, [A, 0.5], param="b", ds=0.1,
                                            ds_max=0.5, p_range=(0, 8))
    assert br.success, br.message
    assert br.p[-1] == pytest.approx(8.0, abs=1e-12)
    assert np.max(np.abs(br.y - np.column_stack([np.full(len(br), A), br.p/A]))) < 1e-12
    assert [s.kind for s in br.special] == ["Hopf"]
    h = br.special[0]
    assert h.located and h.reason == "located"
    assert abs(h.p - (1 + A*A)) < 1e-10
    assert abs(h.omega - A) < 1e-10 and h.period == pytest.approx(2*np.pi/A, abs=1e-9)
    assert abs(h.test) < 1e-12 and h.residual < 1e-12
    assert h.criticality == "supercritical" and h.l1 < 0
    # stable before the Hopf point, a pair with Re > 0 after it
    assert np.all(br.stable[br.p < h.p - 1e-6]) and np.all(br.n_unstable[br.p > h.p] == 2)


def test_brusselator_hopf_callback_agrees(bru_symbolic):
    """A Python callable (finite-difference Jacobian, ~eps^(2/3)): the same Hopf point to
    1e-9 and the same l1 as the compiled system to 1e-8."""
    br = stability.equilibrium_continuation(bru, [A, 0.5], p0=1.0, ds=0.1, ds_max=0.5,
                                            p_range=(0, 8))
    ref = stability.equilibrium_continuation(bru_symbolic, [A, 0.5], param="b", ds=0.1,
                                             ds_max=0.5, p_range=(0, 8))
    h, r = br.special[0], ref.special[0]
    assert h.kind == "Hopf" and h.located
    assert abs(h.p - 5.0) < 1e-9
    assert abs(h.l1 - r.l1) < 1e-8*abs(r.l1)


def _exact_l1(a):
    """Kuznetsov's formula (3.20) evaluated with sympy's exact derivatives, eigenvectors
    and solves at the Brusselator's Hopf point (b = 1 + a^2): an independent
    implementation of the coefficient."""
    x, u = sp.symbols("x u")
    b = 1 + a**2
    f = sp.Matrix([a - (b + 1)*x + x**2*u, b*x - x**2*u])
    X = sp.Matrix([x, u])
    at = {x: a, u: b/a}
    J = f.jacobian(X).subs(at)
    om = sp.sqrt(J.det())
    # q: (J - i om) q = 0, normalised <q, q> = 1; p: (J^T + i om) p = 0, <p, q> = 1
    q = sp.Matrix([J[0, 1], sp.I*om - J[0, 0]])
    q = q/sp.sqrt((q.H*q)[0])
    p = sp.Matrix([J[1, 0], -sp.I*om - J[0, 0]])
    p = p/sp.conjugate((p.H*q)[0])

    def B(v, w):
        return sp.Matrix([sum(sp.diff(fi, X[j], X[k]).subs(at)*v[j]*w[k]
                              for j in range(2) for k in range(2)) for fi in f])

    def C(v, w, z):
        return sp.Matrix([sum(sp.diff(fi, X[j], X[k], X[m]).subs(at)*v[j]*w[k]*z[m]
                              for j in range(2) for k in range(2) for m in range(2))
                          for fi in f])
    qc = q.conjugate()
    a1 = J.inv()*B(q, qc)
    a2 = (2*sp.I*om*sp.eye(2) - J).inv()*B(q, q)
    val = (p.H*C(q, q, qc))[0] - 2*(p.H*B(q, a1))[0] + (p.H*B(qc, a2))[0]
    return float(sp.re(sp.N(val, 30))/(2*om))


def test_l1_against_exact_formula(bru_symbolic):
    """l1 at the Brusselator's Hopf point: the differences of the exact Jacobian
    (extrapolated) against sympy's exact evaluation of the same formula, to 1e-9
    relative, for two values of a; the callable (differences of f) to 1e-7."""
    for a in (2.0, 1.5):
        sysa = bru_symbolic.with_params(a=a, b=1 + a*a)
        hf = stability.first_lyapunov_coefficient(sysa, [a, (1 + a*a)/a])
        ref = _exact_l1(sp.Rational(a).limit_denominator(10))
        assert hf.exact_jacobian and hf.criticality == "supercritical"
        assert abs(hf.l1 - ref) < 1e-9*abs(ref)
        assert hf.l1_error < 1e-8*abs(ref)

        def fa(t, y, b, a=a):
            return [a - (b + 1)*y[0] + y[0]**2*y[1], b*y[0] - y[0]**2*y[1]]
        hc = stability.first_lyapunov_coefficient(fa, [a, (1 + a*a)/a], p=1 + a*a)
        assert not hc.exact_jacobian
        assert abs(hc.l1 - ref) < 1e-7*abs(ref)


def test_hopf_orbits_period_and_amplitude(bru_symbolic):
    """The periodic branch born at the Hopf point: its period tends to 2 pi/a (Kuznetsov;
    REFERENCE.md) -- the periods of the first orbits extrapolated to p_H give it to 1e-8 --
    and the cycles' amplitude rho in the normal-form coordinate obeys the normal form
    rho^2 = -(p - p_H) mu'/(omega l1) (mu' = d Re lambda/db = 1/2), so l1 measured on the
    born orbits agrees with the formula's to 1 % (an independent check of the coefficient
    and of its sign: the cycles exist on the unstable side, supercritical)."""
    br = stability.equilibrium_continuation(bru_symbolic, [A, 0.5], param="b", ds=0.1,
                                            ds_max=0.5, p_range=(0, 8))
    h = br.special[0]
    orbs = stability.hopf_orbits(bru_symbolic, br, h, param="b", amplitude=2e-3, ds=0.002,
                                 ds_max=0.01, max_points=8)
    assert orbs.success and len(orbs) == 8
    dp = orbs.p - h.p
    assert np.all(dp > 0)                    # supercritical: cycles where the focus is unstable
    c = np.polyfit(dp[:5], orbs.period[:5], 2)
    assert abs(c[-1] - 2*np.pi/A) < 1e-8
    # amplitude in the normal-form coordinate z = <p, y - y_eq(b)>, y_eq = (a, b/a)
    k = 0
    y_eq = np.array([A, orbs.p[k]/A])
    r = solve_ivp(bru_symbolic.with_params(b=orbs.p[k]), (0, orbs.period[k]), orbs.y0[k],
                  method="DOP853", rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, orbs.period[k], 64))
    z = np.conj(h.adjoint) @ (r.y - y_eq[:, None])
    rho2 = np.mean(np.abs(z)**2)
    l1_measured = -dp[k]*0.5/(h.omega*rho2)
    assert abs(l1_measured - h.l1) < 1e-2*abs(h.l1)


def test_folds_located():
    """x' = p + x - x^3/3, y' = -y: folds at p = -2/3 (x = 1) and 2/3 (x = -1) to 1e-10,
    located, with a corrected equilibrium (residual <= 1e-12) and |t_p| small."""
    def f(t, y, p):
        return [p + y[0] - y[0]**3/3, -y[1]]
    br = stability.equilibrium_continuation(f, [np.sqrt(3), 0], p0=0.0, direction=-1,
                                            ds=0.05, ds_max=0.2, p_range=(-3, 3),
                                            max_points=100)
    folds = [s for s in br.special if s.kind == "fold"]
    assert len(folds) == 2
    assert abs(folds[0].p + 2/3) < 1e-10 and abs(folds[1].p - 2/3) < 1e-10
    for s in folds:
        assert s.located and s.residual < 1e-12 and abs(s.test) < 1e-6
        assert abs(abs(s.y[0]) - 1) < 1e-6
    assert abs(br.p[-1]) == pytest.approx(3.0, abs=1e-12)


def bautin(c):
    """The Hopf normal form z' = (p + i) z + c z|z|^2 - z|z|^4 (l1 = 2 c with <q, q> = 1)."""
    def f(t, y, p):
        r2 = y[0]**2 + y[1]**2
        g = p + c*r2 - r2*r2
        return [g*y[0] - y[1], g*y[1] + y[0]]
    return f


def test_normal_form_l1_and_degenerate_hopf():
    """l1 = 2 c on the normal form (finite differences of f, extrapolated) for c = -1 and
    0.5; at c = 0 the point is reported degenerate, and hopf_orbits refuses it naming it."""
    for c, crit in ((-1.0, "supercritical"), (0.5, "subcritical")):
        br = stability.equilibrium_continuation(bautin(c), [0, 0], p0=-0.5, ds=0.05,
                                                p_range=(-1, 0.5))
        (h,) = br.special
        assert h.kind == "Hopf" and h.located and h.criticality == crit
        assert abs(h.l1 - 2*c) < 1e-7
    br = stability.equilibrium_continuation(bautin(0.0), [0, 0], p0=-0.5, ds=0.05,
                                            p_range=(-1, 0.5))
    (h,) = br.special
    assert h.criticality == "degenerate"
    assert abs(h.l1) <= max(1e-6*h.l1_scale, h.l1_error)
    with pytest.raises(ValueError, match="degenerate Hopf point"):
        stability.hopf_orbits(bautin(0.0), br, h)


def test_subcritical_hopf_orbits_on_the_stable_side():
    """Subcritical (c = 0.5): the born cycles exist where the focus is stable (p < 0)."""
    f = bautin(0.5)
    br = stability.equilibrium_continuation(f, [0, 0], p0=-0.5, ds=0.05, p_range=(-1, 0.5))
    orbs = stability.hopf_orbits(f, br, br.special[0], amplitude=1e-2, max_points=5,
                                 ds=0.005)
    assert np.all(orbs.p < 0)
    # the normal form: r^2 solves p + c r^2 - r^4 = 0, period 2 pi (theta' = 1)
    r2 = orbs.y0[:, 0]**2 + orbs.y0[:, 1]**2
    assert np.max(np.abs(orbs.p + 0.5*r2 - r2**2)) < 1e-8
    assert np.allclose(orbs.period, 2*np.pi, atol=1e-8)


def test_bad_input():
    with pytest.raises(RuntimeError, match="not an equilibrium"):
        stability.equilibrium_continuation(bru, [40.0, 5.0], p0=1.0, max_iter=3)
    with pytest.raises(ValueError, match="p0"):
        stability.equilibrium_continuation(bru, [A, 0.5])
    with pytest.raises(ValueError, match="outside p_range"):
        stability.equilibrium_continuation(bru, [A, 0.5], p0=1.0, p_range=(2, 3))
    with pytest.raises(ValueError, match="ds"):
        stability.equilibrium_continuation(bru, [A, 0.5], p0=1.0, ds=-1)
    with pytest.raises(ValueError, match="fun"):
        stability.equilibrium_continuation(lambda t, y, p: [0.0], [A, 0.5], p0=1.0)
    with pytest.raises(ValueError, match="no complex eigenvalue pair"):
        stability.first_lyapunov_coefficient(lambda t, y, p: [-y[0], -2*y[1]], [0, 0], p=0)
    br = stability.equilibrium_continuation(bru, [A, 0.5], p0=1.0, ds=0.1, p_range=(0, 3))
    assert br.special == []
    with pytest.raises(ValueError, match="Hopf"):
        stability.hopf_orbits(bru, br, None)


def test_callback_exception_propagates():
    class Boom(Exception):
        pass

    def f(t, y, p):
        if p > 1.5:
            raise Boom("inside")
        return bru(t, y, p)
    with pytest.raises(Boom):
        stability.equilibrium_continuation(f, [A, 0.5], p0=1.0, ds=0.1)
