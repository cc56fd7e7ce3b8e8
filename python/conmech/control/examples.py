"""Underactuated systems a control engineer recognises, with virtual holonomic constraints
for oscillations about the upright equilibrium:

- :func:`cart_pendulum`: the lecture notes' pendulum on a cart (theta from the upright),
  the force on the cart; constraint x = -c theta (Shiriaev, Perram, Canudas-de-Wit 2005
  stabilise oscillations of this system with a constraint of this kind);
- :func:`pendubot`: the Pendubot (two links, torque at the shoulder, elbow passive) with
  the parameters of Block and Spong's Pendubot (theta1..theta5 = 0.0308, 0.0106, 0.0095,
  0.2087, 0.0630 SI, angles here from the upright); constraint q1 = k q2 (phase: the
  passive elbow);
- :func:`double_pendulum_cart`: a double pendulum on a cart, force on the cart and torque
  at the elbow, the shoulder passive (3 degrees of freedom); constraint x = c1 theta1,
  theta2 = c2 theta1 (absolute angles from the upright).

Each returns (plant, constraint). The symbolic ones are compiled once into the cache.
"""
from __future__ import annotations

from ..mechanics import systems
from .plant import ControlledSystem
from .vhc import VirtualConstraint

__all__ = ["cart_pendulum", "pendubot", "double_pendulum_cart"]


def cart_pendulum(c=1.6, M=1.0, m=1.0, l=1.0, g=9.81):
    """The built-in cart pendulum (q = [x, theta], theta from the upright) with the force
    on the cart, and the constraint x = -c theta (phase theta, the passive coordinate).
    For c > l the upright is a centre of the reduced dynamics, with
    alpha = m l (l - c cos theta) < 0 for |theta| < arccos(l/c)."""
    plant = ControlledSystem(systems.cart_pendulum(M=M, m=m, l=l, g=g), actuated=[0])
    return plant, VirtualConstraint(plant, 1, [[0.0, -c]])


def pendubot(k=-0.8, g=9.81):
    """The Pendubot: M = [t1 + t2 + 2 t3 cos q2, t2 + t3 cos q2; ., t2], potential
    U = t4 g cos q1 + t5 g cos(q1 + q2) (q1 the shoulder from the upright, q2 the elbow
    relative), torque on q1. Constraint q1 = k q2 (phase q2): for k in about (-1, -0.55)
    the upright is a centre of the reduced dynamics."""
    # sympy (conmech.symbolic's) is an optional dependency: imported for this example only
    import sympy as sp
    from sympy.physics.mechanics import dynamicsymbols
    from .. import symbolic
    t = dynamicsymbols._t
    q1, q2 = dynamicsymbols("q1 q2")
    t1, t2, t3, t4, t5, gs = sp.symbols("theta1:6 g")
    d1, d2 = q1.diff(t), q2.diff(t)
    T = (t1 + t2 + 2*t3*sp.cos(q2))*d1**2/2 + (t2 + t3*sp.cos(q2))*d1*d2 + t2*d2**2/2
    U = t4*gs*sp.cos(q1) + t5*gs*sp.cos(q1 + q2)
    pars = {t1: 0.0308, t2: 0.0106, t3: 0.0095, t4: 0.2087, t5: 0.0630, gs: g}
    plant = symbolic.lagrangian_system(T - U, [q1, q2], params=pars, inputs=[q1])
    return plant, VirtualConstraint(plant, 1, [[0.0, k]])


def double_pendulum_cart(c1=-1.5, c2=0.0, M=1.0, m1=0.5, m2=0.5, l1=0.5, l2=0.5, g=9.81):
    """A double pendulum (point masses m1, m2 on massless rods l1, l2) on a cart M,
    q = [x, theta1, theta2] (absolute angles from the upright), inputs: the force F on the
    cart and the torque tau at the elbow (generalized forces [F, -tau, tau]); the shoulder
    is passive. Constraint x = c1 theta1, theta2 = c2 theta1 (phase theta1): with the
    defaults the second link stays upright while the first swings, and the cart follows."""
    # sympy (conmech.symbolic's) is an optional dependency: imported for this example only
    import sympy as sp
    from sympy.physics.mechanics import dynamicsymbols
    from .. import symbolic
    t = dynamicsymbols._t
    x, a, b = dynamicsymbols("x theta1 theta2")
    Ms, m1s, m2s, l1s, l2s, gs, F, tau = sp.symbols("M m1 m2 l1 l2 g F tau")
    p1 = sp.Matrix([x + l1s*sp.sin(a), l1s*sp.cos(a)])
    p2 = p1 + sp.Matrix([l2s*sp.sin(b), l2s*sp.cos(b)])
    v1, v2 = p1.diff(t), p2.diff(t)
    T = Ms*x.diff(t)**2/2 + m1s*v1.dot(v1)/2 + m2s*v2.dot(v2)/2
    U = m1s*gs*p1[1] + m2s*gs*p2[1]
    pars = {Ms: M, m1s: m1, m2s: m2, l1s: l1, l2s: l2, gs: g}
    plant = symbolic.lagrangian_system(T - U, [x, a, b], params=pars, forces=[F, -tau, tau],
                                       inputs=[F, tau])
    return plant, VirtualConstraint(plant, 1, [[0.0, c1], [0.0, c2]])
