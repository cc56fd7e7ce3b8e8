"""The seed systems of the lecture notes written as T, U and constraints for
conmech.symbolic, each beside the name and parameters of the hand-written built-in it must
reproduce (shared by test_symbolic_seeds.py and bench/bench_symbolic_builtin.py).

Each entry: name -> (built-in name, parameters in the built-in's order as a dict, a function
returning the arguments of the symbolic constructor, initial (q0, v0), a time span)."""
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

t = dynamicsymbols._t


def D(f):
    return f.diff(t)


def _syms(names):
    return sp.symbols(names)


# ------------------------------------------------------------------ generalized coordinates

def pendulum_angle():
    th = dynamicsymbols("theta")
    m, g, l = _syms("m g l")
    # angle from the downward vertical; bob at (l sin th, -l cos th)
    x, y = l*sp.sin(th), -l*sp.cos(th)
    T = m*(D(x)**2 + D(y)**2)/2
    U = m*g*y
    return T - U, [th]


def cart_pendulum():
    x, th = dynamicsymbols("x theta")
    M, m, l, g = _syms("M m l g")
    # theta from the upward vertical, bob at (x + l sin th, l cos th)
    xb, yb = x + l*sp.sin(th), l*sp.cos(th)
    T = M*D(x)**2/2 + m*(D(xb)**2 + D(yb)**2)/2
    U = m*g*yb
    return T - U, [x, th]


def double_pendulum():
    th1, th2 = dynamicsymbols("theta1 theta2")
    m1, m2, l1, l2, g = _syms("m1 m2 l1 l2 g")
    x1, y1 = l1*sp.sin(th1), -l1*sp.cos(th1)
    x2, y2 = x1 + l2*sp.sin(th2), y1 - l2*sp.cos(th2)
    T = m1*(D(x1)**2 + D(y1)**2)/2 + m2*(D(x2)**2 + D(y2)**2)/2
    U = m1*g*y1 + m2*g*y2
    return T - U, [th1, th2]


def atwood():
    y1 = dynamicsymbols("y1")
    m1, m2, g, L = _syms("m1 m2 g L")
    # y measured downward, y2 = L - y1
    y2 = L - y1
    T = (m1*D(y1)**2 + m2*D(y2)**2)/2
    U = -m1*g*y1 - m2*g*y2
    return T - U, [y1]


def spring_pendulum():
    r, th = dynamicsymbols("r theta")
    m, k, l0, g = _syms("m k l0 g")
    x, y = r*sp.sin(th), -r*sp.cos(th)
    T = m*(D(x)**2 + D(y)**2)/2
    U = m*g*y + k*(r - l0)**2/2
    return T - U, [r, th]


def double_spring_pendulum():
    x1, y1, x2, y2 = dynamicsymbols("x1 y1 x2 y2")
    m1, m2, k1, k2, l1, l2, g = _syms("m1 m2 k1 k2 l1 l2 g")
    T = m1*(D(x1)**2 + D(y1)**2)/2 + m2*(D(x2)**2 + D(y2)**2)/2
    U = m1*g*y1 + m2*g*y2 + k1*(sp.sqrt(x1**2 + y1**2) - l1)**2/2 \
        + k2*(sp.sqrt((x2 - x1)**2 + (y2 - y1)**2) - l2)**2/2
    return T - U, [x1, y1, x2, y2]


def three_springs():
    q = dynamicsymbols("x1 y1 x2 y2 x3 y3")
    m, k, l0 = _syms("m k l0")
    r = [(q[0], q[1]), (q[2], q[3]), (q[4], q[5])]
    T = m*sum(D(c)**2 for c in q)/2

    def dist(a, b):
        return sp.sqrt((a[0] - b[0])**2 + (a[1] - b[1])**2)
    U = k*((dist(r[0], r[1]) - l0)**2 + (dist(r[1], r[2]) - l0)**2
           + (dist(r[0], r[2]) - l0)**2)/2
    return T - U, list(q)


def bead_hoop():
    th = dynamicsymbols("theta")
    m, R, w, g = _syms("m R omega g")
    # hoop spinning at omega about the vertical, bead at angle th from the bottom
    T = m*(R**2*D(th)**2 + w**2*R**2*sp.sin(th)**2)/2
    U = -m*g*R*sp.cos(th)
    return T - U, [th]


def polar_particle():
    r, th = dynamicsymbols("r theta")
    m, mu = _syms("m mu")
    T = m*(D(r)**2 + r**2*D(th)**2)/2
    U = -m*mu/r
    return T - U, [r, th]


def pendulum_moving():
    th = dynamicsymbols("theta")
    m, g, l, a, b, w = _syms("m g l a b w")
    s = a*t**2/2 + b*sp.sin(w*t)            # horizontal motion of the suspension point
    x, y = s + l*sp.sin(th), -l*sp.cos(th)
    T = m*(D(x)**2 + D(y)**2)/2
    U = m*g*y
    return T - U, [th]


