"""Transverse linearisation of a periodic orbit of a planar natural system: Hill's
equation of the normal deviation."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech
from .._core.validate import _state
from .._core.status import raise_status

def transverse(potential: Callable[..., Any], y0: ArrayLike, period: float, omega: float = 0.0,
               t: ArrayLike | None = None, rtol: float = 1e-12) -> dict:
    """Transverse linearisation of a periodic orbit of the planar natural system
    q'' = -grad V(q) + 2 omega J q' (J q' = (-q2', q1'); omega: a rotating frame, e.g.
    Hill's problem is V = -F, omega = -m): the normal deviation obeys Hill's equation
    N'' + Phi(t) N = 0, Phi = n^T V'' n + 3 (phi' - omega)^2 + omega^2 (phi' the turning
    rate of the velocity). ``potential(q)`` returns (V, grad V (2,), Hessian (2, 2)).
    ``t`` (increasing times in [0, period]) samples Phi along the orbit; ``rtol`` is the
    integrators' tolerance (rtol = atol) everywhere.

    Returns a dict: monodromy (2, 2), half_trace, det, multipliers (2,), the 4 x 4
    ``monodromy4`` of the orbit (same tolerance), its stability index
    ``stability_index4`` = (trace - 2)/2 (equal to half_trace: the 2 x 2 multipliers are
    the non-trivial ones; the two come from separate integrations and agree to the
    integration error: ~1e-12 at rtol = 1e-12, ~1e-13 with the orbit and this call at
    rtol = 1e-13), closure (max |y(T) - y0|), and ``phi`` at t.

    :func:`transverse_linearisation` is the construction for any system (any number of
    degrees of freedom, mass matrices, constraints); for two degrees of freedom it gives
    the same Phi(t) (``hill_phi``)."""
    if not callable(potential):
        raise TypeError("potential must be a callable q -> (V, grad, hessian)")
    y0 = _state(y0)
    if y0.size != 4:
        raise ValueError("y0 must be [q1, q2, q1', q2'] (4 values)")
    period = float(period)
    if not period > 0:
        raise ValueError("period must be positive")
    if not (np.isfinite(rtol) and 0 < rtol < 1):
        raise ValueError("rtol must be in (0, 1)")
    tt = np.zeros(0) if t is None else np.ascontiguousarray(np.asarray(t, float).ravel())
    if tt.size and (not np.all(np.isfinite(tt)) or np.any(np.diff(tt) < 0) or tt[0] < 0):
        raise ValueError("t must be finite, non-negative and increasing")

    def pot(q):
        v, g, h = potential(np.array(q))
        g = np.asarray(g, dtype=float).ravel()
        h = np.asarray(h, dtype=float)
        if g.size != 2 or h.shape != (2, 2):
            raise ValueError("potential(q) must return (V, grad (2,), hessian (2, 2))")
        return float(v), g, h
    ttx = tt if tt.size else np.zeros(1)
    phi, m2, ht, det, closure, m4, info, message = _conmech.flat_transverse_callback(
        pot, float(omega), y0, period, float(rtol), ttx)
    if info != 0:
        raise_status(info, message)
    m2 = np.array(m2)
    m4 = np.array(m4)
    out = {"monodromy": m2, "half_trace": float(ht), "det": float(det),
           "multipliers": np.linalg.eigvals(m2), "monodromy4": m4,
           "stability_index4": 0.5*(np.trace(m4) - 2.0), "closure": float(closure)}
    if tt.size:
        out["phi"] = np.array(phi)
    return out
