"""Two index-3 problems of the Test Set for IVP Solvers (F. Mazzia, C. Magherini et al.,
University of Bari; release 2.4), written with :func:`conmech.symbolic.constrained_system`
through their kinetic and potential energies and their constraints:

- :func:`andrews`: Andrews' squeezing mechanism (7 rigid bodies, 7 angles, a 7 x 7 mass
  matrix depending on the angles, 6 loop-closure constraints, a driving torque and a
  spring), t in [0, 0.03]; the reference solution at t = 0.03 is the test set's (PSIDE at
  rtol = atol = 1e-14).
- :func:`car_axis`: the car axis problem (two wheel springs and an axle of fixed length
  whose right end follows a bump, a rheonomic constraint), t in [0, 3]; reference at t = 3
  from the test set.

Each returns a :class:`Problem` (the compiled system, the time span, consistent initial
values, the reference positions, velocities and multipliers, and the test set's initial
accelerations and multipliers where it publishes them). :func:`mescd` is the test set's
mixed significant correct digits, -log10 max_i |y_i - ref_i| / (atol/rtol + |ref_i|).

Parameters, initial values and reference solutions are the test set's published numbers
(problem files andrews.f and caraxis.f). The test set's variables map to conmech's as
y = [q, v, a, lambda] (index-3 form): the positions are y(1:7) (Andrews) and y(1:4) (car
axis). conmech writes the reactions as M q'' = Q + G^T lambda; Andrews' test-set equations
read M q'' = f - G^T lambda, so its published multipliers are stored here with their sign
changed (the car axis uses conmech's sign already).
"""
from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from ..symbolic import constrained_system

__all__ = ["Problem", "andrews", "car_axis", "mescd"]


@dataclass
class Problem:
    """A benchmark problem: `system` (for :func:`conmech.constrained.solve`), `t_span`,
    `q0`, `v0`, the reference `q_ref`, `v_ref`, `lam_ref` at t_span[1], and (when the test
    set gives them) the initial accelerations `a0_ref` and multipliers `lam0_ref`."""
    name: str
    system: object
    t_span: tuple
    q0: np.ndarray
    v0: np.ndarray
    q_ref: np.ndarray
    v_ref: np.ndarray
    lam_ref: np.ndarray
    a0_ref: np.ndarray = field(default=None)
    lam0_ref: np.ndarray = field(default=None)
    a_ref: np.ndarray = field(default=None)


def mescd(y, ref, rtol, atol):
    """The test set's mixed significant correct digits of y against ref (same shape):
    -log10 max_i |y_i - ref_i| / (atol/rtol + |ref_i|)."""
    y = np.asarray(y, float)
    ref = np.asarray(ref, float)
    err = np.max(np.abs(y - ref) / (atol / rtol + np.abs(ref)))
    return float(-np.log10(err)) if err > 0 else np.inf


# ---------------------------------------------------------------- Andrews' mechanism
#: the test set's parameters (andrews.f, common block andcom)
ANDREWS_PARAMS = dict(
    m1=.04325, m2=.00365, m3=.02373, m4=.00706, m5=.07050, m6=.00706, m7=.05498,
    xa=-.06934, ya=-.00227, xb=-0.03635, yb=.03273, xc=.014, yc=.072, c0=4530.0,
    i1=2.194e-6, i2=4.410e-7, i3=5.255e-6, i4=5.667e-7, i5=1.169e-5, i6=5.667e-7,
    i7=1.912e-5, d=28e-3, da=115e-4, e=2e-2, ea=1421e-5, rr=7e-3, ra=92e-5, l0=7785e-5,
    ss=35e-3, sa=1874e-5, sb=1043e-5, sc=18e-3, sd=2e-2, ta=2308e-5, tb=916e-5, u=4e-2,
    ua=1228e-5, ub=449e-5, zf=2e-2, zt=4e-2, fa=1421e-5, mom=33e-3)

ANDREWS_Q0 = np.array([-0.0617138900142764496358948458001, 0.0,
                       0.455279819163070380255912382449, 0.222668390165885884674473185609,
                       0.487364979543842550225598953530, -0.222668390165885884674473185609,
                       1.23054744454982119249735015568])
