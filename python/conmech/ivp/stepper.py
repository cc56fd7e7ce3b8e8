"""Step-by-step integration with SciPy's OdeSolver interface, for every method.

``conmech.DOP853(fun, t0, y0, t_bound, rtol=..., atol=..., max_step=..., first_step=...)``
(and ``RK45`` (SciPy's step control), ``DOPRI5`` (Hairer's), ``VERNER98``, ``RK4``,
``Radau`` (with ``jac``), ``Gauss4``, ``Gauss6``; any method of the table by name with
``conmech.Stepper(fun, t0, y0, t_bound, method="...")``) advance one accepted step per
``step()`` call, as ``scipy.integrate.DOP853`` does: attributes ``t``, ``y``, ``t_old``,
``t_bound``, ``direction``, ``n``, ``status`` ("running", "finished", "failed"),
``step_size``, ``nfev``, ``njev``, ``nlu``; ``dense_output()`` is the continuous extension
of the last step. The steps are those of :func:`conmech.solve_ivp` (the same Fortran
stepper), bit for bit.

The Fortran side keeps no state between calls: the stepper's whole state (t, y, the
stages, the step size and the controller's memory; for Radau the Jacobian and both LU
factorisations) lives in three numpy arrays of the Python object, which the one flat
routine ``flat_stepper_callback`` (or ``_builtin``) reads and writes back in place at every
call. Objects are independent; one object must not be stepped from two threads at once.

As SciPy's solvers: a complex y0 is integrated as its real and imaginary parts (not by
Radau, as SciPy's Radau), an empty y0 finishes at the first step, ``t_bound`` may be
infinite for the adaptive methods, and there is no limit on the number of steps unless
``max_steps`` is given.
"""
import functools
import math
import warnings

import numpy as np

from .. import _conmech
from .._core.callback import Guard, as_result, message_text
from .complex_form import real_form as _real_form
from .dense import ComplexSolution, ConstantDenseOutput, DenseOutput
from .._core.checks import initial_state, real_scalar, step_limit, tolerance
from .implicit import start_jacobian, sparsity_pattern, is_sparse
from .methods import BY_NAME, RK45_SCIPY, method_info
from .._core.native import NativeSystem
from .._core.status import BAD_INPUT

__all__ = ["Stepper", "RungeKutta", "DOP853", "RK45", "DOPRI5", "VERNER98", "RK4", "Radau",
           "Gauss", "Gauss4", "Gauss6", "method_code", "ConstantDenseOutput"]

(_R_T, _R_TOLD, _R_HDONE, _I_NF, _I_FORM, _I_NFEV, _I_NJEV, _I_NLU, _I_NACCEPT, _I_NREJECT,
 _W_Y, _W_FC) = (int(v) - 1 for v in _conmech.flat_stepper_layout())
_START, _STEP, _DENSE, _SIZES = 0, 1, 2, 3      # flat_stepper actions
assert (_I_NJEV, _I_NLU) == (_I_NFEV + 1, _I_NFEV + 2)   # read as one slice
_HUGE = np.finfo(float).max
_COMPLEX_REFUSED = ("`y0` is complex, but the chosen solver does not support integration "
                    "in a complex domain.")


class StepDenseOutput(DenseOutput):
    """Continuous extension of one step (SciPy's DenseOutput interface): ``sol(t)``,
    ``t_old``, ``t``, ``t_min``, ``t_max``."""

    def __init__(self, t_old, t, h, coef, form):
        super().__init__([t_old], [h], coef[:, :, None], t_old, t, form=form)
        self.t_old = t_old
        self.t = t


