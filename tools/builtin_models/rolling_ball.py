"""The rolling rubber ball of the lecture notes ("a non-holonomic system: rubber ball on a
plane, d.o.f. = 2"): a ball of mass m, radius R and central moment of inertia I (isotropic:
a homogeneous ball has I = 2/5 m R^2) rolls without slipping and without spinning about
the vertical on a plane inclined at alpha (downhill = +x; alpha = 0 is the notes' plane).

Excessive coordinates q = [x, y, e0, e1, e2, e3]: the centre (x, y) and the orientation as
a unit quaternion e (no gimbal lock, unlike Euler angles). The angular velocity in space
is w = 2 H(e) e' with the rows

    H_x = [-e1,  e0, -e3,  e2],  H_y = [-e2,  e3,  e0, -e1],  H_z = [-e3, -e2,  e1,  e0].

T = m/2 (x'^2 + y'^2) + I/2 |w|^2 = m/2 (x'^2 + y'^2) + 2 I |e'|^2 on e.e' = 0, so
M = diag(m, m, 4I, 4I, 4I, 4I) (the difference to the exact quadratic form is a multiple
of e, taken up by the holonomic multiplier); U = -m g sin(alpha) x. Constraints (n = 6,
n_hol = 1, n_nh = 3):

    phi = (|e|^2 - 1)/2                  (unit quaternion, holonomic)
    x' - R w_y = 0,  y' + R w_x = 0      (no slip at the contact point -R e_z)
    w_z = 0                              (no spin about the vertical: the rubber ball)

gamma_h = -|e'|^2; gamma_n = -(dA/dt) v = 0 identically, since H(e') e' = 0. The
multipliers of the non-holonomic rows are the contact force (F_x, F_y) and the vertical
reaction torque. Closed forms: on the plane the centre moves on a straight line at
constant speed and e(t) = [cos(|w| t/2), sin(|w| t/2) w/|w|] * e(0); on the incline the
centre moves on a parabola, x'' = g sin(alpha)/(1 + I/(m R^2)), y'' = 0, with
F_x = -I x''/R^2."""
import sympy as sp

from . import Constrained, Param

m = Param("m", 1.0, "mass")
R = Param("R", 1.0, "radius")
inertia = Param("I", 0.4, "central moment of inertia (isotropic)")
g = Param("g", 9.81, "gravity")
alpha = Param("alpha", 0.0, "inclination of the plane (downhill = +x)")
x, y, e0, e1, e2, e3 = q = sp.symbols("x y e0 e1 e2 e3", real=True)
v = sp.symbols("xd yd e0d e1d e2d e3d", real=True)
M, RR, I, G, AL = (p.symbol for p in (m, R, inertia, g, alpha))
ed = sp.Matrix(v[2:])
H = sp.Matrix([[-e1, e0, -e3, e2], [-e2, e3, e0, -e1], [-e3, -e2, e1, e0]])
w = 2*H*ed

SYSTEM = Constrained("rolling_ball", "rolling_ball",
                     "Rubber ball rolling without slip and without spin about the vertical "
                     "on a plane inclined at alpha (the lecture notes' rubber ball), "
                     "q = [x, y, e0, e1, e2, e3] (centre, unit quaternion): one holonomic "
                     "(|e| = 1) and three non-holonomic constraints; I the central moment of "
                     "inertia (2/5 m R^2 for a homogeneous ball).",
                     [m, R, inertia, g, alpha], q=q, v=v,
                     T=M*(v[0]**2 + v[1]**2)/2 + 2*I*(ed.T*ed)[0, 0], U=-M*G*sp.sin(AL)*x,
                     holonomic=[(e0**2 + e1**2 + e2**2 + e3**2 - 1)/2],
                     nonholonomic=[v[0] - RR*w[1], v[1] + RR*w[0], w[2]],
                     # identity orientation, centre velocity (1, 0.5): e' = [0, -y'/(2R),
                     # x'/(2R), 0]
                     q0=[0, 0, 1, 0, 0, 0], v0=[1, 0.5, 0, -0.25/RR, 0.5/RR, 0])
