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

_PAD = np.zeros(1)
_NO_SPEC = np.zeros(1, dtype=np.int64)   # spec kind 0: a built-in system, by name

__all__ = ["BuiltinSystem", "harmonic", "pendulum", "kepler", "arenstorf", "vanderpol", "hill"]


#: Parameters (by position) that must be positive for each built-in system: the system is
#: singular (a division by it) or meaningless otherwise. Checked by BuiltinSystem and
#: conmech.constrained.BuiltinConstrained.
POSITIVE_PARAMS = {
    "pendulum": {1: "l"}, "kepler": {0: "mu"}, "hill": {1: "kappa"},
    "pendulum_angle": {0: "m", 2: "l"}, "cart_pendulum": {0: "M", 1: "m", 2: "l"},
    "double_pendulum": {0: "m1", 1: "m2", 2: "l1", 3: "l2"},
    "atwood": {0: "m1", 1: "m2"}, "spring_pendulum": {0: "m"},
    "double_spring_pendulum": {0: "m1", 1: "m2"}, "three_springs": {0: "m"},
    "bead_hoop": {0: "m", 1: "R"}, "polar_particle": {0: "m"},
    "pendulum_moving": {0: "m", 2: "l"}, "yoyo_angle": {0: "m", 1: "r", 2: "I"},
    "pendulum_xy": {0: "m", 2: "l"}, "rod_two_masses": {1: "l"},
    "double_pendulum_xy": {0: "m1", 1: "m2", 2: "l1", 3: "l2"},
    "atwood_xy": {0: "m1", 1: "m2"}, "pendulum_moving_xy": {0: "m", 2: "l"},
    "yoyo": {0: "m", 1: "r", 2: "I"}, "skate": {0: "m", 1: "I"},
    "hill_spatial": {1: "kappa"}, "cr3bp": {0: "mu"},
    "rolling_disk": {0: "m", 1: "R", 2: "I_roll", 3: "I_turn"},
}
#: Names of the state components of the built-in first-order and generalized systems (for
#: reports such as the direction of a secular drift): coordinates, then velocities.
_COORDS = {"pendulum_angle": ("theta",), "cart_pendulum": ("x", "theta"),
           "double_pendulum": ("theta1", "theta2"), "atwood": ("y1",),
           "spring_pendulum": ("r", "theta"), "double_spring_pendulum": ("x1", "y1", "x2", "y2"),
           "three_springs": ("x1", "y1", "x2", "y2", "x3", "y3"), "bead_hoop": ("theta",),
           "polar_particle": ("r", "theta"), "pendulum_moving": ("theta",),
           "yoyo_angle": ("y",), "harmonic": ("x",), "pendulum": ("theta",),
           "vanderpol": ("x",), "kepler": ("x", "y"), "arenstorf": ("x", "y"),
           "hill": ("x", "y"), "cr3bp": ("x", "y", "z"), "hill_spatial": ("x", "y", "z")}
STATE_NAMES = {k: v + tuple(c + "'" for c in v) for k, v in _COORDS.items()}
#: Parameters that must lie in a closed interval.
RANGE_PARAMS = {"arenstorf": {0: ("mu", 0.0, 1.0)}, "hill": {0: ("m", 0.0, np.inf)},
                "hill_spatial": {0: ("m", 0.0, np.inf)}, "cr3bp": {0: ("mu", 0.0, 0.5)}}


