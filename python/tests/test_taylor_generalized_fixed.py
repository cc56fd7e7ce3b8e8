"""The Taylor recurrences of a generalized system M(q) q'' = Q written out for one order
(conmech.symbolic.taylor_generalized_fixed), which solve_ivp, the Propagator and the
Stepper run with method TAYLOR on its first-order view while the routine stays small:

- the written-out routine gives the loop routine's coefficients to the last bit: the
  double pendulum and the cart pendulum (factorisation in scalars), the cart pendulum with
  the factorisation in loops, and a forced, damped cart pendulum whose forces depend on t
  (the time column) at several orders and times;
- a mass matrix that is not positive definite gives NaN coefficients, as the loop
  routine's;
- solve_ivp and the Propagator run it (the first-order view carries it for the order of
  the tolerances) and take the loop routine's steps to the last bit; a routine past the
  source limit (three links at order 18) is not made and the loop routine runs;
- a tree's (its articulated-body chain's recurrences written out as an ode system's, its
  pivots checked at order 0): the loop routine's coefficients to the last bit, NaN for a
  zero mass at the leaf, and made within its own source limit.
"""
import ctypes

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import conmech  # noqa: E402
import conmech.ivp.taylor as ivp_taylor  # noqa: E402
from conmech import symbolic  # noqa: E402
from conmech.ivp.taylor_generalized import first_order_view  # noqa: E402
from conmech.symbolic import build  # noqa: E402
from conmech.symbolic.pipeline import model_of  # noqa: E402
from conmech.symbolic.printer import _names  # noqa: E402
from conmech.symbolic.taylor import FIXED_EXTRA_FLAGS  # noqa: E402
from conmech.symbolic.taylor_generalized import (generalized_decomposition,  # noqa: E402
                                                 generalized_procedures)
from conmech.symbolic.taylor_generalized_fixed import generalized_fixed_source  # noqa: E402
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402
import taylor_jets  # noqa: E402
from taylor_jets import coefficients, module_source  # noqa: E402


def forced_cart():
    """The cart pendulum pushed by F cos(w t) and damped at its joint: Q depends on t."""
    t = dynamicsymbols._t
    x, th = dynamicsymbols("x theta")
    g, F, w, c = sp.symbols("g F_push w_push c_joint")
    T = x.diff(t)**2 + sp.cos(th)*x.diff(t)*th.diff(t) + th.diff(t)**2/2
    return symbolic.lagrangian_system(T - g*sp.cos(th), [x, th],
                                      params={g: 9.81, F: 0.7, w: 1.3, c: 0.2},
                                      forces=[F*sp.cos(w*t), -c*th.diff(t)])


def _fixed_address(system, order, write_out=None):
    d = model_of(system).derived
    src = generalized_fixed_source(d, order, write_out=write_out)
    lib = ctypes.CDLL(build.compile_source(src, flags=build.FFLAGS + FIXED_EXTRA_FLAGS)[0])
    return lib, ctypes.cast(lib.conmech_taylor_fixed, ctypes.c_void_p).value


def _loop_address(system, write_out=None):
    """The loop routine of the view (the library's), or one built with the factorisation
    in loops (write_out False)."""
    view = first_order_view(system)
    if write_out is None:
        return None, conmech.compiled.function_address(view.taylor["jet"])
    d = model_of(system).derived
    g, _ = generalized_decomposition(d)
    lines = generalized_procedures(g, _names(d), write_out=write_out, npar=len(d.params))
    src = module_source("conmech_tgen_fixed_loops", lines)
    path, _ = build.compile_source(src, None, ["taylor", "taylor_info", "taylor_rhs"])
    return build.load(path, ["taylor", "taylor_info", "taylor_rhs"])[0], \
        build.load(path, ["taylor"])[1]["taylor"]


