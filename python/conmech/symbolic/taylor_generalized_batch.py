"""Taylor's method for ensembles of a generalized system M(t, q) q'' = Q(t, q, q') in SIMD
lanes: the batch coefficient routine of :mod:`conmech.symbolic.taylor_generalized` and the
propagator of :mod:`conmech.symbolic.taylor_batch`.

The coefficient routine ``conmech_taylor_batch(t, order, w, p)`` (t(lanes), w(lanes,
0:order, nw), the states of the first-order view y = [q; v] in the columns 1..2n of w(:, 0,
:) on entry) runs the statements of the scalar routine
(:func:`conmech.symbolic.taylor_generalized.generalized_body`, the factorisation of M_0 and
the triangular solves written out in scalars) with every per-lane value a vector of the
lanes: the accumulators of the history sums, the reciprocals, the Cholesky factor of M_0
(cd<i>, cl<i>_<j>), the right-hand sides of the solves (cr<i>) and the history sums of
M a (cg<i>), each statement in a ``!$omp simd`` loop over the lanes; the loop over the
orders k stays outside, common to the lanes, and the loops over the terms j of the history
sums run inside the lanes' loop (:func:`_lanes_outside`) when they are short (at most
WIDE_REFS per-lane references). Each lane runs the
scalar statement's operations in its order, so each member gets the scalar routine's
coefficients to the last bit, and the propagator (the same for ode systems and the view
of a generalized one) takes the steps of the member's own solve_ivp(method="TAYLOR") run.

A mass matrix that is not positive definite at a lane's expansion point makes that lane's
pivot sqrt(cs) not a positive number (cs <= 0 or NaN: an infinite or NaN reciprocal), so
that lane's accelerations and hence its coefficients are not finite: the propagator
reports that member as failed (a non-finite right-hand side, or a step size too small as
the scalar stepper would), the other lanes unaffected (the scalar routine's early return
has no per-lane equivalent in vector code; the lanes are independent, so none is needed).

For more than :data:`conmech.symbolic.taylor_generalized.WRITE_OUT_MAX` degrees of
freedom the scalar routine factorises M_0 and solves in loops over local arrays (lm, the
lower triangle of M_0 overwritten by its factor; ld, the reciprocal pivots; cr, the
right-hand sides; cg, the history sums of M a); the batch routine runs that loop form
with the lanes as the arrays' first index (lm(l, i, j), ...), each array statement of
the scalar loops (the sum intrinsic over a row section included) in a lanes' loop inside
the same loops over the rows and columns, so each lane again performs the scalar
routine's operations in its order and gets its coefficients to the last bit.

In either form a large system's lanes' loops (order 0, the history sums, an order's
recurrences: thousands of array references, which gcc's dependence analysis gives up on,
leaving the loop scalar) are split into consecutive loops of at most WIDE_REFS references
(:func:`_split_wide`; unsplit, a 10-link pendulum chain's ensemble ran slower in lanes
than member by member, an 8-link chain's at 0.87x-1.02x against 2.3x-2.9x split, one
thread: ``python bench/bench_taylor_generalized_batch.py --system chain10``, ``--system
chain8``). No size is
refused; a generalized system without batch recurrences is one without scalar ones (a
non-smooth expression, an asymmetric M), and one order written out (``fixed``) is not
generated (the loop version serves every order)."""
import re

from .taylor import _decls, _wrap
from .taylor_generalized import WRITE_OUT_MAX, generalized_decomposition, generalized_body
from .taylor_batch import coefficient_head, machine_lanes, run_routine

__all__ = ["batch_lines", "coefficient_routine"]

# the lane-invariant values of the scalar routine: the constants (functions of the
# parameters) and the order's reals
_INVARIANT = re.compile(r"^(tc\d+|fk|rk|rk1)$")
_CONTROL = re.compile(r"^(do |end do$|end if$|else$|if \(.*\) then$|if \(order < 1\) return$)")
_LHS = re.compile(r"^([A-Za-z]\w*)\s*(\(|=)")


def _statements(lines):
    """(indentation, statement) of Fortran lines, continuations (& ... &) joined."""
    out = []
    for x in lines:
        s = x.lstrip()
        if out and out[-1][1].endswith("&"):
            ind, text = out[-1]
            out[-1] = (ind, text[:-1] + s[1:])
        else:
            out.append((x[:len(x) - len(s)], s))
    return out


def _one_line_if(s):
    """The "if (condition)" of a one-line if statement `s`, or None."""
    if not s.startswith("if (") or s.endswith(" then"):
        return None
    depth = 0
    for i, ch in enumerate(s[3:], 3):
        depth += (ch == "(") - (ch == ")")
        if depth == 0:
            return s[:i + 1] if s[i + 1:].strip() else None
    return None


