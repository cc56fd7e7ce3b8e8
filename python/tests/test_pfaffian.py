"""Exactness of Pfaffian constraints (conmech.symbolic.pfaffian): holonomic vs non-holonomic.

Every integrable case asserts the real property: d(mu omega) = 0 symbolically and
grad f = mu a (the integral's gradient is parallel to the form); every non-holonomic case
asserts a non-zero Frobenius residual (and checks it at a point, numerically)."""
import pytest

sp = pytest.importorskip("sympy")

from conmech.symbolic.pfaffian import (exterior_derivative, one_form, pfaffian,  # noqa: E402
                                       pfaffian_from_velocities, pfaffian_system)

x, y, z, t = sp.symbols("x y z t", real=True)


def _zero(e):
    return sp.simplify(sp.trigsimp(sp.simplify(e))) == 0


def assert_holonomic(res, coeffs, coords):
    """mu omega closed and grad f = mu a (parallel to the form, f not constant)."""
    assert res.integrable and res.holonomic
    assert res.residual == {} and res.residual_expr == 0
    mu = res.integrating_factor
    assert mu is not None and not _zero(mu)
    c = [mu * sp.sympify(a) for a in coeffs]
    d = exterior_derivative(one_form(c), coords)
    assert all(_zero(v) for v in d.values())
    f = res.integral
    assert f is not None
    assert any(not _zero(sp.diff(f, q)) for q in coords)
    for q, ci in zip(coords, c):
        assert _zero(sp.diff(f, q) - ci), (q, f, ci)


def assert_nonholonomic(res, point):
    assert not res.integrable and res.integrating_factor is None and res.integral is None
    assert res.residual, "a non-integrable form must have a non-zero omega ^ d omega"
    val = float(sp.N(res.residual_expr.subs(point)))
    assert val > 1e-6


# ------------------------------------------------------------------ the seed's pendulum
def test_pendulum_exact():
    res = pfaffian([x, y], [x, y])
    assert res.exact and res.closedness == {}
    assert_holonomic(res, [x, y], [x, y])
    assert _zero(res.integral - (x ** 2 + y ** 2) / 2)


def test_pendulum_seed_form_with_dt():
    """u_x du_x + (u_y - L) du_y + 0 dt (the lecture notes): exact, integral the circle."""
    ux, uy, L = sp.symbols("u_x u_y L", real=True)
    coeffs = [ux, uy - L, 0]
    res = pfaffian(coeffs, [ux, uy, t])
    assert res.exact
    assert_holonomic(res, coeffs, [ux, uy, t])
    diff = 2 * res.integral - (ux ** 2 + (uy - L) ** 2)  # a constant (here -L^2)
    assert all(_zero(sp.diff(diff, q)) for q in (ux, uy, t))


@pytest.mark.parametrize("factor", [1 + x ** 2 * y ** 4, sp.exp(x * y) * (2 + sp.sin(x)),
                                    1 / (3 + x ** 2 + y)])
def test_pendulum_times_arbitrary_factor_needs_mu(factor):
    coeffs = [x * factor, y * factor]
    res = pfaffian(coeffs, [x, y])
    assert not res.exact, "the multiplied form is not closed: a factor is needed"
    assert_holonomic(res, coeffs, [x, y])
    # the integral is a function of the circle's radius: its gradient is parallel to (x, y)
    f = res.integral
    assert _zero(sp.diff(f, x) * y - sp.diff(f, y) * x)


def test_pendulum_hidden_factor_by_dsolve():
    """(x dx + y dy) (1 + y) / (1 + x^2): the ODE route (dsolve) or an ansatz must find mu."""
    coeffs = [x * (1 + y) / (1 + x ** 2), y * (1 + y) / (1 + x ** 2)]
    res = pfaffian(coeffs, [x, y])
    assert_holonomic(res, coeffs, [x, y])


