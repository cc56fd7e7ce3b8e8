"""conmech.control: plants with inputs, feedback laws and the closed loop, virtual holonomic
constraints and their reduced dynamics, the periodic Riccati equation, orbital
stabilisation by transverse LQR, and bad input."""
import ctypes
import os
import subprocess

import numpy as np
import pytest
import sympy as sp
from scipy.linalg import solve_continuous_are
from sympy.physics.mechanics import dynamicsymbols

from conmech import control, symbolic, systems
from conmech.control import examples

G = 9.81


@pytest.fixture(scope="module")
def cart():
    return examples.cart_pendulum()     # M = m = l = 1, x = -1.6 theta


# ------------------------------------------------------------------ plants and laws

def test_plant_input_matrix_is_exact(cart):
    plant, _ = cart
    x = np.array([0.2, 0.4, -0.3, 0.7])
    f0, bx = plant.rhs(0.0, x, [0.0])
    f1, _ = plant.rhs(0.0, x, [2.5])
    c = np.cos(x[1])
    mm = np.array([[2.0, c], [c, 1.0]])
    assert np.allclose(bx[2:, 0], np.linalg.solve(mm, [1.0, 0.0]), atol=1e-15)
    assert np.allclose(bx[:2], 0)
    assert np.allclose(f1 - f0, 2.5*bx[:, 0], atol=1e-13)     # affine in u
    free = systems.cart_pendulum()
    from conmech import compiled
    assert np.allclose(f0, compiled.evaluate(free, 0.0, x)["f"], atol=1e-15)


def test_symbolic_inputs_coordinates_symbols_and_q_dependent_B():
    t = dynamicsymbols._t
    x, th = dynamicsymbols("x theta")
    M, m, l, g, u = sp.symbols("M m l g u")
    T = (M + m)*x.diff(t)**2/2 + m*l*sp.cos(th)*x.diff(t)*th.diff(t) + m*l**2*th.diff(t)**2/2
    U = m*g*l*sp.cos(th)
    pars = {M: 1.3, m: 0.7, l: 0.9, g: G}
    c1 = symbolic.lagrangian_system(T - U, [x, th], params=pars, inputs=[x])
    assert c1.actuated == (0,) and c1.passive == (1,)
    ref = control.ControlledSystem(systems.cart_pendulum(M=1.3, m=0.7, l=0.9), actuated=[0])
    xs = np.array([0.1, 0.3, 0.2, -0.1])
    assert np.allclose(c1.rhs(0, xs, [0.8])[0], ref.rhs(0, xs, [0.8])[0], atol=1e-14)
    # a horizontal force u at the bob: virtual work u d(x + l sin th): B(q) = [1, l cos th]
    c2 = symbolic.lagrangian_system(T - U, [x, th], params=pars, forces=[u, u*l*sp.cos(th)],
                                    inputs=[u])
    mm = np.array([[2.0, 0.7*0.9*np.cos(0.3)], [0.7*0.9*np.cos(0.3), 0.7*0.81]])
    want = np.linalg.solve(mm, [1.0, 0.9*np.cos(0.3)])
    assert np.allclose(c2.rhs(0, xs, [1.0])[1][2:, 0], want, atol=1e-14)
    with pytest.raises(ValueError, match="linear"):
        symbolic.lagrangian_system(T - U, [x, th], params=pars, forces=[u**2, 0], inputs=[u])


def _compiled_law(tmp_path):
    """A PD law u = -p0 x - p1 x' compiled from C."""
    src = tmp_path/"law.c"
    src.write_text("void law(double t, const double *x, double *u, const double *p)"
                   "{ u[0] = -p[0]*x[0] - p[1]*x[2]; }\n")
    so = tmp_path/"law.so"
    subprocess.run(["gcc", "-O2", "-shared", "-fPIC", "-o", str(so), str(src)], check=True)
    lib = ctypes.CDLL(str(so))
    return control.CompiledLaw(lib.law, 1, params=[3.0, 2.0], keep=lib)


