"""The state transition matrix (variational equations), the monodromy matrix and its
Floquet multipliers."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech
from .._core.native import NativeSystem
from .._core.validate import (_callback, _check_dim, _no_jac_for_builtin, _real, _state,
                              _system_args, _tols)
from .._core.status import raise_status
from ..ivp.methods import BY_NAME
from ..ivp.taylor_generalized import first_order_view

_TAYLOR = BY_NAME["TAYLOR"].code
#: the integrators of a state with its STM: name -> method code
STM_INTEGRATORS = {"DOP853": BY_NAME["DOP853"].code, "TAYLOR": _TAYLOR}


def stm_integrator(system, name, what="integrator"):
    """(the system to integrate, the method code) for the state and its STM by the
    integrator ``name`` ("DOP853" or "TAYLOR", any case; ``what`` names the argument in
    the messages). TAYLOR runs Taylor's method on the variational system's own
    recurrences: ``system`` must be compiled by conmech.symbolic; its variational
    recurrences are compiled here on first need (their entries then in its spec;
    without them Fortran refuses the method), and a generalized system M(q) q'' = Q
    runs its first-order view y = [q; v], whose variational routine expands
    M da = K Phi (conmech.symbolic.taylor_generalized_var)."""
    code = STM_INTEGRATORS.get(name.upper()) if isinstance(name, str) else None
    if code is None:
        raise ValueError(f"{what} must be 'DOP853' or 'TAYLOR', got {name!r}")
    if code != _TAYLOR:
        return system, code
    if not isinstance(system, NativeSystem):
        raise ValueError(f"{what} 'TAYLOR' needs a compiled system with Taylor code "
                         "(conmech.symbolic.ode_system), not a Python function")
    system = first_order_view(system, "var")
    if hasattr(system, "taylor_parts"):
        system.taylor_parts("var")
    return system, code


def stm(system: Any, t_span: Sequence[float], y0: ArrayLike, rtol: float = 1e-12,
        atol: float = 1e-12, jac: Callable[..., ArrayLike] | None = None,
        full_output: bool = False, method: str = "DOP853") -> tuple:
    """(y(t1), Phi(t1)) of the state and its state transition matrix from t0 to t1
    (DOP853 with the same step control on the state and the STM).

    ``jac``: exact Jacobian jac(t, y) -> (n, n) of a Python system (SciPy's name; default:
    central finite differences, accurate to ~1e-6 relative). With ``full_output`` a third
    item, a dict {nfev, njev}, is returned. ``method="TAYLOR"``: Taylor's method on the
    variational system's own recurrences (a system from :func:`conmech.symbolic.ode_system`:
    the state and Phi expanded together, the step controlled on both; a generalized
    system of :mod:`conmech.symbolic` through the accelerations' linear solve, the
    columns of Phi further right-hand sides of the same mass matrix; a tree of
    :mod:`conmech.symbolic` through its articulated-body chain differentiated forward)."""
    y0 = _state(y0)
    _check_dim(system, y0)
    try:
        t0, t1 = t_span
    except (TypeError, ValueError):
        raise ValueError("t_span must be a pair (t0, t1)") from None
    t0, t1 = _real(t0, "t_span[0]"), _real(t1, "t_span[1]")
    rtol, atol = _tols(rtol, atol)
    _no_jac_for_builtin(system, jac)
    njev = 0
    system, code = stm_integrator(system, method, "method")
    if code == _TAYLOR:
        y1, phi, nfev, _, info, message = _conmech.flat_stm_taylor(
            *system._flat_args(), y0, t0, t1, rtol, atol)
    else:
        g, sargs = _system_args(system, y0.size, y0, t0, jac)
        y1, phi, nfev, info, message = _conmech.flat_stm(*sargs, y0, t0, t1, rtol, atol)
        if g is not None:
            g.check()
            njev = g.count("jac")
    if info < 0:
        raise_status(info, message)
    if full_output:
        return np.array(y1), np.array(phi), {"nfev": int(nfev), "njev": njev}
    return np.array(y1), np.array(phi)


def monodromy(system: Any, y0: ArrayLike, period: float, rtol: float = 1e-12,
              atol: float = 1e-12, jac: Callable[..., ArrayLike] | None = None,
              method: str = "DOP853") -> np.ndarray:
    """Monodromy matrix Phi(period) of the orbit through y0 (``jac`` and ``method`` as in
    :func:`stm`)."""
    period = _real(period, "period", 0.0, low_open=True)
    return stm(system, (0.0, period), y0, rtol, atol, jac=jac, method=method)[1]


def floquet(m: ArrayLike, period: float, rel_error: float = 0.0) -> dict:
    """Multipliers (eigenvalues of m), Floquet exponents log(mu)/period and, for a 4 x 4
    monodromy, the trace-based stability index S = (trace - 2)/2. Returns a dict, with
    ``multiplier_error``: an estimate of each multiplier's absolute error for an m known to
    the relative accuracy ``rel_error`` (at least 10 eps; e.g. the integrator's rtol), by
    the statistical condition estimate of conmech_periodic_multipliers (three seeded
    random perturbations of that size, three times the largest change), and ``accuracy``
    (the largest error relative to max(1, |mu|)). For multipliers that keep their digits
    use :func:`periodic_orbit` (method="multiple"): eig of a formed monodromy of an
    unstable orbit loses the small multipliers, and the estimate says so."""
    m = np.asarray(m)
    if m.dtype.kind not in "biuf":
        raise TypeError("m must be a real matrix")
    m = m.astype(float)
    if m.ndim != 2 or m.shape[0] != m.shape[1] or m.size == 0:
        raise ValueError("m must be a non-empty square matrix")
    if not np.all(np.isfinite(m)):
        raise ValueError("m must be finite")
    period = _real(period, "period", 0.0, low_open=True)
    rel_error = max(_real(rel_error, "rel_error", 0.0), 10*np.finfo(float).eps)
    mu = np.linalg.eigvals(m)
    with np.errstate(divide="ignore", invalid="ignore"):   # a zero multiplier: -inf
        expo = np.log(mu.astype(complex))/period
    rng = np.random.default_rng(12345)
    change = np.zeros(mu.size)
    for _ in range(3):
        z = rng.standard_normal(m.shape)
        z *= rel_error*np.linalg.norm(m)/np.linalg.norm(z)
        pert = list(np.linalg.eigvals(m + z))
        for i, v in enumerate(mu):
            j = int(np.argmin(np.abs(np.asarray(pert) - v)))
            change[i] = max(change[i], abs(pert.pop(j) - v))
    err = 3.0*change
    out = {"multipliers": mu, "exponents": expo, "trace": float(np.trace(m)),
           "multiplier_error": err,
           "accuracy": float(np.max(err/np.maximum(1.0, np.abs(mu))))}
    if m.shape == (4, 4):
        out["stability_index"] = 0.5*(np.trace(m) - 2.0)
    return out
