"""Shared by the Taylor tests of generalized systems and trees: calling a compiled Taylor
routine ``name(t, order, w, p)`` directly, the core and variational coefficients of a
system's first-order view and the check of Phi's rows against central differences, the two
generalized systems both test, and the monodromy check of the double pendulum's in-phase
normal mode."""
import ctypes
from decimal import Decimal

import numpy as np
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

import conmech
from conmech import symbolic
from conmech.symbolic import taylor_quad
from conmech.ivp.taylor_generalized import first_order_view
from conmech.symbolic.pipeline import model_of
from conmech.stability import floquet, monodromy, stm, symmetric_orbit

_P = ctypes.POINTER(ctypes.c_double)
_JET = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_int, _P, _P)


def module_source(name, lines):
    """The Fortran source of a module `name` holding the generated procedure `lines` (the
    double kind dp and the C integer of the generated routines)."""
    head = [f"module {name}", "    use, intrinsic :: iso_c_binding, only: c_double, c_int",
            "    implicit none", "    integer, parameter :: dp = c_double", "    public",
            "contains", ""]
    return "\n".join(head + lines + [f"end module {name}", ""])


def coefficients(address, nw, params, y, order, t=0.0):
    """The coefficients y^[0..order] (rows: the components of y) of the Taylor routine at
    `address` whose work array has `nw` columns."""
    w = np.zeros((nw, order + 1))
    w[:len(y), 0] = y
    p = np.ascontiguousarray(params if np.size(params) else np.zeros(1), dtype=float)
    _JET(address)(t, order, w.ctypes.data_as(_P), p.ctypes.data_as(_P))
    return w[:len(y)]


def jets(system, y, order, phi=None, t0=0.0):
    """(core coefficients of y, variational coefficients of [y; vec(Phi)]) at t0 of a
    generalized system or tree with Phi(t0) = phi (default the identity)."""
    view = first_order_view(system, "var")
    tay = view.taylor
    m = len(y)
    phi = np.eye(m) if phi is None else phi
    addr = conmech.compiled.function_address
    core = coefficients(addr(tay["jet"]), tay["nw"], view.params, y, order, t0)
    var = coefficients(addr(tay["var"]), tay["nw_var"], view.params,
                       np.concatenate([y, phi.ravel(order="F")]), order, t0)
    return core, var


def mass(system, q):
    """M(q) of a generalized system or tree, from its model's compiled mass routine."""
    n = len(q)
    m = model_of(system).call("mass", 0.0, np.asarray(q, dtype=float),
                              params=np.asarray(system.params, dtype=float))
    return np.array(m, dtype=float).reshape(n, n)


def rhs(system, y):
    """f(y) = [v; a] of the first-order view (its core routine's first coefficient)."""
    return jets(system, np.asarray(y, dtype=float), 1)[0][:, 1]


def check_stm(system, y0, t1):
    """The Taylor STM over [0, t1] against the DOP853 STM on a sensitive flow; Liouville's
    det Phi = det M(q0)/det M(q1) (unit determinant in (q, p), mapped to (q, v)); the flow
    direction carried along, Phi f(y0) = f(y1) (an autonomous system); the state the Taylor
    solve's own."""
    y_t, phi_t, info = stm(system, (0.0, t1), y0, rtol=1e-12, atol=1e-12, method="TAYLOR",
                           full_output=True)
    y_d, phi_d = stm(system, (0.0, t1), y0, rtol=1e-12, atol=1e-12)
    assert info["nfev"] > 0
    big = np.max(np.abs(phi_d))
    assert big > 2.0          # a sensitive flow: the check is not of the identity
    assert np.max(np.abs(y_t - y_d)) < 1e-9
    assert np.max(np.abs(phi_t - phi_d)) < 1e-8*big
    n = len(y0)//2
    liouville = np.linalg.det(mass(system, y0[:n]))/np.linalg.det(mass(system, y_t[:n]))
    assert abs(np.linalg.det(phi_t) - liouville) < 1e-8*big**2
    f0, f1 = rhs(system, y0), rhs(system, y_t)
    assert np.linalg.norm(phi_t @ f0 - f1) < 1e-8*big*np.linalg.norm(f0)
    r = conmech.solve_ivp(system, (0.0, t1), y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(r.y[:, -1] - y_t)) < 1e-9