# ------------------------------------------------------------------ textbook forms
def test_bernoulli_form_needs_dsolve():
    """dy - (y/x + x^2 y^2) dx = 0 (a Bernoulli equation): no ansatz family closes it, the
    ODE dy/dx = y/x + x^2 y^2 solved by dsolve gives F = x^4 + 4x/y and mu = F_x/a_x."""
    coeffs = [-(y / x + x ** 2 * y ** 2), 1]
    res = pfaffian(coeffs, [x, y])
    assert "dsolve" in res.method
    assert_holonomic(res, coeffs, [x, y])
    gf = [sp.diff(res.integral, q) for q in (x, y)]
    gg = [sp.diff(x ** 4 + 4 * x / y, q) for q in (x, y)]
    assert _zero(gf[0] * gg[1] - gf[1] * gg[0])


def test_y_dx_minus_x_dy():
    coeffs = [y, -x]
    res = pfaffian(coeffs, [x, y])
    assert not res.exact
    assert_holonomic(res, coeffs, [x, y])
    mu = res.integrating_factor
    known = [1 / x ** 2, 1 / y ** 2, 1 / (x * y), 1 / (x ** 2 + y ** 2), -1 / x ** 2,
             -1 / y ** 2, -1 / (x * y), -1 / (x ** 2 + y ** 2)]
    assert any(_zero(mu - k) for k in known), mu


@pytest.mark.parametrize("mu", [1 / x ** 2, 1 / (x ** 2 + y ** 2)])
def test_y_dx_minus_x_dy_textbook_factors_close_it(mu):
    """The textbook factors 1/x^2 and 1/(x^2 + y^2) make y dx - x dy exact."""
    d = exterior_derivative(one_form([mu * y, -mu * x]), [x, y])
    assert all(_zero(v) for v in d.values())
    assert exterior_derivative(one_form([y, -x]), [x, y])  # and the form alone is not


def test_linear_ode_form_one_variable_factor():
    """(x^2 + y^2 + x) dx + y dy: mu = exp(2x) (mu depends on x only)."""
    coeffs = [x ** 2 + y ** 2 + x, y]
    res = pfaffian(coeffs, [x, y])
    assert_holonomic(res, coeffs, [x, y])
    assert _zero(sp.diff(res.integrating_factor, y))


def test_three_variables_exact():
    coeffs = [y * z, x * z, x * y]
    res = pfaffian(coeffs, [x, y, z])
    assert res.exact
    assert_holonomic(res, coeffs, [x, y, z])
    assert _zero(res.integral - x * y * z)


def test_three_variables_needs_factor():
    """yz dx + 2xz dy - 3xy dz: integrable, mu = 1/(xyz), f = x y^2 / z^3 up to a function."""
    coeffs = [y * z, 2 * x * z, -3 * x * y]
    res = pfaffian(coeffs, [x, y, z])
    assert not res.exact
    assert_holonomic(res, coeffs, [x, y, z])
    # f is constant on the level sets of x y^2 / z^3
    g = x * y ** 2 / z ** 3
    gf = sp.Matrix([sp.diff(res.integral, q) for q in (x, y, z)])
    gg = sp.Matrix([sp.diff(g, q) for q in (x, y, z)])
    assert all(_zero(c) for c in gf.cross(gg))


def test_three_variables_common_factor():
    h = (1 + x ** 2 + y ** 2 + z ** 2)
    coeffs = [y * z * h, x * z * h, x * y * h]
    res = pfaffian(coeffs, [x, y, z])
    assert not res.exact
    assert_holonomic(res, coeffs, [x, y, z])


def test_rheonomic_yoyo_constraint_with_dt():
    """du + r dtheta - (vh + ah t) dt = 0 (the lecture notes' yo-yo, linear in u): exact."""
    u, th, r, vh, ah = sp.symbols("u theta r v_h a_h", real=True)
    coeffs = [1, r, -(vh + ah * t)]
    res = pfaffian(coeffs, [u, th, t])
    assert_holonomic(res, coeffs, [u, th, t])
    assert _zero(res.integral - (u + r * th - vh * t - ah * t ** 2 / 2))


