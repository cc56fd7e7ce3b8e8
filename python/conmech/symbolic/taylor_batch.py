"""Taylor's method for ensembles in SIMD lanes: the generated batch propagator.

An ensemble of one symbolic ode system integrates many members with the same recurrences.
heyoka's batch mode runs ``width`` members in lock-step, one SIMD lane each; this module
generates the same for conmech, as Fortran that the compiler vectorises:

- the coefficient routine ``conmech_taylor_batch(t, order, w, p)`` of
  :func:`conmech.symbolic.taylor.c_routine` with a lane dimension first,
  w(lanes, 0:order, nw): every statement of the recurrences is an operation on ``lanes``
  contiguous values, one vector instruction (or two) per statement;
- the propagator ``conmech_taylor_batch_run`` (this module), which steps the lanes
  together with the state, the step, the time and the error scales of each lane in
  arrays of ``lanes`` values: Horner's evaluation of the polynomials, the safety check of
  the step, the error scales and the norms of the last two coefficients are vector
  operations over the lanes with no branch per lane; the per-lane decisions (accept or
  reject, reached the end, failed) are masks held as doubles (so that the compiler's
  selects stay vector ones), and the one logarithm and exponential of the step-size
  formula are per lane. Its steps run in a private routine compiled for the order of the
  written-out recurrences (constant bounds, Horner unrolled) and in another for any
  order.

Lanes are refilled: when a member ends (it reached tf, or failed) its lane takes the next
member of the call at once (its first expansion rides along with the other lanes' next
step), so no lane waits for the slowest member of a group. Each member takes exactly the
steps, and gets exactly the result, of its own :func:`conmech.solve_ivp` run with
method="TAYLOR" (the arithmetic of :mod:`conmech_taylor_core`, operation for operation; the
library is compiled without contraction of multiply-adds and calls glibc's scalar
elementary functions, so vector and scalar code round alike), whatever its lane, its
neighbours, the batch size or the number of threads.

The lane count is the machine's vector width for doubles by default (:func:`machine_lanes`:
8 with AVX-512, 4 with AVX2, else 2), and the library is compiled for that instruction set
(:func:`isa_flags`); ``conmech.ensemble.solve(..., lanes=k)`` builds another width.
"""
import re

from .._core.lanes import LANES     # the lane counts a batch library can be built with
from .isa import isa_flags, machine_lanes, scalar_isa_flags  # noqa: F401 (public names)
from .taylor_recipe import Recipe

#: the version of the generated batch code (a change regenerates the kept sources)
VERSION = 11

__all__ = ["machine_lanes", "isa_flags", "scalar_isa_flags", "coefficient_head",
           "coefficient_routine",
           "run_routine", "LANES"]

_LANE_NAMES = re.compile(r"\b(h\d+|iv\d+|t)\b(?!\()")


def coefficient_head(cname, lanes, nw, npar, ind):
    """The first lines of a batch coefficient routine ``cname(t, order, w, p)`` (bind(C)):
    `lanes` members, t(nl), w(nl, 0:order, nw), p(npar); `ind` the body's indentation."""
    return [f'    subroutine {cname}(t, order, w, p) bind(C, name="{cname}")',
            f"{ind}integer, parameter :: nl = {lanes}",
            f"{ind}real(dp), intent(in) :: t(nl)",
            f"{ind}integer(c_int), value, intent(in) :: order",
            f"{ind}real(dp), intent(inout) :: w(nl, 0:order, {nw})",
            f"{ind}real(dp), intent(in) :: p({npar})"]


