"""Radau IIA and Gauss-Legendre step by step with SciPy's OdeSolver interface.

``conmech.Radau(fun, t0, y0, t_bound, rtol=..., atol=..., jac=..., max_step=...,
first_step=...)`` advances one accepted step per ``step()`` call, as
``scipy.integrate.Radau`` does: attributes ``t``, ``y``, ``t_old``, ``t_bound``,
``direction``, ``n``, ``status``, ``step_size``, ``nfev``, ``njev``, ``nlu``;
``dense_output()`` is the collocation polynomial of the last step. The steps are those of
``conmech.solve_ivp(method="Radau")`` (the same Fortran code, bit for bit), and
``conmech.solve_ivp(..., method=conmech.Radau)`` runs that solver.
``conmech.Gauss4`` / ``conmech.Gauss6`` (s = 2, 3 stages, orders 4 and 6, symplectic, fixed
step ``first_step``, required: the steps are h = (t_bound - t0)/N with N =
ceil(|t_bound - t0|/first_step), as ``solve_ivp(method="GAUSS6", first_step=...)``,
bit for bit; t_bound must then be finite).

As the explicit steppers (conmech/_stepper.py), the Fortran side keeps no state between
calls: the whole state (t, y, f(t, y), the Jacobian, both LU factorisations with their
pivots, the step-size controller's memory and the last collocation polynomial) lives in
three numpy arrays of the Python object, which ``flat_radau_stepper_callback`` (or
``_builtin``) updates in place.
"""
import numpy as np

from . import _conmech
from ._callback import message_text
from ._implicit import jacobian_callback
from ._stepper import RungeKutta, StepDenseOutput, ConstantDenseOutput

__all__ = ["Radau", "Gauss4", "Gauss6"]

_NR, _NI, _NW = (int(v) for v in _conmech.flat_radau_stepper_sizes())
_GNR, _GNI, _GNW = 8, 8, 6      # conmech_gauss: GAUSS_NR, GAUSS_NI, GAUSS_NW
_POWER = 2          # dense form of conmech._ivp.DenseOutput: power basis in x


class Radau(RungeKutta):
    """Radau IIA of order 5 (Hairer's RADAU5 Newton and step control) with SciPy's
    OdeSolver interface, for stiff problems.

    Parameters
    ----------
    fun : callable or conmech.systems.NativeSystem (built-in or compiled)
        ``fun(t, y) -> dydt`` (shape (n,)), or a built-in or compiled system (its own
        Jacobian; no Python in the loop).
    t0, y0, t_bound, max_step, rtol, atol, first_step, vectorized, max_steps :
        As :class:`conmech.DOP853` (first_step None: SciPy's heuristic for Radau).
    jac : callable, array_like or None
        ``jac(t, y) -> (n, n)`` or a constant matrix; None: forward differences (counted
        in nfev). Not with a built-in system.
    jac_sparsity : None
        Accepted for SciPy compatibility; only None (dense Jacobians).
    """

    _code = 5
    order = 5
    error_estimator_order = 3
    n_stages = 3

    def __init__(self, fun, t0, y0, t_bound, max_step=np.inf, rtol=1e-3, atol=1e-6,
                 jac=None, jac_sparsity=None, vectorized=False, first_step=None,
                 max_steps=100000, **extraneous):
        if jac_sparsity is not None:
            raise ValueError("jac_sparsity is not supported: conmech.Radau uses dense "
                             "Jacobians (pass jac, or nothing for finite differences)")
        self._jac_arg = jac
        super().__init__(fun, t0, y0, t_bound, max_step=max_step, rtol=rtol, atol=atol,
                         vectorized=vectorized, first_step=first_step, max_steps=max_steps,
                         **extraneous)

    # ------------------------------------------------------------------ state
    @property
    def y(self):
        """Current state (a copy)."""
        return self._wr[:, 0].copy()

    @property
    def naccept(self):
        return int(self._ir[7])

    @property
    def nreject(self):
        return int(self._ir[8])

    def _call(self, action):
        n = self.n
        if action == 0:
            self._rr = np.zeros(_NR)
            self._ir = np.zeros(_NI + 2 * n, dtype=np.intc)
            self._wr = np.zeros((n, _NW + 4 * n), order="F")
            self._wr[:, 0] = self._y0
            self._failure = []
            if self._builtin:
                if self._jac_arg is not None:
                    raise TypeError("jac cannot be used with a built-in system (it has its "
                                    "own)")
            else:
                self._jac_cb, self._has_jac = jacobian_callback(self._jac_arg, n, (),
                                                                self._failure)
        common = dict(action=action, t0=self.t if action == 0 else 0.0,
                      t_bound=self.t_bound, y0=self._y0, rtol=self._rtol, atol=self._atol,
                      first_step=self._first_step, max_step=self._max_step,
                      max_steps=self._max_steps, r=self._rr, iv=self._ir, w=self._wr)
        if self._builtin:
            info, message = _conmech.flat_radau_stepper_builtin(*self.fun._flat_args(),
                                                                **common)
        else:
            info, message = _conmech.flat_radau_stepper_callback(
                self._rhs, self._jac_cb, has_jac=self._has_jac, **common)
        if self._failure:
            self._guard.fail(self._failure.pop(0))
        if self._guard.failed:
            self.status = "failed"
            self._guard.check()
        self.nfev = int(self._ir[4])
        self.njev = int(self._ir[5])
        self.nlu = int(self._ir[6])
        if action == 1:
            self.t = float(self._rr[2])
        return int(info), message_text(message)

    def dense_output(self):
        """The collocation polynomial of the last step (a callable of t)."""
        if self.t_old is None:
            raise RuntimeError("Dense output is available after a successful step was "
                               "made.")
        if self.t == self.t_old:
            return ConstantDenseOutput(self.t_old, self.t, self.y)
        coef = np.array(self._wr[:, 5:9])
        return StepDenseOutput(float(self._rr[17]), self.t, float(self._rr[12]), coef,
                               _POWER)


