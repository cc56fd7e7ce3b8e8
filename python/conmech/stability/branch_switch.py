"""Branch switching at a branch point (a multiplier through +1: transcritical or
symmetry-breaking pitchfork of periodic orbits in a parameter, or S through +1 in a
conservative family continued in the period); see conmech_branch_switch. Exported as
:func:`conmech.stability.switch_branch_point`."""
from __future__ import annotations

from typing import Any

import numpy as np

from .continuation import Branch, SpecialPoint, continuation

__all__ = ["switch_branch_point"]


def switch_branch_point(system: Any, branch, point, param: str | int | None = None,
                        **options):
    """The second branch through a located branch point of ``branch``.

    ``branch``: a :class:`~conmech.stability.Branch` from
    :func:`~conmech.stability.continuation` by general shooting, in a parameter, or of a
    conservative family along the period (``in_period``; the new branch is continued the
    same way); ``point``: one of its special points of kind 'branch point'.
    ``system``/``param`` as for that continuation. At the point the shooting Jacobian has a
    two-dimensional kernel (computed by SVD); the old branch's tangent (the secant of the
    branch points around ``point``) is removed from it and the remaining direction starts
    the new branch (``direction`` = +1/-1 picks its side; the other options as for
    :func:`~conmech.stability.continuation`). The result's ``kernel_ratio`` (second smallest
    singular value over the third) is small at a genuine branch point.
    """

    if not isinstance(branch, Branch):
        raise TypeError("branch must be the Branch on which the branch point was located")
    if not isinstance(point, SpecialPoint) or point.kind != "branch point":
        raise ValueError("point must be a 'branch point' SpecialPoint of the branch")
    if not any(point is s for s in branch.special):
        raise ValueError("point must be one of branch.special")
    for bad in ("free", "targets", "p0", "_switch", "_tangent", "in_period", "conservative"):
        if bad in options:
            raise ValueError(f"{bad} is not an option of switch_branch_point (general "
                             "shooting, the branch's own kind of continuation)")
    in_period = branch.param == "period"
    if branch.conservative and not in_period:
        raise ValueError("switch_branch_point: a conservative family must be continued in "
                         "the period (in_period=True) for branch switching")
    if in_period:
        options.update(in_period=True, conservative=bool(branch.conservative))
    i = point.index
    if not 0 <= i < len(branch) - 1:
        raise ValueError("the branch point's index is outside the branch")
    autonomous = options.get("autonomous", True)
    with_period = autonomous and not options.get("fixed_period", False) and not in_period

    def x(k):
        parts = [branch.y0[k]]
        if with_period:
            parts.append([branch.period[k]])
        parts.append([branch.p[k]])
        return np.concatenate(parts)
    t_old = x(i + 1) - x(i)
    if not np.linalg.norm(t_old) > 0:
        raise ValueError("the branch points around the branch point coincide")
    return continuation(system, point.y0, point.period, param=param,
                        p0=None if in_period else point.p,
                        _switch=2, _tangent=t_old/np.linalg.norm(t_old), **options)