def coefficient_routine(dec, names, lanes, cname="conmech_taylor_batch"):
    """Fortran lines of the bind(C) routine ``cname(t, order, w, p)`` computing the Taylor
    coefficients of `lanes` members at once, t(lanes), w(lanes, 0:order, nw) (w(:, 0, 1:n)
    the states on entry): the statements of :mod:`conmech.symbolic.taylor`'s loop version
    (the same operations in the same order, so each lane gets the scalar routine's
    coefficients to the last bit) inside ``!$omp simd`` loops over the lanes, innermost:
    one vector instruction per operation for all the lanes."""
    from . import taylor as T
    ind = "        "
    kind = "dp"
    pp = T._Printer(dec, names, False, kind)
    pp.w = lambda k, c: f"w(l, {k}, {c})"
    rc = Recipe(pp, False, "order")
    W = pp.w

    def lane(x):          # the accumulators, reciprocals and t are per lane
        return _LANE_NAMES.sub(lambda mm: f"{mm.group(1)}(l)", x)

    def loop(stmts, at):
        out = [f"{at}!$omp simd", f"{at}do l = 1, nl"]
        for x in stmts:
            out += T._wrap(lane(x), at + "    ")
        return out + [f"{at}end do"]
    one = pp.real(1)
    zero = f"0.0_{kind}"
    nw = dec.ncol
    npar = max(len(dec.params), 1)
    head = coefficient_head(cname, lanes, nw, npar, ind)
    decl = T._decls([c for c, _ in rc.consts], f"real({kind})", ind)
    decl += T._decls([f"{x}(nl)" for x in rc.accs + rc.invs], f"real({kind})", ind)
    decl += [f"{ind}real({kind}) :: fk, rk, rk1", f"{ind}integer :: k, j, l"]
    body = [f"{ind}if (order < 1) return"]
    for c, e in rc.consts:
        body += T._wrap(f"{c} = {e}", ind)
    jstate = [i + 1 for i in range(dec.n) if i + 1 in dec.jcol]
    first = list(rc.s0)
    first += [f"{W(1, i + 1)} = {pp.lin_at(o, 0, True)}" for i, o in enumerate(dec.outputs)]
    first += [f"{W(1, dec.jcol[c])} = {W(1, c)}" for c in jstate]
    body += loop(first, ind)
    E = {"k": "k", "fk": "fk", "rk": "rk"}
    body += [f"{ind}do k = 1, order - 1",
             f"{ind}    fk = real(k, {kind})",
             f"{ind}    rk = {one}/fk",
             f"{ind}    rk1 = {one}/(fk + {one})"]
    body += [f"{ind}    {h} = {zero}" for h in rc.accs]
    plain = [x for x in rc.hist if x[3] is not T._SYM]
    sym = [x for x in rc.hist if x[3] is T._SYM]
    body += T.history_loops(plain, sym, W, kind, pp.real(2), ind, loop)
    cur = [f(E) for f in rc.cur]
    cur += [f"{W('k + 1', i + 1)} = rk1*({pp.lin_at(o, 'k', False)})"
            for i, o in enumerate(dec.outputs)]
    cur += [f"{W('k + 1', dec.jcol[c])} = (fk + {one})*{W('k + 1', c)}" for c in jstate]
    body += loop(cur, ind + "    ")
    body.append(f"{ind}end do")
    return head + decl + body + [f"    end subroutine {cname}", ""]


def fixed_routine(dec, names, lanes, order, cname="conmech_taylor_batch_fixed"):
    """Fortran lines of the bind(C) routine ``cname(t, order, w, p)`` (arguments as
    :func:`coefficient_routine`'s) with the recurrences written out for one `order` (it
    does nothing for another order): the statements of the scalar routine written out
    (:func:`conmech.symbolic.taylor.body_lines` with ``fixed``: no loops, literal indices,
    the values in scalars; the same operations in the same order as the loop version) as
    the body of ONE ``!$omp simd`` loop over the lanes, its scalars private to each lane
    (a BLOCK): the compiler turns every scalar into a vector register of the lanes, the
    whole expansion straight-line vector code, as heyoka's batch mode compiles it (for
    expansions that call no elementary function but square roots: a scalar sin or exp
    call keeps the loop scalar, see taylor_library.batch_entries)."""
    import inspect
    from . import taylor as T
    ind = "        "
    kw = {"paired": False} if "paired" in inspect.signature(T.body_lines).parameters else {}
    decl, body = T.body_lines(dec, names, "dp", 0, False, ind + "        ", order, **kw)
    guard = body[0].strip()
    if not guard.startswith("if (order /="):
        raise ValueError("unexpected written-out Taylor body")
    lane_body = [_LANE_NAMES_FIXED.sub(lambda mm: f"{mm.group(1)}(l)",
                                      x.replace("w(", "w(l, ")) for x in body[1:]]
    nw = dec.ncol
    npar = max(len(dec.params), 1)
    return [f'    subroutine {cname}(t, order, w, p) bind(C, name="{cname}")',
            f"{ind}integer, parameter :: nl = {lanes}",
            f"{ind}real(dp), intent(in) :: t(nl)",
            f"{ind}integer(c_int), value, intent(in) :: order",
            f"{ind}real(dp), intent(inout) :: w(nl, 0:order, {nw})",
            f"{ind}real(dp), intent(in) :: p({npar})",
            f"{ind}integer :: l",
            f"{ind}{guard}",
            f"{ind}!$omp simd",
            f"{ind}do l = 1, nl",
            f"{ind}    block"] + decl + lane_body + \
        [f"{ind}    end block", f"{ind}end do", f"    end subroutine {cname}", ""]


