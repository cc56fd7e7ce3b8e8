"""conmech's status codes, read from the Fortran definitions (``conmech_status``), and the
one mapping from a failed status to a Python exception.

Every Fortran routine returns an integer status: zero or positive is a success (positive: a
run that ended early on a terminal event), negative a failure. A bad argument
(``BAD_INPUT``) is the caller's mistake and becomes a ``ValueError``; any other failure
(singular matrix, no convergence, too many steps, ...) is a property of the problem and
becomes a ``RuntimeError``; the Fortran message names the cause in both.
"""
from .. import _conmech
from .callback import message_text

__all__ = ["SUCCESS", "EVENT_STOP", "TOO_MANY_STEPS", "STEP_TOO_SMALL", "NONFINITE",
           "BAD_INPUT", "SINGULAR", "NO_CONVERGENCE", "LAPACK_ERROR", "USER_ERROR",
           "status_message", "error_for", "raise_status"]

(SUCCESS, EVENT_STOP, TOO_MANY_STEPS, STEP_TOO_SMALL, NONFINITE, BAD_INPUT, SINGULAR,
 NO_CONVERGENCE, LAPACK_ERROR, USER_ERROR) = (int(c) for c in _conmech.flat_status_codes())


def status_message(info):
    """The default text of a status code (conmech_status's ``status_message``)."""
    return message_text(_conmech.flat_status_message(int(info)))


def error_for(info, message=""):
    """The exception for the failed status ``info``: ValueError for a bad argument,
    RuntimeError otherwise, carrying the Fortran message (or the code's default text when
    the routine left it blank)."""
    text = message_text(message) or status_message(info)
    return ValueError(text) if int(info) == BAD_INPUT else RuntimeError(text)


def raise_status(info, message=""):
    """Raise :func:`error_for` ``(info, message)``; callers test the status first."""
    raise error_for(info, message)
