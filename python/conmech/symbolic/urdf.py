"""Robots from URDF files: a spatial tree (:func:`conmech.symbolic.spatial_tree`) from the
Unified Robot Description Format.

:func:`read_urdf` parses a URDF document (a path or the XML text) with the standard
library's ``xml.etree`` and validates it before anything is derived: every number (a
ValueError naming the element and attribute), the joint types (revolute, continuous,
prismatic, fixed; floating and planar joints and ``<mimic>`` are refused), the links of
every joint, the tree (one parent per link, one root, no cycle), the inertials (a moving
link needs one unless ``allow_massless=True``). It returns a :class:`Robot`: the
:class:`~conmech.symbolic.SpatialBody` records (fixed joints merged: the child's inertia
joins its parent's, the child's joints are re-attached with the composed placement), the
coordinates (``q1, q2, ...`` in the order of the movable joints in the file; the joint
and link names stay data and never reach generated code), and per joint the limits
(lower, upper, effort, velocity) and dynamics (damping, friction) as data.

:meth:`Robot.system` (and :func:`from_urdf`, which reads and builds in one call) compiles
it: gravity a run-time parameter ``g`` (default 9.81, along -z), the joint torques inputs
(run-time parameters ``tau1, tau2, ...``, default 0; or expressions), the URDF viscous
damping as forces -c_k q'_k with run-time parameters ``c1, c2, ...`` (``damping=False``
drops them; friction stays data).

Conventions (URDF's, the same as SpatialBody's): a joint's origin (xyz, rpy: roll about x,
pitch about y, yaw about z, R = Rz(yaw) Ry(pitch) Rx(roll)) places the joint frame in the
parent link's frame; the axis (default 1 0 0, normalised) is in the joint frame; the child
link's frame is the joint frame turned by q about the axis (moved by q along it); an
inertial's origin places the centre of mass and the axes of its inertia tensor in the
link's frame.
"""
import math
import os
import xml.etree.ElementTree as ET

import numpy as np
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from .._core.result import Record
from .description import urdf_description_key
from .description_lookup import description_hit
from .spatial import SpatialBody
from .trees import spatial_tree

__all__ = ["Robot", "UrdfJoint", "read_urdf", "from_urdf"]

_MOVABLE = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic"}
_URDF_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")


class UrdfJoint(Record):
    """A joint of a URDF robot as data: name, type, parent and child link, origin (xyz,
    rpy), axis, limits (lower, upper, effort, velocity; None where absent), dynamics
    (damping, friction; 0 where absent) and, for a movable joint, its coordinate (a
    dynamicsymbol) and index."""

    __slots__ = ("name", "type", "parent", "child", "xyz", "rpy", "axis", "lower", "upper",
                 "effort", "velocity", "damping", "friction", "coordinate", "index")

    def __repr__(self):
        return (f"UrdfJoint({self.name!r}, {self.type!r}, parent={self.parent!r}, "
                f"child={self.child!r})")