def _declared(decl):
    """The names declared real in the declaration lines `decl`."""
    names = []
    for _, s in _statements(decl):
        if s.startswith("real("):
            names += [x.strip() for x in s.split("::", 1)[1].split(",")]
    return names


def coefficient_routine(g, names, lanes, cname="conmech_taylor_batch", npar=1):
    """Fortran lines of the bind(C) routine ``cname(t, order, w, p)`` of `lanes` members of
    the generalized system of the decomposition `g` (see the module docstring): the
    scalars of the written-out factorisation up to WRITE_OUT_MAX degrees of freedom, the
    loop form's arrays with a lanes' index beyond."""
    ind = "        "
    loops = g.n > WRITE_OUT_MAX
    decl, body = generalized_body(g, names, ind, not loops)
    # the loop form's local arrays (lm, ld, cr, cg) with the lanes as their first index
    arrays = [] if not loops else ["lm", "ld", "cr", "cg"]
    if loops:
        decl = [x for x in decl if not x.lstrip().startswith(("real(dp) :: lm(",
                                                              "integer :: ii, jj"))]
    reals = _declared(decl)
    lane = [x for x in reals if not _INVARIANT.match(x)]
    consts = [x for x in reals if x.startswith("tc")]
    per_lane = re.compile(r"\b(" + "|".join(map(re.escape, lane + ["t"])) + r")\b(?!\()")

    per_lane_array = re.compile(r"\b(" + "|".join(["w"] + arrays) + r")\(")

    def in_lanes(s):
        return per_lane.sub(lambda mm: f"{mm.group(1)}(l)",
                            per_lane_array.sub(lambda mm: f"{mm.group(1)}(l, ", s))
    out, group, gind = [], [], None

    def flush():
        if group:
            out.extend([f"{gind}!$omp simd", f"{gind}do l = 1, nl"])
            for s in group:
                out.extend(_wrap(s, gind + "    "))
            out.append(f"{gind}end do")
            group.clear()

    def assignment(at, s):
        nonlocal gind
        m = _LHS.match(s)
        if m is None:
            raise ValueError(f"unexpected statement in the generalized Taylor body: {s}")
        lhs = m.group(1)
        if s == "lm = 0.0_dp":
            # the factor's array cleared for every lane at once
            flush()
            out.append(at + s)
            return
        if lhs == "w" or lhs in lane or lhs in arrays:
            if group and at != gind:
                flush()
            gind = at
            group.append(in_lanes(s))
        else:
            rhs = s.split("=", 1)[1]
            if per_lane_array.search(rhs) or per_lane.search(rhs):
                raise ValueError(f"a lane-invariant value depends on a lane: {s}")
            flush()
            out.append(at + s)
    skip = 0
    for at, s in _statements(body):
        if skip:
            # the scalar routine's return on a pivot that is not positive: the lanes'
            # pivots give non-finite coefficients instead (see the module docstring)
            skip += s.startswith("if (") and s.endswith("then")
            skip -= s == "end if"
            continue
        if s.startswith("if (.not. cs > 0.0_dp) then"):
            flush()
            skip = 1
            continue
        if _CONTROL.match(s):
            flush()
            out.append(at + s)
            continue
        cond = _one_line_if(s)
        if cond:
            # if (a condition on the order) statement: the condition common to the lanes
            if per_lane_array.search(cond) or per_lane.search(cond):
                raise ValueError(f"a condition depends on a lane: {s}")
            flush()
            out.append(f"{at}{cond} then")
            assignment(at + "    ", s[len(cond):].strip())
            flush()
            out.append(f"{at}end if")
            continue
        assignment(at, s)
    flush()
    nw = g.ncol
    head = coefficient_head(cname, lanes, nw, npar, ind)
    decls = _decls(consts, "real(dp)", ind)
    decls += _decls([f"{x}(nl)" for x in lane], "real(dp)", ind)
    if loops:
        n = g.n
        decls += [f"{ind}real(dp) :: lm(nl, {n}, {n}), ld(nl, {n}), cr(nl, {n}), "
                  f"cg(nl, {n})", f"{ind}integer :: ii, jj"]
    decls += [f"{ind}real(dp) :: fk, rk, rk1", f"{ind}integer :: k, j, l"]
    if not loops and lanes <= machine_lanes():
        out = _lanes_outside(out)
    out = _split_wide(out)
    return head + decls + out + [f"    end subroutine {cname}", ""]


#: per-lane array references per lanes' loop at most (gcc's dependence analysis gives up on
#: a loop of more than 1000, its parameter loop-max-datarefs-for-datadeps, and leaves it
#: scalar), and per history sums' loop turned inside out
WIDE_REFS = 200
_REF = re.compile(r"\(l[,)]")


def _joined(lines, i):
    """(the statement starting at lines[i] with its continuation lines, next index)."""
    j = i
    while lines[j].rstrip().endswith("&"):
        j += 1
    return lines[i:j + 1], j + 1


