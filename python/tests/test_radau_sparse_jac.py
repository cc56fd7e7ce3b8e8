"""Radau with a callable ``jac`` that returns a scipy.sparse matrix: the first value's
structure becomes the Jacobian's pattern and every value reaches Fortran as its nnz
numbers (flat_sparse_jac.f90), never as an n x n array. Checked on the one-dimensional
Brusselator (Hairer & Wanner II, section IV.1) against SciPy's Radau with the same
sparse jac, against conmech's dense path with the same Jacobian, and for the rules of
the fixed pattern."""
import numpy as np
import pytest
import scipy.integrate
import scipy.sparse as sp

import conmech
from test_radau_sparse import ALPHA, brusselator


def brusselator_jac(nb):
    """The exact Jacobian of test_radau_sparse.brusselator(nb) as a function returning a
    CSC matrix (the structure of the pattern there: tridiagonal blocks and identities)."""
    c = ALPHA * (nb + 1) ** 2
    off = np.full(nb - 1, c)

    def jac(t, y):
        u, v = y[:nb], y[nb:]
        uu = sp.diags([off, 2 * u * v - 4.0 - 2 * c, off], [-1, 0, 1])
        uv = sp.diags(u * u)
        vu = sp.diags(3.0 - 2 * u * v)
        vv = sp.diags([off, -u * u - 2 * c, off], [-1, 0, 1])
        return sp.bmat([[uu, uv], [vu, vv]], format="csc")
    return jac


class NoDense(sp.csc_matrix):
    """A CSC matrix that refuses to become dense: proves the values are taken from its
    sparse storage only."""

    def toarray(self, *a, **k):
        raise AssertionError("densified")

    todense = toarray


def _end_error(a, b):
    return np.max(np.abs(a.y[:, -1] - b.y[:, -1]) / (1e-6 + np.abs(b.y[:, -1])))


@pytest.mark.parametrize("nb", [100, 1000])
def test_sparse_callable_jac_agrees_with_scipy(nb):
    """n = 200 and 2000: the same problem, tolerance and sparse jac in SciPy's Radau
    (SuperLU); two implementations of Radau IIA (Hairer's RADAU5 step control here,
    SciPy's own there) agree at the end to the tolerance and take about as many steps."""
    f, _, y0 = brusselator(nb)
    jac = brusselator_jac(nb)
    kw = dict(method="Radau", rtol=1e-6, atol=1e-6, jac=jac)
    rc = conmech.solve_ivp(f, [0, 10], y0, **kw)
    rs = scipy.integrate.solve_ivp(f, [0, 10], y0, **kw)
    assert rc.success and rs.success
    # measured: end points within 4e-9 (relative), 121 vs 123-124 steps, njev 20-23 vs
    # 21-22, nlu 88-90 vs 84-86
    assert _end_error(rc, rs) < 1e-6
    assert abs(rc.t.size - rs.t.size) <= 0.05 * rs.t.size
    assert abs(rc.njev - rs.njev) <= 0.15 * rs.njev + 1
    assert abs(rc.nlu - rs.nlu) <= 0.10 * rs.nlu


def test_sparse_values_equal_the_dense_path():
    """The same Jacobian as a sparse matrix (sparse LUs on its pattern) and as a dense
    array (LAPACK's LUs): the same steps, Jacobians and LUs, states equal to rounding."""
    nb = 150                                     # n = 300: both paths fit
    f, _, y0 = brusselator(nb)
    jac = brusselator_jac(nb)
    kw = dict(method="Radau", rtol=1e-6, atol=1e-6)
    rs = conmech.solve_ivp(f, [0, 10], y0, jac=jac, **kw)
    rd = conmech.solve_ivp(f, [0, 10], y0, jac=lambda t, y: jac(t, y).toarray(), **kw)
    assert rs.success and rd.success
    assert (rs.nfev, rs.njev, rs.nlu, rs.t.size) == (rd.nfev, rd.njev, rd.nlu, rd.t.size)
    np.testing.assert_allclose(rs.t, rd.t, rtol=1e-9)
    np.testing.assert_allclose(rs.y, rd.y, rtol=1e-8, atol=1e-11)


def test_values_never_densified_and_jac_called_njev_times():
    nb = 1000
    f, _, y0 = brusselator(nb)
    jac = brusselator_jac(nb)
    calls = []

    def sparse_only(t, y):
        calls.append(t)
        return NoDense(jac(t, y))
    r = conmech.solve_ivp(f, [0, 10], y0, method="Radau", rtol=1e-6, atol=1e-6,
                          jac=sparse_only)
    assert r.success, r.message
    # the evaluation before the run serves the first Jacobian: one call per njev
    assert len(calls) == r.njev
    ref = conmech.solve_ivp(f, [0, 10], y0, method="Radau", rtol=1e-6, atol=1e-6, jac=jac)
    np.testing.assert_array_equal(r.y, ref.y)


