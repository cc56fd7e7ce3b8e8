"""Closed kinematic loops on multibody trees, and forces at points of bodies.

A mechanism with closed loops (a four-bar, a slider-crank, a parallel robot) is described
as a spanning tree (:class:`~conmech.symbolic.Body` / :class:`~conmech.symbolic.SpatialBody`
records) plus the joints that close the loops, :class:`Loop` records::

    Loop("coupler", (l, 0), "crank2", (l, 0))                    # planar revolute
    Loop("rod", (l, 0), None, (0, 0), joint="prismatic", axis=(1, 0))   # slider on ground
    Loop("a", (0, 0, 1), "b", (0, 0, 0), joint="spherical")      # spatial ball joint
    Loop("a", (0, 0, 1), "b", (0, 0, 0), joint="revolute", axis=(0, 1, 0))

The tree's coordinates become excessive coordinates with the holonomic constraints of the
loops, and the system a compiled constrained system (:func:`conmech.constrained.solve`:
KKT accelerations and multipliers, projection, RATTLE, Radau on the index-2 form):

- revolute (planar) / spherical (spatial): the two points coincide, phi = x_a - x_b (world
  components; 2 in the plane, 3 in space). The multipliers are the force of the joint on
  body a, world components (on body b: its opposite);
- prismatic (planar): the point of b stays on the line through the point of a along
  ``axis`` (body a's frame), phi_1 = (x_b - x_a) . n_a, and the relative angle is fixed,
  phi_2 = theta_b - theta_a - ``angle``; the multipliers: the normal force on body a and the
  moment on body a;
- revolute (spatial): the points coincide and ``axis`` (body a's frame, unit) stays
  parallel to ``axis_b`` (body b's frame; default the same numbers): phi = [x_a - x_b;
  u_a . w_1; u_a . w_2] with w_1, w_2 a fixed orthonormal pair normal to axis_b.

The constraint Jacobian G comes from the world motion subspaces of the joints on the paths
from the loop's bodies to the ground (the velocity of a body point due to joint j is
S_j,v + S_j,w x x), and gamma = -(dG/dt) v from the bias accelerations of the recursive
velocity pass: no symbolic differentiation of long expressions. Redundant loop constraints
(a parallelogram at its singular configurations, a spatial loop closed by a revolute joint
whose axes are parallel) are handled by conmech's rank-revealing KKT solve (minimum-norm
multipliers; G^T lambda is unique).

:func:`consistent_state` completes initial positions and velocities from the independent
coordinates the user gives (Newton on the loop constraints for the others, a clear
ValueError naming the loop that cannot close).
"""
import numpy as np
import sympy as sp

from .kinematics import _add, _cross, _dot, _path_to_root, relative
from .printer import _decl_temps, assignments
from .tree import _components
from .tree_print import SC_DECL, pos_call
from .loop_report import worst_loop as _worst_loop
from .pipeline import model_of

__all__ = ["Loop", "PointForce", "consistent_state"]

_PLANAR = {"revolute": 2, "prismatic": 2}
_SPATIAL = {"spherical": 3, "revolute": 5}


class Loop:
    """A joint that closes a kinematic loop of a tree.

    Parameters
    ----------
    body_a, body_b : str or None
        The two bodies the joint connects (None: the ground).
    point_a, point_b : coordinates
        The joint's point in body a's frame and in body b's frame (the ground frame for
        None); 2 numbers or expressions for a planar tree, 3 for a spatial tree.
    joint : str
        "revolute" (planar or spatial), "prismatic" (planar) or "spherical" (spatial).
    axis : coordinates, optional
        Prismatic (planar): the slide direction in body a's frame. Revolute (spatial): the
        joint axis in body a's frame, a unit vector of numbers.
    axis_b : coordinates, optional
        Revolute (spatial): the joint axis in body b's frame (default: ``axis``).
    angle : expression, optional
        Prismatic (planar): the relative angle theta_b - theta_a the joint keeps (default 0).
    name : str, optional
        A label for messages (default "loop <k> (a-b)").
    """

    __slots__ = ("body_a", "point_a", "body_b", "point_b", "joint", "axis", "axis_b",
                 "angle", "name")

    def __init__(self, body_a, point_a, body_b, point_b, joint="revolute", axis=None,
                 axis_b=None, angle=0, name=None):
        self.body_a, self.point_a, self.body_b, self.point_b = body_a, point_a, body_b, point_b
        self.joint, self.axis, self.axis_b, self.angle, self.name = (joint, axis, axis_b,
                                                                     angle, name)

    def __repr__(self):
        return (f"Loop({self.body_a!r}, {self.point_a}, {self.body_b!r}, {self.point_b}, "
                f"joint={self.joint!r})")