def yoyo_angle():
    y = dynamicsymbols("y")
    m, r, I, g, ah, vh, h0 = _syms("m r I g ah vh h0")
    yh = h0 + vh*t + ah*t**2/2              # the hand holding the string
    psi = (yh - y)/r                        # unwound angle (the string does not slip)
    T = m*D(y)**2/2 + I*D(psi)**2/2
    U = m*g*y
    return T - U, [y]


GENERALIZED = {
    "pendulum_angle": (dict(m=0.7, g=9.81, l=1.3), pendulum_angle, [1.1], [0.0], 12.0),
    "cart_pendulum": (dict(M=1.3, m=0.7, l=0.9, g=9.81), cart_pendulum, [0.1, 3.0],
                      [0.2, 0.0], 8.0),
    "double_pendulum": (dict(m1=1.0, m2=0.8, l1=1.0, l2=0.7, g=9.81), double_pendulum,
                        [0.4, -0.3], [0.0, 0.2], 8.0),
    "atwood": (dict(m1=2.0, m2=1.0, g=9.81), atwood, [0.0], [0.1], 3.0),
    "spring_pendulum": (dict(m=1.0, k=40.0, l0=1.0, g=9.81), spring_pendulum, [1.2, 0.8],
                        [0.0, 0.0], 8.0),
    "double_spring_pendulum": (dict(m1=1.0, m2=1.2, k1=40.0, k2=35.0, l1=1.0, l2=0.9,
                                    g=9.81), double_spring_pendulum,
                               [0.8, -0.8, 1.5, -1.6], [0.0, 0.0, 0.0, 0.0], 6.0),
    "three_springs": (dict(m=1.0, k=10.0, l0=1.0), three_springs,
                      [0.0, 0.0, 1.2, 0.0, 0.5, 0.9], [0.0, 0.1, 0.0, -0.2, 0.3, 0.1], 8.0),
    "bead_hoop": (dict(m=1.0, R=0.8, omega=5.0, g=9.81), bead_hoop, [0.5], [0.0], 8.0),
    "polar_particle": (dict(m=1.0, mu=1.0), polar_particle, [1.0, 0.0], [0.0, 1.2], 30.0),
    "pendulum_moving": (dict(m=1.0, g=9.81, l=1.0, a=0.2, b=0.1, w=3.0), pendulum_moving,
                        [0.6], [0.0], 10.0),
    "yoyo_angle": (dict(m=1.0, r=0.05, I=1.25e-3, g=9.81, ah=1.5, vh=0.3, h0=0.2),
                   yoyo_angle, [0.2], [0.3], 2.0),
}
# extra parameters the symbolic form needs beyond the built-in's (constants in U only)
EXTRA = {"atwood": dict(L=2.0)}


# ------------------------------------------------------------------ excessive coordinates

def pendulum_xy():
    x, y = dynamicsymbols("x y")
    m, g, l = _syms("m g l")
    T = m*(D(x)**2 + D(y)**2)/2
    return dict(T=T, U=m*g*y, q=[x, y], holonomic=[(x**2 + y**2 - l**2)/2])


def rod_two_masses():
    x1, y1, x2, y2 = dynamicsymbols("x1 y1 x2 y2")
    g, l = _syms("g l")
    T = (D(x1)**2 + D(y1)**2 + D(x2)**2 + D(y2)**2)/2     # unit masses
    U = g*(y1 + y2)
    # the velocity of the rod's centre stays along the rod
    nh = (x2 - x1)*(D(y1) + D(y2)) - (y2 - y1)*(D(x1) + D(x2))
    return dict(T=T, U=U, q=[x1, y1, x2, y2],
                holonomic=[((x2 - x1)**2 + (y2 - y1)**2 - l**2)/2], nonholonomic=[nh])


def double_pendulum_xy():
    x1, y1, x2, y2 = dynamicsymbols("x1 y1 x2 y2")
    m1, m2, l1, l2, g = _syms("m1 m2 l1 l2 g")
    T = m1*(D(x1)**2 + D(y1)**2)/2 + m2*(D(x2)**2 + D(y2)**2)/2
    return dict(T=T, U=g*(m1*y1 + m2*y2), q=[x1, y1, x2, y2],
                holonomic=[(x1**2 + y1**2 - l1**2)/2,
                           ((x2 - x1)**2 + (y2 - y1)**2 - l2**2)/2])


def atwood_xy():
    y1, y2 = dynamicsymbols("y1 y2")
    m1, m2, g, L = _syms("m1 m2 g L")
    return dict(T=(m1*D(y1)**2 + m2*D(y2)**2)/2, U=-g*(m1*y1 + m2*y2), q=[y1, y2],
                holonomic=[L - y1 - y2])


def pendulum_moving_xy():
    x, y = dynamicsymbols("x y")
    m, g, l, a, b, w = _syms("m g l a b w")
    s = a*t**2/2 + b*sp.sin(w*t)
    return dict(T=m*(D(x)**2 + D(y)**2)/2, U=m*g*y, q=[x, y],
                holonomic=[((x - s)**2 + y**2 - l**2)/2])


