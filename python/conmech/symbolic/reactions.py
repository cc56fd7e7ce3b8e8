"""The reactions of a tree's loop-closure joints, per joint and in the joint's frame.

:func:`conmech.constrained.solve` returns the multipliers ``lam`` (one row per loop
equation, in the order of the loops) and their generalized forces; :func:`joint_reactions`
groups the rows per :class:`~conmech.symbolic.Loop` and turns them into the wrench the
joint exerts on its body a (on body b: the opposite), in body a's frame (the ground frame
when body a is the ground), from the meaning of each loop equation (its virtual work
lambda . d phi):

- a point joint (planar revolute, spherical, the point rows of a spatial revolute; phi =
  x_a - x_b): the force lambda on body a at its joint point, rotated into a's frame;
- a spatial revolute's two axis rows (phi_k = u_a . w_k, u_a the axis fixed in a, w_k
  fixed in b normal to b's axis): the moment sum_k lambda_k u_a x w_k on body a (normal to
  the joint axis: a revolute joint transmits no moment about its axis);
- a planar prismatic joint (phi_1 = (x_b - x_a) . n_a, phi_2 = theta_b - theta_a - angle):
  the normal force -lambda_1 n_a on body a, acting at the point of a under b's point, and
  the moment -lambda_2 on body a.

Body orientations come from the joints' placements and the coordinates of the result
(numerically, the same conventions as the generated code: a child's frame is its
parent's turned by the joint's fixed rotation, then by the joint angle about its axis).
"""
import numpy as np
import sympy as sp

from .._core.result import Record
from .kinematics import relative
from .pipeline import model_of

__all__ = ["JointReaction", "joint_reactions"]


class JointReaction(Record):
    """The reaction of one loop-closure joint along a result: ``label``, ``kind`` (the
    joint), ``body_a``, ``body_b`` (names; None: the ground), ``force`` (2 or 3 components
    x nt, on body a, in body a's frame), ``moment`` (on body a, body a's frame: 3 x nt for
    a spatial revolute joint, 1 x nt (about z) for a planar prismatic one, None for joints
    that transmit none), ``rows`` (the slice of the result's ``lam`` it groups)."""

    __slots__ = ("label", "kind", "body_a", "body_b", "force", "moment", "rows")

    def __repr__(self):
        return (f"JointReaction({self.label!r}, {self.kind}, force {self.force.shape}"
                f"{'' if self.moment is None else f', moment {self.moment.shape}'})")


def _rodrigues(u, angle):
    u = np.asarray(u, float)
    u = u/np.linalg.norm(u)
    K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    return np.eye(3) + np.sin(angle)*K + (1 - np.cos(angle))*K @ K


def joint_reactions(system, result):
    """{loop label: :class:`JointReaction`} for a tree with loops (``planar_tree`` /
    ``spatial_tree`` with ``loops=``) and a result of :func:`conmech.constrained.solve`
    on it (its ``q`` and ``lam``)."""
    d = model_of(system).derived
    if d.kind != "constrained" or not getattr(d, "loops", None):
        raise ValueError("system: joint_reactions needs a tree with closed loops (loops=...)")
    q = np.asarray(getattr(result, "q", None), float)
    lam = np.asarray(getattr(result, "lam", None), float)
    if q.ndim != 2 or q.shape[0] != d.n:
        raise ValueError(f"result: its q must have {d.n} rows (a result of "
                         "constrained.solve on this system)")
    rows = sum(item["rows"] for item in d.loops)
    if lam.shape != (rows, q.shape[1]):
        raise ValueError(f"result: its lam must be {rows} x {q.shape[1]}")
    p = np.asarray(getattr(system, "params", d.param_values), float)
    values = dict(zip(d.params, p))

    def num(e):
        return float(sp.sympify(e).xreplace(values))
    joints = d.joints
    jd = [(J.parent, J.kind, np.array([num(x) for x in J.at]),
           np.array([[num(x) for x in row] for row in J.rot]),
           np.array([num(x) for x in J.axis])) for J in joints]
    loops = []
    for item in d.loops:
        e = [num(x) for x in item["exprs"]]
        loops.append((item, e))
    nt = q.shape[1]
    names = list(d.order_names)
    out = {}
    k0 = 0
    for item, e in loops:
        m = item["rows"]
        dim = 2 if d.planar else 3
        kind = item["kind"]
        force = np.zeros((dim, nt))
        moment = None
        if d.planar and kind == "prismatic":
            moment = np.zeros((1, nt))
        elif not d.planar and kind == "revolute":
            moment = np.zeros((3, nt))
        out[item["label"]] = JointReaction(
            label=item["label"], kind=kind,
            body_a=names[item["bodies"][0]] if item["bodies"][0] >= 0 else None,
            body_b=names[item["bodies"][1]] if item["bodies"][1] >= 0 else None,
            force=force, moment=moment, rows=slice(k0, k0 + m))
        k0 += m
    for i in range(nt):
        qrel = relative(joints, list(q[:, i]))
        R = []
        for k, (par, kind, at, rot, axis) in enumerate(jd):
            Rp = R[par] if par >= 0 else np.eye(3)
            Rk = Rp @ rot
            if kind == "revolute":
                Rk = Rk @ _rodrigues(axis, qrel[k])
            R.append(Rk)
        for item, e in loops:
            jr = out[item["label"]]
            lam_i = lam[jr.rows, i]
            ka, kb = item["bodies"]
            Ra = R[ka] if ka >= 0 else np.eye(3)
            Rb = R[kb] if kb >= 0 else np.eye(3)
            dim = item["npt"]
            rest = e[2*dim:]
            if d.planar and item["kind"] == "prismatic":
                n_a = np.array([-rest[1], rest[0]])
                jr.force[:, i] = -lam_i[0]*n_a
                jr.moment[0, i] = -lam_i[1]
                continue
            f = np.zeros(3)
            f[:dim] = lam_i[:dim]
            jr.force[:, i] = (Ra.T @ f)[:dim]
            if jr.moment is not None:         # spatial revolute: the axis rows
                ua = Ra @ np.asarray(rest[:3])
                mw = sum(lam_i[3 + j]*np.cross(ua, Rb @ np.asarray(rest[3 + 3*j:6 + 3*j]))
                         for j in range(2))
                jr.moment[:, i] = Ra.T @ mw
    return out
