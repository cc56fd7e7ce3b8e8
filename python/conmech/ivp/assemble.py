"""The result of a solve_ivp call from the outputs of its Fortran run: SciPy's OdeResult
with its t, y, events and dense output, and SciPy's shapes for the empty cases."""
from __future__ import annotations

import numpy as np

from .dense import ConstantDenseOutput, DenseOutput, OdeSolution
from .result import _MESSAGES, OdeResult


def assemble(out, run, n, ne, t0, tf, y0, with_t_eval, dense_output, form, status,
             message, nfev, naccept, nreject):
    """The OdeResult of the run's outputs out (t, y, events, dense pieces): the status's
    standard message, SciPy's t = [t0, t0] for a zero-length span and lists for an
    unreached t_eval, events per event function, the dense output of the steps (or the
    constant y0 when no step was taken)."""
    if status >= 0:
        message = _MESSAGES.get(status, message)
    t, y = out["t"], out["y"]
    if tf == t0 and not with_t_eval:
        # SciPy's solver makes one (empty) step: t = [t0, t0]
        t, y = np.array([t0, t0]), np.repeat(y0[:, None], 2, axis=1)
    if with_t_eval and t.size == 0:
        t, y = [], []          # SciPy's lists when no point of t_eval was reached
    res = OdeResult(t=t, y=y, sol=None, t_events=None, y_events=None,
                    nfev=nfev, njev=run.njev, nlu=run.nlu, status=status,
                    message=message, success=status >= 0, naccept=naccept,
                    nreject=nreject)
    evs = out["ev"]
    if ne > 0:
        res.t_events = [np.array([te for i, te, _ in evs if i == k]) for k in range(ne)]
        res.y_events = [np.array([ye for i, _, ye in evs if i == k]) for k in range(ne)]
        res.y_events = [ye if ye.size else np.asarray([]) for ye in res.y_events]
    if not dense_output:
        return res
    dense = out.get("dense")
    if dense is not None:
        ts, hs, coef = dense
        if not with_t_eval and len(t):
            t_last = float(t[-1])
        elif status == 1 and evs:
            t_last = evs[-1][1]         # the event that ended the run
        else:
            t_last = float(ts[-1] + hs[-1])
        res.sol = DenseOutput(ts, hs, coef, t0, t_last, form=int(form))
    else:
        # no step (a zero-length span, a failure at the first step): the constant y0 on
        # [t0, t0], as SciPy's OdeSolution of one empty step
        res.sol = OdeSolution([t0, t0], [ConstantDenseOutput(t0, t0, y0)])
    return res