class Robot:
    """A parsed and validated URDF robot (see :func:`read_urdf`).

    Attributes: ``name``; ``root`` (the fixed base link); ``joints`` (the movable joints,
    :class:`UrdfJoint`, in the order of their coordinates); ``fixed_joints``; ``bodies``
    (the SpatialBody records of the moving links, fixed children merged); ``coordinates``
    (dynamicsymbols q1, q2, ...); ``joint_names``; ``lower``, ``upper``, ``effort``,
    ``velocity``, ``damping``, ``friction`` (arrays over the movable joints; NaN where a
    limit is absent)."""

    def __init__(self, name, root, joints, fixed, bodies, coords):
        self.name, self.root, self.joints, self.fixed_joints = name, root, joints, fixed
        self.bodies, self.coordinates = bodies, coords
        self.joint_names = [j.name for j in joints]

        def arr(key):
            return np.array([np.nan if getattr(j, key) is None else getattr(j, key)
                             for j in joints], float)
        self.lower, self.upper = arr("lower"), arr("upper")
        self.effort, self.velocity = arr("effort"), arr("velocity")
        self.damping, self.friction = arr("damping"), arr("friction")

    def __repr__(self):
        return (f"Robot({self.name!r}: {len(self.joints)} movable joints, "
                f"{len(self.fixed_joints)} fixed, root {self.root!r})")

    def system(self, gravity=None, torques="params", damping=True, forces=None,
               params=None, **kw):
        """The compiled spatial tree of the robot.

        gravity : 3 expressions, optional
            Default (0, 0, -g) with the run-time parameter g = 9.81.
        torques : "params", None, list or dict
            "params": a run-time parameter tau_k (default 0) per movable joint
            (``system.with_params(tau3=1.5)``); None: no torques; a list (one expression
            per joint) or a dict {joint name or coordinate: expression} of torques in t,
            the coordinates and their rates.
        damping : bool
            The URDF viscous damping as -c_k q'_k with run-time parameters c_k.
        forces : optional
            Further generalized forces, as in :func:`conmech.symbolic.spatial_tree` (a
            dict may name joints).
        params : dict, optional
            Values of further symbols in gravity, torques and forces.
        kw
            Further keyword arguments, passed to :func:`conmech.symbolic.spatial_tree`
            (method, jacobian, loops, point_forces, flags, model_only, ...).
        """
        t = dynamicsymbols._t
        n = len(self.joints)
        vals = {}
        if gravity is None:
            g = sp.Symbol("g")
            vals[g] = 9.81
            gravity = (0, 0, -g)
        fl = [sp.Integer(0)]*n
        by_name = {j.name: j.index for j in self.joints}
        by_coord = {q: k for k, q in enumerate(self.coordinates)}

        def slot(key, what):
            if isinstance(key, str) and key in by_name:
                return by_name[key]
            if key in by_coord:
                return by_coord[key]
            raise ValueError(f"{what}: {key!r} is neither a movable joint of the robot nor "
                             "a coordinate")
        if isinstance(torques, str) and torques == "params":
            for k in range(n):
                s = sp.Symbol(f"tau{k + 1}")
                vals[s] = 0.0
                fl[k] += s
        else:
            fl = _add_loads(fl, torques, "torques", slot)
        if damping:
            for k, j in enumerate(self.joints):
                if j.damping:
                    c = sp.Symbol(f"c{k + 1}")
                    vals[c] = float(j.damping)
                    fl[k] -= c*self.coordinates[k].diff(t)
        fl = _add_loads(fl, forces, "forces", slot)
        for k, v in (params or {}).items():
            vals[k] = v
        return spatial_tree(self.bodies, vals, gravity=gravity, forces=fl, **kw)


def _add_loads(fl, loads, what, slot):
    """The generalized forces `fl` (one per movable joint) plus the user's `loads`: a dict
    naming joints (their slots by `slot`), a sequence with one entry per joint, or None."""
    if isinstance(loads, dict):
        for key, e in loads.items():
            fl[slot(key, what)] += sp.sympify(e)
        return fl
    if loads is None:
        return fl
    ex = list(loads)
    if len(ex) != len(fl):
        raise ValueError(f"{what} has {len(ex)} entries for {len(fl)} movable joints")
    return [a + sp.sympify(b) for a, b in zip(fl, ex)]


def from_urdf(source, allow_massless=False, **kw):
    """Read the URDF `source` (a path or the XML text) and build its compiled spatial
    tree: ``read_urdf(source, allow_massless).system(**kw)`` (see :meth:`Robot.system`).
    A second call with the same document and arguments (in any process) loads the
    compiled model from the cache without parsing into sympy or deriving anything
    (``conmech.symbolic.description``)."""
    text, origin = _text(source)
    dkey = urdf_description_key(text, allow_massless, kw)
    hit = description_hit(dkey, kw.get("flags"), bool(kw.get("model_only", False)))
    if hit is not None:
        return hit
    return read_urdf(text, allow_massless, origin).system(_description=dkey, **kw)


