"""A bead of mass m on a hoop of radius R spinning at the rate omega about its vertical
diameter, q = [theta] from the bottom: theta'' = (omega^2 cos(theta) - g/R) sin(theta).
The energy is the Jacobi integral m R^2 (theta'^2 - omega^2 sin^2 theta)/2
- m g R cos(theta) (conserved; the kinetic plus potential energy is not)."""
import sympy as sp

from . import Lagrangian, Param

m = Param("m", 1.0, "mass", positive=True)
R = Param("R", 1.0, "radius of the hoop", positive=True)
omega = Param("omega", 5.0, "rate of the hoop")
g = Param("g", 9.81, "gravity")
th, thd = sp.symbols("theta thetad", real=True)
M, Rs, W, G = (p.symbol for p in (m, R, omega, g))

SYSTEM = Lagrangian("bead_hoop", "bead_hoop",
                    "Bead on a hoop spinning at omega: th'' = (omega^2 cos th - g/R) sin th; "
                    "y = [th, th'].", [m, R, omega, g], q=[th], v=[thd],
                    T=M*Rs**2*(thd**2 + W**2*sp.sin(th)**2)/2, U=-M*G*Rs*sp.cos(th),
                    q0=[0.5], v0=[0])
