"""Recursive rigid-body dynamics of kinematic trees, generated as straight-line Fortran.

The mass matrix, the forces, the exact Jacobian of the accelerations and (with closed
loops, see :mod:`conmech.symbolic.loops`) the loop constraints of a tree made by
:func:`conmech.symbolic.planar_tree` or :func:`conmech.symbolic.spatial_tree` come from the
recursive algorithms of rigid-body dynamics evaluated on the bodies' data, not from an
expanded Lagrangian: the construction cost grows like the number of bodies, not like the
size of the expanded kinetic energy.

Everything is in the ground ("world") frame, with Featherstone's 6-D spatial vectors
(motion [omega; v_O], force [n_O; f], v_O the velocity of the body point at the origin):
joint k of body k has the world motion subspace S_k (revolute: [k_w; p_k x k_w], prismatic:
[0; k_w]), depending on the coordinates of the ancestors only.

- Position pass (straight-line, ``tree_pos``): poses, S_k, the spatial inertia of each body
  about the origin (compact: m, h = m c, I_O), the composite inertias Ic_k (subtree sums),
  alpha_k = Ic_k S_k. The composite-rigid-body algorithm gives M_jk = S_j . alpha_k for j an
  ancestor of k (or k itself), zero otherwise (a loop over the ancestor pairs).
- Velocity pass (straight-line, ``tree_vel``): v_k = v_parent + S_k qd_k, psi_k = v_parent x
  S_k (= dS_k/dt), a_k = a_parent + S_k qdd_k + psi_k qd_k (a_0 = -gravity), momenta
  h_k = I_k v_k, forces f_k = I_k a_k + v_k x* h_k, subtree sums F_k and the joint forces of
  inverse dynamics tau_k = S_k . F_k (the recursive Newton-Euler algorithm); Q = tau_user -
  tau(q, v, 0).
- Derivatives of inverse dynamics (the idea of Carpentier and Mansard, RSS 2018: world-frame
  quantities and subtree sums; the formulas below are derived for this code): with
  D_k = sum over the subtree of dI/dt = v x* I - I v x (symmetric, compact), H_k (subtree
  momentum), c_j = -(S_j x a_j + psi_j x v_j), eta_k = D_k S_k - S_k x* H_k,
  Phi_j = S_j x* F_j + Ic_j c_j + D_j psi_j + psi_j x* H_j and
  Omega_j = 2 Ic_j psi_j + D_j S_j + S_j x* H_j::

      d tau_k / d q_j  = alpha_k . c_j + eta_k . psi_j      (j an ancestor of k, or k)
                       = S_k . Phi_j                        (k a strict ancestor of j)
      d tau_k / d qd_j = 2 alpha_k . psi_j + eta_k . S_j    (j an ancestor of k, or k)
                       = S_k . Omega_j                      (k a strict ancestor of j)

  O(n) vectors, then one pair of dot products per ancestor pair.
- The Jacobian of the accelerations d a / d[q, v] = M^-1 R (R = [dQ/dq - d(M a)/dq, dQ/dv])
  solves with the tree-sparse factorisation M = L^T D L (Featherstone's LTDL, branch-induced
  sparsity), no LAPACK; a non-positive pivot gives non-finite output.
- The accelerations themselves are the articulated-body algorithm of tree.py / spatial.py.

Planar trees are spatial trees in the plane z = 0 (revolute joints about z); the structural
zeros fold out of the straight-line code (constants are folded at generation), and the loops
run over the spatial components that are not zero for every body (3 in the plane). Absolute
angles (``coordinates="absolute"``) are relative ones through q_rel = T q (T = 1 - P, P
picking each revolute joint's nearest revolute ancestor): M = T^T M_rel T, Q = tau_user -
T^T tau_rel, R = dtau_user - T^T dID diag(T, T), d a/d[q, v] = T^-1 M_rel^-1 T^-T R.

The generated module holds the straight-line passes as module procedures filling a work
record, the loops as small fixed procedures, and thin bind(C) entry points (``mass``,
``forces``, ``mass_forces``, ``forces_jac``, ``accel``, ``accel_jac``, ``energy``; with loops
the constrained entries). Generated identifiers come from indices only (body names stay
data).
"""
import hashlib
import os