class Stepper:
    """A stepper of any method of the table (SciPy's OdeSolver interface); the classes
    below fix the method, ``Stepper(..., method="NAME")`` takes it by name.

    Parameters
    ----------
    fun : callable or conmech.systems.NativeSystem
        ``fun(t, y) -> dydt`` (shape (n,)), or a built-in or compiled system (no Python in
        the loop; its own Jacobian where the method uses one).
    t0 : float
        Initial time.
    y0 : array_like, shape (n,)
        Initial state.
    t_bound : float
        Boundary time: the integration does not go beyond it (may be infinite for the
        adaptive methods); it also sets the direction of integration.
    max_step : float
        Largest step size (default: no limit).
    rtol, atol : float or array_like of shape (n,)
        Relative and absolute tolerances (SciPy's defaults 1e-3, 1e-6).
    first_step : float or None
        Initial step size (None: the method's heuristic). Fixed-step methods (RK4, Gauss4,
        Gauss6): their step, required.
    vectorized : bool
        Accepted for SciPy compatibility, without effect.
    max_steps : int or None
        Attempted steps allowed over the whole integration (None: no limit, as SciPy).
    jac : callable, array_like, sparse matrix or None
        Methods that use a Jacobian (Radau): ``jac(t, y) -> (n, n)`` (dense or a
        scipy.sparse matrix) or a constant matrix (read once, njev 0); None: finite
        differences (counted in nfev). Not with a built-in system.
    jac_sparsity : array_like, sparse matrix or None
        Methods that use a Jacobian, without ``jac``: the structure of df/dy for finite
        differences by groups of columns (Curtis-Powell-Reid); with n >= 100 and at most
        10% of the entries in it (or a constant sparse ``jac``), Radau's LUs are sparse.
    method : str
        Only for ``Stepper`` itself: the method's name in the table.
    """

    _code = 0
    order = 0
    error_estimator_order = 0
    n_stages = 0

    def __init_subclass__(cls, code=None, order=None, error_estimator_order=None,
                          n_stages=None, **kwargs):
        """A method's class names its table code and SciPy's class attributes in its
        bases' keywords: ``class DOP853(RungeKutta, code=..., order=8, ...)``."""
        super().__init_subclass__(**kwargs)
        for name, value in (("_code", code), ("order", order),
                            ("error_estimator_order", error_estimator_order),
                            ("n_stages", n_stages)):
            if value is not None:
                setattr(cls, name, value)

    def __init__(self, fun, t0, y0, t_bound, max_step=np.inf, rtol=1e-3, atol=1e-6,
                 vectorized=False, first_step=None, max_steps=None, **extraneous):
        code = self._code
        if type(self) is Stepper:
            name = extraneous.pop("method", None)
            entry = BY_NAME.get(str(name).upper()) if isinstance(name, str) else None
            if entry is None or entry.constrained_only:
                raise ValueError(f"method must be a method of the table, one of "
                                 f"{', '.join(sorted(BY_NAME))}, got {name!r}")
            code = entry.code
        self._code = code
        info = method_info(code)
        if info is None:
            raise TypeError(f"{type(self).__name__} is a base class: use a method's class "
                            "(conmech.DOP853, conmech.Gauss6, ...) or conmech.Stepper(..., "
                            "method=NAME)")
        jac = sparsity = None
        if info.uses_jacobian:
            jac = extraneous.pop("jac", None)
            sparsity = extraneous.pop("jac_sparsity", None)
            if jac is not None:
                # SciPy: the pattern only serves finite differences; a constant sparse jac
                # gives its own, for the sparse LUs
                sparsity = jac if is_sparse(jac) and not callable(jac) else None
        if extraneous:
            warnings.warn("The following arguments have no effect for a chosen solver: "
                          + ", ".join(f"`{x}`" for x in extraneous), stacklevel=2)
        self._builtin = isinstance(fun, NativeSystem)
        if not self._builtin and not callable(fun):
            raise TypeError("fun must be callable or a built-in system from "
                            f"conmech.systems, got {type(fun).__name__}")
        t0 = real_scalar(t0, "t0")
        t_bound = real_scalar(t_bound, "t_bound")
        if not math.isfinite(t0):
            raise ValueError("t0 must be finite")
        if math.isnan(t_bound):
            raise ValueError("t_bound must not be NaN")
        y = initial_state(y0, fun, self._builtin, allow_complex=not self._builtin,
                          allow_empty=not self._builtin)
        n = y.size
        self._complex = y.dtype.kind == "c"
        if self._complex and info.uses_jacobian:
            raise ValueError(_COMPLEX_REFUSED)
        self._rtol = tolerance(rtol, "rtol", n)
        self._atol = tolerance(atol, "atol", n)
        if info.name.upper() == "TAYLOR" and self._builtin:
            fun = _taylor_system(fun, self._rtol, self._atol)
        name = type(self).__name__ if type(self) is not Stepper else info.name
        if info.fixed_step:
            if first_step is None:
                raise ValueError(f"first_step is required by {name} (a fixed-step "
                                 "method): pass the step size")
            if not math.isfinite(t_bound) and n:
                raise ValueError(f"t_bound must be finite for {name} (fixed steps over "
                                 "[t0, t_bound])")
        if first_step is None:
            h0 = 0.0
        else:
            h0 = real_scalar(first_step, "first_step")
            if not (h0 > 0 and math.isfinite(h0)):
                raise ValueError("first_step must be positive")
            if h0 > abs(t_bound - t0) and t_bound != t0:
                if not info.fixed_step:
                    raise ValueError("first_step exceeds the length of the interval")
                h0 = abs(t_bound - t0)          # one step, as solve_ivp
        hmax = real_scalar(max_step, "max_step")
        if not hmax > 0:
            raise ValueError("max_step must be positive")
        max_steps = step_limit(max_steps)

        self.fun = fun
        self.t_old = None
        self.t = t0
        self.t_bound = t_bound
        self.vectorized = vectorized
        self.direction = float(np.sign(t_bound - t0)) if t_bound != t0 else 1.0
        self.n = n
        self.status = "running"
        self._nfev_start = 0      # nfev before the state exists (n = 0: fun's one call)
        self._y0 = y.copy()
        self._first_step = h0
        self._max_step = min(hmax, _HUGE)
        self._max_steps = int(max_steps)
        self._pending = None
        self._guard = Guard()
        self._failure = []
        self._r = np.zeros(1)
        self._iv = np.zeros(1, dtype=np.intc)
        # the step routines' message buffer: written (blank-padded bytes) only on failure
        self._msg = np.zeros(256, dtype=np.int8)
        self._cached = {}
        self._step_call = None
        self._sparse_jac = None
        if n == 0:
            # nothing to integrate: SciPy's solver evaluates fun once and finishes at the
            # first step (t = t_bound)
            r = fun(self.t, y.copy())
            as_result(r, (0,), "fun")
            self._nfev_start = 1
            return
        if self._complex:
            # [Re y; Im y] for the real stepper, tolerances per part
            y = np.concatenate([y.real, y.imag])
            self._y0 = y.copy()
            self._rtol = np.concatenate([self._rtol, self._rtol])
            self._atol = np.concatenate([self._atol, self._atol])
            fun = _real_form(fun, n)
        m = y.size
        self._w = np.zeros((m, 1), order="F")
        self._w[:, 0] = y
        if self._complex and sparsity is jac:
            sparsity = None
        nnz, ptr, idx = sparsity_pattern(sparsity, m) if sparsity is not None else \
            (-1, None, np.zeros(1, dtype=np.intc))
        self._pattern = dict(nnz=nnz, sp_ptr=ptr if ptr is not None else
                             np.zeros(m + 1, dtype=np.intc), sp_idx=idx)
        if self._builtin:
            if jac is not None:
                raise TypeError("jac cannot be used with a built-in system (it has its own)")
        else:
            # every return of fun is checked (shape, None, complex) by the one wrapper of
            # conmech._callback; an exception stops the step and is re-raised unchanged
            self._rhs = self._guard.wrap(fun, 2, (m,), "fun")
            # a callable jac is evaluated at (t0, y0) now, as SciPy's Radau does; a sparse
            # value makes its pattern the Jacobian's and the values travel on it
            self._jac_cb, self._has_jac, self._jac_const, self._sparse_jac = start_jacobian(
                jac, m, (), self._failure, t0, y)
            if self._sparse_jac is not None:
                nnz, ptr, idx = self._sparse_jac.pattern
                self._pattern = dict(nnz=nnz, sp_ptr=ptr, sp_idx=idx)
        info_, message, sizes = self._call(_SIZES)
        if info_ == BAD_INPUT:
            raise ValueError(message)
        self._r = np.zeros(max(int(sizes[0]), 1))
        self._iv = np.zeros(max(int(sizes[1]), 1), dtype=np.intc)
        self._w = np.zeros((m, max(int(sizes[2]), 1)), order="F")
        self._sizes = tuple(int(s) for s in sizes)
        info_, message, _ = self._call(_START)
        if info_ == BAD_INPUT:
            raise ValueError(message)
        if info_ < 0:
            self._pending = message      # reported by the first step(), as SciPy would

    # ------------------------------------------------------------------ state
    @property
    def y(self):
        """Current state (a copy)."""
        if self.n == 0:
            return self._y0.copy()
        y = self._w[:, _W_Y].copy() if self._w.shape[1] > _W_Y else self._y0.copy()
        return y[:self.n] + 1j * y[self.n:] if self._complex else y

    @property
    def step_size(self):
        """Size of the last successful step (None before the first one)."""
        return None if self.t_old is None else abs(self.t - self.t_old)

    # the counters are read from the packed state when asked (SciPy's attributes): a step
    # then only reads t back
    @property
    def nfev(self):
        """Evaluations of fun (finite-difference Jacobians included)."""
        iv = self._iv
        return int(iv[_I_NFEV]) if iv.size > _I_NREJECT else self._nfev_start

    @property
    def njev(self):
        """Evaluations of the Jacobian (methods that use one)."""
        iv = self._iv
        return int(iv[_I_NJEV]) if iv.size > _I_NREJECT else 0

    @property
    def nlu(self):
        """LU decompositions (methods that use one)."""
        iv = self._iv
        return int(iv[_I_NLU]) if iv.size > _I_NREJECT else 0

    @property
    def naccept(self):
        return int(self._iv[_I_NACCEPT]) if self._iv.size > _I_NACCEPT else 0

    @property
    def nreject(self):
        return int(self._iv[_I_NREJECT]) if self._iv.size > _I_NREJECT else 0

    def _positional(self, action):
        """The flat routine and its positional arguments for a step or a dense output,
        returning info (a failure's message in self._msg): built once (the state arrays r,
        iv, w are updated in place, so the same objects serve every call). The step routines take only the
        method, the system and the state (the tolerances, t_bound and the Jacobian's
        structure are in the state; the state's sizes are the arrays'), and return no
        array: f2py's conversion of each argument and each returned array is most of the
        Python cost of a step."""
        state = (self._r, self._iv, self._w, self._msg)
        if self._sparse_jac is not None:
            # the system's pattern is not in the packed state: the full argument list
            return (_without_sizes(functools.partial(_conmech.flat_stepper_sparse_jac,
                                                     **self._arguments(action)), self._msg),
                    ())
        if self._builtin:
            return (_conmech.flat_stepper_step_builtin,
                    self.fun._flat_args() + (action, self._code) + state)
        return (_conmech.flat_stepper_step_callback,
                (self._rhs, self._jac_cb, action, self._code, self._has_jac) + state)

    def _call(self, action):
        if action == _STEP or action == _DENSE:
            cached = self._cached.get(action)
            if cached is None:
                cached = self._cached[action] = self._positional(action)
            routine, args = cached
            return self._after(action, None, routine(*args), self._msg)
        common = self._arguments(action)
        if self._sparse_jac is not None:
            sizes, info, message = _conmech.flat_stepper_sparse_jac(**common)
        elif self._builtin:
            sizes, info, message = _conmech.flat_stepper_builtin(*self.fun._flat_args(),
                                                                 **common)
        else:
            sizes, info, message = _conmech.flat_stepper_callback(
                self._rhs, self._jac_cb, has_jac=self._has_jac, jac_const=self._jac_const,
                **common)
        return self._after(action, sizes, info, message)

    def _arguments(self, action):
        """The keyword arguments of the full flat stepper routines for an action."""
        nr, ni, nw = self._r.size, self._iv.size, self._w.shape[1]
        if action == _SIZES:
            nr = ni = nw = 0
        common = dict(action=action, nr=nr, ni=ni, nw=nw,
                      t0=self.t if action in (_START, _SIZES) else 0.0,
                      t_bound=self.t_bound, y0=self._y0, method=self._code,
                      rtol=self._rtol, atol=self._atol, first_step=self._first_step,
                      max_step=self._max_step, max_steps=self._max_steps,
                      r=self._r, iv=self._iv, w=self._w, **self._pattern)
        if self._sparse_jac is not None:
            common.update(fun=self._rhs, jvals=self._sparse_jac.callback)
        return common

    def _after(self, action, sizes, info, message):
        """Failures of the callbacks re-raised, the counts and t read from the state."""
        if self._failure:
            self._guard.fail(self._failure.pop(0))
        if self._guard.failed:
            self.status = "failed"
            self._guard.check()
        info = int(info)
        # the 256-character message is cleaned only when there is one to report (cleaning
        # it costs more than the rest of a step's glue)
        message = message_text(message) if info != 0 else ""
        if action == _STEP and self._iv.size > _I_NREJECT:
            self.t = self._r.item(_R_T)
        return info, message, sizes

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
        t = self.t
        if self.n == 0 or t == self.t_bound:
            self.t_old = t
            self.t = self.t_bound
            self.status = "finished"
            return None
        # the step's call inlined (its routine and arguments built once): a step of a
        # compiled system is a few microseconds, of which Python's calls are a good part
        call = self._step_call
        if call is None:
            call = self._step_call = self._positional(_STEP)
        info = call[0](*call[1])
        if info or self._failure or self._guard.error is not None:
            info, message, _ = self._after(_STEP, None, info, self._msg)
            if info != 0:
                self.status = "failed"
                return message
        else:
            self.t = self._r.item(_R_T)
        self.t_old = t
        if self.direction*(self.t - self.t_bound) >= 0:
            self.status = "finished"
        return None

    def dense_output(self):
        """Continuous extension of the last step (a callable of t)."""
        if self.t_old is None:
            raise RuntimeError("Dense output is available after a successful step was "
                               "made.")
        if self.t == self.t_old or self.n == 0:
            return ConstantDenseOutput(self.t_old, self.t, self.y)
        self._call(_DENSE)
        nf = int(self._iv[_I_NF])
        coef = np.array(self._w[:, _W_FC:_W_FC + nf + 1])
        sol = StepDenseOutput(float(self._r[_R_TOLD]), self.t, float(self._r[_R_HDONE]),
                              coef, int(self._iv[_I_FORM]))
        return ComplexSolution(sol, self.n) if self._complex else sol

    def __repr__(self):
        return (f"conmech.{type(self).__name__}(t={self.t!r}, status={self.status!r}, "
                f"n={self.n}, nfev={self.nfev})")


