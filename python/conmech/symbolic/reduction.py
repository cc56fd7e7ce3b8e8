"""Routh reduction: the dynamics in the remaining coordinates for given values of the
momenta conjugate to cyclic coordinates, and the reconstruction of the cyclic coordinates.

With L = v^T M v / 2 + l1 . v + L0 (M, l1, L0 independent of the cyclic coordinates q_c),
the momenta p_c = M_cc v_c + M_cr v_r + l1_c are constant, = mu; solving for the cyclic
velocities,

    v_c = M_cc^-1 (b - M_cr v_r),     b = mu - l1_c,

and Routh's function R = L - mu . v_c is a Lagrangian for the remaining coordinates q_r:

    R = v_r^T M_red v_r / 2 + (l1_r + M_rc M_cc^-1 b) . v_r - U_amended,
    M_red = M_rr - M_rc M_cc^-1 M_cr,   U_amended = -L0 + b^T M_cc^-1 b / 2,

whose energy E_red = v_r^T M_red v_r / 2 + U_amended is conserved (the lecture notes' cart,
M = m = l = 1, mu = 0: M_red = 1 - cos^2(theta)/2, E_red = (1 - cos^2/2) theta'^2/2 +
g cos theta). The reduced system is compiled like any :func:`lagrangian_system` (the momenta
are run-time parameters p_<name>: ``with_params(p_x=0.3)`` needs no rebuild) and runs
wherever a system runs. The cyclic coordinates follow by quadrature,
q_c(t) = q_c(0) + integral of v_c, on the reduced solution's dense output
(:meth:`ReducedSystem.reconstruct`); when v_c = a0 + sum a_j(q_r) v_r_j with a0 constant
and the form a_j dq_j exact (a_j = dF/dq_j), the closed form q_c = q_c(0) + a0 t +
F(q_r(t)) - F(q_r(0)) is given too (the notes' x(t) = -1/2 sin theta + C0 + C1 t).
"""
import numpy as np
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from .._core.result import Record
from .constructors import lagrangian_system
from .simplify import _quadratic_parts
from .momenta import LagrangianSystem, _build, analysis, is_zero, to_user
from .quadrature import cumulative_dense

__all__ = ["reduce", "ReducedSystem", "Reduction"]


class Reduction(Record):
    """What :func:`reduce` derived. Attributes (sympy expressions in the user's
    dynamicsymbols and parameter names): ``cyclic`` (names), ``momentum_names``
    (the run-time parameters p_<name>), ``remaining`` (names of the reduced coordinates),
    ``routhian``, ``reduced_mass`` (Matrix M_red), ``gyroscopic`` (the coefficients of
    v_r in R), ``amended_potential``, ``energy`` (E_red), ``cyclic_velocity``
    (v_c in the reduced coordinates), ``closed_form`` ({name: q_c(t) - q_c(0)} in t and
    q_r(t), q_r(0) written with a suffix 0; None where no closed form was found),
    ``singular`` (det M_cc, whose zeros make the amended potential singular when a
    momentum is not zero)."""

    __slots__ = ("cyclic", "momentum_names", "remaining", "routhian", "reduced_mass",
                 "gyroscopic", "amended_potential", "energy", "cyclic_velocity", "closed_form",
                 "singular")

    def __repr__(self):
        return (f"Reduction(cyclic={self.cyclic}, remaining={self.remaining}, "
                f"routhian={self.routhian})")


