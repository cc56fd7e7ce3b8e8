"""A state carried from one time to the next: :class:`Propagator`, the counterpart of
heyoka's ``taylor_adaptive.propagate_until`` for conmech's methods.

``solve_ivp`` returns every step's point and builds a result each call, which is what a
user plotting or post-processing a trajectory wants. A user who only needs the state at
given times (a Poincare map, the final state of a shooting iterate, a propagation loop of a
mission-design code) pays for those points and for the checks of every argument at every
call. A Propagator checks the system, the method and the tolerances once (by the rules and
with the messages of solve_ivp), packs the arguments of the flat call once, and then each
:meth:`Propagator.propagate_until` is one Fortran call that integrates from the current
time to the next and returns the state there alone (the run's only output point is the
requested time, so no step's point is stored).

A system compiled or built in (``conmech.systems``, ``conmech.compiled``,
``conmech.symbolic``) takes that one-call route; a Python function or a complex state runs
:func:`conmech.solve_ivp` with ``t_eval=[t]`` (the same result, with solve_ivp's cost per
call). Constrained systems are refused, as by solve_ivp (:mod:`conmech.constrained`
integrates them).
"""
import math
from collections import namedtuple

import numpy as np

from .. import _conmech
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
    stopped (the method's first step is chosen again, Taylor's expansions start there):
    propagating to t1 and then to t2 gives the state at t2 within the tolerances, not
    the bits of one run over [t0, t2]. One propagation to t gives the same state as
    ``solve_ivp(fun, (t0, t), y0, ...).y[:, -1]``.

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
        if self._packed is not None:
            # the one-call route's outputs, kept from call to call (room for two points of
            # the packed system's n: the flat routine asks it; 8 numbers, then the
            # message's 256 bytes)
            n = self._packed[5]
            self._out = np.empty(2*(n + 1))
            self._iout = np.empty(40, dtype=np.int64)

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
                run_fun = first_order_view(fun)
        if not isinstance(run_fun, NativeSystem):
            return None
        # checked, and warned about, by solve_ivp in __init__
        rtol_v = tolerance(rtol, "rtol", n, warn=False)
        atol_v = tolerance(atol, "atol", n, warn=False)
        hmax = min(positive_finite(max_step, "max_step", allow_inf=True),
                   float(np.finfo(float).max))
        prep = prepare(run_fun, code, rtol_v, atol_v, 0.0, hmax,
                       step_limit(max_steps), np.zeros(1))
        rpar = prep[4].copy()           # its last number is the output time of a call
        return (run_fun,) + prep[1:4] + (rpar,) + prep[5:]

    def propagate_until(self, t):
        """Integrate from ``self.t`` to ``t`` (either direction). Returns a
        ``conmech.Propagation`` named tuple (success, status, message, nfev, naccept,
        nreject: the run's evaluations and steps). On success ``self.t`` and ``self.y``
        are the new time and state; on a failure (too many steps, a step size below
        round-off, a non-finite right-hand side) they stay as they were and the result's
        message says what stopped the run."""
        if not (type(t) is float or type(t) is int):
            t = real_scalar(t, "t")
        t = float(t)
        if not math.isfinite(t):
            raise ValueError(f"t must be finite, got {t}")
        if t == self.t:
            return Propagation(True, 0, _MESSAGES[0], 0, 0, 0)
        packed = self._packed
        if packed is not None and packed[1] is packed[0].params and \
                packed[2] is packed[0].spec:
            return self._native(packed, t)
        if packed is not None:          # the system was given new parameters: pack again
            o = self._options
            self._packed = self._pack(self.fun, o["method"], o["rtol"], o["atol"],
                                      o["max_step"], o["max_steps"], self.y.size)
            return self.propagate_until(t)
        res = solve_ivp(self.fun, (self.t, t), self.y, t_eval=[t], **self._options)
        if res.success and len(res.t) == 1:
            self.t, self.y = t, res.y[:, -1].copy()
            return Propagation(True, 0, res.message, res.nfev, res.naccept, res.nreject)
        return Propagation(False, min(res.status, -1), res.message, res.nfev, res.naccept,
                           res.nreject)

    def propagate_for(self, dt):
        """:meth:`propagate_until` ``self.t + dt``."""
        return self.propagate_until(self.t + real_scalar(dt, "dt"))

    def _native(self, packed, t):
        fun, params, spec, ipack, rpar, n, _ = packed
        rpar[-1] = t
        out, iout = self._out, self._iout
        _conmech.flat_solve_packed(ipack, params if params.size else _PAD, spec, rpar,
                                   self.t, t, self.y, out, iout)
        nt, nfev, _, _, naccept, nreject, info, _ = iout[:8].tolist()
        if info == BAD_INPUT:
            raise ValueError(message_text(iout[8:]))
        if info >= 0 and nt == 1:
            self.t, self.y = t, out[1:n + 1].copy()
            return Propagation(True, 0, _MESSAGES[0], nfev, naccept, nreject)
        return Propagation(False, min(info, -1), message_text(iout[8:]), nfev, naccept,
                           nreject)

    def __repr__(self):
        return (f"Propagator({getattr(self.fun, 'name', self.fun)!r}, t={self.t!r}, "
                f"method={self._options['method']!r})")
