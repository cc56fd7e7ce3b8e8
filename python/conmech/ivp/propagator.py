"""A state carried from one time to the next: :class:`Propagator`, the counterpart of
heyoka's ``taylor_adaptive.propagate_until`` for conmech's methods.

``solve_ivp`` returns every step's point and builds a result each call, which is what a
user plotting or post-processing a trajectory wants. A user who only needs the state at
given times (a Poincare map, the final state of a shooting iterate, a propagation loop of a
mission-design code) pays for those points and for the checks of every argument at every
call. A Propagator checks the system, the method and the tolerances once (by the rules and
with the messages of solve_ivp), makes the system, its stepper and the options once in
Fortran memory that it owns (freed with it; a copy makes its own), and then each
:meth:`Propagator.propagate_until` is one Fortran call of three numbers and the state that
integrates from the current time to the next and returns the state there alone (no step's
point is stored, no result is built).

A system compiled or built in (``conmech.systems``, ``conmech.compiled``,
``conmech.symbolic``) takes that one-call route; a Python function or a complex state runs
:func:`conmech.solve_ivp` with ``t_eval=[t]`` (the same result, with solve_ivp's cost per
call). Constrained systems are refused, as by solve_ivp (:mod:`conmech.constrained`
integrates them).
"""
import math
import weakref
from collections import namedtuple

import numpy as np

from .. import _conmech
from .._core import fastcall
from .._core.callback import message_text
from .._core.checks import RTOL_FLOOR, _warn_rtol, initial_state, positive_finite, \
    real_scalar, step_limit, tolerance
from .._core.native import NativeSystem
from .._core.status import BAD_INPUT
from .methods import BY_NAME
from .native_path import _PAD, prepare
from .result import _MESSAGES
from .solve import solve_ivp
from .solve_fast import fast_method_code
from .taylor import with_fixed_order
from .taylor_generalized import first_order_view

__all__ = ["Propagator", "Propagation"]

#: what :meth:`Propagator.propagate_until` returns: success (the time was reached),
#: status (0, or solve_ivp's negative status of a failure), message, and the run's
#: evaluations of the right-hand side and accepted / rejected steps
Propagation = namedtuple("Propagation", "success status message nfev naccept nreject")

# names for the per-call path (a global lookup each, not an attribute chain); a
# Propagation made by tuple.__new__ (its namedtuple constructor is Python code)
_SUCCESS = _MESSAGES[0]
_NOTHING_DONE = Propagation(True, 0, _SUCCESS, 0, 0, 0)
_new_tuple = tuple.__new__
_isfinite = math.isfinite
_F64 = np.dtype(np.float64)
_until = fastcall.until       # (flat_propagation_until, without f2py's wrapper)
_empty = np.empty
_array = np.array
_ndarray = np.ndarray
#: propagate_grid's rule for its times (the flat routine's message)
_GRID_RULE = ("bad input: the times must be finite and sorted strictly from the "
              "propagator's time in one direction")


def _raised_rtol(rtol):
    """rtol (a non-negative finite number, or an array of them) with the values below
    100 eps raised to that floor and SciPy's UserWarning given at the caller of the
    caller (the user's Propagator(...)); anything else unchanged, for solve_ivp's checks
    and messages."""
    if type(rtol) is float or type(rtol) is int or type(rtol) is np.float64:
        if 0 <= rtol < RTOL_FLOOR:
            _warn_rtol(4)
            return RTOL_FLOOR
        return rtol
    if isinstance(rtol, (bool, np.bool_, str, bytes)):
        return rtol
    try:
        arr = np.asarray(rtol)
    except (TypeError, ValueError):
        return rtol
    if arr.dtype.kind not in "iuf" or not np.isfinite(arr).all() or (arr < 0).any() or \
            not (arr < RTOL_FLOOR).any():
        return rtol
    _warn_rtol(4)
    return np.maximum(arr.astype(float), RTOL_FLOOR)