# ------------------------------------------------------------------ non-holonomic
X, Y, TH, PH, R = sp.symbols("x y theta phi R", real=True)
PT = {X: 0.3, Y: -0.2, TH: 0.7, PH: 0.1, R: 1.3}


def test_rolling_coin_each_constraint_non_integrable():
    """Seed 002: x1' + r phi' cos th = 0, y1' - r phi' sin th = 0."""
    q = [X, Y, TH, PH]
    tt = sp.Symbol("t")
    qf = [sp.Function(n)(tt) for n in ("x", "y", "theta", "phi")]
    sub = dict(zip(qf, q))
    e1 = qf[0].diff(tt) + R * qf[3].diff(tt) * sp.cos(qf[2])
    e2 = qf[1].diff(tt) - R * qf[3].diff(tt) * sp.sin(qf[2])
    for e in (e1, e2):
        vel = [f.diff(tt) for f in qf]
        res = pfaffian_from_velocities(e.subs({v: sp.Symbol(f"v{i}") for i, v in
                                               enumerate(vel)}).subs(sub), q,
                                       sp.symbols("v0:4"))
        assert_nonholonomic(res, PT)
    # the pair together: d omega_i ^ omega_1 ^ omega_2 != 0
    sysres = pfaffian_system([[1, 0, 0, R * sp.cos(TH)], [0, 1, 0, -R * sp.sin(TH)]], q)
    assert not sysres.integrable and sysres.residual
    assert all(not r.integrable for r in sysres.each)


def test_rolling_coin_residual_value():
    """omega = dx + R cos th dphi: omega ^ d omega = -R sin th dx ^ dth ^ dphi."""
    res = pfaffian([1, 0, 0, R * sp.cos(TH)], [X, Y, TH, PH])
    assert set(res.residual) == {(0, 2, 3)}
    assert _zero(res.residual[(0, 2, 3)] + R * sp.sin(TH))


def test_skate_knife_edge():
    """-sin th dx + cos th dy = 0: omega ^ d omega = -(sin^2 + cos^2) = -1 != 0 everywhere."""
    res = pfaffian([-sp.sin(TH), sp.cos(TH), 0], [X, Y, TH])
    assert_nonholonomic(res, PT)
    assert list(res.residual.values()) == [-1] or list(res.residual.values()) == [1]


def test_seed_rod_constraints_as_a_system():
    """Seed 000's rod: the rod length (holonomic) and 'the centre velocity along the rod'
    (x2 - x1)(y1' + y2') - (y2 - y1)(x1' + x2') = 0. The length constraint alone is exact;
    the pair is not integrable (the centre constraint is a knife edge at C)."""
    x1, y1, x2, y2 = q = sp.symbols("x1 y1 x2 y2", real=True)
    dx, dy = x2 - x1, y2 - y1
    length = [-dx, -dy, dx, dy]  # d[(dx^2 + dy^2)/2]
    centre = [-dy, dx, -dy, dx]
    r_len = pfaffian(length, q)
    assert_holonomic(r_len, length, q)
    both = pfaffian_system([length, centre], q)
    assert not both.integrable and both.residual
    pt = {x1: 0.1, y1: 0.4, x2: 1.0, y2: -0.3}
    vals = [float(v.subs(pt)) for v in both.residual.values()]
    assert max(abs(v) for v in vals) > 1e-6


def test_rubber_ball_constraints_non_holonomic():
    """The rubber ball (quaternion e, radius R): x' = R w_y, y' = -R w_x, w_z = 0 with
    w = 2 H(e) e' together with |e|^2 = 1: not integrable."""
    e0, e1, e2, e3 = sp.symbols("e0:4", real=True)
    q = [X, Y, e0, e1, e2, e3]
    wx = [0, 0, -2 * e1, 2 * e0, -2 * e3, 2 * e2]
    wy = [0, 0, -2 * e2, 2 * e3, 2 * e0, -2 * e1]
    wz = [0, 0, -2 * e3, -2 * e2, 2 * e1, 2 * e0]
    c1 = [1, 0] + [-R * a for a in wy[2:]]
    c2 = [0, 1] + [R * a for a in wx[2:]]
    res = pfaffian_system([[0, 0, e0, e1, e2, e3], c1, c2, wz], q)
    assert not res.integrable and res.residual
    assert all(not r.integrable for r in res.each[1:])


