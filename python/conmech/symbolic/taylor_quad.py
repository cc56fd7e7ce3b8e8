"""Reference solutions in quadruple precision: Taylor's method in real128 (gfortran's IEEE
binary128, 113-bit significand, unit round-off 9.6e-35) on the recurrences
:mod:`conmech.symbolic.taylor` generates for every smooth ode system, and Hairer's DOP853
in real128 on the same routine's first coefficient (:func:`reference_dop853`, or
``reference(..., method="DOP853")``): two independent methods for one reference.

Values cross the boundary as pairs of doubles (hi, lo), the number being hi + lo exactly
(two doubles hold 106 of the 113 bits of a real128 exactly); :func:`reference` accepts
floats, integers, decimal strings, :class:`decimal.Decimal` and mpmath numbers, and
returns the final state as pairs and as decimal strings::

    res = symbolic.taylor_quad.reference(arenstorf, (0, "17.0652165601579625588917206249"),
                                         ["0.994", "0", "0", "-2.00158510637908252240537862224"],
                                         params={"mu": "0.012277471"}, tol=1e-30)
    res.y_str          # 34 significant digits
"""
from decimal import Decimal, localcontext

import numpy as np

from .. import _conmech
from .._core.callback import message_text
from .._core.native import function_address

__all__ = ["reference", "reference_dop853", "QuadResult", "to_pair", "from_pair"]


def to_pair(x, what="value"):
    """(hi, lo) doubles with hi + lo = x to about 34 significant digits."""
    with localcontext() as ctx:
        ctx.prec = 60
        if isinstance(x, (float, int, np.floating, np.integer)) and not isinstance(x, bool):
            d = Decimal(float(x)) if isinstance(x, (float, np.floating)) else Decimal(int(x))
        elif isinstance(x, str):
            try:
                d = Decimal(x.strip())
            except Exception:
                raise ValueError(f"{what}: cannot read {x!r} as a number") from None
        elif isinstance(x, Decimal):
            d = x
        elif hasattr(x, "_mpf_") or type(x).__name__ == "mpf":
            d = Decimal(str(x))
        else:
            raise TypeError(f"{what} must be a number, a decimal string, a Decimal or an "
                            f"mpmath number, got {type(x).__name__}")
        if not d.is_finite():
            raise ValueError(f"{what} must be finite")
        hi = float(d)
        lo = float(d - Decimal(hi))
    return hi, lo


def from_pair(hi, lo):
    """The decimal string (34 significant digits) of hi + lo."""
    with localcontext() as ctx:
        ctx.prec = 34
        return str(+(Decimal(float(hi)) + Decimal(float(lo))))


class QuadResult(dict):
    """Result of :func:`reference` (keys are attributes): ``y`` (n, 2) pairs (hi, lo),
    ``y_str`` decimal strings, ``y_float`` the doubles nearest, ``t`` the final time (a
    string), ``nsteps`` (accepted steps), ``order``, ``method``, ``status`` (0 success),
    ``message``, ``success``; DOP853 adds ``nfev`` and ``nreject``."""

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError as exc:
            raise AttributeError(name) from exc


def _quad_inputs(system, t_span, y0, params):
    """The generated quadruple-precision routine of `system` and the inputs as pairs:
    (taylor parts, n, y0 pairs (2, n), t_span pairs (2, 2), parameter pairs (2, np))."""
    # the quadruple-precision routine of a lazy system is compiled here, on first need; a
    # generalized system M(q) q'' = Q runs its first-order view y = [q; v]
    from ..ivp.taylor_generalized import first_order_view
    system = first_order_view(system, "qp")
    taylor = system.taylor_parts("qp") if hasattr(system, "taylor_parts") else \
        getattr(system, "taylor", None)
    if not taylor or taylor.get("qp") is None:
        raise ValueError("the system has no quadruple-precision Taylor code (a system from "
                         "conmech.symbolic.ode_system with a smooth right-hand side, or a "
                         "generalized one from lagrangian_system)")
    n = system.dimension
    if isinstance(y0, (str, bytes)) or not hasattr(y0, "__len__") and \
            not hasattr(y0, "__iter__"):
        raise TypeError("y0 must be a sequence of numbers or decimal strings")
    y0 = list(y0)
    if len(y0) != n:
        raise ValueError(f"y0 must have {n} components, got {len(y0)}")
    try:
        t0, t1 = t_span
    except (TypeError, ValueError):
        raise ValueError("t_span must be a pair (t0, tf)") from None
    ypairs = np.array([to_pair(v, f"y0[{i}]") for i, v in enumerate(y0)]).T
    tpairs = np.array([to_pair(t0, "t_span[0]"), to_pair(t1, "t_span[1]")]).T
    values = dict(zip(system.param_names, system.params.tolist()))
    for k, v in (params or {}).items():
        if k not in values:
            raise ValueError(f"unknown parameter {k!r} (parameters: "
                             f"{', '.join(system.param_names) or 'none'})")
        values[k] = v
    pp = [to_pair(values[k], f"params[{k!r}]") for k in system.param_names] or [(0.0, 0.0)]
    return taylor, n, ypairs, tpairs, np.array(pp).T


def _check_max_steps(max_steps):
    if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or \
            max_steps < 1:
        raise ValueError("max_steps must be a positive integer")