# the time in a written-out body (the only per-lane name besides w)
_LANE_NAMES_FIXED = re.compile(r"\b(t)\b(?!\()")


def run_routine(n, nw, npar, lanes, codes, fixed=None):
    """Fortran lines of ``conmech_taylor_batch_run`` for a system of n states, nw work
    columns and npar parameter slots, with `lanes` lanes, and of the module's private
    stepping routines it calls (:func:`step_routines`); they call the coefficient routine
    ``conmech_taylor_batch`` of the same module. codes: the status codes (success,
    too_many_steps, step_too_small, nonfinite). fixed: the order of the written-out routine
    ``conmech_taylor_batch_fixed`` of the module, called for that order (else the loop
    version) by a stepping routine compiled for that order."""
    ok, many, small, nonfin = (int(c) for c in codes)
    run = 1 if 1 not in (ok, many, small, nonfin) else 99     # "still running"
    fmt = dict(n=n, nw=nw, npar=npar, lanes=lanes, ok=ok, many=many, small=small,
               nonfin=nonfin, run=run)
    call = _CALL.format(name="conmech_taylor_batch_steps", ordarg="ord, ")
    if fixed is not None:
        call = _CALL_FIXED.format(p=int(fixed), call=call)
    src = _RUN.format(call=call, **fmt)
    src += _STEPS.format(name="conmech_taylor_batch_steps", ordarg="ord, ",
                         orddecl="integer, intent(in) :: ord", coef=_COEF, **fmt)
    if fixed is not None:
        src += _STEPS.format(name=f"conmech_taylor_batch_steps{int(fixed)}", ordarg="",
                             orddecl=f"integer, parameter :: ord = {int(fixed)}",
                             coef=_COEF_FIXED, **fmt)
    return src.split("\n")


def step_routines(fixed=None):
    """The names of the private stepping routines of :func:`run_routine`'s code."""
    return ["conmech_taylor_batch_steps"] + \
        ([] if fixed is None else [f"conmech_taylor_batch_steps{int(fixed)}"])


_COEF = "            call conmech_taylor_batch(tc, int(ord, c_int), w(:, :, :, nu), p)"
_COEF_FIXED = \
    "            call conmech_taylor_batch_fixed(tc, int(ord, c_int), w(:, :, :, nu), p)"
_CALL = """\
        call {name}({ordarg}m, y, t0, tf, rt, atol, eps, decay, hm, mxs, p, wb, te, st, cnt)"""
_CALL_FIXED = """\
        if (ord == {p}) then
            call conmech_taylor_batch_steps{p}(m, y, t0, tf, rt, atol, eps, decay, hm, mxs, p, &
                                              wb, te, st, cnt)
        else
    {call}
        end if"""

