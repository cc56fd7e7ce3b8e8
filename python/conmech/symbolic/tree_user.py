"""The user's generalized forces of a tree (and those of forces at points of bodies) and
their Jacobian, as procedures of the generated code."""
import sympy as sp

from .kinematics import forward_diff
from .printer import _decl_temps, assignments
from .tree_print import IND as _IND, fast_print, proc as _proc

__all__ = ["user_forces", "has_user_jac", "user_jac"]


def user_forces(d, em, pfc):
    """tree_user_forces(t, q, v, p, fu): the user's generalized forces (user order), with
    those of the forces at points of bodies (pfc: point_force_code's (code, Q))."""
    n, npar = d.n, max(len(d.params), 1)
    fl = [sp.sympify(e) for e in d.user_forces]
    tg = [f"fu({i + 1})" for i, e in enumerate(fl) if e != 0]
    ex = [e for e in fl if e != 0]
    em.reset()
    temps, lines = assignments(tg, ex, em.pr, _IND, prefix="f") if ex else ([], [])
    if pfc is not None:
        code, Q = pfc
        lines += em.defs(code.live(Q), "pf")
        saved = em.pr.names
        em.pr.names = {**saved, **em.local}
        try:
            lines += [f"{_IND}fu({i + 1}) = fu({i + 1}) + "
                      f"{fast_print(sp.sympify(e), em.pr.names, em.pr)}"
                      for i, e in enumerate(Q) if e != 0]
        finally:
            em.pr.names = saved
        temps = temps + list(em.local.values())
    return _proc("subroutine tree_user_forces(t, q, v, p, fu)",
                 [f"{_IND}real(dp), intent(in) :: t, q({n}), v({n}), p({npar})",
                  f"{_IND}real(dp), intent(out) :: fu({n})"] + _decl_temps(temps),
                 [f"{_IND}fu = 0.0_dp"] + lines, "tree_user_forces")


def has_user_jac(d):
    xs = set(d.coords) | set(d.speeds)
    return bool(getattr(d, "point_forces", None)) or any(
        sp.sympify(e).free_symbols & xs for e in d.user_forces)


def user_jac(d, em, pfc):
    """tree_user_jac(t, q, v, p, xt): adds d(user forces)/d[q, v] (and that of the forces
    at points of bodies, by forward differentiation of their code) to the transposed
    Jacobian xt (variables x equations, topological order)."""
    n, npar = d.n, max(len(d.params), 1)
    topo = {J.col: k for k, J in enumerate(d.joints)}
    xs = list(d.coords) + list(d.speeds)

    def target(i, j):
        var = topo[j] if j < n else n + topo[j - n]
        return f"xt({var + 1}, {topo[i] + 1})"
    tg, ex = [], []
    for i, e in enumerate(d.user_forces):
        e = sp.sympify(e)
        if e == 0:
            continue
        for j, x in enumerate(xs):
            if x in e.free_symbols:
                de = sp.diff(e, x)
                if de.has(sp.DiracDelta):
                    de = de.replace(sp.DiracDelta, lambda *a: sp.S.Zero)
                if de != 0:
                    tg.append(target(i, j))
                    ex.append(de)
    gt = [f"gj({k + 1})" for k in range(len(ex))]
    em.reset()
    temps, lines = assignments(gt, ex, em.pr, _IND, prefix="g") if ex else ([], [])
    lines += [f"{_IND}{t} = {t} + {g}" for t, g in zip(tg, gt)]
    if pfc is not None:
        code, Q = pfc
        grads = forward_diff(code, Q, xs)
        outs = [(target(i, j), e) for i, gr in enumerate(grads) for j, e in gr.items()]
        lines += em.defs(code.live([e for _, e in outs]), "pg")
        saved = em.pr.names
        em.pr.names = {**saved, **em.local}
        try:
            lines += [f"{_IND}{t} = {t} + {fast_print(sp.sympify(e), em.pr.names, em.pr)}"
                      for t, e in outs]
        finally:
            em.pr.names = saved
        temps = temps + list(em.local.values())
    return _proc("subroutine tree_user_jac(t, q, v, p, xt)",
                 [f"{_IND}real(dp), intent(in) :: t, q({n}), v({n}), p({npar})",
                  f"{_IND}real(dp), intent(inout) :: xt({2*n}, {n})",
                  f"{_IND}real(dp) :: gj({max(len(ex), 1)})"] + _decl_temps(temps),
                 lines, "tree_user_jac")