def check_phi_rows(system, y, order, t0=0.0):
    """Row block of column c of Phi at order k = d y^[k] / d y0_c: central differences
    (step h, error O(h^2) ~ 1e-10 relative at these orders) of the core routine's
    coefficients; the state rows are the core routine's own to round-off; Phi enters
    linearly (a general Phi0 gives the identity's coefficients times Phi0)."""
    core, var = jets(system, y, order, t0=t0)
    m = y.size
    scale = np.max(np.abs(core), axis=0)
    assert np.all(np.abs(var[:m] - core) <= 64*np.finfo(float).eps*scale)
    h = 1e-5
    for c in range(m):
        e = np.zeros(m)
        e[c] = h
        fd = (jets(system, y + e, order, t0=t0)[0] - jets(system, y - e, order, t0=t0)[0])/(2*h)
        got = var[m + c*m:m + (c + 1)*m]
        for k in range(order + 1):
            ref = max(np.max(np.abs(fd[:, k])), 1e-3)
            assert np.max(np.abs(got[:, k] - fd[:, k])) <= 1e-7*ref, (c, k)
    phi0 = np.arange(1.0, 1.0 + m*m).reshape(m, m)/7.0 - 1.0
    _, var2 = jets(system, y, order, phi0, t0=t0)
    K = order + 1
    blocks = var[m:].reshape(m, m, K)          # [column, row, order] of the identity's
    want = np.einsum("crk,cd->drk", blocks, phi0)
    got2 = var2[m:].reshape(m, m, K)
    assert np.allclose(got2, want, rtol=1e-12, atol=1e-12*np.max(np.abs(want)))


def cart_pendulum():
    """The lecture notes' pendulum on a cart (M = m = l = 1, theta from the upright)."""
    t = dynamicsymbols._t
    x, th = dynamicsymbols("x theta")
    g = sp.Symbol("g")
    T = x.diff(t)**2 + sp.cos(th)*x.diff(t)*th.diff(t) + th.diff(t)**2/2
    return symbolic.lagrangian_system(T - g*sp.cos(th), [x, th], params={g: 9.81})


def double_pendulum():
    """Unit point masses on unit rods, angles from the downward vertical."""
    t = dynamicsymbols._t
    a, b = dynamicsymbols("a b")
    g = sp.Symbol("g")
    ad, bd = a.diff(t), b.diff(t)
    T = ad**2 + ad*bd*sp.cos(a - b) + bd**2/2
    U = -g*(2*sp.cos(a) + sp.cos(b))
    return symbolic.lagrangian_system(T - U, [a, b], params={g: 9.81})


def pendulum_chain(n):
    """A planar chain of n unit point masses on unit rods from a fixed pivot, absolute
    angles from the downward vertical: M_ab = (n - max(a, b)) cos(q_a - q_b) (0-based),
    the potential -g sum_i (n - i) cos(q_i)."""
    t = dynamicsymbols._t
    q = dynamicsymbols(" ".join(f"c{i}" for i in range(n)))
    g = sp.Symbol("g")
    qd = [x.diff(t) for x in q]
    T = sum((n - max(a, b))*sp.cos(q[a] - q[b])*qd[a]*qd[b] if a != b else (n - a)*qd[a]**2
            for a in range(n) for b in range(n))/2
    U = -g*sum((n - i)*sp.cos(q[i]) for i in range(n))
    return symbolic.lagrangian_system(T - U, q, params={g: 9.81})


def tree_chain_bodies(n, spread=None):
    """(bodies, parameters, g) of n point masses on rods pinned at the origin, angles from
    the downward vertical: masses 0.8 + 0.15 i, rods 1.1 - 0.05 i (with `spread`, the
    increments scaled by spread/n: the masses and rods of any n span those of `spread`
    links)."""
    from conmech.symbolic import Body
    th = dynamicsymbols(f"th1:{n + 1}")
    m, ell = sp.symbols(f"m1:{n + 1}"), sp.symbols(f"l1:{n + 1}")
    g = sp.Symbol("g")
    bodies = [Body(f"link{i}", None if i == 0 else f"link{i - 1}", "revolute", th[i],
                   at=(0, 0) if i == 0 else (0, -ell[i - 1]), mass=m[i], com=(0, -ell[i]))
              for i in range(n)]
    def inc(c, i):
        return c*i if spread is None else c*i/n*spread
    params = {**{s: 0.8 + inc(0.15, i) for i, s in enumerate(m)},
              **{s: 1.1 - inc(0.05, i) for i, s in enumerate(ell)}, g: 9.81}
    return bodies, params, g


