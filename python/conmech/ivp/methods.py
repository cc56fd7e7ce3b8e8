"""The integration methods, read once from the Fortran method table (conmech_ode_methods):
names and aliases, order, and whether a method needs its fixed step (``first_step``), takes
a Jacobian, or is for constrained systems only. A method added to the Fortran table is
known here (and to :func:`conmech.solve_ivp` and :class:`conmech.Stepper`) without any
Python edit."""
from dataclasses import dataclass

from .. import _conmech
from .._core.callback import message_text

__all__ = ["MethodInfo", "METHODS", "BY_NAME", "RK45_SCIPY", "method_info"]

#: The flat layer's code of SciPy's RK45: DOPRI5 with SciPy's step control (no Lund
#: stabilisation) and SciPy's initial step (conmech_flat_ode_support METHOD_RK45_SCIPY).
RK45_SCIPY = 12


@dataclass(frozen=True)
class MethodInfo:
    """One entry of the method table."""
    code: int
    name: str
    aliases: tuple
    order: int
    fixed_step: bool
    uses_jacobian: bool
    constrained_only: bool


def _read_table():
    table = {}
    code, max_code = 1, 1
    while code <= max_code:
        found, name, aliases, order, flags, max_code = _conmech.flat_method_info(code)
        if found:
            table[code] = MethodInfo(code, message_text(name), tuple(
                message_text(aliases).split()), int(order), bool(flags[0]), bool(flags[1]),
                bool(flags[2]))
        code += 1
    return table


#: code -> MethodInfo, every method of the Fortran table.
METHODS = _read_table()
#: upper-case name or alias -> MethodInfo.
BY_NAME = {n.upper(): m for m in METHODS.values() for n in (m.name, *m.aliases)}


def method_info(code):
    """The table entry of a method code (RK45_SCIPY: DOPRI5's entry); None if unknown."""
    return BY_NAME["DOPRI5"] if code == RK45_SCIPY else METHODS.get(code)