def check_params(name, params):
    """ValueError naming a parameter of the built-in ``name`` that is out of its range."""
    for i, pname in POSITIVE_PARAMS.get(name, {}).items():
        if i < params.size and not params[i] > 0:
            raise ValueError(f"{pname} of the system '{name}' must be positive, got "
                             f"{params[i]:g}")
    for i, (pname, lo, hi) in RANGE_PARAMS.get(name, {}).items():
        if i < params.size and not lo <= params[i] <= hi:
            raise ValueError(f"{pname} of the system '{name}' must be in [{lo:g}, {hi:g}], "
                             f"got {params[i]:g}")


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

    __slots__ = ("name", "params", "param_names", "dimension", "spec", "_keep")

    def __init__(self, name, params=(), param_names=()):
        if not isinstance(name, str) or not name:
            raise TypeError("name must be a non-empty string")
        params = np.array(params, dtype=float).ravel()
        if not np.all(np.isfinite(params)):
            raise ValueError(f"params of the system '{name}' must be finite")
        check_params(name, params)
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
        self.spec = _NO_SPEC
        self._keep = None

    def _flat_args(self):
        """(name, np, params, nspec, spec): the leading arguments of the flat routines
        that build a system (built-in by name, or compiled from its spec)."""
        p = self.params if self.params.size else _PAD
        nspec = self.spec.size if self.spec is not _NO_SPEC else 0
        return self.name, self.params.size, p, nspec, self.spec

    @property
    def parameters(self):
        """The parameters as a dict (name -> value)."""
        names = self.param_names or tuple(f"p{i}" for i in range(self.params.size))
        return dict(zip(names, self.params.tolist()))

    @property
    def degrees_of_freedom(self):
        """The number of generalized coordinates of a mechanical system in generalized
        coordinates (its holonomic constraints eliminated); None for a first-order system
        without mechanical structure."""
        kind, n, mh, mn, info, _ = _conmech.flat_mech_info(*self._flat_args())
        return int(n) if info == 0 and kind == 2 else None

    def energy(self, y, t=0.0):
        """The energy (first integral) at the state y (time t): T + U of the mechanical
        systems y = [q, q'] (built-in, compiled and symbolic Lagrangian systems; the Jacobi
        integral when the Lagrangian depends on time or has gyroscopic terms), the Jacobi
        integral of the rotating-frame problems (arenstorf, cr3bp: C = 2 Omega - |v|^2;
        hill, hill_spatial: |v|^2 - 2 F), the energy of harmonic, pendulum and kepler.
        ValueError for a system without one (vanderpol, a compiled first-order system), or
        y of the wrong size. A (k, n) array of states gives k energies."""
        ys = np.asarray(y, dtype=float)
        if ys.ndim == 2:
            return np.array([self.energy(row, t) for row in ys])
        ys = np.ascontiguousarray(ys.ravel())
        if ys.size != self.dimension:
            raise ValueError(f"y has {ys.size} components; the system '{self.name}' has "
                             f"{self.dimension}")
        if not np.all(np.isfinite(ys)):
            raise ValueError("y must be finite")
        name, np_, p, nspec, spec = self._flat_args()
        e, info, message = _conmech.flat_system_energy(name, np_, p, nspec, spec, float(t),
                                                       ys)
        if info != 0:
            msg = bytes(message).decode("ascii", "replace").strip() if not isinstance(
                message, str) else message.strip()
            raise ValueError(f"{msg} (system '{self.name}')")
        return float(e)

    @property
    def has_energy(self):
        """Whether :meth:`energy` is defined for this system."""
        try:
            self.energy(np.full(self.dimension, 0.5))
        except ValueError:
            return False
        return True

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


# --- seed systems in generalized coordinates (conmech_systems_mech), y = [q, q'] -----------
# (their excessive-coordinate twins with constraints are in conmech.constrained)

def pendulum_angle(m=1.0, g=9.81, l=1.0):
    """Pendulum m l^2 th'' = -m g l sin th (angle from the downward vertical); y = [th, th']."""
    return BuiltinSystem("pendulum_angle", [m, g, l], ("m", "g", "l"))


def cart_pendulum(M=1.0, m=1.0, l=1.0, g=9.81):
    """Pendulum on a cart (seed 000; theta from the upright); y = [x, th, x', th']."""
    return BuiltinSystem("cart_pendulum", [M, m, l, g], ("M", "m", "l", "g"))


def double_pendulum(m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=9.81):
    """Double pendulum in absolute angles; y = [th1, th2, th1', th2']."""
    return BuiltinSystem("double_pendulum", [m1, m2, l1, l2, g], ("m1", "m2", "l1", "l2", "g"))


def atwood(m1=2.0, m2=1.0, g=9.81):
    """Atwood machine, y1 downward: (m1 + m2) y1'' = (m1 - m2) g; y = [y1, y1']."""
    return BuiltinSystem("atwood", [m1, m2, g], ("m1", "m2", "g"))