class ReducedSystem(LagrangianSystem):
    """The Routh-reduced system (a :class:`LagrangianSystem` in the remaining coordinates,
    state [q_r, q_r']) with its :class:`Reduction` (``reduction``) and the reconstruction
    of the cyclic coordinates (:meth:`reconstruct`, :meth:`cyclic_velocity`)."""

    __slots__ = ("_reduction",)

    def with_params(self, **kw):
        """A copy with new parameter or momentum values (no rebuild)."""
        out = LagrangianSystem.with_params(self, **kw)
        out._reduction = self._reduction
        return out

    @property
    def reduction(self):
        return self._reduction[0]

    @property
    def momenta_values(self):
        """{cyclic coordinate name: its momentum value} (from the run-time parameters)."""
        r = self.reduction
        vals = dict(zip(self.param_names, self.params.tolist()))
        return {c: vals[pn] for c, pn in zip(r.cyclic, r.momentum_names)}

    def cyclic_velocity(self, y, t=0.0):
        """v_c at reduced states y = [q_r, q_r'] (2m,) or (2m, k): compiled."""
        self._check_singular(y)
        return self._reduction[1]()("cyclic_velocity", t, y, self.params)

    def reduced_energy(self, y, t=0.0):
        """E_red at reduced states (compiled; the reduced system's own energy)."""
        self._check_singular(y)
        return self._reduction[1]()("reduced_energy", t, y, self.params)

    def reconstruct(self, sol, q0, t=None):
        """The cyclic coordinates along a reduced solution: q_c(t) = q0 + integral of v_c
        (Gauss-Legendre on each step of the dense output; sol from solve_ivp(...,
        dense_output=True)). q0: their values at sol.t[0] (a number or one per cyclic
        coordinate); t: output times (default sol.t). Returns (k, len(t)) (k = 1: 1-D)."""
        r = self.reduction
        k = len(r.cyclic)
        q0 = np.broadcast_to(np.asarray(q0, dtype=float).ravel(), (k,)) \
            if np.ndim(q0) == 0 or np.size(q0) == 1 else np.asarray(q0, dtype=float).ravel()
        if q0.size != k or not np.all(np.isfinite(q0)):
            raise ValueError(f"q0 must be {k} finite value(s), one per cyclic coordinate "
                             f"({', '.join(r.cyclic)})")
        t = np.asarray(sol.t if t is None else t, dtype=float)
        lib = self._reduction[1]()

        def g(tt, yy):
            self._check_singular(yy)
            return np.asarray(lib("cyclic_velocity", tt, yy, self.params)).reshape(k, -1)
        integral = np.atleast_2d(cumulative_dense(g, sol, t))
        out = q0[:, None] + integral
        return out[0] if k == 1 else out

    def _check_singular(self, y):
        """ValueError naming the momentum when it is nonzero where det M_cc vanishes (the
        amended potential b^T M_cc^-1 b / 2 is singular there)."""
        det = self._reduction[2]
        mv = self.momenta_values
        if det is None or all(v == 0.0 for v in mv.values()):
            return
        y = np.asarray(y, dtype=float)
        m = y.shape[0]//2
        with np.errstate(all="ignore"):
            dv = np.atleast_1d(det(*np.atleast_2d(y.T).T[:m], *self.params))
        if np.any(~np.isfinite(dv) | (np.abs(dv) <= 1e-14)):
            nz = [f"{c} = {v:g}" for c, v in mv.items() if v != 0.0]
            raise ValueError(f"momenta: {', '.join(nz)} /= 0 makes the reduced energy "
                             f"singular where det M_cc = {self.reduction.singular} = 0, "
                             "reached at this state")


def _resolve(items, names, what):
    """Indices of coordinates given as indices, names or dynamicsymbols."""
    out = []
    for c in items:
        if isinstance(c, (bool, np.bool_)):
            raise TypeError(f"{what}: {c!r} is not a coordinate")
        if isinstance(c, (int, np.integer)):
            i = int(c)
            if not 0 <= i < len(names):
                raise ValueError(f"{what}: index {i} out of range (coordinates "
                                 f"{', '.join(names)})")
        else:
            name = c if isinstance(c, str) else (str(c.func) if hasattr(c, "func") and
                                                 isinstance(c, sp.Function) else str(c))
            if name not in names:
                raise ValueError(f"{what}: {c!r} is not a coordinate of the system "
                                 f"({', '.join(names)})")
            i = names.index(name)
        out.append(i)
    return out