class RungeKutta(Stepper):
    """Base class of conmech's explicit Runge-Kutta steppers (parameters: :class:`Stepper`)."""


class DOP853(RungeKutta, code=BY_NAME["DOP853"].code, order=8, error_estimator_order=7,
             n_stages=12):
    """Dormand-Prince 8(5,3) with dense output of order 7 (SciPy's OdeSolver interface)."""


class RK45(RungeKutta, code=RK45_SCIPY, order=5, error_estimator_order=4, n_stages=6):
    """Dormand-Prince 5(4) with SciPy's step control and initial step (as
    ``scipy.integrate.RK45`` and ``conmech.solve_ivp(method="RK45")``: no Lund
    stabilisation, SciPy's ``select_initial_step``), dense output of order 4; SciPy's
    OdeSolver interface. ``conmech.DOPRI5`` is the same pair with Hairer's control."""


class DOPRI5(RungeKutta, code=BY_NAME["DOPRI5"].code, order=5, error_estimator_order=4,
             n_stages=6):
    """Dormand-Prince 5(4) as Hairer's DOPRI5 (Lund-stabilised step control, Hairer's
    initial step, dense output of order 4), SciPy's OdeSolver interface."""


class VERNER98(RungeKutta, code=BY_NAME["VERNER98"].code, order=9,
               error_estimator_order=8, n_stages=16):
    """Verner's 9(8) pair with dense output of order 8 (SciPy's OdeSolver interface)."""


