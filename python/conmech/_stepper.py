"""Step-by-step integration with SciPy's OdeSolver interface.

``conmech.DOP853(fun, t0, y0, t_bound, rtol=..., atol=..., max_step=..., first_step=...)``
(and ``RK45`` (SciPy's step control), ``DOPRI5`` (Hairer's), ``VERNER98``, ``RK4``) advance one accepted step per ``step()``
call, as ``scipy.integrate.DOP853`` does: attributes ``t``, ``y``, ``t_old``,
``t_bound``, ``direction``, ``n``, ``status`` ("running", "finished", "failed"),
``step_size``, ``nfev``, ``njev``, ``nlu``; ``dense_output()`` is the continuous
extension of the last step. The steps are those of :func:`conmech.solve_ivp` (the same
Fortran stepper), bit for bit.

The Fortran side keeps no state between calls: the stepper's whole state (t, y, the
stages, the step size and the controller's memory) lives in three numpy arrays of the
Python object, which the flat routine ``flat_stepper_callback`` (or ``_builtin``) takes in
and writes back at every call. Objects are independent; one object must not be stepped
from two threads at once.
"""
import math
import numbers
import warnings

import numpy as np

from . import _conmech
from ._callback import Guard, message_text
from ._ivp import DenseOutput, _real_scalar, _tolerance
from ._native import NativeSystem

__all__ = ["RungeKutta", "DOP853", "RK45", "DOPRI5", "VERNER98", "RK4", "method_code"]

_NR, _NI, _NW = (int(v) for v in _conmech.flat_stepper_sizes())
_CFC = 25            # first column of the dense coefficients in the packed state (0-based)
_HUGE = np.finfo(float).max
_PAD = np.zeros(1)
_PAD.flags.writeable = False


class StepDenseOutput(DenseOutput):
    """Continuous extension of one step (SciPy's DenseOutput interface): ``sol(t)``,
    ``t_old``, ``t``, ``t_min``, ``t_max``."""

    def __init__(self, t_old, t, h, coef, form):
        super().__init__([t_old], [h], coef[:, :, None], t_old, t, form=form)
        self.t_old = t_old
        self.t = t


class ConstantDenseOutput:
    """The constant y on a step of length zero (as SciPy's ConstantDenseOutput)."""

    def __init__(self, t_old, t, value):
        self.t_old, self.t = t_old, t
        self.t_min, self.t_max = min(t, t_old), max(t, t_old)
        self.value = np.array(value, dtype=float)

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        if t.ndim == 0:
            return self.value.copy()
        return np.repeat(self.value[:, None], t.size, axis=1)


