"""The short path of :func:`conmech.solve_ivp`: a built-in or compiled system without events,
dense output or a Python Jacobian is integrated by one call of the flat routine
flat_solve_native, which returns the points in arrays sized here; only a run with more
points than that room calls back into Python to hand them over."""
import numpy as np

from .. import _conmech
from .._core.callback import message_text
from .._core.status import BAD_INPUT
from .result import _MESSAGES, OdeResult

_PAD = np.zeros(1)
_PAD.flags.writeable = False
# the room for the points of a run returned without a call-back (_solve_native): numbers
# of t and y (8 kB; a run with more points hands them over through a call-back)
_OUT_DOUBLES = 1024


def solve_native(fun, t0, tf, y0, t_ev, with_t_eval, code, rtol, atol, h0, hmax,
                  max_steps):
    """solve_ivp of a built-in or compiled system without events or dense output (checked
    arguments): the result of :func:`_solve` for such a run, from one call of
    flat_solve_native, which returns the points in arrays sized here (t_eval's length,
    else room for _OUT_DOUBLES numbers) and calls ``store`` back only when a run has more."""
    n = y0.size
    neval = t_ev.size
    cap = neval if with_t_eval else max(_OUT_DOUBLES // (n + 1), 2)
    out = []

    def store(t, y, ev_t, ev_y, ev_id, ts, hs, coef):
        # more points than cap: the arrays wrap Fortran memory that is freed on return
        out.append(t.copy())
        out.append(y.reshape(n, t.size).copy())

    t_out, y_out, nt, counts, info, message = _conmech.flat_solve_native(
        *fun._flat_args(), store, t0, tf, y0, code, rtol, atol, h0, hmax,
        max_steps, neval, t_ev if neval else _PAD, cap)
    info = int(info)
    if info == BAD_INPUT:
        raise ValueError(message_text(message))
    if nt < 0:
        t, y = out
    elif nt > 0:
        t, y = t_out[:nt].copy(), y_out[:, :nt].copy()
    else:               # no point stored: a run refused before its first step
        t, y = np.array([t0]), y0[:, None].copy()
    if tf == t0 and not with_t_eval:
        # SciPy's solver makes one (empty) step: t = [t0, t0]
        t, y = np.array([t0, t0]), np.repeat(y0[:, None], 2, axis=1)
    elif with_t_eval and t.size == 0:
        t, y = [], []          # SciPy's lists when no point of t_eval was reached
    nfev, njev, nlu, naccept, nreject = counts.tolist()
    if info >= 0:
        status, message = info, _MESSAGES.get(info) or message_text(message)
    else:
        status, message = -1, message_text(message)
    return OdeResult(t=t, y=y, sol=None, t_events=None, y_events=None, nfev=nfev,
                     njev=njev, nlu=nlu, status=status, message=message,
                     success=status >= 0, naccept=naccept, nreject=nreject)