def reduce(system, cyclic=None, momenta=None, *, flags=None):
    """Routh reduction of a symbolic Lagrangian system (see the module notes).

    Parameters
    ----------
    system : LagrangianSystem
        A system from :func:`conmech.symbolic.lagrangian_system` (or a tree).
    cyclic : list, optional
        The cyclic coordinates to eliminate (indices, names or dynamicsymbols; default: all
        of ``system.cyclic_coordinates``). A coordinate that is not cyclic (L depends on
        it, or a non-conservative force acts on it) is a ValueError naming it.
    momenta : dict, optional
        {coordinate: value} of the conserved momenta (default 0 for each); the values are
        run-time parameters ``p_<name>`` of the reduced system.

    Returns
    -------
    ReducedSystem
        State [q_r, q_r'], with ``reduction`` (:class:`Reduction`: Routhian, reduced mass,
        amended potential, reduced energy, cyclic velocity and its closed-form integral)
        and :meth:`~ReducedSystem.reconstruct`. A singular d p_c / d v_c (M_cc identically
        singular: the cyclic velocity cannot be solved for) and a non-finite momentum are
        ValueErrors naming them; a nonzero momentum where det M_cc vanishes is reported
        when a state there is evaluated.
    """
    a = analysis(system)
    d = a.d
    names = list(d.coord_names)
    n = d.n
    if cyclic is None:
        cyc = list(a.cyclic)
        if not cyc:
            raise ValueError("cyclic: the system has no cyclic coordinate (L depends on "
                             "every coordinate, or forces act on them)")
    else:
        if isinstance(cyclic, (str, int, np.integer)) or isinstance(cyclic, sp.Basic):
            cyclic = [cyclic]
        cyc = _resolve(list(cyclic), names, "cyclic")
    if not cyc or len(set(cyc)) != len(cyc):
        raise ValueError("cyclic: give each cyclic coordinate once")
    for i in cyc:
        if i not in a.ignorable:
            raise ValueError(f"cyclic: '{names[i]}' is not a cyclic coordinate: the "
                             f"Lagrangian depends on it (dL/d{names[i]} = "
                             f"{to_user(a.dLdq[i], d)})")
        if i not in a.cyclic:
            raise ValueError(f"cyclic: '{names[i]}' is not a cyclic coordinate: the "
                             f"non-conservative force {to_user(a.nonconservative[i], d)} "
                             "acts on it (its momentum is not conserved)")
    if len(cyc) == n:
        raise ValueError("cyclic: every coordinate is cyclic; nothing would remain")
    mu_vals = {i: 0.0 for i in cyc}
    if momenta is not None:
        if not isinstance(momenta, dict):
            raise TypeError("momenta must be a dict {cyclic coordinate: value}")
        for key, val in momenta.items():
            (i,) = _resolve([key], names, "momenta")
            if i not in cyc:
                raise ValueError(f"momenta: '{names[i]}' is not among the cyclic "
                                 "coordinates being eliminated")
            if isinstance(val, (bool, np.bool_)):
                raise TypeError(f"momenta['{names[i]}'] must be a real number")
            try:
                v = float(val)
            except (TypeError, ValueError):
                raise TypeError(f"momenta['{names[i]}'] must be a real number, got "
                                f"{val!r}") from None
            if not np.isfinite(v):
                raise ValueError(f"momenta['{names[i]}'] = {v} is not finite: the reduced "
                                 "energy would be singular")
            mu_vals[i] = v
    rem = [i for i in range(n) if i not in cyc]
    q, v = list(d.coords), list(d.speeds)
    parts = _quadratic_parts(a.L, v)
    if parts is None:
        raise ValueError("the Lagrangian is not quadratic in the velocities: Routh "
                         "reduction needs p_c linear in v_c")
    H, l1, L0 = parts
    H = sp.Matrix(H)
    Mcc = H.extract(cyc, cyc)
    Mcr = H.extract(cyc, rem)
    Mrr = H.extract(rem, rem)
    det = sp.factor(sp.cancel(Mcc.det()))
    if is_zero(det):
        bad = ", ".join(f"'{names[i]}'" for i in cyc)
        raise ValueError(f"cyclic: the momenta of {bad} do not depend on their velocities "
                         "(d p_c / d v_c = M_cc is singular): the cyclic velocities cannot "
                         "be solved for")
    pnames = [f"p_{names[i]}" for i in cyc]
    taken = set(d.param_names) | set(names)
    for pn in pnames:
        if pn in taken:
            raise ValueError(f"momenta: the parameter name '{pn}' of the momentum is taken "
                             "by a parameter or coordinate of the system")
    mus = [sp.Dummy(pn, real=True) for pn in pnames]
    A = Mcc.inv() if len(cyc) > 1 else sp.Matrix([[1/Mcc[0, 0]]])
    b = sp.Matrix(mus) - sp.Matrix([l1[i] for i in cyc])
    vr = sp.Matrix([v[i] for i in rem])
    Mred = (Mrr - Mcr.T*A*Mcr).applyfunc(lambda e: sp.factor(sp.cancel(e)))
    gyro = (sp.Matrix([l1[i] for i in rem]) + Mcr.T*A*b).applyfunc(sp.cancel)
    Uam = sp.cancel(-L0 + (b.T*A*b)[0, 0]/2)
    R = (vr.T*Mred*vr)[0, 0]/2 + (gyro.T*vr)[0, 0] - Uam
    vc = (A*(b - Mcr*vr)).applyfunc(sp.cancel)
    Ered = (vr.T*Mred*vr)[0, 0]/2 + Uam
    # non-conservative forces on the remaining coordinates, with v_c eliminated
    sub_vc = {v[i]: vc[k] for k, i in enumerate(cyc)}
    forces_r = []
    for i in rem:
        f = a.nonconservative[i]
        for j in cyc:
            if not is_zero(sp.diff(f, q[j])):
                raise ValueError(f"the non-conservative force on '{names[i]}' depends on "
                                 f"the cyclic coordinate '{names[j]}': no reduction")
        forces_r.append(f.xreplace(sub_vc))
    # the reduced system, in the user's terms (momenta as parameters)
    t = dynamicsymbols._t
    mu_syms = {m_: sp.Symbol(pn) for m_, pn in zip(mus, pnames)}

    def user(e):
        return to_user(e, d).xreplace(mu_syms)
    q_user = [sp.Function(names[i])(t) for i in rem]
    params = dict(zip(d.param_names, d.param_values))
    pvals = dict(zip(d.param_names, np.asarray(system.params, dtype=float).tolist()))
    params.update(pvals)
    params.update({pn: mu_vals[i] for pn, i in zip(pnames, cyc)})
    any_force = any(f != 0 for f in forces_r)
    red = lagrangian_system(user(R), q_user, params=params,
                            forces=[user(f) for f in forces_r] if any_force else None,
                            flags=flags)
    red_model = red._keep[0]
    rd = red_model.derived
    # v_c and E_red compiled as functions of the reduced state
    back = _from_user_map(rd)
    vc_red = sp.Matrix([user(e).xreplace(back) for e in vc])
    Ered_red = user(Ered).xreplace(back)
    cache = {}

    def lib():
        if "lib" not in cache:
            cache["lib"] = _build(rd, [("cyclic_velocity", vc_red, len(cyc))],
                                  scalars=[("reduced_energy", Ered_red)],
                                  module="conmech_symbolic_reconstruction")
        return cache["lib"]
    det_user = user(det)
    det_fun = None
    if not det.free_symbols.isdisjoint(set(q)):
        det_args = [sp.Function(names[i])(t) for i in rem]
        det_fun = sp.lambdify(det_args + [sp.Symbol(pn) for pn in rd.param_names],
                              det_user, modules="numpy")
    info = Reduction(cyclic=[names[i] for i in cyc], momentum_names=pnames,
                     remaining=[names[i] for i in rem], routhian=user(R),
                     reduced_mass=Mred.applyfunc(user), gyroscopic=[user(e) for e in gyro],
                     amended_potential=user(Uam), energy=user(Ered),
                     cyclic_velocity=[user(e) for e in vc],
                     closed_form=_closed_forms(vc, cyc, rem, q, v, d, user),
                     singular=det_user)
    out = ReducedSystem(red.name, red.kind, red.spec, red.params, red.param_names, red._keep)
    out._reduction = (info, lib, det_fun)
    return out