_RUN = """\
    !> Integrate the members y(:, 1:m) from ts(1) to ts(2) in place, {lanes} lanes at a
    !! time (a lane takes the next member as soon as its own has ended), each member
    !! exactly as the scalar Taylor stepper integrates it alone; tol(:, 1) = rtol, tol(:, 2)
    !! = atol, steps of at most hx, at most mxs attempted; ord and decay: the scalar
    !! stepper's order and step factor for these tolerances (conmech_taylor_core's
    !! taylor_order and taylor_decay, given by the caller). st(j): the status of member j,
    !! te(j) where it stopped, cnt(:, j) its expansions (nfev), accepted, rejected steps.
    subroutine conmech_taylor_batch_run(m, y, ts, tol, hx, mxs, ord, decay, p, te, st, cnt) bind(C, name="conmech_taylor_batch_run")
        integer(c_int), value, intent(in) :: m, mxs, ord
        real(dp), intent(inout) :: y({n}, m)
        real(dp), intent(in) :: ts(2), tol({n}, 2), p({npar})
        real(dp), value, intent(in) :: hx, decay
        real(dp), intent(out) :: te(m)
        integer(c_int), intent(out) :: st(m), cnt(3, m)
        integer, parameter :: nl = {lanes}, nw = {nw}
        real(dp), allocatable :: wb(:)
        real(dp) :: rt({n}), atol({n}), t0, tf, eps, hm
        t0 = ts(1)
        tf = ts(2)
        atol = tol(:, 2)
        st = {ok}
        cnt = 0
        te = t0
        if (m < 1 .or. tf == t0) return
        ! the scalar stepper's tolerance and step bound (conmech_taylor_core)
        rt = max(tol(:, 1), epsilon(1.0_dp))
        eps = max(minval(rt), minval(atol))
        hm = min(abs(hx), abs(tf - t0))
        ! two expansions per lane (see the stepping routine), nl*(ord + 1)*nw values each
        allocate (wb(nl*(ord + 1)*nw*2))
{call}
    end subroutine conmech_taylor_batch_run

"""

