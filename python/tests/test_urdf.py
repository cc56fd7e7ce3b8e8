"""conmech.symbolic.read_urdf / from_urdf: the shipped seven-joint arm equals the same tree
written by hand with SpatialBody (rotations from rpy, the hand merged by the parallel-axis
theorem) to 1e-12; continuous, prismatic and chained fixed joints; torques and damping as
run-time parameters, limits as data; every malformed document refused with a ValueError
naming the element, before any derivation."""

import numpy as np
import pytest

sp = pytest.importorskip("sympy")
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402

from conmech import symbolic  # noqa: E402
from conmech.symbolic import SpatialBody  # noqa: E402
from conmech.symbolic.urdf import data_path  # noqa: E402
import symbolic_seeds as seeds  # noqa: E402


@pytest.fixture(scope="session", autouse=True)
def symbolic_cache(tmp_path_factory):
    """The test session's one compile cache (symbolic_seeds.use_test_cache)."""
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


rel = seeds.rel
H = np.pi/2


def rpy(r, p, y):
    """Rz(y) Ry(p) Rx(r), each elementary rotation written out."""
    def rx(a):
        return np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])

    def ry(a):
        return np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])

    def rz(a):
        return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    return rz(y) @ ry(p) @ rx(r)


def inertia(ixx, ixy, ixz, iyy, iyz, izz):
    return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])


def arm7_by_hand():
    """data/arm7.urdf transcribed: joint origins (xyz, rpy), link inertials; the hand on
    the fixed flange joint merged into link7."""
    joints = [((0, 0, 0.333), (0, 0, 0)), ((0, 0, 0), (-H, 0, 0)), ((0, -0.316, 0), (H, 0, 0)),
              ((0.0825, 0, 0), (H, 0, 0)), ((-0.0825, 0.384, 0), (-H, 0, 0)),
              ((0, 0, 0), (H, 0, 0)), ((0.088, 0, 0), (H, 0, 0))]
    links = [(3.8, (0.003, -0.031, -0.070), (0, 0, 0),
              inertia(0.0290, -0.0001, 0.0003, 0.0285, 0.0021, 0.0068)),
             (3.6, (-0.003, -0.029, 0.032), (0, 0, 0),
              inertia(0.0095, -0.0003, 0.0001, 0.0300, 0.0028, 0.0275)),
             (3.3, (0.028, 0.039, -0.066), (0, 0, 0),
              inertia(0.0250, -0.0042, -0.0040, 0.0230, -0.0045, 0.0110)),
             (3.2, (-0.053, 0.104, 0.027), (0, 0, 0),
              inertia(0.0210, 0.0070, -0.0027, 0.0145, 0.0042, 0.0250)),
             (2.1, (-0.011, 0.042, -0.128), (0, 0, 0),
              inertia(0.0290, -0.0001, 0.0008, 0.0260, -0.0045, 0.0060)),
             (1.6, (0.060, -0.014, -0.010), (0, 0.3, 0),
              inertia(0.0020, 0.0002, -0.0005, 0.0040, 0.0001, 0.0050)),
             (0.75, (0.010, 0.004, 0.061), (0, 0, 0),
              inertia(0.0012, -0.0002, -0.0001, 0.0010, -0.0001, 0.0008))]
    # the hand in link7's frame: flange at (0, 0, 0.107), yaw -pi/4; its inertial: yaw pi/4
    Rf, pf = rpy(0, 0, -np.pi/4), np.array([0, 0, 0.107])
    mh, ch = 0.7, pf + Rf @ np.array([0, 0.005, 0.03])
    Ih = Rf @ rpy(0, 0, np.pi/4) @ inertia(0.0017, 0, 0, 0.0005, 0, 0.0019) \
        @ rpy(0, 0, np.pi/4).T @ Rf.T
    m7, c7, _, I7 = links[6]
    m = m7 + mh
    c = (m7*np.array(c7) + mh*ch)/m

    def shift(mi, ci):
        d = np.asarray(ci) - c
        return mi*(d @ d*np.eye(3) - np.outer(d, d))
    links[6] = (m, c, (0, 0, 0), I7 + shift(m7, c7) + Ih + shift(mh, ch))
    qs = dynamicsymbols("h1:8")
    bodies = []
    for i, ((xyz, ang), (mi, ci, irpy, Ii)) in enumerate(zip(joints, links)):
        Ri = rpy(*irpy)
        Iw = Ri @ Ii @ Ri.T
        bodies.append(SpatialBody(f"link{i + 1}", None if i == 0 else f"link{i}", "revolute",
                                  qs[i], axis=(0, 0, 1), at=xyz, rot=rpy(*ang).tolist(),
                                  mass=mi, com=tuple(ci), inertia=((Iw + Iw.T)/2).tolist()))
    return bodies


