"""The vertical rolling disk (a coin rolling upright without slipping) of radius R:
q = [x, y, theta, phi] (contact point, heading, rolling angle), moments of inertia I_roll
about the axle and I_turn about the vertical; x' = R phi' cos(theta),
y' = R phi' sin(theta) (two non-holonomic constraints)."""
import sympy as sp

from . import Constrained, Param

m = Param("m", 1.0, "mass", positive=True)
R = Param("R", 1.0, "radius", positive=True)
i_roll = Param("I_roll", 0.5, "moment of inertia about the axle", positive=True)
i_turn = Param("I_turn", 0.25, "moment of inertia about the vertical", positive=True)
x, y, th, ph = q = sp.symbols("x y theta phi", real=True)
xd, yd, thd, phd = v = sp.symbols("xd yd thetad phid", real=True)
M, RR, IR, IT = (p.symbol for p in (m, R, i_roll, i_turn))

SYSTEM = Constrained("rolling_disk", "rolling_disk",
                     "Vertical rolling disk q = [x, y, theta, phi] (two non-holonomic "
                     "constraints).", [m, R, i_roll, i_turn], q=q, v=v,
                     T=M*(xd**2 + yd**2)/2 + IT*thd**2/2 + IR*phd**2/2, U=0,
                     nonholonomic=[xd - RR*sp.cos(th)*phd, yd - RR*sp.sin(th)*phd],
                     q0=[0, 0, 0, 0], v0=[2*RR, 0, 0.5, 2])
