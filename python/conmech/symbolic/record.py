"""The :class:`Derived` record: the sympy expressions of one derived system in plain
symbols, ready for a code generator (the attribute table is in :mod:`conmech.symbolic.derive`).
The expanded forces Q and their Jacobian R of a structured Lagrangian derivation are computed
only when first read; the heavy expressions are pickled as one blob."""
import pickle

import sympy as sp

from .euler_lagrange import _euler_lagrange
from .inputs import _ae, _as_value


class Derived:
    """Plain record of the derived expressions (attributes: see :mod:`conmech.symbolic.derive`).

    A generalized system derived structurally (``struct`` set, see :func:`_structure`)
    computes its expanded ``Q`` and ``R`` only when they are first read (the compiled code
    uses ``struct`` instead)."""

    def __init__(self, kind, **kw):
        self.kind = kind
        self.t = sp.Symbol("t")
        self.coords, self.speeds, self.accels = [], [], []
        self.params, self.param_names, self.param_values = [], [], []
        for name in ("f", "jac", "M", "Q", "R", "energy", "phi", "G", "phi_t", "gamma_h",
                     "A", "b", "gamma_n", "struct", "gen_forces"):
            setattr(self, name, None)
        self.n_hol = 0
        self.n_nh = 0
        self.rheonomic = False
        self.with_jacobian = True
        for k, v in kw.items():
            setattr(self, k, v)

    # the attributes a compiled system needs; the expressions (large for long chains) are
    # pickled as one blob and read back only when first used (fast derivation-cache hits)
    _LIGHT = frozenset(("kind", "t", "coords", "coord_names", "speeds", "accels", "params",
                        "param_names", "param_values", "n_hol", "n_nh", "rheonomic",
                        "with_jacobian"))

    def __getstate__(self):
        state = {k: v for k, v in self.__dict__.items() if k in self._LIGHT}
        if "_heavy" in self.__dict__:          # expressions not read back yet
            state["_heavy"] = self.__dict__["_heavy"]
        else:
            heavy = {k: v for k, v in self.__dict__.items() if k not in self._LIGHT}
            state["_heavy"] = pickle.dumps(heavy, protocol=pickle.HIGHEST_PROTOCOL)
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)

    def __getattr__(self, name):
        heavy = None if name.startswith("__") else self.__dict__.pop("_heavy", None)
        if heavy is not None:
            self.__dict__.update(pickle.loads(heavy))
        try:
            return self.__dict__[name]
        except KeyError:
            raise AttributeError(name) from None

    @property
    def Q(self):
        if self._Q is None and self.struct is not None:
            _, Q = _euler_lagrange(self.lagrangian, self.coords, self.speeds, self.t)
            self._Q = Q + sp.Matrix(self.gen_forces)
        return self._Q

    @Q.setter
    def Q(self, value):
        self._Q = value

    @property
    def R(self):
        if self._R is None and self.struct is not None and self.with_jacobian:
            Ma = self.M * sp.Matrix(self.accels)
            Q = self.Q
            self._R = _ae((Q - Ma).jacobian(self.coords).row_join(Q.jacobian(self.speeds)))
        return self._R

    @R.setter
    def R(self, value):
        self._R = value

    @property
    def n(self):
        """Number of coordinates (state dimension for an ode)."""
        return len(self.coords)

    def values(self, **kw):
        """The parameter values as a list, with the named ones replaced."""
        vals = list(self.param_values)
        for k, v in kw.items():
            if k not in self.param_names:
                raise ValueError(f"unknown parameter '{k}' (parameters: "
                                 f"{', '.join(self.param_names) or 'none'})")
            vals[self.param_names.index(k)] = _as_value(k, v)
        return vals

    def __repr__(self):
        return (f"Derived(kind={self.kind!r}, coords={self.coords}, "
                f"params={dict(zip(self.param_names, self.param_values))})")
