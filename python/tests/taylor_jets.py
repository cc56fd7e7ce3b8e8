"""Calling a compiled Taylor routine ``name(t, order, w, p)`` directly from a test (shared by
test_taylor_generalized.py and test_taylor_generalized_var.py)."""
import ctypes

import numpy as np

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