def _from_user_map(rd):
    """dynamicsymbols and parameter Symbols -> the plain symbols of a derived record."""
    t = dynamicsymbols._t
    m = {t: rd.t}
    for name, qs, vs in zip(rd.coord_names, rd.coords, rd.speeds):
        f = sp.Function(name)(t)
        m[f.diff(t)] = vs
        m[f] = qs
    for ps, name in zip(rd.params, rd.param_names):
        m[sp.Symbol(name)] = ps
    return m


def _closed_forms(vc, cyc, rem, q, v, d, user):
    """{cyclic name: q_c(t) - q_c(0)} when v_c = a0 + sum a_j v_j with a0 constant and the
    form sum a_j dq_j exact; None for a coordinate where that fails."""
    names = list(d.coord_names)
    qr = [q[i] for i in rem]
    vr = [v[i] for i in rem]
    t = dynamicsymbols._t
    out = {}
    for k, i in enumerate(cyc):
        e = sp.expand(vc[k])
        coeffs = [sp.cancel(sp.diff(e, vj)) for vj in vr]
        a0 = sp.cancel(e.xreplace({vj: 0 for vj in vr}))
        if any(c.free_symbols & set(vr) for c in coeffs) or (a0.free_symbols & set(qr)):
            out[names[i]] = None
            continue
        exact = all(is_zero(sp.diff(coeffs[j1], qr[j2]) - sp.diff(coeffs[j2], qr[j1]))
                    for j1 in range(len(qr)) for j2 in range(j1 + 1, len(qr)))
        if not exact:
            out[names[i]] = None
            continue
        F = sp.Integer(0)
        ok = True
        for j, qj in enumerate(qr):
            rest = sp.cancel(coeffs[j] - sp.diff(F, qj))
            if rest == 0:
                continue
            Fj = sp.integrate(rest, qj)
            if Fj.has(sp.Integral):
                ok = False
                break
            F = F + Fj
        if not ok or not all(is_zero(sp.diff(F, qj) - coeffs[j]) for j, qj in enumerate(qr)):
            out[names[i]] = None
            continue
        F0 = F.xreplace({qj: sp.Symbol(names[r] + "0") for qj, r in zip(qr, rem)})
        out[names[i]] = user(a0)*t + user(F) - to_user(F0, d)
    return out
