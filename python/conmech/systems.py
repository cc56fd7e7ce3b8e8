"""Built-in compiled systems of conmech, for :func:`conmech.solve_ivp`.

Each factory returns a :class:`BuiltinSystem`: a small object carrying the name of a
system of the Fortran registry (``conmech_systems::make_system``) and its parameters in
the documented order. Integrating a built-in system runs entirely in Fortran, with no
Python in the loop.

Other layers add their systems here with one factory each, e.g.::

    def hill():
        return BuiltinSystem("hill", [], ())
"""
import numpy as np

from . import _conmech

__all__ = ["BuiltinSystem", "harmonic", "pendulum", "kepler", "arenstorf", "vanderpol", "hill"]


class BuiltinSystem:
    """A compiled first-order system y' = f(t, y), identified by name and parameters.

    Parameters
    ----------
    name : str
        Name in the Fortran registry (``make_system``).
    params : sequence of float
        Parameters in the registry's order.
    param_names : sequence of str, optional
        Names of the parameters, for ``repr`` and ``parameters``.
    """

    __slots__ = ("name", "params", "param_names", "dimension")

    def __init__(self, name, params=(), param_names=()):
        if not isinstance(name, str) or not name:
            raise TypeError("name must be a non-empty string")
        params = np.array(params, dtype=float).ravel()
        if not np.all(np.isfinite(params)):
            raise ValueError(f"params of the system '{name}' must be finite")
        param_names = tuple(param_names)
        if param_names and len(param_names) != params.size:
            raise ValueError("param_names must match params in length")
        dim = int(_conmech.flat_system_dimension(name))
        if dim <= 0:
            raise ValueError(f"unknown built-in system '{name}'")
        self.name = name
        self.params = params
        self.param_names = param_names
        self.dimension = dim

    @property
    def parameters(self):
        """The parameters as a dict (name -> value)."""
        names = self.param_names or tuple(f"p{i}" for i in range(self.params.size))
        return dict(zip(names, self.params.tolist()))

    def __repr__(self):
        args = ", ".join(f"{k}={v!r}" for k, v in self.parameters.items())
        return f"conmech.systems.{self.name}({args})"


def harmonic(omega=1.0):
    """Harmonic oscillator x'' = -omega^2 x; y = [x, v]."""
    return BuiltinSystem("harmonic", [omega], ("omega",))


def pendulum(g=9.81, l=1.0):
    """Pendulum theta'' = -(g/l) sin(theta); y = [theta, theta']."""
    return BuiltinSystem("pendulum", [g, l], ("g", "l"))


def kepler(mu=1.0):
    """Planar two-body problem r'' = -mu r/|r|^3; y = [x, y, vx, vy]."""
    return BuiltinSystem("kepler", [mu], ("mu",))


def arenstorf(mu=0.012277471):
    """Restricted three-body problem in Arenstorf's rotating frame; y = [x, y, vx, vy]."""
    return BuiltinSystem("arenstorf", [mu], ("mu",))


def vanderpol(mu=1.0):
    """Van der Pol oscillator x'' = mu (1 - x^2) x' - x; y = [x, x']."""
    return BuiltinSystem("vanderpol", [mu], ("mu",))


def hill(m=0.080848933808312, kappa=1.0):
    """Hill's lunar problem x'' - 2 m y' = F_x, y'' + 2 m x' = F_y,
    F = kappa/r + (3/2) m^2 x^2; y = [x, y, x', y'] (analytic Jacobian)."""
    return BuiltinSystem("hill", [m, kappa], ("m", "kappa"))