class PointForce:
    """A force applied at a point of a body of a tree: ``force`` (2 or 3 expressions in t,
    the coordinates and their rates, the parameters) at ``point`` (the body's frame),
    given in the ground frame (``frame="world"``) or in the body's frame (``"body"``). Its
    generalized force is J(q)^T F, J the Jacobian of the point."""

    __slots__ = ("body", "point", "force", "frame")

    def __init__(self, body, point, force, frame="world"):
        self.body, self.point, self.force, self.frame = body, point, force, frame

    def __repr__(self):
        return f"PointForce({self.body!r}, {self.point}, {self.force}, frame={self.frame!r})"


def _vec(x, dim, what):
    return _components(x, dim, what, f"{dim} expressions")


def _perp_pair(u, what):
    """An orthonormal pair normal to the unit vector u (numbers)."""
    try:
        uv = np.array([float(x) for x in u])
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be numbers (a unit vector)") from None
    if abs(np.linalg.norm(uv) - 1) > 1e-12:
        raise ValueError(f"{what} {list(uv)} is not a unit vector")
    e = np.eye(3)[int(np.argmin(np.abs(uv)))]
    w1 = np.cross(uv, e)
    w1 /= np.linalg.norm(w1)
    w2 = np.cross(uv, w1)
    return [sp.Float(x) for x in w1], [sp.Float(x) for x in w2]


def prepare_loops(loops, order, planar):
    """Validated loop records: dicts with kind, the bodies' topological indices (-1: the
    ground), the expressions (points, axes, angle) to resolve, the number of rows, a
    label. ValueError naming the loop for an unknown body, joint or a bad point."""
    if loops is None:
        return []
    if isinstance(loops, Loop):
        loops = [loops]
    loops = list(loops)
    topo = {b.name: k for k, b in enumerate(order)}
    dim = 2 if planar else 3
    kinds = _PLANAR if planar else _SPATIAL
    out = []
    for i, lp in enumerate(loops):
        if not isinstance(lp, Loop):
            raise TypeError(f"loops must be conmech.symbolic.Loop records, got "
                            f"{type(lp).__name__}")
        label = lp.name if lp.name is not None else \
            f"loop {i} ({lp.body_a or 'ground'}-{lp.body_b or 'ground'})"
        if not isinstance(label, str):
            raise TypeError(f"loop {i}: name must be a string")
        idx = []
        for b in (lp.body_a, lp.body_b):
            if b is None:
                idx.append(-1)
            elif isinstance(b, str) and b in topo:
                idx.append(topo[b])
            else:
                raise ValueError(f"{label}: unknown body {b!r}")
        if idx[0] == idx[1]:
            raise ValueError(f"{label}: the joint connects "
                             f"{'the ground' if idx[0] < 0 else repr(lp.body_a)} to itself")
        if lp.joint not in kinds:
            raise ValueError(f"{label}: unknown joint {lp.joint!r} for a "
                             f"{'planar' if planar else 'spatial'} tree (one of "
                             f"{', '.join(kinds)})")
        exprs = _vec(lp.point_a, dim, f"{label}: point_a") + \
            _vec(lp.point_b, dim, f"{label}: point_b")
        item = dict(kind=lp.joint, bodies=tuple(idx), rows=kinds[lp.joint], label=label,
                    npt=dim)
        if planar and lp.joint == "prismatic":
            if lp.axis is None:
                raise ValueError(f"{label}: a prismatic joint needs axis= (the slide "
                                 "direction in body a's frame)")
            ax = _vec(lp.axis, 2, f"{label}: axis")
            if all(e == 0 for e in ax):
                raise ValueError(f"{label}: the axis is zero")
            exprs += ax + _vec([lp.angle], 1, f"{label}: angle")
        elif not planar and lp.joint == "revolute":
            if lp.axis is None:
                raise ValueError(f"{label}: a revolute joint needs axis= (its direction in "
                                 "body a's frame)")
            ua = _vec(lp.axis, 3, f"{label}: axis")
            ub = _vec(lp.axis if lp.axis_b is None else lp.axis_b, 3, f"{label}: axis_b")
            _perp_pair(ua, f"{label}: axis")
            w1, w2 = _perp_pair(ub, f"{label}: axis_b")
            exprs += ua + w1 + w2
        out.append(dict(item, exprs=exprs))
    return out