#: the test set's initial accelerations y(15:21) and multipliers y(22:27) (the latter in
#: conmech's sign convention, see the module documentation)
ANDREWS_A0 = np.array([14222.4439199541138705911625887, -10666.8329399655854029433719415,
                       0.0, 0.0, 0.0, 0.0, 0.0])
ANDREWS_LAM0 = -np.array([98.5668703962410896057654982170, -6.12268834425566265503114393122,
                          0.0, 0.0, 0.0, 0.0])
#: reference solution at t = 0.03 (andrews.f, andsoln: PSIDE, rtol = atol = 1e-14)
ANDREWS_REF = np.array([
    0.1581077119629904e+2, -0.1575637105984298e+2, 0.4082224013073101e-1,
    -0.5347301163226948e+0, 0.5244099658805304e+0, 0.5347301163226948e+0,
    0.1048080741042263e+1, 0.1139920302151208e+4, -0.1424379294994111e+4,
    0.1103291221937134e+2, 0.1929337464421385e+2, 0.5735699284790808e+0,
    -0.1929337464421385e+2, 0.3231791658026955e+0, -0.2463176316945196e+5,
    0.5185037701610329e+5, 0.3241025686413781e+6, 0.5667493645176213e+6,
    0.1674362929479361e+5, -0.5667493645176222e+6, 0.9826520791458422e+4,
    0.1991753333731910e+3, -0.2975531228015052e+2, 0.2306654119098399e+2,
    0.3145271365475927e+2, 0.2264249232082739e+2, 0.1161740700019673e+2])


def andrews(flags=None):
    """Andrews' squeezing mechanism as a compiled constrained system (7 angles beta,
    Theta, gamma, Phi, delta, Omega, epsilon; T = v^T M(q) v / 2 with the test set's mass
    matrix, U the spring's c0 (L - l0)^2 / 2, the driving torque mom on beta, the six
    loop-closure constraints)."""
    P = {k: sp.Symbol(k) for k in ANDREWS_PARAMS}
    globals_ = P
    (m1, m2, m3, m4, m5, m6, m7, xa, ya, xb, yb, xc, yc, c0, i1, i2, i3, i4, i5, i6, i7,
     d, da, e, ea, rr, ra, l0, ss, sa, sb, sc, sd, ta, tb, u, ua, ub, zf, zt, fa,
     mom) = [globals_[k] for k in ANDREWS_PARAMS]
    q = sp.symbols("beta Theta gamma Phi delta Omega epsilon")
    v = sp.symbols("beta_d Theta_d gamma_d Phi_d delta_d Omega_d epsilon_d")
    be, th, ga, ph, de, om, ep = q
    M = sp.zeros(7, 7)
    M[0, 0] = m1*ra**2 + m2*(rr**2 - 2*da*rr*sp.cos(th) + da**2) + i1 + i2
    M[1, 0] = m2*(da**2 - da*rr*sp.cos(th)) + i2
    M[1, 1] = m2*da**2 + i2
    M[2, 2] = m3*(sa**2 + sb**2) + i3
    M[3, 3] = m4*(e - ea)**2 + i4
    M[4, 3] = m4*((e - ea)**2 + zt*(e - ea)*sp.sin(ph)) + i4
    M[4, 4] = (m4*(zt**2 + 2*zt*(e - ea)*sp.sin(ph) + (e - ea)**2) + m5*(ta**2 + tb**2)
               + i4 + i5)
    M[5, 5] = m6*(zf - fa)**2 + i6
    M[6, 5] = m6*((zf - fa)**2 - u*(zf - fa)*sp.sin(om)) + i6
    M[6, 6] = (m6*((zf - fa)**2 - 2*u*(zf - fa)*sp.sin(om) + u**2) + m7*(ua**2 + ub**2)
               + i6 + i7)
    for i in range(7):
        for j in range(i):
            M[j, i] = M[i, j]
    vv = sp.Matrix(v)
    T = (vv.T*M*vv)[0, 0]/2
    xd = sd*sp.cos(ga) + sc*sp.sin(ga) + xb
    yd = sd*sp.sin(ga) - sc*sp.cos(ga) + yb
    lang = sp.sqrt((xd - xc)**2 + (yd - yc)**2)
    U = c0*(lang - l0)**2/2
    cobeth, sibeth = sp.cos(be + th), sp.sin(be + th)
    g = [rr*sp.cos(be) - d*cobeth - ss*sp.sin(ga) - xb,
         rr*sp.sin(be) - d*sibeth + ss*sp.cos(ga) - yb,
         rr*sp.cos(be) - d*cobeth - e*sp.sin(ph + de) - zt*sp.cos(de) - xa,
         rr*sp.sin(be) - d*sibeth + e*sp.cos(ph + de) - zt*sp.sin(de) - ya,
         rr*sp.cos(be) - d*cobeth - zf*sp.cos(om + ep) - u*sp.sin(ep) - xa,
         rr*sp.sin(be) - d*sibeth - zf*sp.sin(om + ep) + u*sp.cos(ep) - ya]
    params = {P[k]: val for k, val in ANDREWS_PARAMS.items()}
    sysm = constrained_system(T, U, list(q), holonomic=g, params=params,
                              forces=[mom, 0, 0, 0, 0, 0, 0], velocities=list(v),
                              simplify=False, flags=flags)
    ref = ANDREWS_REF
    return Problem("andrews", sysm, (0.0, 0.03), ANDREWS_Q0.copy(), np.zeros(7),
                   ref[0:7].copy(), ref[7:14].copy(), -ref[21:27],
                   a0_ref=ANDREWS_A0.copy(), lam0_ref=ANDREWS_LAM0.copy(),
                   a_ref=ref[14:21].copy())


