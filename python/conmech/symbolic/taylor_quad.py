"""Reference solutions in quadruple precision: Taylor's method in real128 (gfortran's IEEE
binary128, 113-bit significand, unit round-off 9.6e-35) on the recurrences
:mod:`conmech.symbolic.taylor` generates for every smooth ode system.

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

__all__ = ["reference", "QuadResult", "to_pair", "from_pair"]


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
    string), ``nsteps``, ``order``, ``status`` (0 success), ``message``, ``success``."""

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError as exc:
            raise AttributeError(name) from exc


def reference(system, t_span, y0, tol=1e-30, params=None, max_steps=1_000_000):
    """Integrate a system made by :func:`conmech.symbolic.ode_system` from t_span[0] to
    t_span[1] by Taylor's method in quadruple precision (order ceil(-ln(tol)/2 + 1), 36 at
    the default 1e-30). y0, the times, tol and the parameters (``params``: {name: value},
    overriding the system's) may be given as decimal strings for full precision."""
    # the quadruple-precision routine of a lazy system is compiled here, on first need
    taylor = system.taylor_parts("qp") if hasattr(system, "taylor_parts") else \
        getattr(system, "taylor", None)
    if not taylor or taylor.get("qp") is None:
        raise ValueError("the system has no quadruple-precision Taylor code (a system from "
                         "conmech.symbolic.ode_system with a smooth right-hand side)")
    n = system.dimension
    y0 = list(y0)
    if len(y0) != n:
        raise ValueError(f"y0 must have {n} components, got {len(y0)}")
    try:
        t0, t1 = t_span
    except (TypeError, ValueError):
        raise ValueError("t_span must be a pair (t0, tf)") from None
    ypairs = np.array([to_pair(v, f"y0[{i}]") for i, v in enumerate(y0)]).T
    tpairs = np.array([to_pair(t0, "t_span[0]"), to_pair(t1, "t_span[1]")]).T
    if not (isinstance(tol, (float, int, str, Decimal)) and float(tol) > 0):
        raise ValueError("tol must be a positive number")
    tolp = np.array(to_pair(tol, "tol"))
    values = dict(zip(system.param_names, system.params.tolist()))
    for k, v in (params or {}).items():
        if k not in values:
            raise ValueError(f"unknown parameter {k!r} (parameters: "
                             f"{', '.join(system.param_names) or 'none'})")
        values[k] = v
    pp = [to_pair(values[k], f"params[{k!r}]") for k in system.param_names] or [(0.0, 0.0)]
    ppairs = np.array(pp).T
    if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or \
            max_steps < 1:
        raise ValueError("max_steps must be a positive integer")
    y1, nsteps, order, info, message = _conmech.flat_taylor_quad(
        fnaddr=function_address(taylor["qp"], "taylor['qp']"), nw=int(taylor["nw"]),
        np=system.params.size, params=np.asfortranarray(ppairs), n=n,
        y0=np.asfortranarray(ypairs), t_span=np.asfortranarray(tpairs), tol=tolp,
        max_steps=int(max_steps))
    y1 = np.array(y1).T
    return QuadResult(y=y1, y_str=[from_pair(a, b) for a, b in y1],
                      y_float=y1[:, 0] + y1[:, 1], t=from_pair(*tpairs[:, 1]),
                      nsteps=int(nsteps), order=int(order), status=int(info),
                      message=message_text(message), success=int(info) == 0)
