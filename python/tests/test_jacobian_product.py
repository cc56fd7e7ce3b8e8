"""The built-ins' structure-aware Jacobian products seen from Python: the STM
of the built-in Arenstorf and Hill systems (integrate_stm through their own J x) agrees
with the 20 variational equations written out in NumPy and integrated as a plain system
(an independent path). Arenstorf's built-in used a finite-difference J before (~1.5e-6)."""
import numpy as np
import pytest

import conmech
from conmech import stability, systems

ARENSTORF_T = 17.0652165601579625588917206249
ARENSTORF_Y0 = np.array([0.994, 0.0, 0.0, -2.00158510637908252240537862224])


def rotating_stm_rhs(grad_hess, c):
    """z' = [f; J Phi] for x'' = U_x + c y', y'' = U_y - c x' (Phi column-major)."""
    def rhs(t, z):
        x, y, u, v = z[:4]
        ux, uy, uxx, uxy, uyy = grad_hess(x, y)
        J = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [uxx, uxy, 0, c], [uxy, uyy, -c, 0.0]])
        phi = z[4:].reshape(4, 4, order="F")
        return np.r_[u, v, ux + c * v, uy - c * u, (J @ phi).ravel(order="F")]
    return rhs


def arenstorf_grad_hess(mu):
    mp = 1.0 - mu

    def gh(x, y):
        x1, x2 = x + mu, x - mp
        s1, s2 = x1 * x1 + y * y, x2 * x2 + y * y
        a1, a2 = mp / s1**1.5, mu / s2**1.5
        b1, b2 = 3 * a1 / s1, 3 * a2 / s2
        return (x - a1 * x1 - a2 * x2, y - a1 * y - a2 * y,
                1 - a1 - a2 + b1 * x1 * x1 + b2 * x2 * x2, (b1 * x1 + b2 * x2) * y,
                1 - a1 - a2 + (b1 + b2) * y * y)
    return gh


def hill_grad_hess(m, kappa):
    def gh(x, y):
        r2 = x * x + y * y
        r3, r5 = r2**1.5, r2**2.5
        return (-kappa * x / r3 + 3 * m * m * x, -kappa * y / r3,
                kappa * (3 * x * x / r5 - 1 / r3) + 3 * m * m, 3 * kappa * x * y / r5,
                kappa * (3 * y * y / r5 - 1 / r3))
    return gh


def reference_stm(rhs, y0, t1):
    r = conmech.solve_ivp(rhs, (0.0, t1), np.r_[y0, np.eye(4).ravel()], method="DOP853",
                          rtol=1e-13, atol=1e-13)
    assert r.success
    return r.y[4:, -1].reshape(4, 4, order="F")


@pytest.mark.parametrize("case", ["arenstorf", "hill"])
def test_builtin_stm_through_jacobian_product(case):
    if case == "arenstorf":
        mu = 0.012277471
        sys_, y0, t1 = systems.arenstorf(mu), ARENSTORF_Y0, ARENSTORF_T
        rhs = rotating_stm_rhs(arenstorf_grad_hess(mu), 2.0)
    else:
        m = 0.080848933808312
        sys_, y0, t1 = systems.hill(m=m), np.array([0.3, 0.0, 0.0, 1.2]), 2.0
        rhs = rotating_stm_rhs(hill_grad_hess(m, 1.0), 2.0 * m)
    ref = reference_stm(rhs, y0, t1)
    mono = stability.monodromy(sys_, y0, t1, rtol=1e-13, atol=1e-13)
    mono = np.asarray(getattr(mono, "M", mono))
    assert np.all(np.isfinite(mono))
    assert np.abs(mono - ref).max() <= 1e-8 * np.abs(ref).max()
