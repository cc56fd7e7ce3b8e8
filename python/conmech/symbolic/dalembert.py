"""D'Alembert's route to the equations of motion: positions of particles (and planar
bodies) as functions of the generalized coordinates, applied forces of any kind, and the
projection of the dynamic equilibrium onto the admissible directions (the lecture notes):

    sum_k (m_k u_k'' - X_k) . du_k/dq_s + (I_k phi_k'' - tau_k) dphi_k/dq_s = 0,
    s = 1 .. n,

with u_k(q, t) the position of particle k (1, 2 or 3 components), X_k the applied force on
it (any expression in t, q, q' and the parameters: gravity, drag, a follower force), and
optionally phi_k(q, t) the angle of a planar rigid body k with central inertia I_k and
applied torque tau_k. Writing u_k'' = J_k q'' + c_k (J_k = du_k/dq, c_k the velocity and
time terms), this is M(t, q) q'' = Q(t, q, q') with

    M = sum_k m_k J_k^T J_k + I_k g_k g_k^T          (g_k = dphi_k/dq),
    Q = Q_applied - sum_k m_k J_k^T c_k - I_k g_k c_phi_k,
    Q_applied,s = sum_k X_k . du_k/dq_s + tau_k dphi_k/dq_s   (the generalized forces),

derived, compiled and run like :func:`conmech.symbolic.lagrangian_system` (exact Jacobian;
the reaction forces never appear). The number of implicit holonomic constraints is
R = (number of Cartesian coordinates) - n, and n = 3N - R is the number of degrees of
freedom (the notes' count): the mapping's Jacobian must have full rank n, else the
coordinates are not independent (a ValueError naming the dependent combination).

When the generalized forces depend on q only, the mapping on q only, and dQ_s/dq_r is
symmetric, the forces derive from a potential V (found by integration): the energy T + V is
the system's conserved energy and L = T - V its Lagrangian (for momenta and cyclic
coordinates); otherwise L = T and Q_applied act as non-conservative forces.
"""
import numpy as np
import sympy as sp

from .pipeline import _construct, _system
from .inputs import _ae, _Coords, _mechanical_inputs, _sympify_list, _unify_time
from .record import Derived
from .simplify import _cheap_simplify
from .momenta import LagrangianSystem, is_zero, to_user

__all__ = ["dalembert_system", "DAlembertSystem", "derive_dalembert"]


class DAlembertSystem(LagrangianSystem):
    """A compiled system derived by :func:`dalembert_system`: a :class:`LagrangianSystem`
    that also reports D'Alembert's quantities: ``generalized_forces`` (Q_s = sum X_k .
    du_k/dq_s + tau_k dphi_k/dq_s, sympy in the user's symbols), ``mass_matrix``,
    ``cartesian_dimension`` (sum of the particles' components), ``implicit_constraints``
    (R = cartesian_dimension - n), ``potential`` (V when the forces are conservative, else
    None)."""

    __slots__ = ()

    def _dal(self):
        return self._keep[0].derived

    @property
    def generalized_forces(self):
        d = self._dal()
        return [to_user(e, d) for e in d.dalembert["Q_applied"]]

    @property
    def mass_matrix(self):
        d = self._dal()
        return d.M.applyfunc(lambda e: to_user(e, d))

    @property
    def cartesian_dimension(self):
        return int(self._dal().dalembert["cartesian"])

    @property
    def implicit_constraints(self):
        return self.cartesian_dimension - self.ndof

    @property
    def potential(self):
        d = self._dal()
        v = d.dalembert["potential"]
        return None if v is None else to_user(v, d)


def _vectors(obj, what):
    """A list of vectors (lists of expressions) from a list of vectors or a D x N Matrix
    (one column per particle, the notes' mapping U)."""
    if obj is None:
        return None
    if isinstance(obj, sp.MatrixBase):
        return [list(obj[:, k]) for k in range(obj.shape[1])]
    out = []
    for k, u in enumerate(obj):
        if isinstance(u, sp.MatrixBase):
            u = list(u)
        elif not isinstance(u, (list, tuple)):
            u = [u]
        if not 1 <= len(u) <= 3:
            raise ValueError(f"{what}[{k}] must have 1, 2 or 3 components, got {len(u)}")
        out.append(list(u))
    return out