@pytest.mark.parametrize("name, y, orders, write_out", [
    ("double_pendulum", [1.2, -0.4, 0.3, 0.1], (2, 9, 18), None),
    ("cart", [0.3, np.pi - 0.7, -0.2, 0.5], (18,), None),
    ("cart", [0.3, np.pi - 0.7, -0.2, 0.5], (14,), False),
    ("forced_cart", [0.1, np.pi - 0.4, 0.25, -0.3], (5, 18), None)])
def test_written_out_routine_gives_the_loop_coefficients(name, y, orders, write_out):
    system = {"double_pendulum": taylor_jets.double_pendulum, "cart": taylor_jets.cart_pendulum,
              "forced_cart": forced_cart}[name]()
    view = first_order_view(system)
    nw = view.taylor["nw"]
    keep, loop = _loop_address(system, write_out)
    for order in orders:
        lib, fixed = _fixed_address(system, order, write_out)
        for t in (0.0, 0.37):
            a = coefficients(fixed, nw, view.params, y, order, t)
            b = coefficients(loop, nw, view.params, y, order, t)
            assert np.all(np.isfinite(a)) and np.array_equal(a, b), (order, t)
            # a genuine expansion: the last order does not vanish
            assert np.max(np.abs(a[:, order])) > 0.0
            # the routine answers its own order only (w left as it was)
            if order > 2:
                c = coefficients(fixed, nw, view.params, y, order - 1, t)
                assert np.array_equal(c[:, 1:], np.zeros_like(c[:, 1:]))
    if name == "forced_cart":       # the forcing reaches the coefficients through t
        assert not np.array_equal(coefficients(fixed, nw, view.params, y, 18, 0.0),
                                  coefficients(fixed, nw, view.params, y, 18, 1.0))


def test_mass_matrix_not_positive_definite_gives_nan_coefficients():
    t = dynamicsymbols._t
    q = dynamicsymbols("q")
    system = symbolic.lagrangian_system(q**2*q.diff(t)**2/2, [q])
    view = first_order_view(system)
    _, fixed = _fixed_address(system, 12)
    a = coefficients(fixed, view.taylor["nw"], view.params, [0.0, 1.0], 12)
    b = coefficients(conmech.compiled.function_address(view.taylor["jet"]), view.taylor["nw"],
                     view.params, [0.0, 1.0], 12)
    assert np.all(np.isnan(a[:, 1:])) and np.all(np.isnan(b[:, 1:]))
    assert np.array_equal(a[:, 0], [0.0, 1.0])


def _loop_only(monkeypatch):
    monkeypatch.setattr(ivp_taylor, "_fixed_system", lambda fun, model, order: fun)
    monkeypatch.setattr(ivp_taylor, "_SYSTEMS", {})


def test_solve_ivp_and_propagator_run_the_written_out_routine(monkeypatch):
    system = taylor_jets.double_pendulum()
    y0 = [1.2, -0.4, 0.3, 0.1]
    tol = 1e-12
    fixed = ivp_taylor.with_fixed_order(first_order_view(system), tol, tol)
    assert "jet_fixed" in fixed.taylor and fixed.taylor["order"] == ivp_taylor.taylor_order(tol)
    r = conmech.solve_ivp(system, (0, 6), y0, method="TAYLOR", rtol=tol, atol=tol)
    p = conmech.Propagator(system, y0, method="TAYLOR", rtol=tol, atol=tol)
    assert "jet_fixed" in p._packed[0].taylor
    assert p.propagate_until(6.0).success
    _loop_only(monkeypatch)
    assert "jet_fixed" not in ivp_taylor.with_fixed_order(first_order_view(system), tol,
                                                          tol).taylor
    r2 = conmech.solve_ivp(system, (0, 6), y0, method="TAYLOR", rtol=tol, atol=tol)
    p2 = conmech.Propagator(system, y0, method="TAYLOR", rtol=tol, atol=tol)
    assert "jet_fixed" not in p2._packed[0].taylor
    assert p2.propagate_until(6.0).success
    assert r.success and r.naccept > 50
    assert np.array_equal(r.t, r2.t) and np.array_equal(r.y, r2.y)
    assert (r.nfev, r.naccept, r.nreject) == (r2.nfev, r2.naccept, r2.nreject)
    assert np.array_equal(p.y, p2.y) and np.array_equal(p.y, r.y[:, -1])