def yoyo():
    y, psi = dynamicsymbols("y psi")
    m, r, I, g, ah, vh, h0 = _syms("m r I g ah vh h0")
    yh = h0 + vh*t + ah*t**2/2
    return dict(T=m*D(y)**2/2 + I*D(psi)**2/2, U=m*g*y, q=[y, psi],
                holonomic=[y + r*psi - yh])


def skate():
    x, y, th = dynamicsymbols("x y theta")
    m, I, g, alpha = _syms("m I g alpha")
    return dict(T=m*(D(x)**2 + D(y)**2)/2 + I*D(th)**2/2, U=-m*g*sp.sin(alpha)*x,
                q=[x, y, th], nonholonomic=[-sp.sin(th)*D(x) + sp.cos(th)*D(y)])


def rolling_disk():
    x, y, th, ph = dynamicsymbols("x y theta phi")
    m, R, Ir, It = _syms("m R I_roll I_turn")
    T = m*(D(x)**2 + D(y)**2)/2 + It*D(th)**2/2 + Ir*D(ph)**2/2
    return dict(T=T, U=0, q=[x, y, th, ph],
                nonholonomic=[D(x) - R*sp.cos(th)*D(ph), D(y) - R*sp.sin(th)*D(ph)])


CONSTRAINED = {
    "pendulum_xy": (dict(m=0.7, g=9.81, l=1.3), pendulum_xy, 10.0),
    "rod_two_masses": (dict(g=9.81, l=1.0), rod_two_masses, 3.0),
    "double_pendulum_xy": (dict(m1=1.0, m2=0.8, l1=1.0, l2=0.7, g=9.81), double_pendulum_xy,
                           5.0),
    "atwood_xy": (dict(m1=2.0, m2=1.0, g=9.81, L=2.0), atwood_xy, 1.0),
    "pendulum_moving_xy": (dict(m=1.0, g=9.81, l=1.0, a=0.2, b=0.1, w=3.0),
                           pendulum_moving_xy, 8.0),
    "yoyo": (dict(m=1.0, r=0.05, I=1.25e-3, g=9.81, ah=1.5, vh=0.3, h0=0.2), yoyo, 2.0),
    "skate": (dict(m=1.0, I=1.0, g=9.81, alpha=0.3), skate, 6.0),
    "rolling_disk": (dict(m=1.0, R=1.0, I_roll=0.5, I_turn=0.25), rolling_disk, 10.0),
}


# ------------------------------------------------------------------ Hill's problem

def hill_ode():
    """Hill's problem as formulas: x'' - 2 m y' = F_x, y'' + 2 m x' = F_y."""
    x, y, u, v = sp.symbols("x y u v")
    m, kappa = sp.symbols("m kappa")
    F = kappa/sp.sqrt(x**2 + y**2) + sp.Rational(3, 2)*m**2*x**2
    return [u, v, 2*m*v + F.diff(x), -2*m*u + F.diff(y)], [x, y, u, v]


def hill_lagrangian():
    """Hill's problem from its Lagrangian in the rotating frame,
    L = (x'^2 + y'^2)/2 + m (x y' - y x') + F(x, y)."""
    x, y = dynamicsymbols("x y")
    m, kappa = sp.symbols("m kappa")
    F = kappa/sp.sqrt(x**2 + y**2) + sp.Rational(3, 2)*m**2*x**2
    return (D(x)**2 + D(y)**2)/2 + m*(x*D(y) - y*D(x)) + F, [x, y]


# ------------------------------------------------------------------ first-order systems

def arenstorf_ode():
    """Arenstorf's equations (restricted three-body problem, rotating frame) as formulas
    for conmech.symbolic.ode_system: (f, [x, y, u, v], the parameter symbol mu)."""
    x, y, u, v, mu = sp.symbols("x y u v mu")
    mp = 1 - mu
    r1 = sp.sqrt((x + mu)**2 + y**2)
    r2 = sp.sqrt((x - mp)**2 + y**2)
    f = [u, v, x + 2*v - mp*(x + mu)/r1**3 - mu*(x - mp)/r2**3,
         y - 2*u - mp*y/r1**3 - mu*y/r2**3]
    return f, [x, y, u, v], mu


def use_test_cache(base):
    """Point CONMECH_CACHE at the test session's compile cache (created under `base` by
    the first test module that asks; shared by every module of the session)."""
    import os
    d = os.environ.get("_CONMECH_TEST_CACHE")
    if not d:
        d = os.path.join(str(base), "conmech_cache")
        os.environ["_CONMECH_TEST_CACHE"] = d
    os.environ["CONMECH_CACHE"] = d
    return d


def rel(a, b):
    """max |a - b| / max |b| (the relative difference the symbolic tests compare with)."""
    import numpy as np
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300)