def test_arm7_equals_the_tree_written_by_hand():
    robot = symbolic.read_urdf(data_path("arm7.urdf"))
    assert robot.name == "conmech_arm7" and robot.root == "base"
    assert robot.joint_names == [f"joint{i}" for i in range(1, 8)]
    assert [j.name for j in robot.fixed_joints] == ["flange"]
    g = sp.Symbol("g")
    ref = symbolic.spatial_tree(arm7_by_hand(), {g: 9.81}, gravity=(0, 0, -g),
                                model_only=True)
    mine = symbolic.from_urdf(data_path("arm7.urdf"), torques=None, damping=False,
                              model_only=True)
    rng = np.random.default_rng(11)
    for _ in range(4):
        q, v = rng.uniform(-2, 2, 7), rng.uniform(-2, 2, 7)
        for entry, args in (("mass", (q,)), ("forces", (q, v)), ("accel", (q, v)),
                            ("energy", (q, v))):
            assert rel(mine.call(entry, 0.0, *args), ref.call(entry, 0.0, *args)) <= 1e-12
    # limits and damping as data, in the order of the coordinates
    assert np.allclose(robot.lower[:3], [-2.8973, -1.7628, -2.8973])
    assert robot.upper[3] == -0.0698 and robot.effort[0] == 87 and robot.velocity[4] == 2.61
    assert np.allclose(robot.damping, [0.5, 0.5, 0.4, 0.4, 0.2, 0.2, 0.1])
    assert np.allclose(robot.friction[:2], [0.1, 0.1])


def test_torques_and_damping_are_run_time_inputs():
    """Default: torques tau_k (parameters, 0) and the damping -c_k q'_k: a torque on joint
    3 adds M^-1 e_3 tau to the accelerations; with_params changes it without a rebuild."""
    sysm = symbolic.from_urdf(data_path("arm7.urdf"))
    model = symbolic.model_of(sysm)
    names = model.derived.param_names
    assert {"g", "tau3", "c3"} <= set(names)
    q, v = np.linspace(0.1, 0.7, 7), np.linspace(-0.3, 0.3, 7)
    p = np.array(sysm.params)
    a0 = model.call("accel", 0.0, q, v, params=p)
    p2 = p.copy()
    p2[names.index("tau3")] = 2.5
    a1 = model.call("accel", 0.0, q, v, params=p2)
    M = model.call("mass", 0.0, q)
    assert rel(a1 - a0, np.linalg.solve(M, 2.5*np.eye(7)[2])) <= 1e-12
    Q0 = model.call("forces", 0.0, q, 0*v, params=p)
    Q1 = model.call("forces", 0.0, q, v, params=p)
    undamped = symbolic.from_urdf(data_path("arm7.urdf"), damping=False, model_only=True)
    Qu = undamped.call("forces", 0.0, q, v) - undamped.call("forces", 0.0, q, 0*v)
    assert rel((Q1 - Q0) - Qu, -np.array([0.5, 0.5, 0.4, 0.4, 0.2, 0.2, 0.1])*v) <= 1e-12
    assert sysm.with_params(tau3=1.0).params[names.index("tau3")] == 1.0


ONE = """<robot name="r">
  <link name="base"/>
  <link name="a"><inertial><origin xyz="0 0 -0.5" rpy="0 0 0"/><mass value="1"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.02"/></inertial></link>
  {extra}
  <joint name="j1" type="{jtype}"><parent link="base"/><child link="a"/>
    <origin xyz="0 0 1" rpy="0 0 0"/><axis xyz="{axis}"/>{limit}</joint>
</robot>"""


def urdf(jtype="revolute", axis="1 0 0", limit='<limit lower="-1" upper="1"/>', extra=""):
    return ONE.format(jtype=jtype, axis=axis, limit=limit, extra=extra)


def test_joint_types():
    """continuous = revolute without limits; prismatic; an axis that is not normalised is
    normalised; two fixed joints in a row merge into the moving link; a fixed joint from
    the base merges into the (fixed) base."""
    q1 = dynamicsymbols("q1")
    rc = symbolic.read_urdf(urdf("continuous", "0 2 0", ""))
    b = rc.bodies[0]
    assert b.joint == "revolute" and list(b.axis) == [0, 1, 0] and np.isnan(rc.lower[0])
    rp = symbolic.read_urdf(urdf("prismatic", "0 0 1"))
    assert rp.bodies[0].joint == "prismatic" and rp.bodies[0].q == q1
    extra = """<link name="c"><inertial><mass value="2"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
    <link name="d"><inertial><origin xyz="0.1 0 0"/><mass value="1"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
    <link name="e"><inertial><mass value="5"/>
      <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
    <joint name="f1" type="fixed"><parent link="a"/><child link="c"/>
      <origin xyz="0 0 -1" rpy="0 0 1.5707963267948966"/></joint>
    <joint name="f2" type="fixed"><parent link="c"/><child link="d"/>
      <origin xyz="0 0 -0.5"/></joint>
    <joint name="f3" type="fixed"><parent link="base"/><child link="e"/></joint>"""
    r = symbolic.read_urdf(urdf(extra=extra))
    assert len(r.bodies) == 1 and len(r.fixed_joints) == 3
    b = r.bodies[0]
    # a: 1 kg at (0, 0, -0.5); c: 2 kg at (0, 0, -1); d: 1 kg at (0, 0.1, -1.5) (turned)
    m = float(b.mass)
    c = np.array([float(x) for x in b.com])
    assert abs(m - 4.0) <= 1e-14
    assert np.max(np.abs(c - (np.array([0, 0, -0.5]) + 2*np.array([0, 0, -1.0])
                              + np.array([0, 0.1, -1.5]))/4)) <= 1e-14
    # the merged inertia about the COM: the parallel-axis theorem by hand
    parts = [(1, [0, 0, -0.5], np.diag([0.1, 0.1, 0.02])), (2, [0, 0, -1], 0.01*np.eye(3)),
             (1, [0, 0.1, -1.5], 0.01*np.eye(3))]
    I = sum(Ii + mi*((np.array(ci) - c) @ (np.array(ci) - c)*np.eye(3)
                     - np.outer(np.array(ci) - c, np.array(ci) - c)) for mi, ci, Ii in parts)
    Ib = np.array([[float(x) for x in row] for row in b.inertia])
    assert np.max(np.abs(Ib - I)) <= 1e-14