def derive_dalembert(mapping, masses, forces, q, params=None, angles=None, inertias=None,
                     torques=None, velocities=None, jacobian=True):
    """The :class:`~conmech.symbolic.derive.Derived` record of :func:`dalembert_system`."""
    t = sp.Symbol("t")
    c = _Coords(q, velocities, t, need_speeds=True)
    n = len(c.plain)
    U = _vectors(mapping, "mapping")
    if not U:
        raise ValueError("mapping: give the position of at least one particle")
    N = len(U)
    dims = [len(u) for u in U]
    m = _sympify_list(list(masses) if isinstance(masses, (list, tuple)) else [masses],
                      "masses")
    if len(m) != N:
        raise ValueError(f"masses has {len(m)} entries for {N} particles")
    X = _vectors(forces, "forces") if forces is not None else [[0]*dk for dk in dims]
    if len(X) != N or any(len(x) != dk for x, dk in zip(X, dims)):
        raise ValueError("forces must give one force vector per particle, with the "
                         "particle's number of components")
    nb = 0
    if angles is not None:
        phi = _sympify_list(list(angles), "angles")
        nb = len(phi)
        if nb > N:
            raise ValueError(f"angles has {nb} entries for {N} particles (body k's centre "
                             "of mass is particle k)")
        inert = _sympify_list(list(inertias), "inertias") if inertias is not None else None
        if inert is None or len(inert) != nb:
            raise ValueError("inertias must give one central moment of inertia per angle")
        tau = _sympify_list(list(torques), "torques") if torques is not None else \
            [sp.Integer(0)]*nb
        if len(tau) != nb:
            raise ValueError("torques must give one torque per angle")
    else:
        if inertias is not None or torques is not None:
            raise ValueError("inertias and torques need angles (the planar bodies' angles)")
        phi, inert, tau = [], [], []
    flat = [e for u in U for e in _sympify_list(u, "mapping")] + m + \
        [e for x in X for e in _sympify_list(x, "forces")] + phi + inert + tau
    flat = _unify_time(flat, t)
    flat, t, psyms, names, values = _mechanical_inputs(flat, c, params, t, "the expressions")
    q_, v_ = c.plain, c.speeds
    pos = 0
    Us = []
    for dk in dims:
        Us.append(sp.Matrix(flat[pos:pos + dk]))
        pos += dk
    ms = flat[pos:pos + N]
    pos += N
    Xs = []
    for dk in dims:
        Xs.append(sp.Matrix(flat[pos:pos + dk]))
        pos += dk
    phs = flat[pos:pos + nb]
    Is = flat[pos + nb:pos + 2*nb]
    taus = flat[pos + 2*nb:pos + 3*nb]
    for k, u in enumerate(Us):
        if u.free_symbols & set(v_):
            raise ValueError(f"mapping[{k}] depends on the velocities: positions are "
                             "functions of q and t")
    for k, ph in enumerate(phs):
        if ph.free_symbols & set(v_):
            raise ValueError(f"angles[{k}] depends on the velocities")
    pv = dict(zip(psyms, values))
    for k, mk in enumerate(ms):
        if mk.free_symbols - set(psyms):
            raise ValueError(f"masses[{k}] must depend on parameters only, got {mk}")
        if not float(mk.xreplace(pv)) > 0:
            raise ValueError(f"masses[{k}] must be positive, got {float(mk.xreplace(pv))}")
    for k, ik in enumerate(Is):
        if ik.free_symbols - set(psyms) or not float(ik.xreplace(pv)) >= 0:
            raise ValueError(f"inertias[{k}] must be a non-negative constant (parameters only)")
    vv = sp.Matrix(v_)
    J = [u.jacobian(q_) for u in Us]
    G = [sp.Matrix([ph]).jacobian(q_) for ph in phs]           # 1 x n
    _check_rank(J, G, ms, Is, q_, psyms, values, t, c.names)
    W = [Jk*vv + sp.diff(u, t) for Jk, u in zip(J, Us)]          # velocities of the points
    C = [w.jacobian(q_)*vv + sp.diff(w, t) for w in W]           # u'' - J q''
    Wp = [(g*vv)[0, 0] + sp.diff(ph, t) for g, ph in zip(G, phs)]
    Cp = [(sp.Matrix([wp]).jacobian(q_)*vv)[0, 0] + sp.diff(wp, t) for wp in Wp]
    M = sp.zeros(n, n)
    Qa = sp.zeros(n, 1)
    Qi = sp.zeros(n, 1)
    for k in range(N):
        M += ms[k]*J[k].T*J[k]
        Qa += J[k].T*Xs[k]
        Qi -= ms[k]*J[k].T*C[k]
    for k in range(nb):
        M += Is[k]*G[k].T*G[k]
        Qa += taus[k]*G[k].T
        Qi -= Is[k]*Cp[k]*G[k].T
    fixed = set(psyms)

    def tidy(e):
        return _cheap_simplify(e, fixed) if sp.count_ops(e) <= 600 else sp.expand(e)
    M = M.applyfunc(tidy)
    Qa = Qa.applyfunc(tidy)
    Qi = Qi.applyfunc(tidy)
    if M.free_symbols & set(v_):
        raise ValueError("the mass matrix depends on the velocities")
    T = sp.expand(sum((ms[k]*(W[k].T*W[k])[0, 0] for k in range(N)), sp.Integer(0))/2
                  + sum((Is[k]*Wp[k]**2 for k in range(nb)), sp.Integer(0))/2)
    T = tidy(T)
    V = _potential(Qa, q_, v_, t, Us, phs)
    if V is not None:
        L, gen = T - V, [sp.Integer(0)]*n
        energy = sp.expand((vv.T*M*vv)[0, 0]/2) + V
    else:
        L, gen, energy = T, list(Qa), None
    Q = Qa + Qi
    d = Derived("generalized", t=t, coords=q_, coord_names=c.names, speeds=v_,
                accels=c.accels, params=psyms, param_names=names, param_values=values,
                M=M, energy=energy, lagrangian=L, struct=None, gen_forces=gen,
                with_jacobian=bool(jacobian))
    d.Q = Q
    if jacobian:
        Ma = M*sp.Matrix(c.accels)
        d.R = _ae((Q - Ma).jacobian(q_).row_join(Q.jacobian(v_)))
    d.dalembert = {"Q_applied": list(Qa), "cartesian": sum(dims), "potential": V,
                   "particles": N, "bodies": nb}
    return d