def test_closed_loop_python_and_compiled_laws_agree_and_events(tmp_path, cart):
    plant, _ = cart
    cl = _compiled_law(tmp_path)
    py = lambda t, x: [-3.0*x[0] - 2.0*x[2]]  # noqa: E731
    x0 = [0.1, np.pi - 0.2, 0.0, 0.0]         # hanging, with a cart offset
    r1 = control.simulate(plant, cl, (0, 3), x0, t_eval=np.linspace(0, 3, 31))
    r2 = control.simulate(plant, py, (0, 3), x0, t_eval=np.linspace(0, 3, 31))
    assert r1.success and r2.success
    assert np.max(np.abs(r1.y - r2.y)) <= 1e-12
    assert np.allclose(r1.u[0], -3*r1.y[0] - 2*r1.y[2], atol=1e-14)

    def cross(t, x):                          # the pendulum passes the hanging position
        return x[1] - np.pi
    cross.terminal = True
    r3 = control.simulate(plant, cl, (0, 3), x0, events=cross)
    assert r3.status == 1 and r3.t_events[0].size == 1
    assert abs(r3.y_events[0][0][1] - np.pi) <= 1e-10
    assert r3.t[-1] == pytest.approx(r3.t_events[0][0], abs=1e-12)


# ------------------------------------------------------------- virtual constraints

def test_reduced_dynamics_coefficients_closed_form(cart):
    """Cart pendulum, x = Phi(theta): alpha = m l cos(th) Phi' + m l^2,
    beta = m l cos(th) Phi'', gamma = -m g l sin(th) (M = m = l = 1); the same for a
    non-polynomial constraint x = -1.6 sin(theta) through its Chebyshev series."""
    plant, vhc = cart
    th = np.linspace(-0.6, 0.6, 13)
    al, be, ga = vhc.coefficients(th)
    assert np.allclose(al, np.cos(th)*(-1.6) + 1, atol=1e-14)
    assert np.allclose(be, 0, atol=1e-14)
    assert np.allclose(ga, -G*np.sin(th), atol=1e-13)
    s = sp.Symbol("theta")
    v2 = control.VirtualConstraint(plant, 1, [-1.6*sp.sin(s)], interval=(-1, 1))
    al, be, ga = v2.coefficients(th)
    assert np.allclose(al, np.cos(th)*(-1.6*np.cos(th)) + 1, atol=1e-12)
    assert np.allclose(be, np.cos(th)*(1.6*np.sin(th)), atol=1e-11)


def test_integral_is_constant_and_period_by_quadrature(cart):
    """Along a reduced solution I(theta, theta') stays at its start value (zero through
    the reference point) to 1e-10; the period from the integral by quadrature equals the
    integrated one to 1e-10."""
    _, vhc = cart
    red = vhc.reduced()
    orb = red.periodic_orbit(0.4)
    assert abs(orb.period - orb.period_quadrature) <= 1e-10
    assert orb.quadrature_error <= 1e-10
    t, st = red.solve([0.4, 0.0], (0, orb.period), np.linspace(0, orb.period, 60))
    i0 = red.integral(st[:, 0], st[:, 1], 0.4, 0.0)
    assert np.max(np.abs(i0)) <= 1e-10
    # another solution (not through the reference point): I constant, not zero
    t, st = red.solve([0.25, 0.3], (0, 2.0), np.linspace(0, 2.0, 50))
    i1 = red.integral(st[:, 0], st[:, 1], 0.4, 0.0)
    assert np.max(np.abs(i1 - i1[0])) <= 1e-10 and abs(i1[0]) > 0.1
    # the reduced dynamics is the full closed loop on the constraint
    r = control.simulate(vhc.plant, vhc.feedback(25.0, 10.0), (0, orb.period), orb.x0,
                         t_eval=orb.t, rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(r.y[1] - orb.states[:, 0])) <= 1e-9
    assert np.max(np.abs(r.y[0] + 1.6*r.y[1])) <= 1e-9          # x = -1.6 theta kept
    assert np.max(np.abs(r.y[:, -1] - orb.x0)) <= 1e-9          # periodic


def test_equilibria_of_the_reduced_dynamics(cart):
    _, vhc = cart
    eq = vhc.reduced().equilibria((-1, 1))
    assert len(eq) == 1 and eq[0][1] == "centre" and abs(eq[0][0]) < 1e-12
    assert eq[0][2] == pytest.approx(np.sqrt(G/0.6), rel=1e-6)   # gamma'/alpha = g/0.6