class RK4(RungeKutta, code=BY_NAME["RK4"].code, order=4, error_estimator_order=0,
          n_stages=4):
    """Classical fixed-step RK4 (step ``first_step``), SciPy's OdeSolver interface."""


class Radau(Stepper, code=BY_NAME["RADAU5"].code, order=5, error_estimator_order=3,
            n_stages=3):
    """Radau IIA of order 5 (Hairer's RADAU5 Newton and step control) with SciPy's
    OdeSolver interface, for stiff problems; ``dense_output()`` is the collocation
    polynomial of the last step.

    Parameters as :class:`Stepper`, with ``jac`` (callable ``jac(t, y) -> (n, n)``, a
    constant matrix, or None: forward differences counted in nfev; not with a built-in
    system, which has its own) and ``jac_sparsity`` (grouped differences, and sparse LUs
    for n >= 100 at most 10% dense).
    """


class Gauss(Stepper):
    """Base class of the Gauss-Legendre steppers (fixed step ``first_step``, required:
    the steps are h = (t_bound - t0)/N with N = ceil(|t_bound - t0|/first_step), as
    ``solve_ivp(method="GAUSS6", first_step=...)``, bit for bit; t_bound finite). No
    Jacobian is used (fixed-point iteration of the stages to round-off); a step whose
    iteration does not converge fails with the time."""