def _check_rank(J, G, ms, Is, q, params, values, t, names):
    """ValueError when the stacked Jacobian [J_k; g_k] of the mapping has rank < n at
    every sampled configuration (the coordinates are not independent)."""
    n = len(q)
    rows = [Jk for Jk in J] + [g for g in G]
    if not rows:
        return
    A = sp.Matrix.vstack(*rows)
    f = sp.lambdify([t] + list(q) + list(params), A, modules="numpy")
    rng = np.random.default_rng(7)
    worst = None
    for trial in range(3):
        vals = [rng.uniform(0.3, 1.3)] + list(rng.uniform(-1.0, 1.0, n)) + list(values)
        try:
            with np.errstate(all="ignore"):
                Am = np.asarray(f(*vals), dtype=float)
        except (ValueError, ZeroDivisionError, TypeError):
            return
        if not np.all(np.isfinite(Am)):
            return
        u, s, vt = np.linalg.svd(Am)
        rank = int(np.sum(s > 1e-10*max(s[0], 1e-300))) if s.size else 0
        if rank == n:
            return
        worst = (rank, vt[-1])
    rank, null = worst
    comb = " + ".join(f"{c:.3g} {nm}" for c, nm in zip(null, names) if abs(c) > 1e-6)
    raise ValueError(f"mapping: its Jacobian du/dq has rank {rank} < {n} (the number of "
                     f"coordinates) at every sampled configuration: the coordinates are not "
                     f"independent (the positions do not change along {comb})")