# ---------------------------------------------------------------- the car axis
#: the test set's parameters (caraxis.f)
CAR_AXIS_PARAMS = dict(eps=1e-2, M=10.0, L=1.0, L0=0.5, r=0.1, w=10.0, g=1.0)
#: reference solution at t = 3 (caraxis.f, carsoln): positions, velocities, multipliers
CAR_AXIS_REF = np.array([
    0.4934557842755629e-001, 0.4969894602303324e+000, 0.1041742524885400e+001,
    0.3739110272652214e+000, -0.7705836840321485e-001, 0.7446866596327776e-002,
    0.1755681574942899e-001, 0.7703410437794031e+000, -0.4736886750784630e-002,
    -0.1104680411345730e-002])


def car_axis(flags=None):
    """The car axis problem as a compiled constrained system: q = (xl, yl, xr, yr), T =
    k |v|^2 / 2 with k = M eps^2 / 2, the two wheel springs (rest length L0) and gravity
    k g in U, the constraints xb(t) xl + yb(t) yl = 0 (the axle is perpendicular to the
    left spring's anchor direction, yb = r sin(w t), xb = sqrt(L^2 - yb^2): rheonomic) and
    (xl - xr)^2 + (yl - yr)^2 = L^2."""
    t = sp.Symbol("t")
    eps, Mm, L, L0, r, w, g = sp.symbols("eps M L L0 r w g")
    q = sp.symbols("xl yl xr yr")
    v = sp.symbols("xl_d yl_d xr_d yr_d")
    xl, yl, xr, yr = q
    k = Mm*eps**2/2
    yb = r*sp.sin(w*t)
    xb = sp.sqrt(L**2 - yb**2)
    Ll = sp.sqrt(xl**2 + yl**2)
    Lr = sp.sqrt((xr - xb)**2 + (yr - yb)**2)
    T = k*sum(x**2 for x in v)/2
    U = (Ll - L0)**2/2 + (Lr - L0)**2/2 + k*g*(yl + yr)
    hol = [xb*xl + yb*yl, (xl - xr)**2 + (yl - yr)**2 - L**2]
    params = {sp.Symbol(k_): val for k_, val in CAR_AXIS_PARAMS.items()}
    sysm = constrained_system(T, U, list(q), holonomic=hol, params=params,
                              velocities=list(v), simplify=False, flags=flags)
    p = CAR_AXIS_PARAMS
    q0 = np.array([0.0, p["L0"], p["L"], p["L0"]])
    v0 = np.array([-p["L0"] / p["L"], 0.0, -p["L0"] / p["L"], 0.0])
    ref = CAR_AXIS_REF
    return Problem("car_axis", sysm, (0.0, 3.0), q0, v0, ref[0:4].copy(), ref[4:8].copy(),
                   ref[8:10].copy())
