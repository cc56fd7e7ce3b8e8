"""The variational system of a symbolic tree by Taylor's method (conmech.symbolic.taylor_tree_var:
forward-mode differentiation of the articulated-body chain, the tangents further
definitions of the chain) and its recurrences in quadruple precision
(conmech.symbolic.taylor_tree.tree_quad_routine).

- the generated coefficients of [y; Phi] against the core routine's (the state rows) and
  against central differences of the core routine's coefficients in the initial state
  (the Phi rows: d y^[k] / d y0, order by order), for the double pendulum tree, an arm
  on a slide (a prismatic joint, a spring, dampers, a torque in t) and two joints of the
  shipped spatial arm (URDF); a general Phi0 gives the identity's
  coefficients times Phi0;
- stm(method="TAYLOR") of the double pendulum tree (two motions) against the DOP853 STM (an
  independent route: the Jacobian of the accelerations from the tree's own generated
  code), and Liouville's formula in (q, v): the flow is symplectic in (q, p), p = M(q) v,
  so det Phi = det M(q(t0)) / det M(q(t1)); Phi(t1) f(y0) = f(y1) along the solution;
- the double pendulum tree and the double pendulum built from its Lagrangian (the mass
  matrix route, conmech.symbolic.taylor_generalized_var) give the same STM;
- the monodromy of a nonlinear normal mode of the double pendulum tree (found by symmetric
  shooting on the default route) through the Taylor route: the orbit's multipliers, the
  flow direction kept, the DOP853 monodromy;
- quadruple precision: the double and triple pendulum trees by Taylor in real128 against
  Hairer's DOP853 in real128 (a second method on the routine's first coefficient) to
  1e-24, and a double Taylor run's error measured against it;
- a tree with a non-smooth force has no variational part: a ValueError with the reason.
"""
import copy

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

from conmech import symbolic  # noqa: E402
from conmech.stability import stm  # noqa: E402
from conmech.symbolic import planar_tree  # noqa: E402
from conmech.symbolic.pipeline import model_of  # noqa: E402
from conmech.symbolic.taylor_library import TREE_VAR_OPT, _part_flags  # noqa: E402
import symbolic_seeds as seeds  # noqa: E402
import taylor_jets  # noqa: E402
from taylor_jets import check_phi_rows, check_stm, jets  # noqa: E402
from test_taylor_tree import chain  # noqa: E402
from conmech.symbolic.urdf import data_path  # noqa: E402
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402


@pytest.fixture(scope="session", autouse=True)
def symbolic_cache(tmp_path_factory):
    """The test session's one compile cache (symbolic_seeds.use_test_cache)."""
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


def pendulum_tree(N, unit=False):
    """N point masses on rods, pinned at the origin, absolute angles from the downward
    vertical (unit: unit masses and rods, the double pendulum of taylor_jets)."""
    bodies, params, g = chain(N)
    if unit:
        params = {s: (9.81 if s == g else 1.0) for s in params}
    return planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute")


@pytest.fixture(scope="module")
def double_tree():
    return pendulum_tree(2, unit=True)


@pytest.fixture(scope="module")
def triple_tree():
    return pendulum_tree(3)


# ------------------------------------------------------------------ coefficients

def cart_arm():
    """An arm on a horizontal prismatic slide (spring, damper), with an offset and an
    inertia, driven by a torque that depends on t and damped: the joints, forces in q, v
    and t of the branched tree of test_taylor_tree on two bodies."""
    t = dynamicsymbols._t
    x, a = dynamicsymbols("x a")
    m0, m1, I1, k, c, l1, tau0, w, g = sp.symbols("m0 m1 I1 k c l1 tau0 w g")
    bodies = [symbolic.Body("cart", None, "prismatic", x, axis=(1, 0), mass=m0),
              symbolic.Body("arm", "cart", "revolute", a, at=(0.1, 0.2), mass=m1,
                            com=(l1/2, -0.05), inertia=I1)]
    params = {m0: 2.0, m1: 1.0, I1: 0.08, k: 3.0, c: 0.3, l1: 1.0, tau0: 0.5, w: 1.7,
              g: 9.81}
    forces = {"cart": -k*x - c*x.diff(t), a: tau0*sp.sin(w*t) - c*a.diff(t)}
    return planar_tree(bodies, params, gravity=(0, -g), forces=forces)


def two_joint_arm():
    """The first two joints of the shipped seven-joint arm (URDF text: the links and
    joints beyond link2 dropped)."""
    import xml.etree.ElementTree as ET
    root = ET.parse(data_path("arm7.urdf")).getroot()
    keep = {"base", "link1", "link2"}
    for el in list(root):
        if el.tag == "link" and el.get("name") not in keep or \
                el.tag == "joint" and el.find("child").get("link") not in keep:
            root.remove(el)
    return symbolic.from_urdf(ET.tostring(root, encoding="unicode"))


