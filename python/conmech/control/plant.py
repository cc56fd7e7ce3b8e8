"""Mechanical systems with inputs, M(q) q'' = Q(q, q') + B(q) u, feedback laws and the
closed-loop simulation (Fortran: conmech_mech_plant, conmech_control_system)."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import math

import numpy as np

from .. import _conmech
from .._core.callback import Guard, as_result, message_text
from .._core.driver_events import first_crossing_events
from ..ivp.solve import DenseOutput, OdeResult, _METHOD_CODES
from .._core.native import NativeSystem, function_address
from .._core.status import BAD_INPUT, raise_status

__all__ = ["ControlledSystem", "FeedbackLaw", "PythonLaw", "CompiledLaw", "ZeroLaw",
           "simulate"]

_PAD = np.zeros(1)
_PADI = np.zeros(1, dtype=np.intc)
_NO_PY = None


class ControlledSystem:
    """A system in generalized coordinates with inputs: M(q) q'' = Q(q, q') + B(q) u.

    Parameters
    ----------
    system : a built-in generalized system (``conmech.systems.cart_pendulum()``,
        ``double_pendulum()``, ...) or a compiled/symbolic one (``symbolic.lagrangian_system``,
        ``symbolic.planar_tree``, ``compiled.generalized_system``); the state is [q, q'].
    actuated : indices of the actuated coordinates (one input each: B = their columns of
        the identity, e.g. the force on a cart, the torque at a joint), or
    B : a constant input matrix (ndof x m), or
    input_matrix : a compiled function with the C signature
        ``void B(double t, const double *q, double *b, const double *p)``
        (column-major ndof x m; an address, ctypes function, numba cfunc or
        LowLevelCallable) with ``n_inputs`` = m and its parameters ``input_params``.

    Attributes: ``system``, ``ndof``, ``n_inputs``, ``B`` (constant case),
    ``passive`` (the coordinates without an input, for selection matrices).
    """

    def __init__(self, system, actuated=None, *, B=None, input_matrix=None, n_inputs=None,
                 input_params=(), keep=None):
        if not isinstance(system, NativeSystem):
            raise TypeError("system must be a built-in or compiled system in generalized "
                            "coordinates (e.g. conmech.systems.cart_pendulum() or "
                            "conmech.symbolic.lagrangian_system(...))")
        kind, n, mh, mn, info, message = _conmech.flat_mech_info(*system._flat_args())
        if kind != 2:
            raise ValueError(f"system must be in generalized coordinates (M q'' = Q); "
                             f"{system!r} is not")
        self.system = system
        self.ndof = int(n)
        given = [x is not None for x in (actuated, B, input_matrix)]
        if sum(given) != 1:
            raise ValueError("give exactly one of actuated, B or input_matrix")
        self._baddr = 0
        self._bpar = np.zeros(0)
        self._keep = keep
        self.passive = None
        if actuated is not None:
            try:
                idx = [int(i) for i in np.ravel(actuated)]
            except (TypeError, ValueError):
                raise TypeError("actuated must be a sequence of coordinate indices") from None
            if not idx or any(i < 0 or i >= self.ndof for i in idx) or len(set(idx)) != len(idx):
                raise ValueError(f"actuated must hold distinct coordinate indices in "
                                 f"0..{self.ndof - 1}, got {list(np.ravel(actuated))}")
            b = np.zeros((self.ndof, len(idx)))
            for j, i in enumerate(idx):
                b[i, j] = 1.0
            self.B = b
            self.actuated = tuple(idx)
            self.passive = tuple(i for i in range(self.ndof) if i not in idx)
        elif B is not None:
            b = np.asarray(B, dtype=float)
            if b.ndim == 1:
                b = b[:, None]
            if b.ndim != 2 or b.shape[0] != self.ndof or b.shape[1] < 1 or \
                    not np.all(np.isfinite(b)):
                raise ValueError(f"B must be a finite {self.ndof} x m matrix")
            if np.linalg.matrix_rank(b) < b.shape[1]:
                raise ValueError("B must have independent columns")
            self.B = b
            self.actuated = None
        else:
            if n_inputs is None:
                raise ValueError("n_inputs is required with input_matrix")
            m = int(n_inputs)
            if m < 1:
                raise ValueError("n_inputs must be >= 1")
            self._baddr = function_address(input_matrix, "input_matrix")
            self._bpar = np.ascontiguousarray(np.asarray(input_params, dtype=float).ravel())
            self.B = np.zeros((self.ndof, m))
            self.actuated = None
            self._keep = (keep, input_matrix)
        self.n_inputs = self.B.shape[1]
        self.dimension = 2*self.ndof

    def _flat(self):
        """Keyword arguments of the flat control routines describing the plant."""
        name, np_, p, nspec, spec = self.system._flat_args()
        bp = self._bpar if self._bpar.size else _PAD
        return dict(name=name, np=np_, params=p, nspec=nspec, spec=spec,
                    bmat=np.asfortranarray(self.B), baddr=self._baddr,
                    nbp=self._bpar.size, bpar=bp)

    def rhs(self, t, x, u):
        """F(t, x, u) (2 ndof) and the input matrix dF/du (2 ndof x m) at one state."""
        x = np.ascontiguousarray(np.asarray(x, dtype=float).ravel())
        u = np.ascontiguousarray(np.asarray(u, dtype=float).ravel())
        if x.size != self.dimension or u.size != self.n_inputs:
            raise ValueError(f"x must have {self.dimension} and u {self.n_inputs} values")
        dx, bx, info, message = _conmech.flat_control_plant_eval(
            **self._flat(), t=float(t), x=x, u=u)
        if info != 0:
            raise_status(info, message)
        return np.array(dx), np.array(bx)

    def __repr__(self):
        return (f"ControlledSystem({self.system!r}, ndof={self.ndof}, "
                f"n_inputs={self.n_inputs})")


class FeedbackLaw:
    """A feedback law u = k(t, x) that Fortran evaluates: ``_flat()`` gives its
    description (ilaw, rlaw, Python callable or None). Subclasses: :class:`PythonLaw`,
    :class:`CompiledLaw`, :class:`ZeroLaw`, the virtual-constraint feedback and the
    transverse LQR of :mod:`conmech.control`."""

    n_inputs = 0

    def _flat(self):
        raise NotImplementedError

    def __call__(self, plant, t, x):
        """u at (t, x) (one state (N,) or many (nx, N) with t a scalar or (nx,))."""
        return evaluate_law(plant, self, t, x)


class ZeroLaw(FeedbackLaw):
    """u = 0 (the open loop)."""

    def __init__(self, n_inputs):
        self.n_inputs = int(n_inputs)

    def _flat(self):
        return np.array([0, self.n_inputs], dtype=np.int64), np.zeros(0), None


class PythonLaw(FeedbackLaw):
    """u = fun(t, x) from a Python callable (called from Fortran at every evaluation)."""

    def __init__(self, fun, n_inputs):
        if not callable(fun):
            raise TypeError("fun must be a callable fun(t, x) -> u")
        self.fun = fun
        self.n_inputs = int(n_inputs)

    def _flat(self):
        return np.array([1, self.n_inputs], dtype=np.int64), np.zeros(0), self.fun


class CompiledLaw(FeedbackLaw):
    """u from a compiled function with the C signature
    ``void law(double t, const double *x, double *u, const double *p)``
    (an address, ctypes function, numba cfunc or LowLevelCallable)
    with parameters ``params``: no Python in the loop."""

    def __init__(self, fun, n_inputs, params=(), keep=None):
        self.address = function_address(fun, "law")
        self.n_inputs = int(n_inputs)
        self.params = np.ascontiguousarray(np.asarray(params, dtype=float).ravel())
        self._keep = (fun, keep)

    def _flat(self):
        return (np.array([2, self.n_inputs, self.address], dtype=np.int64), self.params,
                None)


def _as_law(plant, law):
    if isinstance(law, FeedbackLaw):
        lw = law
    elif callable(law):
        lw = PythonLaw(law, plant.n_inputs)
    elif law is None:
        lw = ZeroLaw(plant.n_inputs)
    else:
        raise TypeError("law must be a conmech.control law, a callable law(t, x) or None")
    if lw.n_inputs != plant.n_inputs:
        raise ValueError(f"the law gives {lw.n_inputs} inputs; the plant has "
                         f"{plant.n_inputs}")
    return lw


def _law_args(plant, law, guard):
    ilaw, rlaw, pyfun = law._flat()
    m = plant.n_inputs
    if pyfun is not None:
        cb = guard.wrap(pyfun, 2, (m,), "law")
    else:
        cb = guard.wrap(lambda t, x: np.zeros(m), 2, (m,), "law")
    return dict(nil=ilaw.size, ilaw=np.ascontiguousarray(ilaw, dtype=np.int64),
                nrl=rlaw.size, rlaw=np.ascontiguousarray(rlaw) if rlaw.size else _PAD,
                pylaw=cb)


def evaluate_law(plant, law, t, x):
    """u = law(t, x) at one state (N,) -> (m,) or many (nx, N) -> (nx, m)."""
    law = _as_law(plant, law)
    x = np.asarray(x, dtype=float)
    one = x.ndim == 1
    xs = np.atleast_2d(x)
    if xs.shape[1] != plant.dimension:
        raise ValueError(f"states must have {plant.dimension} components")
    ts = np.broadcast_to(np.asarray(t, dtype=float), (xs.shape[0],)).copy()
    g = Guard()
    us, info, message = _conmech.flat_control_law_eval(
        **plant._flat(), **_law_args(plant, law, g), n=plant.dimension, ts=ts,
        xs=np.asfortranarray(xs.T))
    g.check()
    if info != 0:
        raise_status(info, message)
    us = np.array(us).T
    return us[0] if one else us


def simulate(plant: ControlledSystem, law: Any, t_span: Sequence[float], x0: ArrayLike, *,
             method: str = "DOP853", t_eval: ArrayLike | None = None,
             dense_output: bool = False, events=None, rtol: float = 1e-10,
             atol: float = 1e-10, first_step: float | None = None,
             max_step: float = np.inf, max_steps: int = 1000000) -> OdeResult:
    """Integrate the closed loop x' = F(t, x, law(t, x)) in Fortran (the law: a conmech
    control law, e.g. the virtual-constraint feedback or the transverse LQR, run with no
    Python in the loop; a :class:`CompiledLaw`; or a Python callable ``law(t, x)``).

    SciPy's arguments and result (``t``, ``y``, ``sol``, ``t_events``, ``y_events``,
    ``nfev``, ``status``, ``success``); ``events`` are functions ``g(t, x)`` with the
    attributes ``terminal`` (bool: stop at the first crossing) and ``direction``; the
    result also holds ``u`` (m, nt), the inputs at the output times.
    """
    if not isinstance(plant, ControlledSystem):
        raise TypeError("plant must be a conmech.control.ControlledSystem")
    law = _as_law(plant, law)
    n = plant.dimension
    x0 = np.ascontiguousarray(np.asarray(x0, dtype=float).ravel())
    if x0.size != n or not np.all(np.isfinite(x0)):
        raise ValueError(f"x0 must hold {n} finite values")
    try:
        t0, t1 = (float(v) for v in t_span)
    except (TypeError, ValueError):
        raise ValueError("t_span must be a pair (t0, t1)") from None
    if not (math.isfinite(t0) and math.isfinite(t1)) or t0 == t1:
        raise ValueError("t_span must hold two different finite times")
    code = _METHOD_CODES.get(str(method).upper().replace("VERN9", "VERNER98"))
    if code is None or code > 4:
        raise ValueError("method must be 'RK45', 'DOPRI5', 'DOP853', 'VERNER98' or 'RK4'")
    for nm, v in (("rtol", rtol), ("atol", atol)):
        if not (np.isfinite(v) and v > 0):
            raise ValueError(f"{nm} must be positive and finite")
    settings = first_crossing_events(events, "the closed-loop solve")
    ne = len(settings)
    te = np.zeros(0) if t_eval is None else np.ascontiguousarray(
        np.asarray(t_eval, dtype=float).ravel())
    g = Guard()
    funs = [s[0] for s in settings]

    def events_cb(t, y):
        if g.error is not None:
            return np.full(max(ne, 1), np.nan)
        try:
            return np.array([float(as_result(f(t, y.copy()), (), f"events[{i}]"))
                             for i, f in enumerate(funs)]) if ne else _PAD
        except BaseException as exc:   # noqa: B036 (kept, re-raised by check())
            g.fail(exc)
            return np.full(max(ne, 1), np.nan)
    out = {}

    def store(t, y, ev_t, ev_y, ev_id, ts, hs, coef):
        out["t"] = t.copy()
        out["y"] = y.reshape(n, t.size).copy()
        out["ev"] = [(int(i) - 1, float(tt), ev_y.reshape(n, -1)[:, k].copy())
                     for k, (tt, i) in enumerate(zip(ev_t, ev_id))]
        out["dense"] = (ts.copy(), hs.copy(), coef.reshape(n, -1, ts.size).copy()) \
            if ts.size else None
    largs = _law_args(plant, law, g)
    nfev, naccept, nreject, form, info, message = _conmech.flat_control_solve(
        **plant._flat(), **largs, events=events_cb, store=store, n=n,
        t_span=np.array([t0, t1]), y0=x0, method=code, rtol=np.full(n, float(rtol)),
        atol=np.full(n, float(atol)), first_step=float(first_step or 0.0),
        max_step=float(max_step) if np.isfinite(max_step) else np.finfo(float).max,
        max_steps=int(max_steps), dense=int(bool(dense_output)), neval=te.size,
        t_eval=te if te.size else _PAD, ne=ne,
        ev_dir=np.array([s[2] for s in settings], dtype=np.intc) if ne else _PADI,
        ev_term=np.array([int(s[1] > 0) for s in settings], dtype=np.intc) if ne else _PADI)
    g.check()
    if info == BAD_INPUT:
        raise_status(info, message)
    t = out.get("t", np.array([t0]))
    y = out.get("y", x0[:, None].copy())
    res = OdeResult(t=t, y=y, sol=None, t_events=None, y_events=None, nfev=int(nfev),
                    njev=0, nlu=0, status=int(info) if info <= 0 else 1,
                    message=message_text(message), success=info >= 0,
                    naccept=int(naccept), nreject=int(nreject))
    if ne:
        evs = out.get("ev", [])
        res.t_events = [np.array([te_ for i, te_, _ in evs if i == k]) for k in range(ne)]
        res.y_events = [np.array([ye for i, _, ye in evs if i == k]).reshape(-1, n)
                        for k in range(ne)]
    if dense_output and out.get("dense") is not None:
        ts, hs, coef = out["dense"]
        res.sol = DenseOutput(ts, hs, coef, t0, float(t[-1]) if t.size else t1,
                              form=int(form))
    if t.size and np.all(np.isfinite(y)):
        res.u = evaluate_law(plant, law, t, y.T).T
    else:
        res.u = None
    return res
