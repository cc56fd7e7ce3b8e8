"""solve_ivp on a state of dimension zero: nothing to integrate, but SciPy's result (one
call of fun, events of t alone located by bisection, t_eval, a constant dense output)."""
import math

import numpy as np

from .._core.callback import as_result
from .dense import ConstantDenseOutput, OdeSolution
from .result import _MESSAGES, OdeResult

__all__ = ["solve_empty", "bisect"]


def solve_empty(fun, builtin, args, t0, tf, y0, t_ev, with_t_eval, dense, settings,
                 vectorized):
    """A state of dimension zero (SciPy's solvers finish at once): fun is called once
    (its return must be empty), the events are functions of t alone and located by
    bisection on [t0, tf] (tf finite)."""
    y = y0.copy()
    yy = y[:, None] if vectorized else y
    r = fun(t0, yy, *args)
    as_result(r if r is not None else None, (0,), "fun")
    t_end, status = tf, 0
    t_events = y_events = None
    if settings:
        t_events = [[] for _ in settings]
        remaining = [c for _, c, _, _ in settings]
        found = []
        if math.isfinite(tf) and tf != t0:
            for k, (e, _, d, _) in enumerate(settings):
                ga = float(as_result(e(t0, y.copy(), *args), (), f"events[{k}]"))
                gb = float(as_result(e(tf, y.copy(), *args), (), f"events[{k}]"))
                if (ga < 0 <= gb and d >= 0) or (ga > 0 >= gb and d <= 0):
                    found.append((bisect(lambda t: e(t, y.copy(), *args), t0, tf, ga, gb),
                                  k))
        for te, k in sorted(found, key=lambda x: (x[0] - t0) * math.copysign(1, tf - t0)):
            if status == 1:
                break
            t_events[k].append(te)
            if remaining[k] > 0:
                remaining[k] -= 1
                if remaining[k] == 0:
                    t_end, status = te, 1
        y_events = [np.zeros((len(te), 0)) if te else np.asarray([]) for te in t_events]
        t_events = [np.asarray(te) for te in t_events]
    if with_t_eval:
        sgn = math.copysign(1.0, tf - t0)
        t = t_ev[(t_ev - t_end) * sgn <= 0]
    else:
        t = np.array([t0, t_end])
    sol = OdeSolution([t0, t_end], [ConstantDenseOutput(t0, t_end, y)]) if dense else None
    return OdeResult(t=t, y=np.zeros((0, t.size), dtype=y.dtype), sol=sol,
                     t_events=t_events, y_events=y_events, nfev=1, njev=0, nlu=0,
                     status=status, message=_MESSAGES[status], success=True, naccept=0,
                     nreject=0)


def bisect(g, a, b, ga, gb):
    """A zero of g(t) between a and b (g(a) = ga, g(b) = gb of opposite signs or gb = 0)
    by bisection to the spacing of doubles."""
    if gb == 0:
        return b
    for _ in range(2100):
        m = 0.5 * (a + b)
        if m == a or m == b:
            break
        gm = float(g(m))
        if gm == 0:
            return m
        if (gm < 0) == (ga < 0):
            a, ga = m, gm
        else:
            b = m
    return b
