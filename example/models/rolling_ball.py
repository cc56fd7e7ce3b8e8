"""The rolling rubber ball of seed 001 from T, U and its constraints, for
`python -m conmech.symbolic emit` (a constrained system in excessive coordinates).

q = [x, y, e0, e1, e2, e3]: the centre and the orientation as a unit quaternion; the
space-frame angular velocity is w = 2 H(e) e'. T = m/2 (x'^2 + y'^2) + I/2 |w|^2, which is
m/2 (x'^2 + y'^2) + 2 I |e'|^2 on |e| = 1, e.e' = 0; U = -m g sin(alpha) x (a plane inclined
at alpha, downhill = +x). Constraints: |e|^2 = 1 (holonomic); no slip x' = R w_y,
y' = -R w_x, and no spin w_z = 0 (the rubber ball): non-holonomic.

    python -m conmech.symbolic emit example/models/rolling_ball.py \\
        -o example/rolling_ball_model.f90
"""
import sympy as sp

from conmech.symbolic.derive import derive_constrained

name = "rolling_ball_sym"


def inputs():
    """Keyword arguments of conmech.symbolic.constrained_system(**inputs())."""
    x, y, e0, e1, e2, e3 = q = sp.symbols("x y e0 e1 e2 e3")
    v = sp.symbols("xd yd e0d e1d e2d e3d")
    m, R, I, g, alpha = sp.symbols("m R I g alpha")
    ed = sp.Matrix(v[2:])
    H = sp.Matrix([[-e1, e0, -e3, e2], [-e2, e3, e0, -e1], [-e3, -e2, e1, e0]])
    w = 2 * H * ed
    T = m / 2 * (v[0] ** 2 + v[1] ** 2) + 2 * I * (ed.T * ed)[0, 0]
    U = -m * g * sp.sin(alpha) * x
    return dict(T=T, U=U, q=q, holonomic=[(e0 ** 2 + e1 ** 2 + e2 ** 2 + e3 ** 2 - 1) / 2],
                nonholonomic=[v[0] - R * w[1], v[1] + R * w[0], w[2]],
                params={m: 1.3, R: 0.7, I: 0.2, g: 9.81, alpha: 0.3}, velocities=v)


def model():
    return derive_constrained(**inputs())