def prepare_point_forces(forces, order, planar):
    """Validated point forces: dicts with the body's topological index and the
    expressions (point, force) to resolve."""
    if forces is None:
        return []
    if isinstance(forces, PointForce):
        forces = [forces]
    topo = {b.name: k for k, b in enumerate(order)}
    dim = 2 if planar else 3
    out = []
    for i, pf in enumerate(forces):
        if not isinstance(pf, PointForce):
            raise TypeError(f"point_forces must be conmech.symbolic.PointForce records, "
                            f"got {type(pf).__name__}")
        if pf.body not in topo:
            raise ValueError(f"point force {i}: unknown body {pf.body!r}")
        if pf.frame not in ("world", "body"):
            raise ValueError(f"point force {i}: frame must be 'world' or 'body', got "
                             f"{pf.frame!r}")
        exprs = _vec(pf.point, dim, f"point force {i}: point") + \
            _vec(pf.force, dim, f"point force {i}: force")
        out.append(dict(body=topo[pf.body], frame=pf.frame, npt=dim, exprs=exprs))
    return out


def count_rows(items):
    return sum(it["rows"] for it in items)


def _pad(x):
    return list(x) + [0]*(3 - len(x))


class _LoopCode:
    """The loop rows as expressions in the loaded positions (phi, G) and velocities
    (gamma), and their procedures."""

    def __init__(self, d, joints, lpos, vel):
        self.d = d
        n = len(joints)
        self.phi, self.gamma = [], []
        self.G = []                        # rows: {topological column: expr}
        g0 = [0, 0, 0] + [-x for x in d.gravity]
        qrel = None

        def frame(k):
            """(R, p, v, bias a) of body k (ground: identity, zeros)."""
            if k < 0:
                I3 = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
                return I3, [0, 0, 0], [0]*6, [0]*6
            P = lpos[k]
            a = [x - y for x, y in zip(vel[k]["a_load"], g0)]
            return P["R"], P["p"], vel[k]["v_load"], a

        def point(k, x):
            """World position, velocity, bias acceleration of the body-k point x."""
            R, p, v, a = frame(k)
            xw = [p[i] + sum(R[i][m]*x[m] for m in range(3)) for i in range(3)]
            w, vo = v[:3], v[3:]
            xd = _add(vo, _cross(w, xw))
            xdd = _add(_add(a[3:], _cross(a[:3], xw)), _cross(w, xd))
            return xw, xd, xdd

        def jcols(k, x):
            """{j: d x / d qrel_j} for the joints on body k's path."""
            return {j: _add(lpos[j]["S"][3:], _cross(lpos[j]["S"][:3], x))
                    for j in _path_to_root(joints, k)}

        def vector(k, u):
            """World vector u fixed in body k: value, rate, bias second derivative."""
            R, p, v, a = frame(k)
            uw = [sum(R[i][m]*u[m] for m in range(3)) for i in range(3)]
            ud = _cross(v[:3], uw)
            udd = _add(_cross(a[:3], uw), _cross(v[:3], ud))
            return uw, ud, udd

        def rows_sub(ca, cb, comps):
            """G rows of x_a - x_b for the given components."""
            for c in comps:
                row = {}
                for j, col in ca.items():
                    row[j] = row.get(j, 0) + col[c]
                for j, col in cb.items():
                    row[j] = row.get(j, 0) - col[c]
                self.G.append(row)

        for item in d.loops:
            ka_, kb_ = item["bodies"]
            e = item["exprs"]
            dim = item["npt"]
            pa, pb = _pad(e[:dim]), _pad(e[dim:2*dim])
            rest = e[2*dim:]
            xa, xad, xadd = point(ka_, pa)
            xb, xbd, xbdd = point(kb_, pb)
            ca = jcols(ka_, xa) if ka_ >= 0 else {}
            cb = jcols(kb_, xb) if kb_ >= 0 else {}
            kind = item["kind"]
            if not (d.planar and kind == "prismatic"):     # the points coincide
                comps = range(2) if d.planar else range(3)
                for c in comps:
                    self.phi.append(xa[c] - xb[c])
                    self.gamma.append(-(xadd[c] - xbdd[c]))
                rows_sub(ca, cb, comps)
            if d.planar and kind == "prismatic":
                ax, ang = rest[:2], rest[2]
                na = [-ax[1], ax[0], 0]
                nw, nd, ndd = vector(ka_, na)
                dd = [xb[i] - xa[i] for i in range(3)]
                ddd = [xbd[i] - xad[i] for i in range(3)]
                dddd = [xbdd[i] - xadd[i] for i in range(3)]
                self.phi.append(_dot(dd, nw))
                self.gamma.append(-(_dot(dddd, nw) + 2*_dot(ddd, nd) + _dot(dd, ndd)))
                row = {}
                for j, col in cb.items():
                    row[j] = row.get(j, 0) + _dot(col, nw)
                for j, col in ca.items():
                    row[j] = row.get(j, 0) - _dot(col, nw)
                for j in (_path_to_root(joints, ka_) if ka_ >= 0 else []):
                    row[j] = row.get(j, 0) + _dot(dd, _cross(lpos[j]["S"][:3], nw))
                self.G.append(row)
                # the relative angle: theta = sum of the relative revolute angles on the path
                if qrel is None:
                    qrel = relative(joints, d.coords)
                row, th = {}, 0
                for sgn, k in ((1, kb_), (-1, ka_)):
                    for j in (_path_to_root(joints, k) if k >= 0 else []):
                        if joints[j].kind == "revolute":
                            row[j] = row.get(j, 0) + sgn
                            th += sgn*qrel[j]
                self.phi.append(th - ang)
                self.gamma.append(sp.Integer(0))
                self.G.append(row)
            if not d.planar and kind == "revolute":
                ua = rest[:3]
                w1, w2 = rest[3:6], rest[6:9]
                u, ud, udd = vector(ka_, ua)
                for wb in (w1, w2):
                    w, wd, wdd = vector(kb_, wb)
                    self.phi.append(_dot(u, w))
                    self.gamma.append(-(_dot(udd, w) + 2*_dot(ud, wd) + _dot(u, wdd)))
                    row = {}
                    for j in (_path_to_root(joints, ka_) if ka_ >= 0 else []):
                        row[j] = row.get(j, 0) + _dot(_cross(lpos[j]["S"][:3], u), w)
                    for j in (_path_to_root(joints, kb_) if kb_ >= 0 else []):
                        row[j] = row.get(j, 0) + _dot(u, _cross(lpos[j]["S"][:3], w))
                    self.G.append(row)
        # columns in the user's coordinates: G_user = G_rel T (absolute planar angles)
        self.Gu = []
        for row in self.G:
            out = {}
            for j, e in row.items():
                out[j] = out.get(j, 0) + e
                if joints[j].ka >= 0:
                    out[joints[j].ka] = out.get(joints[j].ka, 0) - e
            self.Gu.append({joints[j].col: e for j, e in out.items()})
        del n

    def expressions(self):
        out = list(self.phi) + list(self.gamma)
        for row in self.G:
            out += list(row.values())
        return out

    def procedures(self, em, n, npar):
        I = "        "
        T = f"{I}real(dp), value, intent(in) :: t"
        P = f"{I}real(dp), intent(in) :: p({npar})"
        W = f"{I}type(tree_work) :: w\n{SC_DECL}"
        h = len(self.phi)
        out = []

        def proc(name, args, decls, pre, targets, exprs, zero=None):
            em.reset()
            pr = em.pr
            temps, lines = assignments(targets, exprs, pr, I, prefix="c") if exprs \
                else ([], [])
            head = f'subroutine conmech_{name}({", ".join(args)}) bind(C, name="conmech_{name}")'
            body = pre + ([f"{I}{zero} = 0.0_dp"] if zero else []) + lines
            return [f"    {head}"] + decls + _decl_temps(temps) + body + \
                [f"    end subroutine conmech_{name}", ""]
        out += proc("phi", ["t", "q", "c", "p"],
                    [T, f"{I}real(dp), intent(in) :: q({n})",
                     f"{I}real(dp), intent(out) :: c({h})", P, W],
                    pos_call(em), [f"c({i + 1})" for i in range(h)], self.phi)
        tg, ex = [], []
        for i, row in enumerate(self.Gu):
            for j, e in sorted(row.items()):
                if sp.sympify(e) != 0:
                    tg.append(f"g({i + 1}, {j + 1})")
                    ex.append(e)
        out += proc("phi_jac", ["t", "q", "g", "p"],
                    [T, f"{I}real(dp), intent(in) :: q({n})",
                     f"{I}real(dp), intent(out) :: g({h}, {n})", P, W],
                    pos_call(em), tg, ex, zero="g")
        out += proc("phi_gamma", ["t", "q", "v", "gam", "p"],
                    [T, f"{I}real(dp), intent(in) :: q({n}), v({n})",
                     f"{I}real(dp), intent(out) :: gam({h})", P, W,
                     f"{I}real(dp) :: z({n})"],
                    [f"{I}z = 0.0_dp"] + pos_call(em)
                    + [f"{I}call tree_vel(t, q, v, z, p, w, .false.)"],
                    [f"gam({i + 1})" for i in range(h)], self.gamma)
        return out


