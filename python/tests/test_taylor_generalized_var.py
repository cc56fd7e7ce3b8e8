"""The variational system of a generalized system M(q) q'' = Q by Taylor's method
(conmech.symbolic.taylor_generalized_var: the columns of Phi further right-hand sides of
the series-Cholesky solve with M, M da = (dQ/dy - dM/dy . a) Phi), and its recurrences in
quadruple precision (conmech.symbolic.taylor_generalized.generalized_quad_routine).

- the generated coefficients of [y; Phi] against the core routine's (the state rows) and
  against central differences of the core routine's coefficients in the initial state
  (the Phi rows: d y^[k] / d y0, order by order), for a system where every entry of M but
  one varies and the forces hold velocity products, and for the double pendulum; the
  factorisation in loops gives the written-out coefficients;
- stm(method="TAYLOR") of the double pendulum and the cart pendulum against the DOP853
  STM (an independent route: the Jacobian of the accelerations from its own generated
  code), and Liouville's formula in (q, v): the flow is symplectic in (q, p), p = M(q) v,
  so det Phi = det M(q(t0)) / det M(q(t1));
- the monodromy of a nonlinear normal mode of the double pendulum (found by symmetric
  shooting on the default route) through the Taylor route: the orbit's multipliers, the
  flow direction kept (Phi f(y0) = f(y0)), the DOP853 monodromy;
- quadruple precision: the double pendulum by Taylor in real128 against Hairer's DOP853 in
  real128 (a second method on the routine's first coefficient) to 1e-23, and the double
  Taylor run at 1e-13 to 1e-12.
"""
import numpy as np
import pytest

sp = pytest.importorskip("sympy")

from conmech import symbolic  # noqa: E402
from conmech.symbolic import build  # noqa: E402
from conmech.symbolic.pipeline import model_of  # noqa: E402
from conmech.symbolic.printer import _names  # noqa: E402
from conmech.symbolic.taylor_generalized_var import (variational_decomposition,  # noqa: E402
                                                     variational_procedures)
import taylor_jets  # noqa: E402
from taylor_jets import (check_phi_rows, check_stm, coefficients, jets,  # noqa: E402
                         module_source)



@pytest.fixture(scope="module")
def rational():
    """M(q) = [[1 + q2^2, q1], [q1, 2]], U = (q1^2 + q2^2)/2 + q1 q2^2 / 3."""
    t = sp.Symbol("t")
    q1, q2 = sp.Function("q1")(t), sp.Function("q2")(t)
    M = sp.Matrix([[1 + q2**2, q1], [q1, 2]])
    qd = sp.Matrix([q1.diff(t), q2.diff(t)])
    L = (qd.T*M*qd)[0]/2 - (q1**2 + q2**2)/2 - q1*q2**2/3
    return symbolic.lagrangian_system(L, [q1, q2])


@pytest.fixture(scope="module")
def cart():
    return taylor_jets.cart_pendulum()


@pytest.fixture(scope="module")
def double_pendulum():
    return taylor_jets.double_pendulum()


# ------------------------------------------------------------------ coefficients

@pytest.mark.parametrize("which", ["rational", "double_pendulum"])
def test_phi_rows_are_the_derivatives_of_the_state_coefficients(which, request):
    """Row block of column c of Phi at order k = d y^[k] / d y0_c: central differences
    (step h, error O(h^2) ~ 1e-10 relative at these orders) of the core routine's
    coefficients, the state rows and Phi's linearity (taylor_jets.check_phi_rows)."""
    system = request.getfixturevalue(which)
    y = np.array([0.5, -1/3, 0.2, 0.75]) if which == "rational" else \
        np.array([1.2, -0.4, 0.3, 0.1])
    check_phi_rows(system, y, 10)


def test_factorisation_in_loops_gives_the_written_out_coefficients(cart):
    d = model_of(cart).derived
    g, why = variational_decomposition(d)
    assert why is None
    lines = variational_procedures(g, _names(d), write_out=False, npar=len(d.params))
    src = module_source("conmech_tgen_var_loop_form", lines)
    assert "do jj = 1, 2" in src
    entries = ["taylor_var", "taylor_var_info"]
    path, _ = build.compile_source(src, None, entries)
    lib, addr = build.load(path, entries)
    y = np.array([0.3, np.pi - 0.7, -0.2, 0.5])
    z = np.concatenate([y, np.eye(4).ravel()])
    loops = coefficients(addr["taylor_var"], g.ncol, cart.params, z, 16)
    written = jets(cart, y, 16)[1]
    assert np.all(np.isfinite(written))
    assert np.allclose(loops, written, rtol=1e-13, atol=1e-13*np.max(np.abs(written)))


# ------------------------------------------------------------------ integration

def test_taylor_stm_agrees_with_dop853_liouville_and_the_flow(cart, double_pendulum):
    check_stm(double_pendulum, [1.2, -0.4, 0.3, 0.1], 5.0)
    check_stm(cart, [0.0, np.pi - 0.7, 0.3, 0.0], 3.0)


def test_monodromy_of_a_normal_mode(double_pendulum):
    """The in-phase normal mode's Taylor monodromy (taylor_jets): the default route's, the
    flow direction kept, the orbit's multipliers."""
    taylor_jets.check_normal_mode_monodromy(double_pendulum)


def test_quadruple_precision_agrees_with_dop853_in_real128(double_pendulum):
    taylor_jets.check_quadruple_reference(double_pendulum, ["1.2", "-0.4", "0.3", "0.1"],
                                          1e-28, 1e-25, "1e-23", moved=2)
