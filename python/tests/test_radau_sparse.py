"""Radau's sparse LU path (jac_sparsity or a constant sparse jac, n >= 100, at most 10%
dense) on the one-dimensional Brusselator (Hairer & Wanner II, section IV.1) and a heat
equation: the same steps, Jacobians and LUs as the dense path where both fit, and SciPy's
Radau (SuperLU) with the same sparsity where only the sparse one does."""
import numpy as np
import pytest
import scipy.integrate
import scipy.sparse as sp

import conmech

ALPHA = 1.0 / 50.0


def brusselator(nb):
    """u_i = y[i], v_i = y[nb + i] (blocks: the pattern is not banded), u = 1, v = 3 at
    both ends; its pattern and initial state."""
    c = ALPHA * (nb + 1) ** 2

    def f(t, y):
        u, v = y[:nb], y[nb:]
        ue = np.concatenate(([1.0], u, [1.0]))
        ve = np.concatenate(([3.0], v, [3.0]))
        du = 1.0 + u * u * v - 4.0 * u + c * (ue[:-2] - 2.0 * u + ue[2:])
        dv = 3.0 * u - u * u * v + c * (ve[:-2] - 2.0 * v + ve[2:])
        return np.concatenate((du, dv))
    tri = sp.diags([np.ones(nb - 1), np.ones(nb), np.ones(nb - 1)], [-1, 0, 1])
    eye = sp.identity(nb)
    pattern = sp.bmat([[tri, eye], [eye, tri]]).tocsc()
    x = np.arange(1, nb + 1) / (nb + 1)
    y0 = np.concatenate((1.0 + np.sin(2 * np.pi * x), np.full(nb, 3.0)))
    return f, pattern, y0


def test_sparse_and_dense_paths_take_the_same_steps():
    f, pattern, y0 = brusselator(150)            # n = 300: both paths fit
    kw = dict(method="Radau", rtol=1e-6, atol=1e-6)
    rs = conmech.solve_ivp(f, [0, 10], y0, jac_sparsity=pattern, **kw)
    rd = conmech.solve_ivp(f, [0, 10], y0, **kw)    # dense differences and LUs
    assert rs.success and rd.success
    # grouped differences give the dense quotients on the pattern (zero elsewhere), so
    # the two paths differ only in the rounding of the LUs
    assert (rs.njev, rs.nlu, rs.t.size) == (rd.njev, rd.nlu, rd.t.size)
    assert rs.nfev < rd.nfev
    np.testing.assert_allclose(rs.t, rd.t, rtol=1e-8)
    np.testing.assert_allclose(rs.y, rd.y, rtol=1e-7, atol=1e-10)


@pytest.mark.parametrize("nb", [5000])
def test_large_sparse_brusselator_agrees_with_scipy(nb):
    f, pattern, y0 = brusselator(nb)             # n = 10,000: no dense LU would fit
    kw = dict(method="Radau", rtol=1e-6, atol=1e-6, jac_sparsity=pattern)
    rc = conmech.solve_ivp(f, [0, 10], y0, **kw)
    rs = scipy.integrate.solve_ivp(f, [0, 10], y0, **kw)
    assert rc.success and rs.success
    # two independent implementations at rtol 1e-6: the end points agree to the tolerance
    err = np.max(np.abs(rc.y[:, -1] - rs.y[:, -1]) / (1e-6 + np.abs(rs.y[:, -1])))
    assert err < 1e-4
    # and the effort is SciPy's (the same step control): within 25%
    assert abs(rc.t.size - rs.t.size) <= 0.25 * rs.t.size
    assert abs(rc.nlu - rs.nlu) <= 0.25 * rs.nlu


def test_constant_sparse_jac_heat_equation():
    """y' = A y, A the 1-D Laplacian (n = 2000): the exact solution along A's eigenvector
    sin(k pi x) decays as exp(lambda t); a constant sparse jac takes the sparse path."""
    n = 2000
    h = 1.0 / (n + 1)
    a = sp.diags([np.ones(n - 1), -2 * np.ones(n), np.ones(n - 1)], [-1, 0, 1]).tocsc() / h**2
    x = np.arange(1, n + 1) * h
    y0 = np.sin(np.pi * x)
    lam = -4.0 / h**2 * np.sin(np.pi * h / 2) ** 2
    r = conmech.solve_ivp(lambda t, y: a @ y, [0, 0.1], y0, method="Radau", jac=a,
                          rtol=1e-8, atol=1e-10)
    assert r.success and r.njev == 0
    np.testing.assert_allclose(r.y[:, -1], y0 * np.exp(lam * 0.1), rtol=0, atol=1e-8)
    s = scipy.integrate.solve_ivp(lambda t, y: a @ y, [0, 0.1], y0, method="Radau", jac=a,
                                  rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(r.y[:, -1], s.y[:, -1], rtol=0, atol=1e-8)


def test_radau_stepper_with_sparsity_matches_solve_ivp():
    f, pattern, y0 = brusselator(1000)
    st = conmech.Radau(f, 0.0, y0, 2.0, rtol=1e-5, atol=1e-5, jac_sparsity=pattern)
    ts = [0.0]
    while st.status == "running":
        st.step()
        ts.append(st.t)
    r = conmech.solve_ivp(f, [0, 2], y0, method="Radau", rtol=1e-5, atol=1e-5,
                          jac_sparsity=pattern)
    assert st.status == "finished"
    np.testing.assert_array_equal(np.array(ts), r.t)
    np.testing.assert_array_equal(st.y, r.y[:, -1])