class RungeKutta:
    """Base class of conmech's explicit Runge-Kutta steppers (SciPy's OdeSolver interface).

    Parameters
    ----------
    fun : callable or conmech.systems.NativeSystem (built-in or compiled)
        ``fun(t, y) -> dydt`` (shape (n,)), or a built-in system (no Python in the loop).
    t0 : float
        Initial time.
    y0 : array_like, shape (n,)
        Initial state.
    t_bound : float
        Boundary time: the integration does not go beyond it (may be infinite); it also
        sets the direction of integration.
    max_step : float
        Largest step size (default: no limit).
    rtol, atol : float or array_like of shape (n,)
        Relative and absolute tolerances (SciPy's defaults 1e-3, 1e-6).
    first_step : float or None
        Initial step size (None: SciPy's heuristic for RK45, Hairer's for the others).
        RK4: its fixed step, required.
    vectorized : bool
        Accepted for SciPy compatibility, without effect.
    max_steps : int
        Attempted steps allowed over the whole integration.
    """

    _code = 0
    order = 0
    error_estimator_order = 0
    n_stages = 0

    def __init__(self, fun, t0, y0, t_bound, max_step=np.inf, rtol=1e-3, atol=1e-6,
                 vectorized=False, first_step=None, max_steps=100000, **extraneous):
        if extraneous:
            warnings.warn("The following arguments have no effect for a chosen solver: "
                          + ", ".join(f"`{x}`" for x in extraneous), stacklevel=2)
        self._builtin = isinstance(fun, NativeSystem)
        if not self._builtin and not callable(fun):
            raise TypeError("fun must be callable or a built-in system from "
                            f"conmech.systems, got {type(fun).__name__}")
        t0 = _real_scalar(t0, "t0")
        t_bound = _real_scalar(t_bound, "t_bound")
        if not math.isfinite(t0):
            raise ValueError("t0 must be finite")
        if math.isnan(t_bound):
            raise ValueError("t_bound must not be NaN")
        y0_in = np.asarray(y0)
        if y0_in.dtype.kind == "c":
            raise TypeError("y0 must be real: complex states are not supported")
        try:
            y = np.array(y0_in, dtype=float)
        except (TypeError, ValueError):
            raise TypeError("y0 must be an array of real numbers") from None
        if y.ndim != 1:
            raise ValueError(f"y0 must be 1-dimensional, got shape {y.shape}")
        n = y.size
        if n == 0:
            raise ValueError("y0 must not be empty")
        if not np.isfinite(y).all():
            raise ValueError("y0 contains NaN or Inf")
        if self._builtin and n != fun.dimension:
            raise ValueError(f"y0 must have shape ({fun.dimension},) for the system "
                             f"'{fun.name}', got {y.shape}")
        self._rtol = _tolerance(rtol, "rtol", n)
        self._atol = _tolerance(atol, "atol", n)
        if first_step is None:
            h0 = 0.0
        else:
            h0 = _real_scalar(first_step, "first_step")
            if not (h0 > 0 and math.isfinite(h0)):
                raise ValueError("first_step must be positive")
            if h0 > abs(t_bound - t0) and t_bound != t0 and self._code != 1:
                raise ValueError("first_step exceeds the length of the interval")
        if self._code == 1 and first_step is None:
            raise ValueError("first_step is required by RK4 (a fixed-step method): pass the "
                             "step size")
        hmax = _real_scalar(max_step, "max_step")
        if not hmax > 0:
            raise ValueError("max_step must be positive")
        if isinstance(max_steps, (bool, np.bool_)) or \
                not isinstance(max_steps, numbers.Integral):
            raise TypeError("max_steps must be an integer")
        if not 1 <= max_steps <= 2**31 - 1:
            raise ValueError("max_steps must be positive (and below 2**31)")

        self.fun = fun
        self.t_old = None
        self.t = t0
        self.t_bound = t_bound
        self.vectorized = vectorized
        self.direction = float(np.sign(t_bound - t0)) if t_bound != t0 else 1.0
        self.n = n
        self.status = "running"
        self.nfev = 0
        self.njev = 0
        self.nlu = 0
        self._y0 = y.copy()
        self._first_step = h0
        self._max_step = min(hmax, _HUGE)
        self._max_steps = int(max_steps)
        self._r = np.zeros(_NR)
        self._iv = np.zeros(_NI, dtype=np.intc)
        self._w = np.zeros((n, _NW), order="F")
        self._w[:, 0] = y
        self._pending = None
        self._probe = 0
        self._guard = Guard()
        if not self._builtin:
            # every return of fun is checked (shape, None, complex) by the one wrapper of
            # conmech._callback; an exception stops the step and is re-raised unchanged
            self._rhs = self._guard.wrap(fun, 2, (n,), "fun")
        info, message = self._call(0)
        if info == -4:
            raise ValueError(message)
        if info < 0:
            self._pending = message      # reported by the first step(), as SciPy would

    # ------------------------------------------------------------------ state
    @property
    def y(self):
        """Current state (a copy)."""
        return self._w[:, 0].copy()

    @property
    def step_size(self):
        """Size of the last successful step (None before the first one)."""
        return None if self.t_old is None else abs(self.t - self.t_old)

    @property
    def naccept(self):
        return int(self._iv[16])

    @property
    def nreject(self):
        return int(self._iv[17])

    def _call(self, action):
        common = dict(action=action, t0=self.t if action == 0 else 0.0,
                      t_bound=self.t_bound, y0=self._y0, method=self._code,
                      rtol=self._rtol, atol=self._atol, first_step=self._first_step,
                      max_step=self._max_step, max_steps=self._max_steps,
                      r=self._r, iv=self._iv, w=self._w)
        if self._builtin:
            info, message = _conmech.flat_stepper_builtin(*self.fun._flat_args(), **common)
        else:
            info, message = _conmech.flat_stepper_callback(self._rhs, **common)
        if self._guard.failed:
            self.status = "failed"
            self._guard.check()
        message = message_text(message)
        self.nfev = int(self._iv[15]) + self._probe
        if action == 1:
            self.t = float(self._r[0])
        return int(info), message

    # ------------------------------------------------------------------ SciPy's API
    def step(self):
        """Advance one accepted step. Returns None on success, else the failure message
        (status "failed"). Raises RuntimeError on a finished or failed solver."""
        if self.status != "running":
            raise RuntimeError("Attempt to step on a failed or finished solver.")
        if self._pending is not None:
            self.status = "failed"
            message, self._pending = self._pending, None
            return message
        if self.t == self.t_bound:
            self.t_old = self.t
            self.status = "finished"
            return None
        t = self.t
        info, message = self._call(1)
        if info != 0:
            self.status = "failed"
            return message
        self.t_old = t
        if self.direction*(self.t - self.t_bound) >= 0:
            self.status = "finished"
        return None

    def dense_output(self):
        """Continuous extension of the last step (a callable of t)."""
        if self.t_old is None:
            raise RuntimeError("Dense output is available after a successful step was "
                               "made.")
        if self.t == self.t_old:
            return ConstantDenseOutput(self.t_old, self.t, self.y)
        self._call(2)
        nf = int(self._iv[2])
        coef = np.array(self._w[:, _CFC:_CFC + nf + 1])
        return StepDenseOutput(self.t_old, self.t, float(self._r[5]), coef, int(self._iv[3]))

    def __repr__(self):
        return (f"conmech.{type(self).__name__}(t={self.t!r}, status={self.status!r}, "
                f"n={self.n}, nfev={self.nfev})")