class Gauss(RungeKutta):
    """Base class of the Gauss-Legendre steppers (fixed step, SciPy's OdeSolver interface).

    Parameters as :class:`conmech.DOP853`, except ``first_step``: the step (required), and
    ``t_bound``: finite. No Jacobian is used (fixed-point iteration of the stages to
    round-off); a step whose iteration does not converge fails with the time.
    """

    _code = 0
    n_stages = 0

    def __init__(self, fun, t0, y0, t_bound, first_step=None, **options):
        if first_step is None:
            raise ValueError(f"first_step is required by {type(self).__name__} (a "
                             "fixed-step method): pass the step size")
        if not np.isfinite(float(t_bound)):
            raise ValueError(f"t_bound must be finite for {type(self).__name__} (fixed "
                             "steps over [t0, t_bound])")
        h = float(first_step)
        if h > abs(float(t_bound) - float(t0)) > 0:
            first_step = abs(float(t_bound) - float(t0))     # one step, as solve_ivp
        super().__init__(fun, t0, y0, t_bound, first_step=first_step, **options)

    @property
    def y(self):
        """Current state (a copy)."""
        return self._wr[:, 0].copy()

    @property
    def naccept(self):
        return int(self._ir[5])

    @property
    def nreject(self):
        return 0

    def _call(self, action):
        n = self.n
        if action == 0:
            self._rr = np.zeros(_GNR)
            self._ir = np.zeros(_GNI, dtype=np.intc)
            self._wr = np.zeros((n, _GNW), order="F")
            self._wr[:, 0] = self._y0
        common = dict(action=action, method=self._code, t0=self.t if action == 0 else 0.0,
                      t_bound=self.t_bound, y0=self._y0, first_step=self._first_step,
                      max_steps=self._max_steps, r=self._rr, iv=self._ir, w=self._wr)
        if self._builtin:
            info, message = _conmech.flat_gauss_stepper_builtin(*self.fun._flat_args(),
                                                                **common)
        else:
            info, message = _conmech.flat_gauss_stepper_callback(self._rhs, **common)
        if self._guard.failed:
            self.status = "failed"
            self._guard.check()
        self.nfev = int(self._ir[4])
        if action == 1:
            self.t = float(self._rr[2])
        return int(info), message_text(message)

    def dense_output(self):
        """The collocation polynomial of the last step (a callable of t)."""
        if self.t_old is None:
            raise RuntimeError("Dense output is available after a successful step was "
                               "made.")
        if self.t == self.t_old:
            return ConstantDenseOutput(self.t_old, self.t, self.y)
        s = self.n_stages
        coef = np.array(self._wr[:, 2:3 + s])
        return StepDenseOutput(float(self._rr[4]), self.t, self.t - float(self._rr[4]),
                               coef, _POWER)


class Gauss4(Gauss):
    """Gauss-Legendre collocation with 2 stages (order 4, symplectic), fixed step."""
    _code = 6
    order = 4
    n_stages = 2


class Gauss6(Gauss):
    """Gauss-Legendre collocation with 3 stages (order 6, symplectic), fixed step."""
    _code = 7
    order = 6
    n_stages = 3