def tree_chain(n, spread=None):
    """The chain of :func:`tree_chain_bodies` as a planar tree in absolute angles
    (symbolic.planar_tree: its articulated-body chain)."""
    from conmech.symbolic import planar_tree
    bodies, params, g = tree_chain_bodies(n, spread)
    return planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute")


def metronomes_on_a_cart(n):
    """n pendulums (unit masses, lengths 1 + i/10) hanging from a cart (mass 2, on a
    spring of stiffness 5) that moves on a line: n + 1 degrees of freedom [x, th_1..th_n],
    M(q) the arrow matrix with M_00 = 2 + n, M_0i = l_i cos(th_i), M_ii = l_i**2 (its
    Cholesky factor is full: every column after the first fills in)."""
    t = dynamicsymbols._t
    x = dynamicsymbols("x")
    th = dynamicsymbols(" ".join(f"th{i}" for i in range(n)))
    g = sp.Symbol("g")
    ell = [1 + sp.Rational(i, 10) for i in range(n)]
    xd = x.diff(t)
    T = (2 + n)*xd**2/2 + sum(ell[i]*sp.cos(th[i])*xd*th[i].diff(t) +
                              ell[i]**2*th[i].diff(t)**2/2 for i in range(n))
    U = 5*x**2/2 - g*sum(ell[i]*sp.cos(th[i]) for i in range(n))
    return symbolic.lagrangian_system(T - U, [x] + list(th), params={g: 9.81})


def check_normal_mode_monodromy(system):
    """The Taylor monodromy of the double pendulum `system`'s in-phase nonlinear normal
    mode (b/a -> sqrt(2), omega^2 -> g (2 - sqrt(2)) at small amplitude; released at rest,
    its velocities vanish again at half the period) against the default route's, the
    flow direction f(y0) kept over a period and the multipliers those of the orbit's own
    route; returns the Taylor route's multipliers."""
    g = 9.81
    a0 = 0.3
    period = 2*np.pi/np.sqrt(g*(2 - np.sqrt(2)))
    orb = symmetric_orbit(system, [a0, np.sqrt(2)*a0, 0.0, 0.0], free=[1], targets=[2, 3],
                          period=period, free_time=True)
    y0, T = np.asarray(orb.y0), float(orb.period)
    mt = monodromy(system, y0, T, method="TAYLOR")
    md = monodromy(system, y0, T)
    assert np.max(np.abs(mt - md)) < 1e-8*np.max(np.abs(md))
    f = rhs(system, y0)
    assert np.linalg.norm(mt @ f - f) < 1e-8*np.linalg.norm(f)
    mu_t = np.sort_complex(floquet(mt, T)["multipliers"])
    mu_o = np.sort_complex(np.asarray(orb.multipliers))
    assert np.max(np.abs(mu_t - mu_o)) < 1e-5
    return mu_t


def check_quadruple_reference(system, y0, tol, dop_rtol, agree, moved=1):
    """The quadruple-precision Taylor reference over [0, 2] from the decimal strings y0
    (to `tol`) against quadruple-precision DOP853 (to `dop_rtol`): they agree to `agree`,
    the state moved beyond `moved`, and a double Taylor run at 1e-13 is off by a positive
    error below 1e-12 against it."""
    r = taylor_quad.reference(system, (0, 2), y0, tol=tol)
    d = taylor_quad.reference_dop853(system, (0, 2), y0, rtol=dop_rtol)
    assert r.success and d.success and r.order > 30
    diff = [abs(Decimal(u) - Decimal(v)) for u, v in zip(r.y_str, d.y_str)]
    assert max(diff) < Decimal(agree), diff
    assert max(abs(Decimal(u)) for u in r.y_str) > Decimal(moved)
    s = conmech.solve_ivp(system, (0, 2), [float(v) for v in y0], method="TAYLOR",
                          rtol=1e-13, atol=1e-13)
    err = np.max(np.abs(s.y[:, -1] - r.y_float))
    assert 0 < err < 1e-12