def test_constraint_not_regular_along_the_orbit(cart):
    plant, _ = cart
    v = control.VirtualConstraint(plant, 1, [[0.0, -1.6, 2.0]])   # alpha = 0 near 0.148
    with pytest.raises(ValueError, match="not regular"):
        v.reduced().periodic_orbit(-0.3)


def test_constraint_bad_input(cart):
    plant, _ = cart
    with pytest.raises(ValueError, match="phase"):
        control.VirtualConstraint(plant, 2, [[0.0, 1.0]])
    with pytest.raises(ValueError, match="coefficients"):
        control.VirtualConstraint(plant, 1, [[0.0, 1.0], [1.0, 0.0]])
    with pytest.raises(ValueError, match="interval"):
        control.VirtualConstraint(plant, 1, [sp.sin(sp.Symbol("theta"))])
    two = control.ControlledSystem(systems.double_pendulum(), B=np.eye(2))
    with pytest.raises(ValueError, match="passive"):
        control.VirtualConstraint(two, 0, [[0.0, 1.0]])


# ---------------------------------------------------------------- Riccati equation

def test_riccati_constant_coefficients_equal_the_algebraic_solution():
    """Constant A, B: the periodic solution is the ARE's (SciPy solve_continuous_are)."""
    a = np.array([[0.0, 1.0], [2.0, -0.5]])
    b = np.array([[0.0], [1.0]])
    q = np.diag([2.0, 1.0])
    r = np.array([[0.5]])
    res = control.periodic_riccati(lambda t: a, lambda t: b, 1.3, q, r)
    p = solve_continuous_are(a, b, q, r)
    assert np.max(np.abs(res.P - p)) <= 1e-10*np.max(np.abs(p))
    assert res.periodicity <= 1e-10 and res.min_eigenvalue > 0
    cl = np.linalg.eigvals(a + b @ res.K[0])
    assert np.allclose(np.sort(np.abs(res.closed_loop_multipliers)),
                       np.sort(np.abs(np.exp(1.3*cl))), rtol=1e-9)


def test_riccati_periodic_coefficients():
    """A Mathieu-type oscillator x'' + (1 + 0.8 cos 2t) x = u (period pi, unstable at this
    depth): P periodic to 1e-10, positive definite, the Riccati equation satisfied
    (P' by central differences), the closed loop stable."""
    def a(t):
        return np.array([[0.0, 1.0], [-(1 + 0.8*np.cos(2*t)), 0.0]])
    b = lambda t: np.array([[0.0], [1.0]])  # noqa: E731
    t = np.linspace(0, np.pi, 7)[1:-1]
    h = 1e-5
    tt = np.sort(np.concatenate([t - h, t, t + h, [0.0, np.pi]]))
    res = control.periodic_riccati(a, b, np.pi, np.eye(2), 1.0, t=tt)
    assert res.periodicity <= 1e-10 and res.min_eigenvalue > 0
    assert np.allclose(res.P[0], res.P[-1], atol=1e-9)
    assert np.all(np.abs(res.closed_loop_multipliers) < 1)
    for tc in t:
        i = int(np.argmin(np.abs(tt - tc)))
        dp = (res.P[i + 1] - res.P[i - 1])/(tt[i + 1] - tt[i - 1])
        p = res.P[i]
        resid = dp + a(tc).T @ p + p @ a(tc) - p @ b(tc) @ b(tc).T @ p + np.eye(2)
        assert np.max(np.abs(resid)) <= 1e-6*np.max(np.abs(p))


def test_riccati_without_stabilising_solution():
    """x' = x (unstable) with no input: not stabilisable."""
    with pytest.raises(RuntimeError, match="no stabilising periodic solution"):
        control.periodic_riccati(lambda t: np.eye(1), lambda t: np.zeros((1, 1)), 1.0)


# ------------------------------------------------------------ orbital stabilisation