class DOP853(RungeKutta):
    """Dormand-Prince 8(5,3) with dense output of order 7 (SciPy's OdeSolver interface)."""
    _code = 3
    order = 8
    error_estimator_order = 7
    n_stages = 12


class RK45(RungeKutta):
    """Dormand-Prince 5(4) with SciPy's step control and initial step (as
    ``scipy.integrate.RK45`` and ``conmech.solve_ivp(method="RK45")``: no Lund
    stabilisation, SciPy's ``select_initial_step``), dense output of order 4; SciPy's
    OdeSolver interface. ``conmech.DOPRI5`` is the same pair with Hairer's control."""
    _code = 12
    order = 5
    error_estimator_order = 4
    n_stages = 6


class DOPRI5(RungeKutta):
    """Dormand-Prince 5(4) as Hairer's DOPRI5 (Lund-stabilised step control, Hairer's
    initial step, dense output of order 4), SciPy's OdeSolver interface."""
    _code = 2
    order = 5
    error_estimator_order = 4
    n_stages = 6


class VERNER98(RungeKutta):
    """Verner's 9(8) pair with dense output of order 8 (SciPy's OdeSolver interface)."""
    _code = 4
    order = 9
    error_estimator_order = 8
    n_stages = 16


class RK4(RungeKutta):
    """Classical fixed-step RK4 (step ``first_step``), SciPy's OdeSolver interface."""
    _code = 1
    order = 4
    error_estimator_order = 0
    n_stages = 4


_SCIPY_COUNTERPARTS = {"RK45": 12, "DOP853": 3, "Radau": 5}   # 5: conmech.Radau


def method_code(method):
    """Method code of a stepper class (conmech's, or SciPy's RK45/DOP853/Radau); 0 if none."""
    if isinstance(method, type):
        if issubclass(method, RungeKutta):
            return method._code
        if method.__module__.startswith("scipy.integrate"):
            return _SCIPY_COUNTERPARTS.get(method.__name__, 0)
    return 0