@pytest.mark.parametrize("which", ["double_tree", "cart_arm", "spatial"])
def test_phi_rows_are_the_derivatives_of_the_state_coefficients(which, request):
    """Row block of column c of Phi at order k = d y^[k] / d y0_c: central differences
    (step h, error O(h^2) ~ 1e-10 relative at these orders) of the core routine's
    coefficients, the state rows and Phi's linearity (taylor_jets.check_phi_rows)."""
    if which == "spatial":
        system = two_joint_arm()
        y = np.array([0.2, -0.4, -0.5, 0.3])
    elif which == "cart_arm":
        system = cart_arm()
        y = np.array([0.3, -0.4, 0.5, -0.7])
    else:
        system = request.getfixturevalue(which)
        y = np.array([1.2, -0.4, 0.3, 0.1])
    check_phi_rows(system, y, 8, t0=0.7)


# ------------------------------------------------------------------ integration

def test_taylor_stm_agrees_with_dop853_liouville_and_the_flow(double_tree):
    check_stm(double_tree, [1.2, -0.4, 0.3, 0.1], 5.0)
    check_stm(double_tree, [0.3, 2.5, -1.0, 0.4], 4.0)


def test_a_trees_variational_routine_is_compiled_at_its_own_optimisation(double_tree):
    """A tree's variational library is built with TREE_VAR_OPT in place of -O3 (its
    compile time), a Lagrangian system's and the tree's other parts with the defaults,
    and flags given to the model are kept as given."""
    tree_model = model_of(double_tree)
    flags = _part_flags(tree_model, "var")
    assert TREE_VAR_OPT in flags and "-O3" not in flags
    assert _part_flags(tree_model, "core") is None
    assert _part_flags(model_of(taylor_jets.double_pendulum()), "var") is None
    given = copy.copy(tree_model)
    given.flags = ["-O2", "-fPIC", "-shared"]
    assert _part_flags(given, "var") == given.flags


def test_tree_and_lagrangian_give_the_same_stm(double_tree):
    """The double pendulum as a tree (the articulated-body chain differentiated forward)
    and from its Lagrangian (M da = K Phi solved order by order): one STM."""
    lag = taylor_jets.double_pendulum()
    y0 = [1.2, -0.4, 0.3, 0.1]
    y_tree, phi_tree = stm(double_tree, (0.0, 5.0), y0, method="TAYLOR")
    y_lag, phi_lag = stm(lag, (0.0, 5.0), y0, method="TAYLOR")
    big = np.max(np.abs(phi_lag))
    assert big > 2.0
    assert np.max(np.abs(y_tree - y_lag)) < 1e-9
    assert np.max(np.abs(phi_tree - phi_lag)) < 1e-8*big
    # and their coefficients at a point, order by order, to round-off
    y = np.array(y0)
    _, var_tree = jets(double_tree, y, 12)
    _, var_lag = jets(lag, y, 12)
    scale = np.max(np.abs(var_lag), axis=0)
    assert np.all(np.abs(var_tree - var_lag) <= 1e-13*scale)


def test_monodromy_of_a_normal_mode(double_tree):
    """The in-phase normal mode's Taylor monodromy (taylor_jets): the default route's, the
    flow direction kept, the orbit's multipliers; a stable conservative orbit has them all
    on the unit circle (a pair at 1, a pair of modulus 1)."""
    mu_t = taylor_jets.check_normal_mode_monodromy(double_tree)
    assert np.max(np.abs(np.abs(mu_t) - 1)) < 1e-6


def test_a_non_smooth_tree_has_no_variational_part():
    bodies, params, g = chain(2)
    th = [b.q for b in bodies]
    tree = planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute",
                       forces=[-sp.Abs(th[0]), 0])
    with pytest.raises(ValueError, match="smooth"):
        stm(tree, (0.0, 1.0), [0.3, 0.2, 0.0, 0.1], method="TAYLOR")


# ------------------------------------------------------------------ quadruple precision

@pytest.mark.parametrize("which", ["double_tree", "triple_tree"])
def test_quadruple_precision_agrees_with_dop853_in_real128(which, request):
    system = request.getfixturevalue(which)
    y0 = ["1.2", "-0.4", "0.3", "0.1"] if which == "double_tree" else \
        ["1.2", "0.4", "-0.5", "0", "0.3", "-0.2"]
    taylor_jets.check_quadruple_reference(system, y0, 1e-30, 1e-27, "1e-24")