def spring_pendulum(m=1.0, k=40.0, l0=1.0, g=9.81):
    """Spring pendulum in polar coordinates; y = [r, th, r', th']."""
    return BuiltinSystem("spring_pendulum", [m, k, l0, g], ("m", "k", "l0", "g"))


def double_spring_pendulum(m1=1.0, m2=1.0, k1=40.0, k2=40.0, l1=1.0, l2=1.0, g=9.81):
    """Double spring pendulum in Cartesian coordinates; y = [x1, y1, x2, y2, velocities]."""
    return BuiltinSystem("double_spring_pendulum", [m1, m2, k1, k2, l1, l2, g],
                         ("m1", "m2", "k1", "k2", "l1", "l2", "g"))


def three_springs(m=1.0, k=10.0, l0=1.0):
    """Three equal masses joined pairwise by springs; y = [x1, y1, x2, y2, x3, y3, vel.]."""
    return BuiltinSystem("three_springs", [m, k, l0], ("m", "k", "l0"))


def bead_hoop(m=1.0, R=1.0, omega=5.0, g=9.81):
    """Bead on a hoop spinning at omega: th'' = (omega^2 cos th - g/R) sin th; y = [th, th']."""
    return BuiltinSystem("bead_hoop", [m, R, omega, g], ("m", "R", "omega", "g"))


def polar_particle(m=1.0, mu=1.0):
    """Particle in polar coordinates, U = -m mu / r; y = [r, th, r', th']."""
    return BuiltinSystem("polar_particle", [m, mu], ("m", "mu"))


def pendulum_moving(m=1.0, g=9.81, l=1.0, a=0.0, b=0.1, w=3.0):
    """Pendulum with suspension s(t) = a t^2/2 + b sin(w t) (rheonomic); y = [th, th']."""
    return BuiltinSystem("pendulum_moving", [m, g, l, a, b, w], ("m", "g", "l", "a", "b", "w"))


def yoyo_angle(m=1.0, r=0.05, I=1.25e-3, g=9.81, ah=0.0, vh=0.0, h0=0.0):
    """Yo-yo on a string moving as h0 + vh t + ah t^2/2; y = [y, y']."""
    return BuiltinSystem("yoyo_angle", [m, r, I, g, ah, vh, h0],
                         ("m", "r", "I", "g", "ah", "vh", "h0"))


__all__ += ["pendulum_angle", "cart_pendulum", "double_pendulum", "atwood", "spring_pendulum",
            "double_spring_pendulum", "three_springs", "bead_hoop", "polar_particle",
            "pendulum_moving", "yoyo_angle"]


# --- seed systems in excessive coordinates with constraints, for conmech.constrained.solve --

def _constrained(name, params):
    from .constrained import BuiltinConstrained
    return BuiltinConstrained(name, params)


def pendulum_xy(m=1.0, g=9.81, l=1.0):
    """Point mass on a circle, q = [x, y], phi = (x^2 + y^2 - l^2)/2 (constrained.solve)."""
    return _constrained("pendulum_xy", [m, g, l])


def rod_two_masses(g=9.81, l=1.0):
    """Two unit masses on a rod, centre velocity along the rod (holonomic + non-holonomic)."""
    return _constrained("rod_two_masses", [g, l])


def double_pendulum_xy(m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=9.81):
    """Double pendulum in Cartesian coordinates q = [x1, y1, x2, y2], two constraints."""
    return _constrained("double_pendulum_xy", [m1, m2, l1, l2, g])


def atwood_xy(m1=2.0, m2=1.0, g=9.81, L=2.0):
    """Atwood machine q = [y1, y2] (downward), y1 + y2 = L; the multiplier is the tension."""
    return _constrained("atwood_xy", [m1, m2, g, L])


def pendulum_moving_xy(m=1.0, g=9.81, l=1.0, a=0.0, b=0.1, w=3.0):
    """Pendulum with a moving suspension (s(t) = a t^2/2 + b sin w t), rheonomic."""
    return _constrained("pendulum_moving_xy", [m, g, l, a, b, w])


