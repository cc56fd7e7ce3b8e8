"""Initial value problems: :func:`solve_ivp` (solve.py) over the method table
(methods.py), the steppers with SciPy's OdeSolver interface (stepper.py), dense output
(dense.py), implicit-method options and Jacobian callbacks (implicit.py), the Taylor
method's glue to the symbolic front end (taylor.py), a state carried from one time to
the next in one Fortran call each (propagator.py) and ensembles in OpenMP threads
(ensemble.py). The public names are re-exported by :mod:`conmech`."""