# ------------------------------------------------------------------ derived systems
def test_pfaffian_of_derived_systems():
    """The rubber ball's non-holonomic constraints are not integrable; the pendulum's
    x x' + y y' = 0 given as 'non-holonomic' is found holonomic with f = (x^2 + y^2)/2; a
    rheonomic Pfaffian constraint x' - w t = 0 integrates to x - w t^2/2."""
    from conmech.symbolic import pfaffian_of
    from conmech.symbolic.derive import derive_constrained
    e0, e1, e2, e3 = sp.symbols("e0:4")
    q = sp.symbols("x y e0 e1 e2 e3")
    v = sp.symbols("xd yd e0d e1d e2d e3d")
    Rb = sp.Symbol("R")
    ed = sp.Matrix(v[2:])
    H = sp.Matrix([[-e1, e0, -e3, e2], [-e2, e3, e0, -e1], [-e3, -e2, e1, e0]])
    w = 2 * H * ed
    d = derive_constrained(ed.dot(ed) + (v[0] ** 2 + v[1] ** 2) / 2, 0, list(q),
                           holonomic=[(e0 ** 2 + e1 ** 2 + e2 ** 2 + e3 ** 2
                                       - 1) / 2],
                           nonholonomic=[v[0] - Rb * w[1], v[1] + Rb * w[0], w[2]],
                           params={Rb: 0.7}, velocities=v)
    r = pfaffian_of(d)
    assert not r.integrable and r.residual
    assert all(not e.integrable for e in r.each)
    xs, ys, xd, yd, wv = sp.symbols("x y xd yd w")
    d2 = derive_constrained((xd ** 2 + yd ** 2) / 2, 9.81 * ys, [xs, ys],
                            nonholonomic=[xs * xd + ys * yd, xd - wv * sp.Symbol("t")],
                            params={wv: 2.0}, velocities=[xd, yd])
    r2 = pfaffian_of(d2)
    tt = sp.Symbol("t")
    assert r2.each[0].integrable and r2.each[1].integrable
    back = dict(zip(d2.coords, [xs, ys]))   # the derivation may rename the coordinates
    back[d2.t] = tt
    back.update({p: sp.Symbol(n) for p, n in zip(d2.params, d2.param_names)})
    f0, f1 = r2.each[0].integral.xreplace(back), r2.each[1].integral.xreplace(back)
    assert all(_zero(sp.diff(2 * f0 - xs ** 2 - ys ** 2, s)) for s in (xs, ys, tt))
    assert all(_zero(sp.diff(f1 - (xs - wv * tt ** 2 / 2), s))
               for s in (xs, ys, tt))
    with pytest.raises(ValueError, match="no non-holonomic"):
        pfaffian_of(derive_constrained((xd ** 2 + yd ** 2) / 2, 0, [xs, ys],
                                       holonomic=[xs ** 2 + ys ** 2 - 1], velocities=[xd, yd]))
    with pytest.raises(TypeError, match="Derived"):
        pfaffian_of(42)


# ------------------------------------------------------------------ bad input
def test_bad_input():
    with pytest.raises(ValueError, match="coefficients for"):
        pfaffian([x], [x, y])
    with pytest.raises(TypeError, match="Symbol"):
        pfaffian([x, y], [x, x + y])
    with pytest.raises(ValueError, match="zero"):
        pfaffian([0, 0], [x, y])
    with pytest.raises(ValueError, match="distinct"):
        pfaffian([x, y], [x, x])
    v = sp.symbols("v0:2")
    with pytest.raises(ValueError, match="not linear"):
        pfaffian_from_velocities(v[0] ** 2 + v[1], [x, y], v)
    with pytest.raises(ValueError, match="t="):
        pfaffian_from_velocities(v[0] + 1, [x, y], v)
