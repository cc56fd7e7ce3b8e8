"""The result of :func:`conmech.solve_ivp` (SciPy's OdeResult) and its status messages."""
import numpy as np

from .._core.result import DictResult

__all__ = ["OdeResult"]

_MESSAGES = {
    0: "The solver successfully reached the end of the integration interval.",
    1: "A termination event occurred.",
}


class OdeResult(DictResult):
    """Result of :func:`solve_ivp`: a dict whose keys are also attributes (as SciPy's).

    Keys: t, y, sol, t_events, y_events, nfev, njev, nlu, status, message, success,
    and conmech's extras naccept, nreject.
    """

    def __repr__(self):
        keys = ("message", "success", "status", "t", "y", "sol", "t_events", "y_events",
                "nfev", "njev", "nlu")
        width = max(map(len, keys)) + 1
        lines = []
        for k in keys:
            v = self.get(k)
            if isinstance(v, np.ndarray) and v.size > 6:
                v = f"array of shape {v.shape}"
            lines.append(f"{k.rjust(width)}: {v!r}" if not isinstance(v, str) else
                         f"{k.rjust(width)}: {v}")
        return "\n".join(lines)
