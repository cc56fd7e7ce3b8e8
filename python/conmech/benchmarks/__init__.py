"""Published benchmark problems of constrained mechanics, ready to solve:

- :mod:`conmech.benchmarks.bari`: Andrews' squeezing mechanism and the car axis problem
  of the Test Set for IVP Solvers (University of Bari), with their reference solutions and
  the test set's accuracy measure (mixed significant correct digits, :func:`mescd`);
- :mod:`conmech.benchmarks.iftomm`: the IFToMM library of computational benchmark
  problems for multibody dynamics: A01, the simple pendulum, and A02, the N-four-bar
  mechanism, with their closed forms; A04, Bricard's over-constrained mechanism, and A05,
  the stiff flyball governor, as spatial trees.

Each problem is built with :func:`conmech.symbolic.constrained_system` (kinetic and
potential energies and holonomic constraints) or :func:`conmech.symbolic.spatial_tree`
and compiled on first use (cached).
"""
from .bari import Problem, andrews, car_axis, mescd
from .iftomm import (a01_exact, a01_pendulum, a02_exact, a02_n_four_bar, a04_bricard, a04_p3,
                     a05_governor)

__all__ = ["Problem", "andrews", "car_axis", "mescd", "a01_pendulum", "a01_exact",
           "a02_n_four_bar", "a02_exact", "a04_bricard", "a04_p3", "a05_governor"]
