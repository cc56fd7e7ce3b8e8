"""``symbolic.lagrangian_system(L, q, ..., inputs=...)``: a :class:`ControlledSystem` from a
Lagrangian, with B(q) u in the equations M q'' = Q + B u (B compiled when it depends on q).

Two steps around the uncontrolled derivation: :func:`input_matrix` reads B and the forces
at u = 0 from ``inputs``; the plant is derived from L with those forces; then
:func:`controlled_system` attaches B (a constant matrix, or compiled code for B(q)).
"""
from __future__ import annotations

import numpy as np
import sympy as sp

from ..control.plant import ControlledSystem
from .build import compile_source, load
from .printer import FortranPrinter, _procedure

__all__ = ["input_matrix", "controlled_system"]


def _as_list(x):
    if isinstance(x, sp.MatrixBase):
        return list(x)
    if isinstance(x, (list, tuple)):
        return list(x)
    return [x]


def input_matrix(q, forces, inputs):
    """(B, forces at u = 0) of M q'' = Q + B u (:func:`conmech.symbolic.lagrangian_system`).

    ``inputs`` is one of
    - a list of coordinates (elements of ``q``): each gets its own input (a force or torque
      on that coordinate; B = the columns e_i);
    - a list of input symbols u_1..u_m that appear linearly in ``forces`` (e.g. a force of
      fixed direction applied at a moving point): B = d forces / d u, the plant's forces
      those at u = 0;
    - a sympy Matrix B (ndof x m) in the coordinates and parameters.
    A B that depends on q is compiled with the model (``void B(t, q, b, p)``)."""
    qs = _as_list(q)
    n = len(qs)
    if isinstance(inputs, sp.MatrixBase):
        bmat = sp.Matrix(inputs)
        if bmat.shape[0] != n or bmat.shape[1] < 1:
            raise ValueError(f"inputs: B must be an {n} x m matrix")
        f0 = forces
    else:
        items = _as_list(inputs)
        if not items:
            raise ValueError("inputs must not be empty")
        if all(any(it == qq for qq in qs) for it in items):
            idx = [next(i for i, qq in enumerate(qs) if qq == it) for it in items]
            if len(set(idx)) != len(idx):
                raise ValueError("inputs: a coordinate is listed twice")
            bmat = sp.zeros(n, len(idx))
            for j, i in enumerate(idx):
                bmat[i, j] = 1
            f0 = forces
        elif all(isinstance(it, sp.Symbol) for it in items):
            if forces is None:
                raise ValueError("inputs given as symbols must appear in forces=")
            fl = [sp.sympify(f) for f in _as_list(forces)]
            if len(fl) != n:
                raise ValueError(f"forces has {len(fl)} components for {n} coordinates")
            bmat = sp.Matrix([[sp.diff(f, u) for u in items] for f in fl])
            for f in fl:
                for u in items:
                    for u2 in items:
                        if sp.simplify(sp.diff(f, u, u2)) != 0:
                            raise ValueError(f"the forces must be linear in the inputs; "
                                             f"{f} is not")
            sub0 = {u: 0 for u in items}
            f0 = [f.subs(sub0) for f in fl]
            for f in f0:
                if f.free_symbols & set(items):
                    raise ValueError("the forces must be linear in the inputs")
        else:
            raise ValueError("inputs must be coordinates of q, input symbols appearing in "
                             "forces, or a matrix B")
    return bmat, f0


def controlled_system(plant, bmat, q, params):
    """The :class:`ControlledSystem` of ``plant`` (derived with the forces at u = 0) and the
    input matrix ``bmat`` from :func:`input_matrix`."""
    qs = _as_list(q)
    n = len(qs)
    m = bmat.shape[1]
    pvals = {}
    for k, v in (params or {}).items():
        pvals[k.name if isinstance(k, sp.Symbol) else str(k)] = float(v)
    # the parameters by name, the coordinates by position
    byname = {s.name: s for s in bmat.free_symbols if isinstance(s, sp.Symbol)}
    coordsub = {qq: sp.Symbol(f"__q{i}") for i, qq in enumerate(qs)}
    bq = bmat.subs(coordsub)
    bq = bq.subs({byname[nm]: v for nm, v in pvals.items() if nm in byname})
    qsyms = set(coordsub.values())
    extra = {s for s in bq.free_symbols if s not in qsyms}
    if extra:
        raise ValueError(f"B may depend on the coordinates and parameters only; unknown "
                         f"{sorted(map(str, extra))}")
    if not (bq.free_symbols & qsyms):
        b = np.array(bq.tolist(), dtype=float)
        if np.linalg.matrix_rank(b) < m:
            raise ValueError("B must have independent columns")
        cs = ControlledSystem(plant, B=b)
        if all(np.count_nonzero(b[:, j]) == 1 and np.max(b[:, j]) == 1 for j in range(m)):
            cs.actuated = tuple(int(np.argmax(b[:, j])) for j in range(m))
            cs.passive = tuple(i for i in range(n) if i not in cs.actuated)
        return cs
    return _compiled_input_matrix(plant, bmat, qs, pvals, m)


def _compiled_input_matrix(plant, bmat, qs, pvals, m):
    """Generate and compile ``conmech_input_matrix(t, q, b, p)`` for a q-dependent B."""
    n = len(qs)
    names = list(pvals)
    psyms = [sp.Symbol(f"__p{i}") for i in range(len(names))]
    byname = {s.name: s for s in bmat.free_symbols if isinstance(s, sp.Symbol)}
    csyms = [sp.Symbol(f"__c{i}", real=True) for i in range(n)]
    expr = bmat.subs({qq: c for qq, c in zip(qs, csyms)})
    expr = expr.subs({byname[nm]: p for nm, p in zip(names, psyms) if nm in byname})
    pr = FortranPrinter({**{c: f"q({i + 1})" for i, c in enumerate(csyms)},
                         **{p: f"p({i + 1})" for i, p in enumerate(psyms)},
                         sp.Symbol("t"): "t"})
    ind = "        "
    decls = [f"{ind}real(dp), value, intent(in) :: t", f"{ind}real(dp), intent(in) :: q({n})",
             f"{ind}real(dp), intent(out) :: b({n}, {m})",
             f"{ind}real(dp), intent(in) :: p({max(len(names), 1)})"]
    proc = _procedure(pr, "conmech_input_matrix", ["t", "q", "b", "p"], decls,
                      [("b", expr, True)])
    src = "\n".join(["!> Generated by conmech.control: the input matrix B(t, q). Do not edit.",
                     "module conmech_control_input_matrix",
                     "    use, intrinsic :: iso_c_binding, only: c_double",
                     "    implicit none", "    integer, parameter :: dp = c_double",
                     "    public", "contains", ""] + proc
                    + ["end module conmech_control_input_matrix", ""])
    path, _ = compile_source(src, symbols=["input_matrix"])
    lib, addr = load(path, ["input_matrix"])
    return ControlledSystem(plant, input_matrix=addr["input_matrix"], n_inputs=m,
                            input_params=[pvals[nm] for nm in names], keep=lib)