_STEPS = """\
    !> The lanes' steps of conmech_taylor_batch_run for the order ord; w: two expansions per
    !! lane, the current one (the polynomial of the step being tried, cu) and the new one
    !! (at the step's end, nu): a step accepted makes the new one current (the two swap), a
    !! lane whose step is rejected keeps its own. Every per-lane quantity is an array over
    !! the lanes and every per-step operation a vector one over them, the decisions masks;
    !! only the logarithm and exponential of the next step (glibc's scalar functions, as
    !! the scalar stepper calls them) and the rare paths (a rejected step, a lane that
    !! ends) run lane by lane.
    subroutine {name}({ordarg}m, y, t0, tf, rt, atol, eps, decay, hm, mxs, p, w, te, st, cnt)
        {orddecl}
        integer(c_int), intent(in) :: m, mxs
        real(dp), intent(inout) :: y({n}, m)
        real(dp), intent(in) :: t0, tf, rt({n}), atol({n}), eps, decay, hm, p({npar})
        real(dp), intent(out) :: w({lanes}, 0:ord, {nw}, 2)
        real(dp), intent(inout) :: te(m)
        integer(c_int), intent(inout) :: st(m), cnt(3, m)
        integer, parameter :: nl = {lanes}, n = {n}
        real(dp), parameter :: check_max = 10.0_dp, fl = 16.0_dp*epsilon(1.0_dp)
        ! the margin of the choice of the smaller radius without its logarithms (below)
        real(dp), parameter :: margin = 1.0e-9_dp
        real(dp) :: t(nl), tlo(nl), h(nl), hc(nl), tc(nl), e(nl, n), yc(nl, n), yn(nl, n)
        real(dp) :: ea(nl, n)
        real(dp) :: dy(nl, n), err(nl), s1(nl), s2(nl), ym(nl), a1(nl), a2(nl), q(nl)
        real(dp) :: posneg, lg, rho, s, bb, lo, tn, tl, r, pw
        ! the lanes' flags (1 or 0), counters, members and statuses are doubles (small
        ! integers, exact), tested by comparisons in the lane loops: the compiler makes
        ! vector compares and blends of them (logicals or integers read from memory
        ! beside doubles become a branch per lane)
        integer, parameter :: i8 = selected_int_kind(18)
        integer(i8) :: b1, b2
        integer :: l, i, k, j, next, cu, nu, e1, e2
        real(dp) :: mem(nl), done(nl), nst(nl), na(nl), nr(nl), nx(nl), pick(nl)
        real(dp) :: fresh(nl), hit(nl), stp(nl), acc(nl), rej(nl), ok(nl), z(nl)
        real(dp) :: yv, go, a, b
        posneg = sign(1.0_dp, tf - t0)
        w = 0.0_dp
        cu = 1
        t = t0
        tlo = 0.0_dp
        h = 0.0_dp
        e = 1.0_dp
        yc = 0.0_dp
        mem = 0
        done = {ok}             ! an empty lane: filled at once
        nst = 0
        na = 0
        nr = 0
        nx = 0
        fresh = 0.0_dp
        next = 1
        do
            ! lanes whose member has ended: its results out, the next member in (fresh:
            ! its first expansion is made in this round, beside the others' steps); a
            ! lane left empty is "running" with no member (mem = 0)
            if (any(done /= {run})) then
                do l = 1, nl
                    if (done(l) == {run}) cycle
                    j = nint(mem(l))
                    if (j /= 0) then
                        y(:, j) = yc(l, :)
                        te(j) = t(l)
                        st(j) = nint(done(l), c_int)
                        cnt(:, j) = nint([nx(l), na(l), nr(l)], c_int)
                        mem(l) = 0
                    end if
                    done(l) = {run}
                    if (next > m) cycle
                    mem(l) = real(next, dp)
                    yc(l, :) = y(:, next)
                    t(l) = t0
                    tlo(l) = 0.0_dp
                    h(l) = 0.0_dp
                    fresh(l) = 1.0_dp
                    nst(l) = 0
                    na(l) = 0
                    nr(l) = 0
                    nx(l) = 0
                    next = next + 1
                end do
                if (all(mem == 0)) exit
            end if
            ! each running lane's step: the scalar stepper's limits, then its candidate
            !$omp simd private(go, a, b)
            do l = 1, nl
                go = merge(1.0_dp, 0.0_dp, mem(l) /= 0.0_dp .and. fresh(l) == 0.0_dp)
                a = real({small}, dp)
                b = real({many}, dp)
                done(l) = merge(b, merge(a, done(l), go /= 0.0_dp .and. .not. &
                                (0.1_dp*abs(h(l)) > abs(t(l))*epsilon(1.0_dp))), &
                                go /= 0.0_dp .and. nst(l) >= real(mxs, dp))
                stp(l) = merge(1.0_dp, 0.0_dp, go /= 0.0_dp .and. done(l) == {run})
                hit(l) = merge(1.0_dp, 0.0_dp, stp(l) /= 0.0_dp .and. &
                               (t(l) + h(l) - tf)*posneg >= 0.0_dp)
                a = (tf - t(l)) - tlo(l)
                b = t(l) + merge(a, h(l), hit(l) /= 0.0_dp)
                hc(l) = merge(merge(a, h(l), hit(l) /= 0.0_dp), 0.0_dp, stp(l) /= 0.0_dp)
                tc(l) = merge(b, t(l), stp(l) /= 0.0_dp)
                nst(l) = nst(l) + stp(l)
                nx(l) = nx(l) + merge(1.0_dp, stp(l), fresh(l) /= 0.0_dp .and. mem(l) /= 0.0_dp)
            end do
            ! the polynomials at the candidate steps (Horner, the value and its
            ! derivative in one pass), all lanes at once; a lane without a step expands
            ! at its current state (a new member: its initial state)
            nu = 3 - cu
            do i = 1, n
                !$omp simd
                do l = 1, nl
                    yn(l, i) = w(l, ord, i, cu)
                    dy(l, i) = 0.0_dp
                end do
            end do
            do k = ord - 1, 0, -1
                do i = 1, n
                    !$omp simd
                    do l = 1, nl
                        dy(l, i) = yn(l, i) + hc(l)*dy(l, i)
                        yn(l, i) = w(l, k, i, cu) + hc(l)*yn(l, i)
                    end do
                end do
            end do
            do i = 1, n
                !$omp simd private(a, b)
                do l = 1, nl
                    a = yn(l, i)
                    b = yc(l, i)
                    w(l, 0, i, nu) = merge(a, b, stp(l) /= 0.0_dp)
                end do
            end do
{coef}
            ! the safety check of every lane's step: h (P'(h) - f(t + h, P(h))) against
            ! the scales, f there from the new expansion's first coefficients
            err = 0.0_dp
            do i = 1, n
                !$omp simd
                do l = 1, nl
                    err(l) = max(err(l), abs(hc(l)*(dy(l, i) - w(l, 1, i, nu)))/(e(l, i) &
                                 + fl*(abs(yn(l, i)) + abs(hc(l)*dy(l, i)))))
                end do
            end do
            ! accepted or rejected; the time of an accepted step, t + h in double length
            ! (Knuth's TwoSum, as the scalar stepper), tf where the step hits the end
            !$omp simd private(s, bb, lo, tn, tl, a, b)
            do l = 1, nl
                err(l) = err(l)/real(ord + 1, dp)
                ok(l) = merge(1.0_dp, 0.0_dp, stp(l) /= 0.0_dp .and. err(l) <= check_max)
                rej(l) = stp(l) - ok(l)
                nr(l) = nr(l) + rej(l)
                na(l) = na(l) + ok(l)
                s = t(l) + hc(l)
                bb = s - t(l)
                lo = (t(l) - (s - bb)) + (hc(l) - bb)
                lo = lo + tlo(l)
                tn = s + lo
                tl = lo - (tn - s)
                a = merge(tf, tn, hit(l) /= 0.0_dp)
                b = merge(0.0_dp, tl, hit(l) /= 0.0_dp)
                t(l) = merge(a, t(l), ok(l) /= 0.0_dp)
                tlo(l) = merge(b, tlo(l), ok(l) /= 0.0_dp)
                a = real({ok}, dp)
                done(l) = merge(a, done(l), ok(l) /= 0.0_dp .and. hit(l) /= 0.0_dp)
                acc(l) = merge(1.0_dp, ok(l), fresh(l) /= 0.0_dp .and. mem(l) /= 0.0_dp)
            end do
            ! rejected steps: the step shrunk by the check's ratio; the lanes that did not
            ! accept keep their current expansion (copied into the new buffer)
            if (any(rej /= 0.0_dp)) then
                do l = 1, nl
                    if (rej(l) == 0.0_dp) cycle
                    if (err(l) == err(l) .and. err(l) <= huge(1.0_dp)) then
                        h(l) = hc(l)*max(0.1_dp, min(0.5_dp, 0.8_dp*(check_max/err(l))** &
                                                     (1.0_dp/real(ord + 1, dp))))
                    else
                        h(l) = 0.1_dp*hc(l)
                    end if
                end do
            end if
            if (any(acc == 0.0_dp .and. mem /= 0.0_dp)) then
                do l = 1, nl
                    if (mem(l) /= 0.0_dp .and. acc(l) == 0.0_dp) w(l, :, 1:n, nu) = w(l, :, 1:n, cu)
                end do
            end if
            cu = nu
            ! accepted lanes: the new state, expansion and scales; the norms of the last
            ! two coefficients (Jorba and Zou)
            ym = 0.0_dp
            do i = 1, n
                !$omp simd private(a, b, yv)
                do l = 1, nl
                    a = yn(l, i)
                    b = yc(l, i)
                    yv = merge(a, b, ok(l) /= 0.0_dp)
                    yc(l, i) = yv
                    ym(l) = max(ym(l), abs(yv))
                end do
            end do
            ! z: 0 where the new first coefficients are finite, else a NaN
            z = 0.0_dp
            s1 = 0.0_dp
            s2 = 0.0_dp
            ! (the new scales in a loop of their own: beside the select, their maxima
            ! make the loop scalar)
            do i = 1, n
                !$omp simd
                do l = 1, nl
                    ea(l, i) = max(atol(i), rt(i)*ym(l), tiny(1.0_dp))
                end do
            end do
            do i = 1, n
                !$omp simd
                do l = 1, nl
                    z(l) = z(l) + 0.0_dp*w(l, 1, i, cu)
                    e(l, i) = merge(ea(l, i), e(l, i), acc(l) /= 0.0_dp)
                    s1(l) = max(s1(l), abs(w(l, ord - 1, i, cu))/e(l, i))
                    s2(l) = max(s2(l), abs(w(l, ord, i, cu))/e(l, i))
                end do
            end do
            ! the next step h = min(rho, hm) from the radius rho = exp(lg) decay, lg the
            ! smaller of -log(a1)/(ord - 1) and -log(a2)/ord (conmech_taylor_core's
            ! taylor_next_rho, the same value): which one is smaller is known without the
            ! logarithms when q = a1 (a1/a2)**(ord - 1) (> 1: the first) is off 1 by more
            ! than the margin (far more than the rounding of q or of the logarithms), so
            ! one logarithm per lane (pick); else both, or the exponent test, lane by lane
            !$omp simd private(r, pw, a)
            do l = 1, nl
                fresh(l) = merge(0.0_dp, fresh(l), acc(l) /= 0.0_dp)
                a = real({nonfin}, dp)
                done(l) = merge(a, done(l), .not. (z(l) == 0.0_dp) .and. acc(l) /= 0.0_dp)
                a1(l) = s1(l)*eps
                a2(l) = s2(l)*eps
                r = a1(l)/a2(l)
                pw = r
                do j = 2, ord - 1
                    pw = pw*r
                end do
                q(l) = a1(l)*pw
                a = merge(1.0_dp, merge(2.0_dp, 0.0_dp, q(l) < 1.0_dp - margin), &
                          q(l) > 1.0_dp + margin)
                pick(l) = merge(a, 0.0_dp, a1(l) >= tiny(1.0_dp) .and. a1(l) <= huge(1.0_dp) &
                                .and. a2(l) >= tiny(1.0_dp) .and. a2(l) <= huge(1.0_dp) .and. &
                                pw >= tiny(1.0_dp) .and. pw <= huge(1.0_dp))
            end do
            do l = 1, nl
                if (acc(l) == 0.0_dp .or. done(l) /= {run}) cycle
                if (pick(l) == 1.0_dp) then
                    lg = -log(a1(l))/real(ord - 1, dp)
                else if (pick(l) == 2.0_dp) then
                    lg = -log(a2(l))/real(ord, dp)
                else
                    lg = huge(1.0_dp)
                    b1 = ishft(transfer(a1(l), 0_i8), -52)
                    b2 = ishft(transfer(a2(l), 0_i8), -52)
                    if (s1(l) > 0.0_dp .and. s2(l) > 0.0_dp .and. b1 >= 1 .and. &
                        b1 <= 2046 .and. b2 >= 1 .and. b2 <= 2046) then
                        e1 = int(b1) - 1022
                        e2 = int(b2) - 1022
                        if ((e1 - 1)*ord > e2*(ord - 1)) then
                            lg = -log(a1(l))/real(ord - 1, dp)
                        else if ((e2 - 1)*(ord - 1) > e1*ord) then
                            lg = -log(a2(l))/real(ord, dp)
                        else
                            lg = min(-log(a1(l))/real(ord - 1, dp), -log(a2(l))/real(ord, dp))
                        end if
                    else
                        if (s1(l) > 0.0_dp) lg = -log(a1(l))/real(ord - 1, dp)
                        if (s2(l) > 0.0_dp) lg = min(lg, -log(a2(l))/real(ord, dp))
                    end if
                end if
                rho = huge(1.0_dp)
                if (lg < log(huge(1.0_dp))) rho = exp(lg)*decay
                h(l) = min(rho, hm)*posneg
            end do
        end do
    end subroutine {name}

"""