class Gauss4(Gauss, code=BY_NAME["GAUSS4"].code, order=4, n_stages=2):
    """Gauss-Legendre collocation with 2 stages (order 4, symplectic), fixed step."""


class Gauss6(Gauss, code=BY_NAME["GAUSS6"].code, order=6, n_stages=3):
    """Gauss-Legendre collocation with 3 stages (order 6, symplectic), fixed step."""


def _taylor_system(fun, rtol, atol):
    """The system a Taylor stepper runs, as solve_ivp runs it: a generalized symbolic
    system's first-order view (its recurrences solve with M(q) order by order); the
    recurrences built if still pending, and written out for the order of the tolerances.
    Other systems as they are (the Fortran stepper names what they lack)."""
    from .taylor import with_fixed_order
    from .taylor_generalized import first_order_view
    if not getattr(fun, "taylor", None):        # reading it builds a pending Taylor part
        fun = first_order_view(fun)
    if getattr(fun, "taylor", None):
        fun = with_fixed_order(fun, rtol, atol)
    return fun


def _without_sizes(routine, msg):
    """A full flat stepper routine (sizes, info, message) as a step routine (info; the
    message of a failure written into the buffer msg as the step routines write it)."""
    def call():
        _, info, message = routine()
        if info:
            msg[:] = np.frombuffer(bytes(message)[:msg.size].ljust(msg.size), dtype=np.int8)
        return info
    return call


def _butcher(cls):
    """SciPy's class attributes A, B, C (the Butcher tableau of the propagated solution,
    n_stages stages) from the Fortran tableau of the method."""
    s = cls.n_stages
    a, b, c = _conmech.flat_rk_tableau(cls._code)
    cls.A = np.array(a[:s, :s], order="C")     # C order: row sums as SciPy adds them
    cls.B = np.array(b[:s])
    cls.C = np.array(c[:s])


for _cls in (RK45, DOPRI5, DOP853, VERNER98):
    _butcher(_cls)

_SCIPY_COUNTERPARTS = {"RK45": RK45_SCIPY, "DOP853": DOP853._code, "Radau": Radau._code}


def method_code(method):
    """Method code of a stepper class (conmech's, or SciPy's RK45/DOP853/Radau); 0 if none."""
    if isinstance(method, type):
        if issubclass(method, Stepper):
            return method._code
        if method.__module__.startswith("scipy.integrate"):
            return _SCIPY_COUNTERPARTS.get(method.__name__, 0)
    return 0