class Propagator:
    """y' = fun(t, y) carried forward: ``p = Propagator(fun, y0, t0=0.0, method="RK45",
    rtol=1e-3, atol=1e-6)``, then ``p.propagate_until(t)`` integrates from ``p.t`` to
    ``t`` and, when the run reaches ``t``, sets ``p.t = t`` and ``p.y`` to the state
    there (a new array; the earlier one is left as it was).

    Parameters
    ----------
    fun, y0, method, rtol, atol, max_step, max_steps
        As for :func:`conmech.solve_ivp` (the same defaults, checks and messages);
        ``max_steps`` bounds the steps of each propagation.
    t0 : float
        The time of ``y0``.

    Notes
    -----
    Each propagation is a run of its own that starts from the state where the last one
    stopped (the method's first step is chosen again): propagating to t1 and then to t2
    gives the state at t2 within the tolerances, not the bits of one run over [t0, t2].
    One propagation to t gives the same state as ``solve_ivp(fun, (t0, t), y0,
    ...).y[:, -1]``. With method TAYLOR a propagation from where the last one ended
    continues that run's stepper: the expansion its last step made there is the new
    run's start, so the new run takes the steps a fresh one would, with one evaluation
    less (the same bits for a system that does not depend on t). Setting ``t`` or ``y``
    by hand starts a fresh run.

    Examples
    --------
    >>> import numpy as np, conmech
    >>> p = conmech.Propagator(conmech.systems.harmonic(), [1.0, 0.0],
    ...                        method="DOP853", rtol=1e-12, atol=1e-12)
    >>> p.propagate_until(np.pi).success
    True
    >>> bool(abs(p.y[0] + 1.0) < 1e-10)
    True
    """

    def __init__(self, fun, y0, t0=0.0, method="RK45", *, rtol=1e-3, atol=1e-6,
                 max_step=math.inf, max_steps=None):
        t0 = real_scalar(t0, "t0")
        if not math.isfinite(t0):
            raise ValueError(f"t0 must be finite, got {t0}")
        # SciPy's warning about an rtol below 100 eps at the user's call, not at the
        # validating call below (rtol raised to that floor, as the solvers do themselves)
        rtol = _raised_rtol(rtol)
        self._options = dict(method=method, rtol=rtol, atol=atol, max_step=max_step,
                             max_steps=max_steps)
        # every rule of solve_ivp, with its messages, on a zero-length run
        solve_ivp(fun, (t0, t0), y0, **self._options)
        self.fun = fun
        self.t = t0
        self._packed = None
        builtin = isinstance(fun, NativeSystem)
        y = initial_state(y0, fun, builtin, allow_complex=not builtin,
                          allow_empty=not builtin)
        self.y = y
        if builtin and isinstance(method, str):
            self._packed = self._pack(fun, method, rtol, atol, max_step, max_steps,
                                      y.size)
        self._iout = np.empty(40, dtype=np.int64)   # 8 numbers, then the message's bytes
        self._counts = self._iout[:8]       # (a view made once: no slice per call)
        self._handle = 0
        if self._packed is not None:
            self._open()

    def _open(self):
        """Keep the packed system, its stepper and options in Fortran memory (freed with
        this object, or when a repacking replaces them)."""
        fun, params, spec, ipack, rpar, n, _ = self._packed
        iout = self._iout
        _conmech.flat_propagation_new(ipack, params if params.size else _PAD, spec, rpar,
                                      n, iout)
        if iout[6] == BAD_INPUT:
            raise ValueError(message_text(iout[8:]))
        self._handle = int(iout[7])
        self._free = weakref.finalize(self, _conmech.flat_propagation_free, self._handle)

    def _repack(self):
        """Pack again (the system was given new parameter or function arrays), in new
        Fortran memory; the packed arguments, or None."""
        o = self._options
        self._free()
        self._handle = 0
        self._packed = self._pack(self.fun, o["method"], o["rtol"], o["atol"],
                                  o["max_step"], o["max_steps"], self.y.size)
        if self._packed is not None:
            self._open()
        return self._packed

    @staticmethod
    def _pack(fun, method, rtol, atol, max_step, max_steps, n):
        """The packed arguments of the one-call route (native_path.prepare with one
        output time, its last number in rpar), or None where solve_ivp takes another
        route for this system and method."""
        code = fast_method_code(method)     # 0: a method the one-call route does not take
        if not code:
            return None
        run_fun = fun
        if code == BY_NAME["TAYLOR"].code:
            if getattr(fun, "taylor", None):
                run_fun = with_fixed_order(fun, rtol, atol)
            elif getattr(fun, "kind", None) == "generalized":
                run_fun = with_fixed_order(first_order_view(fun), rtol, atol)
        if not isinstance(run_fun, NativeSystem):
            return None
        # checked, and warned about, by solve_ivp in __init__
        rtol_v = tolerance(rtol, "rtol", n, warn=False)
        atol_v = tolerance(atol, "atol", n, warn=False)
        hmax = min(positive_finite(max_step, "max_step", allow_inf=True),
                   float(np.finfo(float).max))
        return prepare(run_fun, code, rtol_v, atol_v, 0.0, hmax, step_limit(max_steps))

    def propagate_until(self, t):
        """Integrate from ``self.t`` to ``t`` (either direction). Returns a
        ``conmech.Propagation`` named tuple (success, status, message, nfev, naccept,
        nreject: the run's evaluations and steps). On success ``self.t`` and ``self.y``
        are the new time and state; on a failure (too many steps, a step size below
        round-off, a non-finite right-hand side) they stay as they were and the result's
        message says what stopped the run."""
        if type(t) is not float:
            t = float(t if type(t) is int else real_scalar(t, "t"))
        if not _isfinite(t):
            raise ValueError(f"t must be finite, got {t}")
        if t == self.t:
            return _NOTHING_DONE
        packed = self._packed
        if packed is not None:
            params = packed[1]
            if params is self.fun.params and packed[2] is packed[0].spec:
                # the one-call route: the run's state is a new array (self.y is left as
                # it was)
                y = self.y
                y = y.copy() if type(y) is _ndarray and y.dtype is _F64 else \
                    _array(y, float)
                iout = self._iout
                _until(self._handle, params if params.size else _PAD, self.t, t, y, iout)
                nt, nfev, _, _, naccept, nreject, info, _ = self._counts.tolist()
                if nt == 1 and info >= 0:
                    self.t = t
                    self.y = y
                    return _new_tuple(Propagation, (True, 0, _SUCCESS, nfev, naccept,
                                                    nreject))
                if info == BAD_INPUT:
                    raise ValueError(message_text(iout[8:]))
                return Propagation(False, min(info, -1), message_text(iout[8:]), nfev,
                                   naccept, nreject)
        if packed is not None:          # the system was given new parameters: pack again
            self._repack()
            return self.propagate_until(t)
        res = solve_ivp(self.fun, (self.t, t), self.y, t_eval=[t], **self._options)
        if res.success and len(res.t) == 1:
            self.t, self.y = t, res.y[:, -1].copy()
            return Propagation(True, 0, res.message, res.nfev, res.naccept, res.nreject)
        return Propagation(False, min(res.status, -1), res.message, res.nfev, res.naccept,
                           res.nreject)

    def propagate_grid(self, times):
        """The states at ``times`` (finite, strictly sorted from ``self.t`` in one
        direction; the first may be ``self.t``) from one run from ``self.t`` to the
        last of them, its steps' continuous extension evaluated at the others (Taylor's:
        the step's polynomial), as ``solve_ivp(fun, (self.t, times[-1]), self.y,
        t_eval=times)`` gives them (heyoka's ``propagate_grid``); for a compiled or
        built-in system in one Fortran call, which continues a Taylor run where the last
        propagation ended as :meth:`propagate_until` does. Returns ``(Propagation, ys)``:
        the run's counts, success and message, and ys of shape (n, len(times)),
        ``ys[:, j]`` the state at ``times[j]``, NaN from the first time not reached.
        ``self.t`` and ``self.y`` become the last time reached and its state."""
        ts = np.asarray(times, dtype=float)
        if ts.ndim != 1 or ts.size == 0:
            raise ValueError("times must be a non-empty one-dimensional sequence")
        packed = self._packed
        if packed is not None and not (packed[1] is self.fun.params and
                                       packed[2] is packed[0].spec):
            packed = self._repack()
        if packed is not None:
            # the times are checked by the flat routine (finite, sorted strictly)
            params = packed[1]
            iout = self._iout
            y = self.y
            y = y.copy() if type(y) is np.ndarray and y.dtype is _F64 else np.array(y, float)
            ys = _empty((y.size, ts.size), order="F")
            _conmech.flat_propagation_grid(self._handle, params if params.size else _PAD,
                                           self.t, ts, y, ys, iout)
            reached, nfev, _, _, naccept, nreject, info, _ = iout[:8].tolist()
            if info == BAD_INPUT:
                raise ValueError(message_text(iout[8:]))
            message = _SUCCESS if info >= 0 else message_text(iout[8:])
        else:
            # solve_ivp's route (a Python right-hand side, a complex state), with the
            # flat routine's rules for the times
            d = np.diff(ts, prepend=self.t)
            if ts[-1] < self.t:
                d = -d
            if not np.isfinite(ts).all() or (d < 0).any() or (d[1:] == 0).any():
                raise ValueError(_GRID_RULE)
            res = solve_ivp(self.fun, (self.t, float(ts[-1])), self.y, t_eval=ts,
                            **self._options)
            reached, nfev, naccept, nreject = len(res.t), res.nfev, res.naccept, \
                res.nreject
            info, message = (0, res.message) if res.success else (min(res.status, -1),
                                                                   res.message)
            ys = np.full((self.y.size, ts.size), np.nan, dtype=res.y.dtype)
            ys[:, :reached] = res.y
            y = ys[:, reached - 1].copy() if reached else None
        if reached:
            self.t, self.y = float(ts[reached - 1]), y
        return (_new_tuple(Propagation, (info >= 0, min(info, 0), message, nfev, naccept,
                                         nreject)), ys)

    def propagate_for(self, dt):
        """:meth:`propagate_until` ``self.t + dt``."""
        return self.propagate_until(self.t + real_scalar(dt, "dt"))

    def __reduce__(self):
        # a copy (copy, deepcopy, pickle) is a Propagator of its own at the same time and
        # state, with Fortran memory of its own
        o = self._options
        return (_restored, (self.fun, self.y.copy(), self.t, o["method"], o["rtol"],
                            o["atol"], o["max_step"], o["max_steps"]))

    def __repr__(self):
        return (f"Propagator({getattr(self.fun, 'name', self.fun)!r}, t={self.t!r}, "
                f"method={self._options['method']!r})")


def _restored(fun, y, t, method, rtol, atol, max_step, max_steps):
    return Propagator(fun, y, t, method, rtol=rtol, atol=atol, max_step=max_step,
                      max_steps=max_steps)
