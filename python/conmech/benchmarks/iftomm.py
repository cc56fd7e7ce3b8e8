"""Problems of the IFToMM library of computational benchmark problems for multibody
dynamics (M. Gonzalez, D. Dopico, U. Lugris, J. Cuadrado, "A benchmarking system for MBS
simulation software", Multibody System Dynamics 16 (2006) 179-190; problem specifications
at lim.ii.udc.es/mbsbenchmark), written with :func:`conmech.symbolic.constrained_system`:

- :func:`a01_pendulum`: A01, the planar simple pendulum (a lumped mass of 1 kg on a
  massless link of 1 m, gravity 9.81 N/kg along -y, released at rest from the horizontal
  position x = +1 m, simulated for 2000 s). Its reference is the time history of the
  point's x and y (tolerances 1e-1 low and 1e-3 high precision); here the closed form
  replaces it: with theta the angle from the downward vertical, k = sin(theta0 / 2) and
  w = sqrt(g / L), theta(t) = 2 arcsin(k sn(K(k) - w t | k^2)) (Jacobi's sn, K the
  complete elliptic integral of the first kind), :func:`a01_exact`.

The other problems of the library's group A (A02 N-four-bar, A04 Bricard mechanism, A05
flyball governor) are not provided here.
"""
import numpy as np
import sympy as sp

from .bari import Problem

__all__ = ["a01_pendulum", "a01_exact", "A01_PARAMS"]

#: A01's data (the specification's values)
A01_PARAMS = dict(m=1.0, L=1.0, g=9.81)


def a01_pendulum(flags=None):
    """A01 in Cartesian coordinates q = (x, y): T = m |v|^2 / 2, U = m g y and the link
    constraint (x^2 + y^2 - L^2) / 2 = 0; released at rest from (L, 0), t in [0, 2000].
    The Problem's q_ref and v_ref are the closed form at t = 2000 (:func:`a01_exact`)."""
    from ..symbolic import constrained_system
    m, L, g = sp.symbols("m L g")
    x, y = sp.symbols("x y")
    vx, vy = sp.symbols("x_d y_d")
    T = m * (vx ** 2 + vy ** 2) / 2
    U = m * g * y
    params = {sp.Symbol(k): v for k, v in A01_PARAMS.items()}
    sysm = constrained_system(T, U, [x, y], holonomic=[(x ** 2 + y ** 2 - L ** 2) / 2],
                              params=params, velocities=[vx, vy], simplify=False,
                              flags=flags)
    tf = 2000.0
    q_ref, v_ref = a01_exact(np.array([tf]))
    return Problem("A01 pendulum", sysm, (0.0, tf), np.array([A01_PARAMS["L"], 0.0]),
                   np.zeros(2), q_ref[:, 0], v_ref[:, 0], np.zeros(0))


def a01_exact(t):
    """The closed-form motion of A01 at the times t: positions (2, nt) and velocities
    (2, nt) of the point, from Jacobi's elliptic functions (the argument reduced modulo
    the period 4K, so long times keep their accuracy)."""
    from scipy.special import ellipj, ellipk
    p = A01_PARAMS
    L, g = p["L"], p["g"]
    w = np.sqrt(g / L)
    k = np.sin(np.pi / 4)           # theta0 = pi/2: released from the horizontal
    mpar = k * k
    K = ellipk(mpar)
    u = np.mod(K - w * np.asarray(t, float), 4 * K)
    sn, cn, dn, _ = ellipj(u, mpar)
    theta = 2 * np.arcsin(k * sn)
    # d theta/dt = 2 k cn dn (-w) / sqrt(1 - k^2 sn^2), and sqrt(1 - k^2 sn^2) = dn
    theta_d = -2 * k * w * cn
    q = np.array([L * np.sin(theta), -L * np.cos(theta)])
    v = np.array([L * np.cos(theta) * theta_d, L * np.sin(theta) * theta_d])
    return q, v
