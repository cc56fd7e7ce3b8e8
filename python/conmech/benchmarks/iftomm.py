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

- :func:`a02_n_four_bar`: A02, N parallelogram four-bar linkages in a row, which pass
  singular configurations; reference: its one-degree-of-freedom closed form,
  :func:`a02_exact` (the published data file is not used).

The library's A04 (Bricard mechanism) and A05 (flyball governor) are not provided here.
"""
import numpy as np
import sympy as sp

from ..symbolic import constrained_system
from .bari import Problem

__all__ = ["a01_pendulum", "a01_exact", "A01_PARAMS", "a02_n_four_bar", "a02_exact", "A02_PARAMS"]

#: A01's data (the specification's values)
A01_PARAMS = dict(m=1.0, L=1.0, g=9.81)


def a01_pendulum(flags=None):
    """A01 in Cartesian coordinates q = (x, y): T = m |v|^2 / 2, U = m g y and the link
    constraint (x^2 + y^2 - L^2) / 2 = 0; released at rest from (L, 0), t in [0, 2000].
    The Problem's q_ref and v_ref are the closed form at t = 2000 (:func:`a01_exact`)."""
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


#: A02's data: N windows, links of length L and mass m (uniform rods)
A02_PARAMS = dict(m=1.0, L=1.0, g=9.81)


def a02_n_four_bar(N=40, flags=None):
    """A02, the assembly of N parallelogram four-bar linkages (2N + 1 uniform rods of 1 m
    and 1 kg: N + 1 cranks pivoted at (i L, 0), i = 0..N, and N couplers, coupler i joining
    the tips of cranks i - 1 and i), gravity 9.81 along -y, 20 s. Coordinates: the crank
    angles phi_0..phi_N and the coupler angles psi_1..psi_N (from the x axis); 2N loop
    constraints (the coupler's far end on the next crank's tip); the mass matrix depends on
    the angles (each coupler's centre moves with the crank it hangs on). Start: cranks
    vertical (phi = pi/2, couplers horizontal), the tip B0 of the first crank moving at
    1 m/s along +x. The motion then stays a parallelogram (one degree of freedom) and
    passes the horizontal position, where the constraints become dependent (N + 1 degrees
    of freedom instantaneously), twice per revolution: :func:`a02_exact` is its closed
    form. The Problem's q_ref, v_ref are the position and velocity of B0 (not q) from the
    closed form at t = 20."""
    m, L, g = sp.symbols("m L g")
    phi = sp.symbols(f"phi0:{N + 1}")
    psi = sp.symbols(f"psi1:{N + 1}")
    dphi = sp.symbols(f"phi0:{N + 1}_d")
    dpsi = sp.symbols(f"psi1:{N + 1}_d")
    T, U = 0, 0
    tip = []
    for i in range(N + 1):       # cranks: rotation about the pivot (i L, 0)
        T += m * L ** 2 / 3 * dphi[i] ** 2 / 2
        U += m * g * L / 2 * sp.sin(phi[i])
        tip.append((i * L + L * sp.cos(phi[i]), L * sp.sin(phi[i]),
                    -L * sp.sin(phi[i]) * dphi[i], L * sp.cos(phi[i]) * dphi[i]))
    hol = []
    for i in range(1, N + 1):    # coupler i from tip i-1, angle psi_i
        x0, y0, vx0, vy0 = tip[i - 1]
        c, s = sp.cos(psi[i - 1]), sp.sin(psi[i - 1])
        vcx = vx0 - L / 2 * s * dpsi[i - 1]
        vcy = vy0 + L / 2 * c * dpsi[i - 1]
        T += m * (vcx ** 2 + vcy ** 2) / 2 + m * L ** 2 / 12 * dpsi[i - 1] ** 2 / 2
        U += m * g * (y0 + L / 2 * s)
        hol += [x0 + L * c - tip[i][0], y0 + L * s - tip[i][1]]
    params = {sp.Symbol(k): v for k, v in A02_PARAMS.items()}
    q = list(phi) + list(psi)
    sysm = constrained_system(T, U, q, holonomic=hol, params=params,
                              velocities=list(dphi) + list(dpsi), simplify=False,
                              flags=flags)
    L_ = A02_PARAMS["L"]
    q0 = np.concatenate([np.full(N + 1, np.pi / 2), np.zeros(N)])
    v0 = np.concatenate([np.full(N + 1, -1.0 / L_), np.zeros(N)])
    tf = 20.0
    b_ref, bv_ref = a02_exact(np.array([tf]), N)
    return Problem(f"A02 N-four-bar (N = {N})", sysm, (0.0, tf), q0, v0, b_ref[:, 0],
                   bv_ref[:, 0], np.zeros(0))


def a02_exact(t, N=40):
    """The closed-form motion of A02 at the times t: the position (2, nt) and velocity
    (2, nt) of B0, the tip of the first crank. Every crank turns by the same angle phi and
    the couplers translate, so T = I phi'^2 / 2 with I = m L^2 ((N + 1)/3 + N) and U = m g
    L sin(phi) ((N + 1)/2 + N): a pendulum in theta = phi + pi/2 with w^2 = (g/L)((N + 1)/2
    + N)/((N + 1)/3 + N), released inverted with theta' = -1/L and going over the top:
    theta = 2 am(K(k) - W t / 2 | k) with W^2 = theta'(0)^2 + 4 w^2 and k = 4 w^2 / W^2
    (Jacobi's amplitude, the argument reduced modulo 2K)."""
    from scipy.special import ellipj, ellipk
    p = A02_PARAMS
    L, g = p["L"], p["g"]
    w2 = g / L * ((N + 1) / 2 + N) / ((N + 1) / 3 + N)
    th_d0 = -1.0 / L
    W = np.sqrt(th_d0 ** 2 + 4 * w2)
    mpar = 4 * w2 / W ** 2
    K = ellipk(mpar)
    u = K - W * np.asarray(t, float) / 2
    n = np.floor(u / (2 * K))
    _, _, dn, ph = ellipj(u - 2 * K * n, mpar)
    theta = 2 * (ph + n * np.pi)
    theta_d = -W * dn
    phi = theta - np.pi / 2
    b = np.array([L * np.cos(phi), L * np.sin(phi)])
    bv = np.array([-L * np.sin(phi) * theta_d, L * np.cos(phi) * theta_d])
    return b, bv