import sympy as sp

from sympy.physics.mechanics import dynamicsymbols

from .inputs import _Coords, _mechanical_inputs, _unify_time
from .kinematics import Code, joints_planar, joints_spatial  # noqa: F401
from .loops import count_rows, prepare_loops, prepare_point_forces
from .record import Derived
from .spatial import SpatialBody, build_spatial_tree
from .tree import Body, build_tree
from .tree_fortran import generate_tree

__all__ = ["TreeDerived", "derive_recursive", "Code"]


class TreeDerived(Derived):
    """The derived record of a tree built by the recursive algorithms: the canonical
    symbols (``coords``, ``speeds``, ``params``, ...), the normalised joints, the user's
    generalized forces, gravity, the loops (:mod:`conmech.symbolic.loops`) and the
    options; :meth:`generate_fortran` writes the module (called by
    :func:`conmech.symbolic.codegen.generate`). It has no expanded M, Q or R: the
    Lagrangian route (``method="lagrangian"``, or ``derive_tree`` /
    ``derive_spatial_tree``) gives those."""

    def generate_fortran(self, module, model_values=None):
        return generate_tree(self, module, model_values)

    @property
    def lagrangian(self):
        """L = T - U in the canonical symbols, built from the bodies' data when first read
        (for the analysis of momenta and cyclic coordinates; the compiled code never needs
        it); None for a tree with forces at points of bodies (their generalized forces are
        not kept as expressions)."""
        if "_lagrangian" not in self.__dict__:
            self._energies()
        return self.__dict__["_lagrangian"]

    @property
    def energy(self):
        """T + U in the canonical symbols (the Jacobi integral of the tree, which is
        scleronomic), built like :attr:`lagrangian` when first read."""
        if self.__dict__.get("_energy") is None:
            self._energies()
        return self.__dict__["_energy"]

    @energy.setter
    def energy(self, value):
        self.__dict__["_energy"] = value

    def _energies(self):
        T, U = _tree_energies(self)
        self.__dict__["_energy"] = T + U
        self.__dict__["_lagrangian"] = None if self.point_forces else T - U


def _tree_energies(d):
    """(T, U) of the tree of a TreeDerived record: its canonical data rebuilt as bodies
    whose coordinates are functions of time, their energies, then the coordinates and their
    rates replaced by the canonical symbols."""
    tt = dynamicsymbols._t
    qf = [sp.Function(f"cq{i}")(tt) for i in range(d.n)]
    index = {name: J.col for name, J in zip(d.order_names, d.joints)}
    bodies = []
    for b in d.aba_order:
        c, q = d.cdata[b.name], qf[index[b.name]]
        if d.planar:
            bodies.append(Body(b.name, b.parent, b.joint, q, at=c[0], axis=c[1], mass=c[2],
                               com=c[3], inertia=c[4]))
        else:
            bodies.append(SpatialBody(b.name, b.parent, b.joint, q, axis=list(c[2]),
                                      at=list(c[0]), rot=c[1], mass=c[3], com=list(c[4]),
                                      inertia=c[5]))
    if d.planar:
        parts = build_tree(bodies, d.gravity[:2], None,
                           "absolute" if d.absolute else "relative", lazy=True)
    else:
        parts = build_spatial_tree(bodies, d.gravity, None, lazy=True)
    rates = {f.diff(tt): v for f, v in zip(qf, d.speeds)}
    values = dict(zip(qf, d.coords))
    return tuple(sp.sympify(e).xreplace(rates).xreplace(values).xreplace({tt: d.t})
                 for e in parts["energies"]())