def _chunks(stmts):
    """The statements (lists of lines) in consecutive groups of at most WIDE_REFS
    references to per-lane arrays (one statement alone when it has more)."""
    out, cur, refs = [], [], 0
    for st in stmts:
        r = sum(len(_REF.findall(x)) for x in st)
        if cur and refs + r > WIDE_REFS:
            out.append(cur)
            cur, refs = [], 0
        cur.append(st)
        refs += r
    if cur:
        out.append(cur)
    return out


def _split_wide(lines):
    """The lanes' loops of more than WIDE_REFS references split into consecutive lanes'
    loops: a large system's loops of order 0, of the history sums and of an order's
    recurrences reach thousands of references, which the compiler leaves scalar (an
    8-link pendulum chain written out: 851, 1008 and 1990). Each lane runs the same
    statements in the same order (a lane's values live in its own elements), so its bits
    are those of the unsplit loop. The loops over the terms j of such a system keep the
    lanes' loops inside (:func:`_lanes_outside` not applied to them: a lanes' loop
    outside a loop over the terms of many accumulators is not vectorised, or holds them
    in memory rather than registers)."""
    out, i = [], 0
    while i < len(lines):
        x = lines[i]
        s = x.lstrip()
        at = x[:len(x) - len(s)]
        if s == "!$omp simd" and i + 1 < len(lines) and lines[i + 1] == f"{at}do l = 1, nl":
            end = lines.index(f"{at}end do", i + 2)
            body = lines[i + 2:end]
            if not any(y.lstrip().startswith(("do ", "end do", "if ")) for y in body):
                stmts, k = [], 0
                while k < len(body):
                    st, k = _joined(body, k)
                    stmts.append(st)
                for ch in _chunks(stmts):
                    out += [x, lines[i + 1]] + [y for st in ch for y in st]
                    out.append(f"{at}end do")
                i = end + 1
                continue
        out.append(x)
        i += 1
    return out


def _lanes_outside(lines):
    """The loops over the terms j of the history sums whose only statement is a loop over
    the lanes, turned inside out: the lanes' loop outside, vectorised as a whole by the
    compiler, each lane's accumulators held in a vector register over the terms rather than
    loaded and stored at every term (each lane adds the same terms in the same order).
    For lanes that fill one vector register at most: more lanes than the machine's vector
    width take two registers per accumulator, too many to hold (the double pendulum with
    8 lanes on AVX2: 1,226,678 instructions per member inside out against 1,041,875,
    callgrind; 4 lanes: 1,073,734 against 1,279,308). Only a loop of at most WIDE_REFS
    per-lane references: a longer one keeps more accumulators than the registers hold
    (the 8-link chain's 228, 1008 references: gcc vectorises that lanes' loop outside
    with the accumulators spilled to memory, an expansion with 8 lanes on AVX-512 about
    a fifth slower than with the lanes' loops inside, split; groups of 16 accumulators
    outside are not vectorised at all, "control flow in loop")."""
    out, i = [], 0
    while i < len(lines):
        x = lines[i]
        s = x.lstrip()
        at = x[:len(x) - len(s)]
        if s.startswith("do j = ") and i + 2 < len(lines) and \
                lines[i + 1] == f"{at}    !$omp simd" and \
                lines[i + 2] == f"{at}    do l = 1, nl":
            end = lines.index(f"{at}    end do", i + 3)
            refs = sum(len(_REF.findall(y)) for y in lines[i + 3:end])
            if lines[end + 1] == f"{at}end do" and refs <= WIDE_REFS:
                out += [f"{at}!$omp simd", f"{at}do l = 1, nl", f"{at}    {s}"]
                out += lines[i + 3:end]
                out += [f"{at}    end do", f"{at}end do"]
                i = end + 2
                continue
        out.append(x)
        i += 1
    return out


def batch_lines(d, names, lanes, fixed, dec_cache, codes):
    """(Fortran lines, entry names, reason) of the batch part of a generalized model's
    Taylor library with `lanes` lanes: the coefficient routine and the propagator
    ``conmech_taylor_batch_run`` (:func:`conmech.symbolic.taylor_batch.run_routine` for
    the 2n states of the first-order view); codes: the propagator's status codes. No
    routine written out for one order (`fixed`): refused with the reason."""
    if "g" not in dec_cache:
        dec_cache["g"] = generalized_decomposition(d)
    g, why = dec_cache["g"]
    if g is None:
        return [], [], why
    if fixed is not None:
        return [], [], ("the batch recurrences of a generalized system M(q) q'' = Q are "
                        "not written out for one order (the loop version serves every "
                        "order)")
    npar = max(len(d.params), 1)
    return coefficient_routine(g, names, lanes, npar=npar) + \
        run_routine(2*g.n, g.ncol, npar, lanes, codes), \
        ["taylor_batch", "taylor_batch_run"], None