def yoyo(m=1.0, r=0.05, I=1.25e-3, g=9.81, ah=0.0, vh=0.0, h0=0.0):
    """Yo-yo q = [y, psi] on a string moving as h0 + vh t + ah t^2/2 (rheonomic)."""
    return _constrained("yoyo", [m, r, I, g, ah, vh, h0])


def skate(m=1.0, I=1.0, g=9.81, alpha=0.3):
    """Ice-skate blade / knife edge on an incline, q = [x, y, theta] (non-holonomic)."""
    return _constrained("skate", [m, I, g, alpha])


def rolling_disk(m=1.0, R=1.0, I_roll=0.5, I_turn=0.25):
    """Vertical rolling disk q = [x, y, theta, phi] (two non-holonomic constraints)."""
    return _constrained("rolling_disk", [m, R, I_roll, I_turn])


def rolling_ball(m=1.0, R=1.0, I=0.4, g=9.81, alpha=0.0):
    """Rubber ball rolling without slip and without spin about the vertical on a plane
    inclined at alpha (seed 001), q = [x, y, e0, e1, e2, e3] (centre, unit quaternion): one
    holonomic (|e| = 1) and three non-holonomic constraints; I the central moment of
    inertia (2/5 m R^2 for a homogeneous ball)."""
    return _constrained("rolling_ball", [m, R, I, g, alpha])


__all__ += ["pendulum_xy", "rod_two_masses", "double_pendulum_xy", "atwood_xy",
            "pendulum_moving_xy", "yoyo", "skate", "rolling_disk", "rolling_ball"]


def hill(m=0.080848933808312, kappa=1.0):
    """Hill's lunar problem x'' - 2 m y' = F_x, y'' + 2 m x' = F_y,
    F = kappa/r + (3/2) m^2 x^2; y = [x, y, x', y'] (analytic Jacobian)."""
    return BuiltinSystem("hill", [m, kappa], ("m", "kappa"))


def pendulum_chain_xy(N=8, m=1.0, l=1.0, g=9.81):
    """Chain of N Cartesian pendulums q = [x1, y1, ..., xN, yN], N rod constraints (a
    diagonal mass and a banded constraint Jacobian: O(N) per step in constrained.solve)."""
    try:
        whole = float(N) == int(N) and 1 <= int(N) <= 100000
    except (TypeError, ValueError, OverflowError):
        whole = False
    if isinstance(N, bool) or not whole:
        raise ValueError(f"pendulum_chain_xy: N must be a whole number of links in "
                         f"1..100000, got {N!r}")
    return _constrained("pendulum_chain_xy", [int(N), m, l, g])


__all__ += ["pendulum_chain_xy"]


def hill_spatial(m=0.080848933808312, kappa=1.0):
    """Hill's lunar problem in space: x'' - 2 m y' = F_x, y'' + 2 m x' = F_y, z'' = F_z,
    F = kappa/r + (3/2) m^2 x^2 - (1/2) m^2 z^2 (so z'' + m^2 z = -kappa z/r^3), in the
    units of :func:`hill` (synodic month 2 pi); y = [x, y, z, x', y', z'] (analytic
    Jacobian); energy: the Jacobi integral |v|^2 - 2 F."""
    return BuiltinSystem("hill_spatial", [m, kappa], ("m", "kappa"))


def cr3bp(mu=0.012150585609624):
    """The spatial circular restricted three-body problem in the rotating frame: primaries
    of masses 1 - mu at (-mu, 0, 0) and mu at (1 - mu, 0, 0) (0 < mu <= 1/2; default the
    Earth-Moon value), x'' - 2 y' = Omega_x, y'' + 2 x' = Omega_y, z'' = Omega_z,
    Omega = (x^2 + y^2)/2 + (1 - mu)/r1 + mu/r2; y = [x, y, z, x', y', z'] (analytic
    Jacobian and Jacobian product); energy: the Jacobi constant C = 2 Omega - |v|^2.
    :mod:`conmech.cr3bp` has its libration points and families."""
    return BuiltinSystem("cr3bp", [mu], ("mu",))


__all__ += ["hill_spatial", "cr3bp"]