def reference(system, t_span, y0, tol=1e-30, params=None, max_steps=1_000_000,
              method="TAYLOR"):
    """Integrate a system made by :func:`conmech.symbolic.ode_system` (or a generalized
    system M(q) q'' = Q of :mod:`conmech.symbolic`, through its first-order view y = [q; v])
    from t_span[0] to t_span[1] by Taylor's method in quadruple precision (order
    ceil(-ln(tol)/2 + 1), 36 at the default 1e-30), or with ``method="DOP853"`` by :func:`reference_dop853` with
    rtol = atol = tol. y0, the times, tol and the parameters (``params``: {name: value},
    overriding the system's) may be given as decimal strings for full precision."""
    method = _method_name(method)
    if method == "DOP853":
        return reference_dop853(system, t_span, y0, rtol=tol, atol=tol, params=params,
                                max_steps=max_steps)
    if not (isinstance(tol, (float, int, str, Decimal)) and not isinstance(tol, bool)):
        raise ValueError("tol must be a positive number")
    taylor, n, ypairs, tpairs, ppairs = _quad_inputs(system, t_span, y0, params)
    if not float(tol) > 0:
        raise ValueError("tol must be a positive number")
    tolp = np.array(to_pair(tol, "tol"))
    _check_max_steps(max_steps)
    y1, nsteps, order, info, message = _conmech.flat_taylor_quad(
        fnaddr=function_address(taylor["qp"], "taylor['qp']"), nw=int(taylor["nw"]),
        np=system.params.size, params=np.asfortranarray(ppairs), n=n,
        y0=np.asfortranarray(ypairs), t_span=np.asfortranarray(tpairs), tol=tolp,
        max_steps=int(max_steps))
    y1 = np.array(y1).T
    return QuadResult(y=y1, y_str=[from_pair(a, b) for a, b in y1],
                      y_float=y1[:, 0] + y1[:, 1], t=from_pair(*tpairs[:, 1]),
                      nsteps=int(nsteps), order=int(order), status=int(info),
                      message=message_text(message), success=int(info) == 0,
                      method="TAYLOR")


def _method_name(method):
    if not isinstance(method, str):
        raise TypeError(f"method must be a string, got {type(method).__name__}")
    name = method.strip().upper()
    if name not in ("TAYLOR", "DOP853"):
        raise ValueError(f"method must be 'TAYLOR' or 'DOP853', got {method!r}")
    return name


def _tolerance(value, what):
    """A tolerance as a pair: rtol in [1e-32, 1) (below 1e-32 it asks for more than
    DOP853's coefficients, printed to about 30 digits, and real128's 34 can give), atol
    positive and finite (a zero atol would make the error scale of a zero component zero)."""
    if isinstance(value, bool) or value is None:
        raise TypeError(f"{what} must be a number, a decimal string, a Decimal or an "
                        f"mpmath number, got {type(value).__name__}")
    pair = to_pair(value, what)
    if what == "atol":
        if not pair[0] > 0:
            raise ValueError(f"atol must be positive, got {value!r}")
    # compared as the nearest double, as the Fortran side does: "1e-32" to any precision
    # is accepted
    elif not 1e-32 <= pair[0] < 1:
        raise ValueError(f"{what} must lie in [1e-32, 1), got {value!r} (DOP853's "
                         "coefficients carry about 30 digits, real128 34)")
    return np.array(pair)


def reference_dop853(system, t_span, y0, rtol=1e-25, atol=None, params=None,
                     max_steps=1_000_000, fixed_steps=None):
    """Integrate a system made by :func:`conmech.symbolic.ode_system` from t_span[0] to
    t_span[1] by Hairer's DOP853 in quadruple precision: the 8(5,3) pair, its error estimator
    and step-size control, the error per component scaled by atol + rtol |y| (atol defaults
    to rtol; rtol in [1e-32, 1), atol positive). The right-hand side is the first Taylor
    coefficient of the system's generated quadruple-precision routine. ``fixed_steps=N``
    takes N equal steps without error control (for measuring the order). Inputs as in
    :func:`reference`; the result is a :class:`QuadResult` with ``nfev``, ``nsteps``
    (accepted steps), ``nreject`` and ``order`` 8."""
    taylor, n, ypairs, tpairs, ppairs = _quad_inputs(system, t_span, y0, params)
    rtolp = _tolerance(rtol, "rtol")
    atolp = rtolp if atol is None else _tolerance(atol, "atol")
    _check_max_steps(max_steps)
    if fixed_steps is None:
        fixed_steps = 0
    elif isinstance(fixed_steps, bool) or not isinstance(fixed_steps, (int, np.integer)) \
            or fixed_steps < 1:
        raise ValueError("fixed_steps must be a positive integer or None")
    y1, counts, info, message = _conmech.flat_dop853_quad(
        fnaddr=function_address(taylor["qp"], "taylor['qp']"), nw=int(taylor["nw"]),
        np=system.params.size, params=np.asfortranarray(ppairs), n=n,
        y0=np.asfortranarray(ypairs), t_span=np.asfortranarray(tpairs), rtol=rtolp,
        atol=atolp, max_steps=int(max_steps), fixed_steps=int(fixed_steps))
    y1 = np.array(y1).T
    nfev, _attempts, naccept, nreject = (int(c) for c in counts)
    return QuadResult(y=y1, y_str=[from_pair(a, b) for a, b in y1],
                      y_float=y1[:, 0] + y1[:, 1], t=from_pair(*tpairs[:, 1]),
                      nsteps=naccept, nfev=nfev, nreject=nreject, order=8,
                      status=int(info), message=message_text(message),
                      success=int(info) == 0, method="DOP853")
