#!/usr/bin/env python3
"""Wall clock of solve_ivp's fixed cost, in one process: the symbolic Kepler system (zero
span and one period at 1e-12, DOP853 and TAYLOR), the built-in Kepler system over a short
span, and a Python right-hand side against SciPy's solve_ivp (zero span and (0, 0.1),
DOP853 and RK45). Each figure is the minimum over 7 batches (us per call); run it on a
quiet machine and give `uptime` beside the figures.

    python bench/solve_ivp_fixed_cost.py
"""
import time

import numpy as np
import scipy.integrate as si
import sympy as sp

import conmech
from conmech import symbolic
x, y, u, v = sp.symbols("x y u v")
r3 = (x**2 + y**2)**sp.Rational(3, 2)
kep = symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])
e=0.9; y0=[1-e,0.0,0.0,np.sqrt((1+e)/(1-e))]
bk=conmech.systems.kepler()
def tmin(f, n=500):
    f()
    best=1e9
    for _ in range(7):
        a=time.perf_counter()
        for _ in range(n): f()
        best=min(best,(time.perf_counter()-a)/n)
    return best*1e6
for m in ["DOP853","TAYLOR"]:
    print(m, "symbolic Kepler zero span %.1f us"%tmin(lambda: conmech.solve_ivp(kep,(0,0),y0,method=m,rtol=1e-12,atol=1e-12)),
          "one period 1e-12 %.1f us"%tmin(lambda: conmech.solve_ivp(kep,(0,2*np.pi),y0,method=m,rtol=1e-12,atol=1e-12),200))
print("built-in Kepler, DOP853, span 0.01: %.1f us"%tmin(lambda: conmech.solve_ivp(bk,(0,0.01),[0.5,0,0,3**0.5],method="DOP853")))
f=lambda t,y: [y[2],y[3],-y[0],-y[1]]
for m in ["DOP853", "RK45"]:
    for span in [(0,0),(0,0.1)]:
        c=tmin(lambda: conmech.solve_ivp(f,span,[1.,0,0,1.],method=m),200)
        s=tmin(lambda: si.solve_ivp(f,span,[1.,0,0,1.],method=m),200)
        print(f"Python rhs {m} span {span}: conmech {c:.1f} us, SciPy {s:.1f} us")