@pytest.fixture(scope="module")
def cart_lqr(cart):
    plant, vhc = cart
    orb = vhc.reduced().periodic_orbit(0.3)
    return orb, control.orbital_stabilisation(plant, orb, Q=np.eye(3), R=0.1, kp=25.0,
                                               kd=10.0)


def test_transverse_lqr_design(cart_lqr):
    orb, ctrl = cart_lqr
    assert ctrl.dimension == 3
    assert ctrl.periodicity <= 1e-10 and ctrl.min_eigenvalue > 0
    assert np.all(np.abs(ctrl.multipliers) < 1)
    # the open loop (constraint feedback only): the neutral multiplier 1 of the family
    assert np.min(np.abs(ctrl.open_loop_multipliers - 1)) <= 1e-8
    # the nonlinear closed loop's N x N monodromy: 1 (the flow) and the transverse ones
    nl = ctrl.nonlinear_multipliers
    nontrivial = nl[np.argsort(np.abs(nl - 1))][1:]
    assert np.max(np.abs(np.sort_complex(nontrivial) - np.sort_complex(ctrl.multipliers))) \
        <= 1e-6
    # A_perp, B_perp, P, K are periodic
    for arr in (ctrl.A, ctrl.B, ctrl.P, ctrl.K):
        assert np.allclose(arr[0], arr[-1], atol=1e-8*max(1, np.max(np.abs(arr))))
    # on the orbit: tau = t, xi = 0
    tau, xi, d = ctrl.project(orb.x0)
    assert d <= 1e-8 and np.max(np.abs(xi)) <= 1e-8


def test_nonlinear_closed_loop_converges(cart_lqr):
    """Perturbed starts: the orbital distance shrinks by 1e3 within 30 periods."""
    from conmech.control.plots import perturbed_runs
    orb, ctrl = cart_lqr
    t, dist, xi, runs = perturbed_runs(ctrl, n_starts=3, size=0.02, periods=30,
                                       samples_per_period=2)
    assert np.all(dist[:, -1] <= 1e-3*dist[:, 0])
    # without the transverse feedback (the constraint feedback only) the distance does
    # not shrink: the reduced family is neutral
    r = control.simulate(ctrl.plant, ctrl.nominal, (0, 30*ctrl.period), runs[0].y[:, 0],
                         t_eval=[0, 30*ctrl.period])
    d = ctrl.distance(r.y.T)
    assert d[-1] > 0.1*d[0]


def test_uncontrollable_transverse_linearisation():
    """Two uncoupled pendulums, only the first actuated, the orbit a swing of the second:
    its energy (multiplier 1) cannot be reached by the input."""
    from scipy.special import ellipk
    t = dynamicsymbols._t
    a, b = dynamicsymbols("a b")
    g = sp.Symbol("g")
    L = a.diff(t)**2/2 + b.diff(t)**2/2 + g*sp.cos(a) + g*sp.cos(b)
    two = symbolic.lagrangian_system(L, [a, b], params={g: G}, inputs=[a])
    amp = 0.5
    period = 4*ellipk(np.sin(amp/2)**2)/np.sqrt(G)
    law = control.PythonLaw(lambda t, x: [-20*x[0] - 6*x[2]], 1)
    with pytest.raises(ValueError, match="uncontrollable"):
        control.orbital_stabilisation(two, ([0, amp, 0, 0], period), law, rtol=1e-10,
                                      atol=1e-10)


def test_design_bad_input(cart, cart_lqr):
    plant, vhc = cart
    orb, _ = cart_lqr
    with pytest.raises(ValueError, match="not periodic"):
        control.orbital_stabilisation(plant, (orb.x0, 1.1*orb.period), vhc.feedback(25, 10))
    with pytest.raises(RuntimeError, match="no stabilising periodic solution"):
        control.orbital_stabilisation(plant, orb, Q=np.zeros((3, 3)), kp=25.0, kd=10.0)
    with pytest.raises(ValueError, match="Q must be"):
        control.orbital_stabilisation(plant, orb, Q=np.ones((2, 2)))
    with pytest.raises(ValueError, match="R must be positive"):
        control.orbital_stabilisation(plant, orb, R=-1.0)
    with pytest.raises(ValueError, match="nominal law"):
        control.orbital_stabilisation(plant, (orb.x0, orb.period))
