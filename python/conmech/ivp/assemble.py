"""The result of a solve_ivp call from its segments (a terminal event that is not the last
restarts the run: each restart is a segment): SciPy's OdeResult with its t, y, events and
dense output, and SciPy's shapes for the empty cases."""
from __future__ import annotations

import numpy as np

from .dense import ConstantDenseOutput, DenseOutput, OdeSolution
from .result import _MESSAGES, OdeResult


def drop_first_point(out, with_t_eval):
    """A continuation segment repeats its start point (the event): drop it."""
    if not with_t_eval and out["t"].size:
        out["t"] = out["t"][1:]
        out["y"] = out["y"][:, 1:]
    return out


def assemble(segs, run, n, ne, t0, tf, y0, with_t_eval, dense_output, form, status,
             message, nfev, naccept, nreject):
    """The OdeResult of the segments segs (each: t, y, events, dense pieces) of one run:
    the status's standard message, SciPy's t = [t0, t0] for a zero-length span and lists
    for an unreached t_eval, events per event function, the dense output of all pieces
    (or the constant y0 when no step was taken)."""
    if status >= 0:
        message = _MESSAGES.get(status, message)
    ts = [s["t"] for s in segs]
    ys = [s["y"] if s["y"] is not None else np.repeat(y0[:, None], s["t"].size, axis=1)
          for s in segs]
    if len(segs) == 1:      # one segment (no terminal event restarted it): its own arrays
        t, y = ts[0], ys[0]
    else:
        t = np.concatenate(ts) if ts else np.array([t0])
        y = np.concatenate(ys, axis=1) if ys else y0[:, None].copy()
    if tf == t0 and not with_t_eval:
        # SciPy's solver makes one (empty) step: t = [t0, t0]
        t, y = np.array([t0, t0]), np.repeat(y0[:, None], 2, axis=1)
    if with_t_eval and t.size == 0:
        t, y = [], []          # SciPy's lists when no point of t_eval was reached
    res = OdeResult(t=t, y=y, sol=None, t_events=None, y_events=None,
                    nfev=nfev, njev=run.njev, nlu=run.nlu, status=status,
                    message=message, success=status >= 0, naccept=naccept,
                    nreject=nreject)
    if ne > 0:
        evs = [e for s in segs for e in s["ev"]]
        res.t_events = [np.array([te for i, te, _ in evs if i == k]) for k in range(ne)]
        res.y_events = [np.array([ye for i, _, ye in evs if i == k]) for k in range(ne)]
        res.y_events = [ye if ye.size else np.asarray([]) for ye in res.y_events]
    if not dense_output:
        return res
    dens = [s["dense"] for s in segs if s.get("dense") is not None]
    if dens:
        t_last = float(t[-1]) if not with_t_eval and len(t) else None
        last = dens[-1]
        if t_last is None:
            t_last = float(last[0][-1] + last[1][-1])
            if status == 1 and ne > 0 and any(s["ev"] for s in segs):
                t_last = [e for s in segs for e in s["ev"]][-1][1]
        res.sol = DenseOutput(np.concatenate([d[0] for d in dens]),
                              np.concatenate([d[1] for d in dens]),
                              np.concatenate([d[2] for d in dens], axis=2), t0, t_last,
                              form=int(form))
    else:
        # no step (a zero-length span, a terminal event at t0, a failure at the first
        # step): the constant y0 on [t0, t0], as SciPy's OdeSolution of one empty step
        res.sol = OdeSolution([t0, t0], [ConstantDenseOutput(t0, t0, y0)])
    return res