def _text(source):
    if isinstance(source, (bytes, bytearray)):
        source = source.decode("utf-8")
    if isinstance(source, os.PathLike):
        source = os.fspath(source)
    if not isinstance(source, str):
        raise TypeError("source must be a path or the URDF text")
    if source.lstrip().startswith("<"):
        return source, "<string>"
    if not os.path.isfile(source):
        raise ValueError(f"URDF file {source!r} does not exist")
    with open(source, encoding="utf-8") as fh:
        return fh.read(), source


def _numbers(el, attr, count, where, default=None):
    """`count` finite numbers from attribute `attr` of element `el` (default when the
    attribute is absent; None default: required)."""
    raw = el.get(attr) if el is not None else None
    if raw is None:
        if default is None:
            raise ValueError(f"{where}: <{el.tag if el is not None else '?'}> needs the "
                             f"attribute {attr}=")
        return list(default)
    parts = raw.split()
    if len(parts) != count:
        raise ValueError(f"{where}: <{el.tag} {attr}=\"{raw}\">: {count} number"
                         f"{'s' if count > 1 else ''} expected")
    out = []
    for p in parts:
        try:
            x = float(p)
        except ValueError:
            raise ValueError(f"{where}: <{el.tag} {attr}=\"{raw}\">: {p!r} is not a "
                             "number") from None
        if not math.isfinite(x):
            raise ValueError(f"{where}: <{el.tag} {attr}=\"{raw}\">: not finite")
        out.append(x)
    return out


def _rpy(r, p, y):
    """R = Rz(y) Ry(p) Rx(r) (URDF's fixed-axis roll, pitch, yaw)."""
    cr, sr, cp, sp_, cy, sy = (math.cos(r), math.sin(r), math.cos(p), math.sin(p),
                               math.cos(y), math.sin(y))
    return np.array([[cy*cp, cy*sp_*sr - sy*cr, cy*sp_*cr + sy*sr],
                     [sy*cp, sy*sp_*sr + cy*cr, sy*sp_*cr - cy*sr],
                     [-sp_, cp*sr, cp*cr]])


def _origin(el, where):
    o = el.find("origin")
    xyz = _numbers(o, "xyz", 3, where, (0.0, 0.0, 0.0)) if o is not None else [0.0]*3
    rpy = _numbers(o, "rpy", 3, where, (0.0, 0.0, 0.0)) if o is not None else [0.0]*3
    return np.array(xyz), np.array(rpy)


def _inertial(link, where):
    """(mass, com, inertia tensor about the COM in the link frame) or None."""
    el = link.find("inertial")
    if el is None:
        return None
    xyz, rpy = _origin(el, where + " <inertial>")
    m_el = el.find("mass")
    if m_el is None:
        raise ValueError(f"{where}: <inertial> has no <mass>")
    m = _numbers(m_el, "value", 1, where)[0]
    if m < 0:
        raise ValueError(f"{where}: negative mass {m}")
    i_el = el.find("inertia")
    if i_el is None:
        raise ValueError(f"{where}: <inertial> has no <inertia>")
    v = {k: _numbers(i_el, k, 1, where)[0] for k in ("ixx", "ixy", "ixz", "iyy", "iyz",
                                                    "izz")}
    I = np.array([[v["ixx"], v["ixy"], v["ixz"]], [v["ixy"], v["iyy"], v["iyz"]],
                  [v["ixz"], v["iyz"], v["izz"]]])
    R = _rpy(*rpy)
    I = R @ I @ R.T
    return m, xyz, (I + I.T)/2


def _merge(a, b):
    """Two (mass, com, inertia about the com) in the same frame as one."""
    if a is None:
        return b
    if b is None:
        return a
    m1, c1, I1 = a
    m2, c2, I2 = b
    m = m1 + m2
    if m == 0:
        return (0.0, np.zeros(3), I1 + I2)
    c = (m1*c1 + m2*c2)/m

    def shift(mi, ci):
        d = ci - c
        return mi*(d @ d*np.eye(3) - np.outer(d, d))
    I = I1 + shift(m1, c1) + I2 + shift(m2, c2)
    return (m, c, (I + I.T)/2)


def _moved(inert, R, p):
    """An inertial given in a frame placed by (R, p) in its parent's, in the parent's."""
    if inert is None:
        return None
    m, c, I = inert
    return (m, p + R @ c, R @ I @ R.T)