def test_a_large_routine_is_not_made():
    """Three links at order 18: the written-out source passes the limit (its code would
    leave the instruction caches), the loop routine runs."""
    system = taylor_jets.pendulum_chain(3)
    d = model_of(system).derived
    assert len(generalized_fixed_source(d, 18)) > ivp_taylor.FIXED_MAX_SOURCE_GENERALIZED
    view = first_order_view(system)
    assert "jet_fixed" not in ivp_taylor.with_fixed_order(view, 1e-12, 1e-12).taylor
    # a low order stays below it
    assert len(generalized_fixed_source(d, 9)) <= ivp_taylor.FIXED_MAX_SOURCE_GENERALIZED
    # the double pendulum: written out at order 18 (1e-12), not at order 24 (1e-16), where
    # the loop routine was measured faster
    double = taylor_jets.double_pendulum()
    view = first_order_view(double)
    assert "jet_fixed" in ivp_taylor.with_fixed_order(view, 1e-12, 1e-12).taylor
    assert "jet_fixed" not in ivp_taylor.with_fixed_order(view, 1e-16, 1e-16).taylor


def test_tree_written_out_routine_gives_the_loop_coefficients():
    """A tree's recurrences (its articulated-body chain) written out: the loop routine's
    coefficients to the last bit, and NaN from order 1 on when a pivot is not positive (a
    zero mass at the leaf), as the loop routine gives them."""
    from conmech.symbolic.taylor_generalized_fixed import tree_fixed_source
    system = taylor_jets.tree_chain(2)
    d = model_of(system).derived
    y = [0.3, -0.2, 0.25, -0.1]
    for leaf in (None, 0.0):
        view = first_order_view(system if leaf is None else system.with_params(m2=leaf))
        nw = view.taylor["nw"]
        loop = conmech.compiled.function_address(view.taylor["jet"])
        for order in (8, 14):
            src = tree_fixed_source(d, order)
            lib = ctypes.CDLL(build.compile_source(src, flags=build.FFLAGS +
                                                   FIXED_EXTRA_FLAGS)[0])
            fixed = ctypes.cast(lib.conmech_taylor_fixed, ctypes.c_void_p).value
            a = coefficients(fixed, nw, view.params, y, order, 0.2)
            b = coefficients(loop, nw, view.params, y, order, 0.2)
            if leaf is None:
                assert np.all(np.isfinite(a)) and np.array_equal(a, b), order
                assert np.max(np.abs(a[:, order])) > 0.0
            else:
                assert np.all(np.isnan(a[:, 1:])) and np.all(np.isnan(b[:, 1:]))


def test_tree_routine_made_within_its_limit():
    """Two point masses as a tree: written out at order 14 (108 kB of source), not at
    order 24 (274 kB, past FIXED_MAX_SOURCE_TREE: the loop routine runs)."""
    from conmech.symbolic.taylor_generalized_fixed import tree_fixed_source
    system = taylor_jets.tree_chain(2)
    d = model_of(system).derived
    view = first_order_view(system)
    assert len(tree_fixed_source(d, 14)) <= ivp_taylor.FIXED_MAX_SOURCE_TREE
    assert "jet_fixed" in ivp_taylor.with_fixed_order(view, 1e-8, 1e-8).taylor
    assert len(tree_fixed_source(d, 24)) > ivp_taylor.FIXED_MAX_SOURCE_TREE
    assert "jet_fixed" not in ivp_taylor.with_fixed_order(view, 1e-16, 1e-16).taylor
    r = conmech.solve_ivp(system, (0, 2), [0.3, -0.2, 0.25, -0.1], method="TAYLOR",
                          rtol=1e-8, atol=1e-8)
    assert r.success and r.nfev == r.naccept + r.nreject + 1