@pytest.mark.parametrize("text, match", [
    (urdf(jtype="hinge"), "joint 'j1': unknown joint type 'hinge'"),
    (urdf(jtype="floating"), "joint 'j1': floating joints are not supported"),
    (urdf(axis="1 0"), r"joint 'j1': <axis xyz=\"1 0\">: 3 numbers expected"),
    (urdf(axis="1 x 0"), r"joint 'j1'.*'x' is not a number"),
    (urdf(axis="nan 0 1"), "joint 'j1'.*not finite"),
    (urdf(axis="0 0 0"), "joint 'j1': the axis is zero"),
    (urdf(limit='<limit lower="1" upper="-1"/>'), "joint 'j1'.*lower > upper"),
    (urdf(limit='<mimic joint="j0"/>'), "joint 'j1': <mimic> is not supported"),
    (urdf().replace('<child link="a"/>', '<child link="zz"/>'),
     "joint 'j1': unknown child link 'zz'"),
    (urdf().replace('<mass value="1"/>', '<mass value="-1"/>'), "link 'a': negative mass"),
    (urdf().replace('<mass value="1"/>', '<mass value="1kg"/>'),
     "link 'a'.*'1kg' is not a number"),
    (urdf().replace('<mass value="1"/>', ''), "link 'a': <inertial> has no <mass>"),
    (urdf().replace('ixx="0.1"', 'ixx="0.1 0.2"'), r"link 'a'.*1 number expected"),
    (urdf().replace('<link name="a"><inertial>', '<link name="a"><foo>').replace(
        '</inertial></link>', '</foo></link>'),
     r"link 'a' \(moved by joint 'j1'\) has no <inertial>"),
    ("<robot><link name='a'/>", "not well-formed XML"),
    ("<model name='x'/>", "the root element is <model>"),
    (urdf(extra='<link name="b"/><link name="c"/><joint name="j2" type="fixed">'
                '<parent link="b"/><child link="c"/></joint><joint name="j3" type="fixed">'
                '<parent link="c"/><child link="b"/></joint>'),
     "the joints form a cycle: j[23] -> j[23] -> j[23]"),
    (urdf(extra='<joint name="j2" type="fixed"><parent link="base"/><child link="a"/>'
                '</joint>'), "link 'a' is the child of two joints"),
    (urdf(extra='<link name="lonely"/>'), "2 root links"),
])
def test_bad_urdf(text, match):
    with pytest.raises(ValueError, match=match):
        symbolic.read_urdf(text)


def test_bad_arguments(tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        symbolic.read_urdf(str(tmp_path / "nope.urdf"))
    with pytest.raises(TypeError, match="path or the URDF text"):
        symbolic.read_urdf(3)
    path = tmp_path / "one.urdf"
    path.write_text(urdf())
    assert symbolic.read_urdf(path).joint_names == ["j1"]
    r = symbolic.read_urdf(urdf())
    with pytest.raises(ValueError, match="'nope' is neither a movable joint"):
        r.system(torques={"nope": 1.0})
    with pytest.raises(ValueError, match="torques has 2 entries for 1 movable joints"):
        r.system(torques=[1.0, 2.0])
    with pytest.raises(ValueError, match="no robot description 'x.urdf'"):
        data_path("x.urdf")


def test_robot_arm_example_runs():
    """example/robot_arm.py: the shipped arm read, compiled, simulated; its accelerations
    equal M^-1 Q."""
    import os
    import re
    import subprocess
    import sys
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    r = subprocess.run([sys.executable, os.path.join(root, "example", "robot_arm.py")],
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr
    assert "7 movable joints" in r.stdout and "successfully" in r.stdout
    err = float(re.search(r"vs M\^-1 Q: (\S+)", r.stdout).group(1))
    assert err <= 1e-10
