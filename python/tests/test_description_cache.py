"""The description cache (conmech.symbolic.description): a second construction of the same
tree or URDF robot, in a new process, loads the compiled model without deriving anything;
its key changes with every input that shapes the generated code (each field of each body,
gravity, forces, loops, point forces, parameters, options, the URDF text and every
argument of from_urdf) and is the same in another process."""
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

sp = pytest.importorskip("sympy")
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402

from conmech import symbolic  # noqa: E402
from conmech.symbolic import Body, Loop, PointForce, SpatialBody  # noqa: E402
from conmech.symbolic.description import (tree_description_key,  # noqa: E402
                                          urdf_description_key)
import symbolic_seeds as seeds  # noqa: E402


@pytest.fixture(scope="session", autouse=True)
def symbolic_cache(tmp_path_factory):
    """The test session's one compile cache (symbolic_seeds.use_test_cache)."""
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


a1, a2 = dynamicsymbols("a1 a2")
m, l, g, k = sp.symbols("m l g k")
PARAMS = {m: 1.0, l: 1.0, g: 9.81, k: 0.5}


def base():
    """The keyword arguments of a planar tree: two rods, a loop to the ground, a point
    force, a spring."""
    return dict(
        bodies=[Body("a", None, "revolute", a1, at=(0, 0), mass=m, com=(l/2, 0),
                     inertia=m*l**2/12),
                Body("b", "a", "revolute", a2, at=(l, 0), mass=m, com=(l/2, 0),
                     inertia=m*l**2/12)],
        params=dict(PARAMS), gravity=(0, -g), forces={"a": -k*a1},
        loops=[Loop("b", (l, 0), None, (1, 0))],
        point_forces=[PointForce("b", (l, 0), (0, -k))],
        options=("absolute", "recursive", "auto", True), flags=None)


def key(kw):
    return tree_description_key("tree", kw["bodies"], kw["params"], kw["gravity"],
                                kw["forces"], kw["loops"], kw["point_forces"],
                                kw["options"], kw["flags"])


def variants():
    """One change of every input that reaches the generated code."""
    out = []
    for i in range(2):
        for field, value in (("name", "z"), ("parent", None if i else "b"),
                             ("joint", "prismatic"), ("q", dynamicsymbols("z")),
                             ("at", (0, 1)), ("axis", (0, 1)), ("mass", 2*m),
                             ("com", (l/3, 0)), ("inertia", m*l**2/3)):
            kw = base()
            setattr(kw["bodies"][i], field, value)
            out.append((f"body {i}.{field}", kw))
    for name, change in (
            ("body order", lambda kw: kw["bodies"].reverse()),
            ("gravity", lambda kw: kw.update(gravity=(0, -2*g))),
            ("forces", lambda kw: kw.update(forces={"a": -k*a1**3})),
            ("forces on another body", lambda kw: kw.update(forces={"b": -k*a1})),
            ("no loop", lambda kw: kw.update(loops=None)),
            ("loop point", lambda kw: setattr(kw["loops"][0], "point_b", (1.5, 0))),
            ("loop joint", lambda kw: setattr(kw["loops"][0], "joint", "prismatic")),
            ("loop axis", lambda kw: setattr(kw["loops"][0], "axis", (1, 0))),
            ("loop body", lambda kw: setattr(kw["loops"][0], "body_a", "a")),
            ("loop angle", lambda kw: setattr(kw["loops"][0], "angle", 1)),
            ("loop name", lambda kw: setattr(kw["loops"][0], "name", "x")),
            ("point force", lambda kw: setattr(kw["point_forces"][0], "force", (k, 0))),
            ("point force frame", lambda kw: setattr(kw["point_forces"][0], "frame", "body")),
            ("parameter name", lambda kw: kw.update(params={**PARAMS, "extra": 1.0})),
            ("parameter order", lambda kw: kw.update(params=dict(reversed(PARAMS.items())))),
            ("coordinates", lambda kw: kw.update(options=("relative",) + kw["options"][1:])),
            ("method", lambda kw: kw.update(options=("absolute", "lagrangian", "auto", True))),
            ("simplify", lambda kw: kw.update(options=("absolute", "recursive", False, True))),
            ("jacobian", lambda kw: kw.update(options=("absolute", "recursive", "auto", False))),
            ("flags", lambda kw: kw.update(flags=["-O1", "-fPIC", "-shared"]))):
        kw = base()
        change(kw)
        out.append((name, kw))
    return out


def test_tree_key_changes_with_every_input():
    k0 = key(base())
    assert k0 is not None and k0 == key(base())          # the same description: one key
    seen = {k0: "base"}
    for name, kw in variants():
        kk = key(kw)
        assert kk is not None, name
        assert kk not in seen, f"{name} gives the key of {seen.get(kk)}"
        seen[kk] = name
    # parameter values: part of the key (their checks run on the ordinary path)
    kw = base()
    kw["params"][m] = 3.0
    assert key(kw) not in seen
    # something without an exact representation: no description key (the ordinary path)
    kw = base()
    kw["bodies"][0].mass = object()
    assert key(kw) is None


