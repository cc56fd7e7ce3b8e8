"""Messages about the closed loops of a tree (conmech.symbolic.loops): which loop is
described, and which one cannot close at given positions. Kept apart from the loop
constraints themselves so that the compiled model (pipeline.py) can name a loop that does
not close without importing the loop construction, which imports the pipeline."""
import numpy as np
import sympy as sp

__all__ = ["worst_loop", "describe_loop", "closure_error"]


def worst_loop(d, r):
    """The description of the loop with the largest residual in r (phi's rows)."""
    k, worst, found = 0, -1.0, None
    for item in d.loops:
        m = item["rows"]
        x = float(np.max(np.abs(r[k:k + m])))
        if x > worst:
            worst, found = x, item
        k += m
    return describe_loop(d, found) if found is not None else ""


def describe_loop(d, item):
    """A loop for messages: its label, joint, bodies and points (the points in their
    bodies' frames, parameters by name)."""
    names = list(getattr(d, "order_names", ())) or None
    dim = item["npt"]
    e = item["exprs"]

    def body(k):
        if k < 0:
            return "the ground"
        return repr(names[k]) if names else f"body {k}"

    named = {ps: sp.Symbol(nm) for ps, nm in zip(getattr(d, "params", ()),
                                                 getattr(d, "param_names", ()))}
    value = dict(zip(getattr(d, "params", ()), getattr(d, "param_values", ())))

    def pt(x):
        x = [sp.sympify(v) for v in x]
        text = "(" + ", ".join(str(v.xreplace(named)) for v in x) + ")"
        try:
            num = [float(v.xreplace(value)) for v in x]
        except (TypeError, ValueError):
            return text
        shown = "(" + ", ".join(f"{v:.6g}" for v in num) + ")"
        return text if shown == text else f"{text} = {shown}"
    ka, kb = item["bodies"]
    return (f"{item['label']} ({item['kind']} joint of {body(ka)} at {pt(e[:dim])} and "
            f"{body(kb)} at {pt(e[dim:2*dim])})")


def closure_error(model, system, q0, t0=0.0):
    """None when the loops of the tree `system` (made from `model`) close at q0 (or it has
    none); otherwise the ValueError that names the loop with the largest residual and
    that residual (:meth:`conmech.symbolic.CompiledModel.closure_error`)."""
    d = model.derived
    if d.kind != "constrained" or not getattr(d, "loops", None):
        return None
    p = np.asarray(getattr(system, "params", d.param_values), dtype=float)
    r = np.asarray(model.call("phi", float(t0), np.asarray(q0, float), params=p))
    res = float(np.max(np.abs(r), initial=0.0))
    return ValueError(f"{worst_loop(d, r)} cannot close at the initial positions q0 "
                      f"(residual {res:.3g}; no position near q0 satisfies the loop "
                      "constraints: links too short to reach, or a crank angle the "
                      "linkage cannot take; symbolic.consistent_state completes q0 from "
                      "the independent coordinates)")