def read_urdf(source, allow_massless=False, _source_name=None):
    """Parse and validate a URDF document (a path or the XML text); returns a
    :class:`Robot` (see the module docstring). Every problem is a ValueError naming the
    element, found before anything is derived."""
    text, origin_name = _text(source)
    origin_name = _source_name or origin_name
    try:
        root_el = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ValueError(f"{origin_name}: not well-formed XML ({exc})") from None
    if root_el.tag != "robot":
        raise ValueError(f"{origin_name}: the root element is <{root_el.tag}>, not <robot>")
    rname = root_el.get("name", "")
    links = {}
    for el in root_el.findall("link"):
        nm = el.get("name")
        if not nm:
            raise ValueError(f"{origin_name}: a <link> without a name")
        if nm in links:
            raise ValueError(f"link {nm!r} is defined twice")
        links[nm] = el
    if not links:
        raise ValueError(f"{origin_name}: no <link>")
    joints, child_of = [], {}
    for el in root_el.findall("joint"):
        nm = el.get("name")
        if not nm:
            raise ValueError(f"{origin_name}: a <joint> without a name")
        where = f"joint {nm!r}"
        if any(j.name == nm for j in joints):
            raise ValueError(f"{where} is defined twice")
        typ = el.get("type")
        if typ not in _URDF_TYPES:
            raise ValueError(f"{where}: unknown joint type {typ!r} (URDF: revolute, "
                             "continuous, prismatic, fixed, floating, planar)")
        if typ in ("floating", "planar"):
            raise ValueError(f"{where}: {typ} joints are not supported (revolute, "
                             "continuous, prismatic, fixed)")
        if el.find("mimic") is not None:
            raise ValueError(f"{where}: <mimic> is not supported")
        ends = []
        for tag in ("parent", "child"):
            e = el.find(tag)
            if e is None or not e.get("link"):
                raise ValueError(f"{where}: no <{tag} link=...>")
            if e.get("link") not in links:
                raise ValueError(f"{where}: unknown {tag} link {e.get('link')!r}")
            ends.append(e.get("link"))
        if ends[0] == ends[1]:
            raise ValueError(f"{where}: the link {ends[0]!r} is its own parent")
        if ends[1] in child_of:
            raise ValueError(f"link {ends[1]!r} is the child of two joints, "
                             f"{child_of[ends[1]]!r} and {nm!r} (a URDF robot is a tree)")
        child_of[ends[1]] = nm
        xyz, rpy = _origin(el, where)
        axis = None
        if typ in _MOVABLE:
            ax = el.find("axis")
            axis = np.array(_numbers(ax, "xyz", 3, where, (1.0, 0.0, 0.0))
                            if ax is not None else [1.0, 0.0, 0.0])
            nrm = np.linalg.norm(axis)
            if nrm == 0:
                raise ValueError(f"{where}: the axis is zero")
            axis = axis/nrm
        lim = el.find("limit")
        lo = up = eff = vel = None
        if lim is not None:
            def opt(a):
                return _numbers(lim, a, 1, where)[0] if lim.get(a) is not None else None
            lo, up, eff, vel = opt("lower"), opt("upper"), opt("effort"), opt("velocity")
            if lo is not None and up is not None and lo > up:
                raise ValueError(f"{where}: <limit lower={lo} upper={up}>: lower > upper")
        dyn = el.find("dynamics")
        damp = fric = 0.0
        if dyn is not None:
            damp = _numbers(dyn, "damping", 1, where, (0.0,))[0]
            fric = _numbers(dyn, "friction", 1, where, (0.0,))[0]
            if damp < 0 or fric < 0:
                raise ValueError(f"{where}: negative damping or friction")
        joints.append(UrdfJoint(name=nm, type=typ, parent=ends[0], child=ends[1], xyz=xyz,
                                rpy=rpy, axis=axis, lower=lo, upper=up, effort=eff,
                                velocity=vel, damping=damp, friction=fric))
    # the tree: one root, no cycle
    roots = [nm for nm in links if nm not in child_of]
    by_child = {j.child: j for j in joints}
    for nm in links:
        seen, cur = [], nm
        while cur in by_child:
            j = by_child[cur]
            if j.name in seen:
                cyc = seen[seen.index(j.name):] + [j.name]
                raise ValueError("the joints form a cycle: " + " -> ".join(cyc))
            seen.append(j.name)
            cur = j.parent
    if len(roots) != 1:
        raise ValueError(f"{origin_name}: {len(roots)} root links ({', '.join(roots)}); a "
                         "URDF robot has exactly one")
    root = roots[0]
    inert = {nm: _inertial(el, f"link {nm!r}") for nm, el in links.items()}
    # fixed joints: merge each fixed child into the nearest link that is the root or the
    # child of a movable joint; placement of a link in that "body" frame
    children = {}
    for j in joints:
        children.setdefault(j.parent, []).append(j)
    body_of, place = {root: root}, {root: (np.eye(3), np.zeros(3))}
    order, stack = [], [root]
    while stack:
        nm = stack.pop()
        for j in sorted(children.get(nm, []), key=lambda x: joints.index(x), reverse=True):
            if j.type == "fixed":
                R0, p0 = place[nm]
                Rj = _rpy(*j.rpy)
                body_of[j.child] = body_of[nm]
                place[j.child] = (R0 @ Rj, p0 + R0 @ j.xyz)
            else:
                body_of[j.child] = j.child
                place[j.child] = (np.eye(3), np.zeros(3))
                order.append(j)
            stack.append(j.child)
    merged = {}
    for nm in links:
        R, p = place[nm]
        merged[body_of[nm]] = _merge(merged.get(body_of[nm]), _moved(inert[nm], R, p))
    movable = [j for j in joints if j.type != "fixed"]
    movable.sort(key=lambda j: joints.index(j))
    coords = dynamicsymbols(" ".join(f"q{k + 1}" for k in range(len(movable)))) \
        if movable else []
    if len(movable) == 1:
        coords = [coords]
    if not movable:
        raise ValueError(f"{origin_name}: no movable joint")
    bodies = []
    for k, j in enumerate(movable):
        j.coordinate, j.index = coords[k], k
        pb = body_of[j.parent]
        R0, p0 = place[j.parent]
        at = p0 + R0 @ j.xyz
        rot = R0 @ _rpy(*j.rpy)
        mi = merged.get(j.child)
        if mi is None or (mi[0] == 0 and not np.any(mi[2])):
            if not allow_massless:
                raise ValueError(f"link {j.child!r} (moved by joint {j.name!r}) has no "
                                 "<inertial> (nor a fixed child with one); give it one, or "
                                 "read_urdf(..., allow_massless=True) for massless links")
            mi = (0.0, np.zeros(3), np.zeros((3, 3)))
        m, c, I = mi
        bodies.append(SpatialBody(
            j.child, None if pb == root else pb, _MOVABLE[j.type], coords[k],
            axis=[_num(x) for x in j.axis], at=[_num(x) for x in at],
            rot=[[_num(x) for x in row] for row in rot], mass=_num(m),
            com=[_num(x) for x in c],
            inertia=[[_num(x) for x in row] for row in I] if np.any(I) else None))
    fixed = [j for j in joints if j.type == "fixed"]
    return Robot(rname, root, movable, fixed, bodies, list(coords))


def _num(x):
    """A number for the bodies' data: exact 0, 1 and -1 where the value is one of them to
    round-off (cos(pi/2) = 6e-17 of an rpy rotation would otherwise cost multiplications
    in the generated code), else the float."""
    for k in (0, 1, -1):
        if abs(x - k) <= 1e-14:
            return sp.Integer(k)
    return sp.Float(x)


def data_path(name):
    """The path of a robot description shipped with conmech (``conmech/symbolic/data``),
    e.g. ``data_path("arm7.urdf")``."""
    here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", name)
    if not os.path.isfile(here):
        avail = sorted(f for f in os.listdir(os.path.dirname(here)) if f.endswith(".urdf"))
        raise ValueError(f"no robot description {name!r} (shipped: {', '.join(avail)})")
    return here