def test_keys_are_the_same_in_another_process():
    code = textwrap.dedent("""
        import sys
        sys.path.insert(0, %r)
        import test_description_cache as t
        from conmech.symbolic.urdf import data_path
        from conmech.symbolic.description import urdf_description_key
        text = open(data_path("arm7.urdf")).read()
        print(t.key(t.base()), urdf_description_key(text, False, {"damping": False}))
    """) % os.path.dirname(__file__)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=600, env=dict(os.environ, PYTHONHASHSEED="123"))
    assert out.returncode == 0, out.stderr
    from conmech.symbolic.urdf import data_path
    with open(data_path("arm7.urdf")) as fh:
        text = fh.read()
    assert out.stdout.split() == [key(base()), urdf_description_key(text, False,
                                                                    {"damping": False})]


TWO = """<robot name="r">
  <link name="base"/>
  <link name="a"><inertial><origin xyz="0 0 -0.5" rpy="0 0 0"/><mass value="1"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.02"/></inertial></link>
  <link name="b"><inertial><origin xyz="0 0 -0.4" rpy="0 0 0"/><mass value="{mass}"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.02"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
    <origin xyz="0 0 1" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <dynamics damping="0.3"/></joint>
  <joint name="j2" type="continuous"><parent link="a"/><child link="b"/>
    <origin xyz="0 0 -1" rpy="0 0 0"/><axis xyz="0 1 0"/></joint>
</robot>"""


def test_urdf_key_changes_with_the_text_and_every_argument():
    text = TWO.format(mass="2")
    k0 = urdf_description_key(text, False, {})
    keys = {k0}
    for t_, am, kw in ((TWO.format(mass="2.5"), False, {}), (text, True, {}),
                       (text, False, {"damping": False}), (text, False, {"torques": None}),
                       (text, False, {"gravity": (0, 0, -1)}),
                       (text, False, {"params": {"x": 1.0}}),
                       (text, False, {"method": "lagrangian"}),
                       (text, False, {"jacobian": False}),
                       (text, False, {"flags": ["-O2", "-fPIC", "-shared"]}),
                       (text, False, {"forces": [sp.Symbol("x"), 0]})):
        kk = urdf_description_key(t_, am, kw)
        assert kk is not None and kk not in keys
        keys.add(kk)
    assert urdf_description_key(text, False, {}) == k0


def _run(code):
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                         text=True, timeout=900, env=dict(os.environ))
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_a_second_construction_in_a_new_process_derives_nothing(tmp_path):
    """from_urdf and planar_tree, built once here; then in new processes where parsing
    the URDF into sympy records, building the tree and deriving raise: the construction
    still succeeds (from the description cache) and computes the same accelerations."""
    text = TWO.format(mass="2")
    path = tmp_path / "two.urdf"
    path.write_text(text)
    robot = symbolic.from_urdf(str(path))
    kw = base()
    symbolic.planar_tree(kw["bodies"], kw["params"], gravity=kw["gravity"],
                         forces=kw["forces"], coordinates="absolute",
                         point_forces=kw["point_forces"])
    y = np.array([0.3, -0.2, 0.5, 0.7])
    out = _run(f"""
        import sys, numpy as np
        sys.path.insert(0, {os.path.dirname(__file__)!r})
        import conmech.symbolic.urdf as U, conmech.symbolic.spatial as S
        import conmech.symbolic.tree as T, conmech.symbolic.recursive as R
        def boom(*a, **k):
            raise AssertionError("derivation work on a description hit")
        U.read_urdf = S.build_spatial_tree = T.build_tree = R.derive_recursive = boom
        from conmech import symbolic
        import test_description_cache as t
        r = symbolic.from_urdf({str(path)!r})
        kw = t.base()
        m2 = symbolic.planar_tree(kw["bodies"], kw["params"], gravity=kw["gravity"],
                                  forces=kw["forces"], coordinates="absolute",
                                  point_forces=kw["point_forces"])
        print("description" in symbolic.model_of(r).times,
              "description" in symbolic.model_of(m2).times, [float(x) for x in m2.params])
        y = np.array([0.3, -0.2, 0.5, 0.7])
        print(*symbolic.model_of(r).call("accel", 0.0, y[:2], y[2:]))
    """)
    lines = out.strip().splitlines()
    assert lines[0] == f"True True {list(PARAMS.values())}"
    acc = np.array([float(x) for x in lines[1].split()])
    ref = symbolic.model_of(robot).call("accel", 0.0, y[:2], y[2:])
    assert np.max(np.abs(acc - ref)) == 0.0
