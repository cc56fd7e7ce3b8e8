"""Mechanical systems: the built-in systems (systems.py, generated from their models),
constrained systems and their solver (constrained.py), systems compiled to the C ABI and
model libraries (compiled.py), degrees of freedom n = N - R (degrees_of_freedom.py). The
modules are public as ``conmech.systems``, ``conmech.constrained``, ``conmech.compiled``
and ``conmech.degrees_of_freedom``."""
