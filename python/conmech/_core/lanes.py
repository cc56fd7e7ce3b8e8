"""The SIMD lane counts of the Taylor method's ensemble route.

A batch library of a model's Taylor recurrences integrates this many members in the lanes
of one vector loop; the ensembles (conmech.ivp.ensemble) check a user's ``lanes`` against
them and the symbolic layer (conmech.symbolic.taylor_batch) builds libraries for them. The
constant lives below both so that neither imports the other."""

__all__ = ["LANES"]

#: the lane counts of the SIMD Taylor route (conmech.symbolic.taylor_batch)
LANES = (1, 2, 4, 8, 16)