def loop_code(d, joints, lpos, vel):
    return _LoopCode(d, joints, lpos, vel)


def consistent_state(system, q0, v0=None, independent=None, tol=1e-12, max_iter=50):
    """Initial positions and velocities on the loop constraints of a tree with closed
    loops (a system from :func:`conmech.symbolic.planar_tree` or ``spatial_tree`` with
    ``loops=``).

    The coordinates listed in ``independent`` (indices, or the coordinates' names or
    dynamicsymbols) keep their values from ``q0`` and ``v0``; the others start from
    ``q0`` and are solved for by Newton's method on phi(q) = 0 (minimum-norm steps, so
    redundant loop constraints are fine), their rates from G v = 0 (least squares, the
    minimum-norm solution). ``independent=None``: every coordinate may move (the
    minimum-norm correction of q0 and v0). Returns (q, v). A loop that cannot close (no
    solution near q0 for the given independent coordinates, e.g. links too short to
    reach): ValueError naming the loop and its residual."""
    model = model_of(system)
    d = model.derived
    if d.kind != "constrained" or not getattr(d, "loops", None):
        raise ValueError("consistent_state needs a tree with closed loops (loops=...)")
    n = d.n
    q = np.array(q0, dtype=float).ravel()
    if q.shape != (n,) or not np.all(np.isfinite(q)):
        raise ValueError(f"q0 must have {n} finite values")
    v = np.zeros(n) if v0 is None else np.array(v0, dtype=float).ravel()
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise ValueError(f"v0 must have {n} finite values")
    ind = _indices(independent, d)
    dep = [i for i in range(n) if i not in ind]
    if not dep:
        raise ValueError("independent lists every coordinate: nothing left to solve for")
    p = np.asarray(getattr(system, "params", d.param_values), dtype=float)
    t0 = 0.0

    def phi(x):
        return model.call("phi", t0, x, params=p)

    def G(x):
        return model.call("phi_jac", t0, x, params=p)
    r = phi(q)
    best = np.max(np.abs(r))
    for _ in range(max_iter):
        if best <= tol:
            break
        step = np.linalg.lstsq(G(q)[:, dep], -r, rcond=1e-12)[0]
        lam, improved = 1.0, False
        while lam >= 1e-4:
            qt = q.copy()
            qt[dep] += lam*step
            rt = phi(qt)
            if np.all(np.isfinite(rt)) and np.max(np.abs(rt)) < best:
                q, r, best, improved = qt, rt, np.max(np.abs(rt)), True
                break
            lam /= 2
        if not improved:
            break
    if not best <= max(tol, 1e-10):
        raise ValueError(_worst_loop(d, r) + f": the loops cannot close at these initial "
                         f"positions (residual {best:.3g} after Newton's method on the "
                         f"{'dependent' if ind else ''} coordinates "
                         f"{[d.coord_names[i] for i in dep]})")
    Gq = G(q)
    rhs = -Gq[:, ind] @ v[ind] if ind else np.zeros(Gq.shape[0])
    if ind:
        v[dep] = np.linalg.lstsq(Gq[:, dep], rhs, rcond=1e-12)[0]
    else:
        v = v - np.linalg.lstsq(Gq, Gq @ v, rcond=1e-12)[0]
    res = np.max(np.abs(Gq @ v), initial=0.0)
    if not res <= 1e-9*max(1.0, np.max(np.abs(v))):
        raise ValueError(f"the velocities of the independent coordinates "
                         f"{[d.coord_names[i] for i in ind]} are not compatible with the "
                         f"loops at these positions (residual {res:.3g} of G v = 0)")
    return q, v


def _indices(independent, d):
    if independent is None:
        return []
    if isinstance(independent, (str, int, np.integer)) or isinstance(independent, sp.Basic):
        independent = [independent]
    out = []
    for x in independent:
        if isinstance(x, (int, np.integer)) and not isinstance(x, bool):
            i = int(x)
            if not 0 <= i < d.n:
                raise ValueError(f"independent: index {i} out of range (0..{d.n - 1})")
        else:
            name = x if isinstance(x, str) else str(getattr(x, "func", x))
            if name not in d.coord_names:
                raise ValueError(f"independent: {x!r} is not a coordinate "
                                 f"({', '.join(d.coord_names)})")
            i = d.coord_names.index(name)
        if i not in out:
            out.append(i)
    return out
