"""Shared by the Taylor tests of generalized systems and trees: calling a compiled Taylor
routine ``name(t, order, w, p)`` directly, the two generalized systems both test, and the
monodromy check of the double pendulum's in-phase normal mode."""
import ctypes

import numpy as np
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from conmech import symbolic
from conmech.stability import floquet, monodromy, symmetric_orbit

_P = ctypes.POINTER(ctypes.c_double)
_JET = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_int, _P, _P)


def coefficients(address, nw, params, y, order, t=0.0):
    """The coefficients y^[0..order] (rows: the components of y) of the Taylor routine at
    `address` whose work array has `nw` columns."""
    w = np.zeros((nw, order + 1))
    w[:len(y), 0] = y
    p = np.ascontiguousarray(params if np.size(params) else np.zeros(1), dtype=float)
    _JET(address)(t, order, w.ctypes.data_as(_P), p.ctypes.data_as(_P))
    return w[:len(y)]


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


def check_normal_mode_monodromy(system, flow):
    """The Taylor monodromy of the double pendulum `system`'s in-phase nonlinear normal
    mode (b/a -> sqrt(2), omega^2 -> g (2 - sqrt(2)) at small amplitude; released at rest,
    its velocities vanish again at half the period) against the default route's, the
    flow direction ``flow(y0)`` kept over a period and the multipliers those of the orbit's
    own route; returns the Taylor route's multipliers."""
    g = 9.81
    a0 = 0.3
    period = 2*np.pi/np.sqrt(g*(2 - np.sqrt(2)))
    orb = symmetric_orbit(system, [a0, np.sqrt(2)*a0, 0.0, 0.0], free=[1], targets=[2, 3],
                          period=period, free_time=True)
    y0, T = np.asarray(orb.y0), float(orb.period)
    mt = monodromy(system, y0, T, method="TAYLOR")
    md = monodromy(system, y0, T)
    assert np.max(np.abs(mt - md)) < 1e-8*np.max(np.abs(md))
    f = flow(y0)
    assert np.linalg.norm(mt @ f - f) < 1e-8*np.linalg.norm(f)
    mu_t = np.sort_complex(floquet(mt, T)["multipliers"])
    mu_o = np.sort_complex(np.asarray(orb.multipliers))
    assert np.max(np.abs(mu_t - mu_o)) < 1e-5
    return mu_t