def _potential(Qa, q, v, t, Us, phs):
    """V with Q_applied = -dV/dq when the forces are conservative (Q depends on q only,
    the mapping on q only, dQ_s/dq_r symmetric and the integration succeeds), else None."""
    n = len(q)
    bad = set(v) | {t}
    if any(e.free_symbols & bad for e in Qa) or any(u.free_symbols & {t} for u in Us) or \
            any(ph.free_symbols & {t} for ph in phs):
        return None
    for i in range(n):
        for j in range(i + 1, n):
            if not is_zero(sp.diff(Qa[i], q[j]) - sp.diff(Qa[j], q[i])):
                return None
    V = sp.Integer(0)
    for j, qj in enumerate(q):
        rest = sp.expand(-Qa[j] - sp.diff(V, qj))
        if rest == 0:
            continue
        Vj = sp.integrate(rest, qj)
        if Vj.has(sp.Integral):
            return None
        V = V + Vj
    if not all(is_zero(sp.diff(V, qj) + Qa[j]) for j, qj in enumerate(q)):
        return None
    return V


def dalembert_system(mapping, masses, forces=None, q=None, params=None, *, angles=None,
                     inertias=None, torques=None, velocities=None, jacobian=True,
                     flags=None, model_only=False):
    """A compiled system in generalized coordinates from D'Alembert's principle (see the
    module notes).

    Parameters
    ----------
    mapping : list or Matrix
        The particles' positions u_k(q, t): a list of vectors (1 to 3 components each) or a
        D x N Matrix with one column per particle (the notes' mapping U).
    masses : list
        One mass per particle (expressions of the parameters).
    forces : list or Matrix, optional
        The applied forces X_k (same shapes as mapping; any expressions in t, q, q' and
        the parameters).
    q : list
        The generalized coordinates (dynamicsymbols, or Symbols with ``velocities=``).
    params : dict
        {Symbol or name: value}.
    angles, inertias, torques : list, optional
        Planar rigid bodies: the angle phi_k(q, t) of body k (whose centre of mass is
        particle k), its central moment of inertia, the applied torque.

    Returns
    -------
    DAlembertSystem
        With ``generalized_forces``, ``mass_matrix``, ``implicit_constraints``,
        ``degrees_of_freedom``; it runs wherever a system runs.
    """
    if q is None:
        raise ValueError("q: give the generalized coordinates")
    inputs = [_flatten(x) for x in (
        mapping if not isinstance(mapping, sp.MatrixBase) else mapping.T.tolist(),
        list(masses) if isinstance(masses, (list, tuple)) else [masses],
        forces if not isinstance(forces, sp.MatrixBase) else forces.T.tolist(),
        q, angles, inertias, torques, velocities)]
    model = _construct("dalembert", inputs, params, (bool(jacobian),),
                       lambda: derive_dalembert(mapping, masses, forces, q, params, angles,
                                                inertias, torques, velocities, jacobian),
                       flags, True)
    if model_only:
        return model
    s = _system(model)
    return DAlembertSystem(s.name, s.kind, s.spec, s.params, s.param_names, s._keep)


def _flatten(x):
    """A sympy Tuple of the nested lists (for the derivation cache's key)."""
    if x is None:
        return None
    if isinstance(x, sp.MatrixBase):
        return _flatten(x.tolist())
    if isinstance(x, (list, tuple, sp.Tuple)):
        return sp.Tuple(*[_flatten(e) if isinstance(e, (list, tuple, sp.Tuple)) else
                          sp.sympify(e) for e in x])
    return sp.sympify(x)