def test_later_values_in_other_structures_land_on_the_pattern():
    """After a first value with the full structure, values with an entry dropped
    (eliminated zero), as a COO matrix with duplicate entries, or as a dense array land on
    the first pattern: the run equals, bit for bit, the one given the same values with
    the full structure every time."""
    nb = 100
    f, _, y0 = brusselator(nb)
    jac = brusselator_jac(nb)

    def zeroed(t, y):                # J with its entry (0, 1) zero (kept explicitly)
        m = jac(t, y)
        m[0, 1] = 0.0
        return m

    def in_turn(forms):
        calls = []

        def j(t, y):
            calls.append(t)
            if len(calls) == 1:
                return jac(t, y)
            return forms[len(calls) % len(forms)](zeroed(t, y))
        return j

    def dropped(m):
        m = m.copy()
        m.eliminate_zeros()
        return m

    def duplicated(m):
        c = m.tocoo()
        return sp.coo_matrix((np.r_[c.data / 2, c.data / 2],
                              (np.r_[c.row, c.row], np.r_[c.col, c.col])), shape=m.shape)
    kw = dict(method="Radau", rtol=1e-6, atol=1e-6)
    r = conmech.solve_ivp(f, [0, 2], y0, jac=in_turn([dropped, duplicated,
                                                        lambda m: m.toarray()]), **kw)
    ref = conmech.solve_ivp(f, [0, 2], y0, jac=in_turn([lambda m: m]), **kw)
    assert r.success and ref.success
    assert r.njev > 3
    assert (r.njev, r.nlu) == (ref.njev, ref.nlu)
    np.testing.assert_array_equal(r.t, ref.t)
    np.testing.assert_array_equal(r.y, ref.y)


def test_an_entry_outside_the_first_pattern_is_refused():
    nb = 100
    f, _, y0 = brusselator(nb)
    jac = brusselator_jac(nb)
    first = []

    def growing(t, y):
        m = jac(t, y)
        if not first:
            first.append(t)
            return m
        m = m.tolil()
        m[0, nb + 5] = 1.0                         # not in the first structure
        return m.tocsc()
    with pytest.raises(ValueError, match=r"\(0, 105\) outside the sparsity pattern"):
        conmech.solve_ivp(f, [0, 10], y0, method="Radau", jac=growing)


def test_bad_shapes_and_exceptions_reach_the_caller():
    nb = 100
    f, _, y0 = brusselator(nb)
    with pytest.raises(ValueError, match="expected to have shape"):
        conmech.solve_ivp(f, [0, 1], y0, method="Radau",
                          jac=lambda t, y: sp.identity(2 * nb + 1, format="csc"))
    # a later sparse value of the wrong shape
    jac0 = brusselator_jac(nb)
    seen = []

    def shrinking(t, y):
        seen.append(t)
        return jac0(t, y) if len(seen) == 1 else sp.identity(2 * nb - 1, format="csc")
    with pytest.raises(ValueError, match=r"expected to have shape \(200, 200\)"):
        conmech.solve_ivp(f, [0, 10], y0, method="Radau", jac=shrinking)

    class Boom(Exception):
        pass
    jac = brusselator_jac(nb)
    n_calls = []

    def failing(t, y):
        n_calls.append(t)
        if len(n_calls) > 2:
            raise Boom("from jac")
        return jac(t, y)
    with pytest.raises(Boom, match="from jac"):
        conmech.solve_ivp(f, [0, 10], y0, method="Radau", jac=failing)


def test_args_reach_the_sparse_jac():
    nb = 100
    f, _, y0 = brusselator(nb)
    jac = brusselator_jac(nb)
    r1 = conmech.solve_ivp(lambda t, y, s: s * f(t, y), [0, 1], y0, method="Radau",
                           jac=lambda t, y, s: s * jac(t, y), args=(1.0,))
    r2 = conmech.solve_ivp(f, [0, 1], y0, method="Radau", jac=jac)
    np.testing.assert_array_equal(r1.y, r2.y)


def test_radau_stepper_with_sparse_jac_matches_solve_ivp():
    nb = 1000
    f, _, y0 = brusselator(nb)
    jac = brusselator_jac(nb)
    st = conmech.Radau(f, 0.0, y0, 2.0, rtol=1e-5, atol=1e-5, jac=jac)
    ts = [0.0]
    while st.status == "running":
        assert st.step() is None
        ts.append(st.t)
    r = conmech.solve_ivp(f, [0, 2], y0, method="Radau", rtol=1e-5, atol=1e-5, jac=jac)
    assert st.status == "finished"
    np.testing.assert_array_equal(np.array(ts), r.t)
    np.testing.assert_array_equal(st.y, r.y[:, -1])
    assert (st.njev, st.nlu) == (r.njev, r.nlu)
    # the continuous extension of the last step ends at the state
    np.testing.assert_allclose(st.dense_output()(st.t), st.y, rtol=1e-12, atol=1e-14)