def derive_recursive(parts, params, planar, absolute=False, loops=(), jacobian=True,
                     point_forces=()):
    """The :class:`TreeDerived` record of a planar or spatial tree (parts from
    tree.build_tree / spatial.build_spatial_tree), with the loop closures `loops`
    (:class:`conmech.symbolic.loops.Loop`) and the point forces `point_forces`
    (:class:`conmech.symbolic.loops.PointForce`). Resolves every symbol to the canonical
    real symbols (an unknown symbol or a parameter without a value: ValueError naming it)."""
    t = sp.Symbol("t")
    order, data = parts["order"], parts["data"]
    coords = parts["q"]
    c = _Coords(coords, None, t, need_speeds=True)
    # every expression of the description, flattened (then put back by position)
    flat = []

    def put(e):
        flat.append(sp.sympify(e))
        return len(flat) - 1
    if planar:
        slots = {b.name: (put(data[b.name][0][0]), put(data[b.name][0][1]),
                          put(data[b.name][1][0]), put(data[b.name][1][1]),
                          put(data[b.name][2]), put(data[b.name][3][0]),
                          put(data[b.name][3][1]), put(data[b.name][4])) for b in order}
    else:
        slots = {}
        for b in order:
            at, rot, axis, m, com, Ic = data[b.name]
            slots[b.name] = ([put(x) for x in at], [put(x) for x in rot],
                             [put(x) for x in axis], put(m), [put(x) for x in com],
                             [put(x) for x in Ic])
    g_slots = [put(x) for x in parts["gravity"]]
    f_slots = [put(x) for x in parts["forces"]]
    loop_items = prepare_loops(loops, order, planar)
    l_slots = [[put(x) for x in item["exprs"]] for item in loop_items]
    pf_items = prepare_point_forces(point_forces, order, planar)
    pf_slots = [[put(x) for x in item["exprs"]] for item in pf_items]
    exprs = _unify_time(flat, t)
    exprs, t, psyms, names, values = _mechanical_inputs(exprs, c, params, t,
                                                        "the tree's description")
    geometry = set(range(len(flat))) - set(f_slots) - {i for s in pf_slots for i in s}
    qv = set(c.plain) | set(c.speeds) | {t}
    for i in geometry:
        if exprs[i].free_symbols & qv:
            raise ValueError(f"the geometry, masses, inertias, gravity and loop points must "
                             f"depend on parameters only, got {exprs[i]}")
    ex = exprs.__getitem__
    user_index = {b.name: coords.index(b.q) for b in order}
    if planar:
        cdata = {}
        for b in order:
            s = slots[b.name]
            cdata[b.name] = ((ex(s[0]), ex(s[1])), (ex(s[2]), ex(s[3])), ex(s[4]),
                             (ex(s[5]), ex(s[6])), ex(s[7]))
        joints = joints_planar(order, user_index, cdata, absolute, lambda e: e)
    else:
        cdata = {}
        for b in order:
            s = slots[b.name]
            cdata[b.name] = (sp.Matrix([ex(i) for i in s[0]]),
                             sp.Matrix(3, 3, [ex(i) for i in s[1]]),
                             sp.Matrix([ex(i) for i in s[2]]), ex(s[3]),
                             sp.Matrix([ex(i) for i in s[4]]),
                             sp.Matrix(3, 3, [ex(i) for i in s[5]]))
        joints = joints_spatial(order, user_index, cdata, lambda e: e)
    gravity = [ex(i) for i in g_slots]
    if planar:
        gravity = gravity + [0]
    forces = [ex(i) for i in f_slots]
    for item, sl in zip(loop_items, l_slots):
        item["exprs"] = [ex(i) for i in sl]
    for item, sl in zip(pf_items, pf_slots):
        item["exprs"] = [ex(i) for i in sl]
    d = TreeDerived("constrained" if loop_items else "generalized", t=t, coords=c.plain,
                    coord_names=c.names, speeds=c.speeds, accels=c.accels, params=psyms,
                    param_names=names, param_values=values, with_jacobian=bool(jacobian))
    d.joints = joints
    d.gravity = gravity
    d.user_forces = forces
    d.gen_forces = None if pf_items else list(forces)
    d.loops = loop_items
    d.point_forces = pf_items
    d.planar = bool(planar)
    d.absolute = bool(absolute)
    d.cdata = cdata
    d.order_names = [b.name for b in order]
    d.aba_order = list(order)
    d.energy = None         # T + U, built when first read
    if loop_items:
        d.n_hol = count_rows(loop_items)
        d.rheonomic = False
    return d

