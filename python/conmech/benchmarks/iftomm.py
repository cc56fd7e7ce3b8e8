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

- :func:`a04_bricard`: A04, Bricard's mechanism (five rods and six revolute joints in a
  closed loop, over-constrained: one degree of freedom where Gruebler counts none), as a
  spatial tree with a loop-closure joint; the point P3 by :func:`a04_p3`.

- :func:`a05_governor`: A05, the stiff flyball governor (spring-damper couplers), as a
  spatial tree with the couplers as generalized forces.

The library publishes A04's and A05's reference solutions as plots and data files that
were not reachable here: their tests check the conserved quantities and two independent
constructions of each mechanism instead (python/tests/test_iftomm_spatial.py).
"""
import numpy as np
import sympy as sp
from scipy.special import ellipj, ellipk
from sympy.physics.mechanics import dynamicsymbols

from ..symbolic import Loop, SpatialBody, constrained_system, spatial_tree
from .bari import Problem

__all__ = ["a01_pendulum", "a01_exact", "A01_PARAMS", "a02_n_four_bar", "a02_exact", "A02_PARAMS",
           "a04_bricard", "a04_p3", "A04_PARAMS", "a05_governor", "A05_PARAMS"]

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


# ---------------------------------------------------------------- A04: Bricard's mechanism

#: A04's data: five uniform rods of square cross-section (side a), gravity along -y
A04_PARAMS = dict(m=1.0, L=1.0, a=0.1, g=9.81)

# The closed chain O -> A -> B -> C -> D -> E (-> O through the ground): the joint points
# for L = 1 and the unit axis of the joint at each (perpendicular to both rods it joins)
_A04_POINTS = dict(O=(0, 0, 0), A=(1, 0, 0), B=(1, -1, 0), C=(1, -1, 1), D=(0, -1, 1),
                   E=(0, 0, 1))
_A04_AXES = dict(O=(0, 1, 0), A=(0, 0, 1), B=(1, 0, 0), C=(0, 1, 0), D=(0, 0, 1),
                 E=(1, 0, 0))


def _rod_inertia(m, L, a, along):
    """Inertia tensor about the centre of a rod of square section a x a along axis
    `along` (0, 1, 2): m a^2 / 6 about its own axis, m (L^2 + a^2) / 12 across."""
    d = [m*(L**2 + a**2)/12]*3
    d[along] = m*a**2/6
    return sp.diag(*d)


def a04_bricard(cut="E", flags=None):
    """A04, Bricard's mechanism: five uniform rods (1 m, 1 kg, square section 0.1 m) and
    six revolute joints forming a closed loop with the ground, O(0, 0, 0) - A(1, 0, 0) -
    B(1, -1, 0) - C(1, -1, 1) - D(0, -1, 1) - E(0, 0, 1), the ground closing E - O; every
    joint axis is perpendicular to the two rods it joins (O: y, A: z, B: x, C: y, D: z, E:
    x). Gruebler's count gives 6 - 6 = 0 degrees of freedom, the special geometry one: the
    loop constraints are redundant everywhere (the constraint Jacobian has rank 4 of its 5
    rows). Gravity 9.81 along -y; released at rest from this position; 10 s. The benchmark's
    observed quantities are the trajectory of P3 = B, the tip of the second rod
    (:func:`a04_p3`), and the conservation of the mechanical energy.

    A spatial tree (:func:`conmech.symbolic.spatial_tree`) with one loop-closure joint:
    ``cut="E"``: the chain O-A-B-C-D-E of the five rods from the ground at O, closed by the
    revolute joint at E; ``cut="B"``: two chains, O-A-B (rods 1, 2) and E-D-C-B (rods 5, 4,
    3), closed by the revolute joint at B. The two are different coordinates and different
    loop equations of the same mechanism (a check of each other). Coordinates: the joint
    angles of rods 1..5 (their parent joints), all 0 at the start. Returns a
    :class:`~conmech.benchmarks.bari.Problem` whose references are None: no published
    numbers of the reference solution were reachable (its plots only)."""
    if cut not in ("E", "B"):
        raise ValueError(f"cut must be 'E' or 'B', got {cut!r}")
    m, L, a, g = sp.symbols("m L a g")
    q = dynamicsymbols("r1:6")
    P = {k: sp.Matrix(v)*L for k, v in _A04_POINTS.items()}

    def rod(name, parent, k, frm, to, origin_parent):
        """Rod `name` from joint `frm` to point `to`, its frame at `frm` aligned with the
        ground's (all angles 0 at the start), jointed at `frm` to `parent` (whose frame
        sits at `origin_parent`)."""
        d = P[to] - P[frm]
        along = [i for i in range(3) if d[i] != 0][0]
        return SpatialBody(name, parent, "revolute", q[k], axis=_A04_AXES[frm],
                           at=tuple(P[frm] - P[origin_parent]), mass=m, com=tuple(d/2),
                           inertia=_rod_inertia(m, L, a, along))
    if cut == "E":
        bodies = [rod("rod1", None, 0, "O", "A", "O"), rod("rod2", "rod1", 1, "A", "B", "O"),
                  rod("rod3", "rod2", 2, "B", "C", "A"), rod("rod4", "rod3", 3, "C", "D", "B"),
                  rod("rod5", "rod4", 4, "D", "E", "C")]
        loop = Loop("rod5", tuple(P["E"] - P["D"]), None, tuple(P["E"]), joint="revolute",
                    axis=_A04_AXES["E"], name="Bricard loop closed at E (rod5-ground)")
    else:
        bodies = [rod("rod1", None, 0, "O", "A", "O"), rod("rod2", "rod1", 1, "A", "B", "O"),
                  rod("rod5", None, 4, "E", "D", "O"), rod("rod4", "rod5", 3, "D", "C", "E"),
                  rod("rod3", "rod4", 2, "C", "B", "D")]
        bodies = [bodies[i] for i in (0, 1, 4, 3, 2)]      # coordinates r1..r5 in order
        loop = Loop("rod2", tuple(P["B"] - P["A"]), "rod3", tuple(P["B"] - P["C"]),
                    joint="revolute", axis=_A04_AXES["B"],
                    name="Bricard loop closed at B (rod2-rod3)")
    params = {sp.Symbol(k): v for k, v in A04_PARAMS.items()}
    sysm = spatial_tree(bodies, params, gravity=(0, -g, 0), loops=[loop], flags=flags)
    return Problem(f"A04 Bricard mechanism (cut at {cut})", sysm, (0.0, 10.0), np.zeros(5),
                   np.zeros(5), None, None, None)


def _rot(axis, angle):
    """Rotation matrix about a unit coordinate axis (Rodrigues)."""
    u = np.asarray(axis, float)
    K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    return np.eye(3) + np.sin(angle)*K + (1 - np.cos(angle))*K @ K


def a04_p3(q):
    """The position of P3 = B (the tip of the second rod) for coordinates q (5,) or
    (5, nt) of :func:`a04_bricard` (either cut: rods 1 and 2 hang from O in both)."""
    q = np.asarray(q, float)
    cols = q.reshape(5, -1)
    out = np.empty((3, cols.shape[1]))
    L = A04_PARAMS["L"]
    for k, (r1, r2) in enumerate(zip(cols[0], cols[1])):
        R1 = _rot(_A04_AXES["O"], r1)
        R2 = R1 @ _rot(_A04_AXES["A"], r2)
        out[:, k] = R1 @ np.array([L, 0, 0]) + R2 @ np.array([0, -L, 0])
    return out[:, 0] if q.ndim == 1 else out


# ---------------------------------------------------------------- A05: flyball governor

#: A05's data: density of the shaft, rods and slider; the point masses; the spring-damper
#: couplers (stiffness, damping, rest length); gravity; the shaft's initial rate
A05_PARAMS = dict(rho=3000.0, m_ball=5.0, K=8e5, C=4e4, L0=0.5, g=9.81,
                  omega0=2*np.pi)


def a05_governor(method="recursive", flags=None):
    """A05, the stiff flyball governor: a vertical shaft (1 x 0.01 x 0.01 m, density 3000
    kg/m^3) turning freely about z on the ground at the origin; a slider (a cube of 0.1 m,
    same density) sliding along it at height s; two rods (as the shaft) pinned to the
    shaft's top at (+-0.05, 0, 1) in the shaft's plane, each carrying a 5 kg point mass at
    its far end (1 m from the pin); instead of rigid couplers, spring-dampers (stiffness
    8e5 N/m, damping 4e4 N s/m, rest length 0.5 m) join each rod's middle to the slider's
    side (+-0.05, 0, s). Gravity 9.81 along -z. Start: s = 0.5 m, the rods at 30 degrees
    below the horizontal (the springs at rest), the shaft turning at 2 pi rad/s, the other
    rates 0; 10 s. The benchmark's observed quantity is s(t).

    A spatial tree (:func:`conmech.symbolic.spatial_tree`; ``method="lagrangian"``: the
    same tree through the Lagrangian derivation, a second derivation to check the first)
    with coordinates q = (phi, s, theta1, theta2): the shaft's angle, the slider's height,
    the rods' angles from the downward vertical (outwards positive); the spring-dampers
    enter as generalized forces -(K (d - L0) + C d') dd/dq of the coupler lengths d(s,
    theta). The couplers make it stiff (eigenvalues near -K/C and -C/m): an implicit
    method is the natural choice. The angular momentum about z is conserved (no torque
    about the shaft), the energy decreases by the dampers' work. Returns a
    :class:`~conmech.benchmarks.bari.Problem` (system for :func:`conmech.solve_ivp`,
    state [q, q']) whose references are None: no published numbers of s(t) were
    reachable (its plot only)."""
    t = dynamicsymbols._t
    phi, s, th1, th2 = dynamicsymbols("phi s theta1 theta2")
    rho, mb, K, C, L0, g = sp.symbols("rho m_ball K C L0 g")
    mr = rho*sp.Rational(1, 10000)              # a rod (and the shaft): 1 x 0.01 x 0.01
    ms = rho*sp.Rational(1, 1000)               # the slider: a cube of 0.1
    w = sp.Rational(1, 100)
    Ibar = sp.diag(mr*(1 + w**2)/12, mr*(1 + w**2)/12, mr*w**2/6)     # along z
    Icube = sp.eye(3)*ms*sp.Rational(2, 100)/12
    m_rod = mr + mb                 # a rod with its ball: centre of mass on the rod
    c_rod = (mr*sp.Rational(1, 2) + mb)/m_rod   # distance from the pin
    # inertia of rod + ball about their common centre, rod frame (the rod along -z)
    I_rod = Ibar + sp.diag(1, 1, 0)*(mr*(c_rod - sp.Rational(1, 2))**2 + mb*(1 - c_rod)**2)
    bodies = [SpatialBody("shaft", None, "revolute", phi, axis=(0, 0, 1), mass=mr,
                          com=(0, 0, sp.Rational(1, 2)), inertia=Ibar),
              SpatialBody("slider", "shaft", "prismatic", s, axis=(0, 0, 1), mass=ms,
                          inertia=Icube),
              SpatialBody("rod1", "shaft", "revolute", th1, axis=(0, -1, 0),
                          at=(w*5, 0, 1), mass=m_rod, com=(0, 0, -c_rod), inertia=I_rod),
              SpatialBody("rod2", "shaft", "revolute", th2, axis=(0, 1, 0),
                          at=(-w*5, 0, 1), mass=m_rod, com=(0, 0, -c_rod), inertia=I_rod)]
    forces = {}
    for th in (th1, th2):
        # the coupler from the slider's side (0.05, s) to the rod's middle (0.05 +
        # sin(theta)/2, 1 - cos(theta)/2), in the plane of the shaft and the rod
        d = sp.sqrt((sp.sin(th)/2)**2 + (1 - sp.cos(th)/2 - s)**2)
        dd = d.diff(t)
        tension = K*(d - L0) + C*dd
        for qk in (s, th):
            forces[qk] = forces.get(qk, 0) - tension*d.diff(qk)
    params = {sp.Symbol(k): v for k, v in A05_PARAMS.items() if k != "omega0"}
    sysm = spatial_tree(bodies, params, gravity=(0, 0, -g), forces=forces, method=method,
                        flags=flags)
    q0 = np.array([0.0, 0.5, np.pi/3, np.pi/3])
    v0 = np.array([A05_PARAMS["omega0"], 0.0, 0.0, 0.0])
    return Problem("A05 flyball governor", sysm, (0.0, 10.0), q0, v0, None, None, None)
