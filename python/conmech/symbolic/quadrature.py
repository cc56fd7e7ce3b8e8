"""Quadrature of a function of the state along a dense solution: Gauss-Legendre on every
step of the dense output, so that the quadrature error is far below the interpolant's.

The dense output of an explicit Runge-Kutta step is a polynomial in t of degree <= 8
(DOP853: 7, VERNER98: 8); a function g(y(t)) of it is smooth on each step, and an 8-point
Gauss-Legendre rule (exact for degree 15) on each step integrates it to round-off relative
to the interpolant's own error.
"""
import numpy as np

__all__ = ["dense_segments", "integrate_dense", "cumulative_dense"]

_X, _W = np.polynomial.legendre.leggauss(8)
_X = 0.5*(_X + 1.0)
_W = 0.5*_W


def dense_segments(sol, t_span=None):
    """The step boundaries of a dense solution (``sol.sol.ts`` of conmech's DenseOutput or
    SciPy's OdeSolution) in ascending order, clipped to t_span (default: the solution's
    interval). ValueError when the solution has no dense output."""
    dense = getattr(sol, "sol", None)
    if dense is None or not callable(dense):
        raise ValueError("solution: a dense output is needed (solve_ivp(..., "
                         "dense_output=True))")
    ts = np.asarray(getattr(dense, "ts", None) if getattr(dense, "ts", None) is not None
                    else sol.t, dtype=float)
    ts = np.unique(ts)
    lo, hi = ts[0], ts[-1]
    if t_span is not None:
        a, b = sorted(float(x) for x in t_span)
        if a < lo - 1e-12*max(1.0, abs(lo)) or b > hi + 1e-12*max(1.0, abs(hi)):
            raise ValueError(f"t_span ({a}, {b}) is outside the solution's interval "
                             f"[{lo}, {hi}]")
        inner = ts[(ts > a) & (ts < b)]
        ts = np.concatenate([[a], inner, [b]])
    return ts


def _nodes(ts):
    h = np.diff(ts)
    tn = (ts[:-1, None] + h[:, None]*_X[None, :]).ravel()
    wn = (h[:, None]*_W[None, :]).ravel()
    return tn, wn, h.size


def integrate_dense(g, sol, t_span=None):
    """The integral of g(t, Y) over t_span along the dense solution, where Y (n, m) holds
    states at times t (m,) and g returns m values (or (k, m) for k integrands). Returns a
    float (or k values)."""
    ts = dense_segments(sol, t_span)
    tn, wn, _ = _nodes(ts)
    vals = np.asarray(g(tn, np.asarray(sol.sol(tn), dtype=float)), dtype=float)
    return vals @ wn if vals.ndim > 1 else float(vals @ wn)


def cumulative_dense(g, sol, t_out):
    """The integral of g(t, Y) from the solution's first time to each of the times t_out,
    along the dense solution: array (k, len(t_out)) (k = 1 for a scalar integrand:
    shape (len(t_out),))."""
    t_out = np.atleast_1d(np.asarray(t_out, dtype=float))
    ts = dense_segments(sol)
    t0 = float(np.asarray(sol.t, dtype=float)[0])
    tn, wn, nseg = _nodes(ts)
    vals = np.atleast_2d(np.asarray(g(tn, np.asarray(sol.sol(tn), dtype=float)), dtype=float))
    k = vals.shape[0]
    seg = (vals*wn[None, :]).reshape(k, nseg, _X.size).sum(axis=2)
    cum = np.concatenate([np.zeros((k, 1)), np.cumsum(seg, axis=1)], axis=1)   # at ts

    def from_start(times):
        # the whole steps before each time plus a Gauss-Legendre rule on the partial step
        idx = np.clip(np.searchsorted(ts, times, side="right") - 1, 0, nseg - 1)
        start = ts[idx]
        hp = times - start
        tp = (start[:, None] + hp[:, None]*_X[None, :]).ravel()
        vp = np.atleast_2d(np.asarray(g(tp, np.asarray(sol.sol(tp), dtype=float)),
                                      dtype=float))
        part = (vp.reshape(k, times.size, _X.size)*(hp[:, None]*_W[None, :])[None]).sum(
            axis=2)
        return cum[:, idx] + part
    out = from_start(t_out)
    if t0 != ts[0]:            # a backward integration: measured from its first time
        out = out - from_start(np.array([t0]))
    return out[0] if k == 1 else out
