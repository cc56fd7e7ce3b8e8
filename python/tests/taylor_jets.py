"""Shared by test_taylor_generalized.py and test_taylor_generalized_var.py: calling a compiled
Taylor routine ``name(t, order, w, p)`` directly, and the two generalized systems both test."""
import ctypes

import numpy as np
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from conmech import symbolic

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
