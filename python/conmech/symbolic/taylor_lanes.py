"""The written-out Taylor recurrences' history sums and their pairing into 2-lane
statements (:func:`conmech.symbolic.taylor.fixed_order_source`).

A history sum of order k is written out with literal indices, the terms in the loop
version's order (so the same bits): the oldest coefficients first, the two terms that
hold an order k - 1 coefficient last (:func:`history_terms`). Sums of the same form are paired, as a compiler's SLP
vectorizer pairs isomorphic operations: the two sums become the two lanes of one statement
in a loop over the lanes ``ln = 1, 2`` marked ``!$omp simd`` (gfortran vectorizes it when
compiled with -fopenmp-simd; its own vectorizer leaves such code scalar), the paired
columns stored as the two rows of an array g<m>(2, 0:p). Products and squares whose sums
pair have their current-order terms paired too, and so have state components whose
derivatives are one scaled column each. Each lane runs the scalar statement's operations
in the same order: the coefficients keep their bits.
"""
import re

import sympy as sp

#: marks a symmetric history sum (a square): sum_{j=1..k-1} a[j] a[k-j] is computed as
#: 2 sum_{j < k - j} a[j] a[k-j] + a[k/2]^2 (k even), half the multiply-adds
_SYM = "sym"


def history_terms(k):
    """The order of the terms j = 1 .. k - 1 of a history sum of order k (term j: a[j]
    b[k-j]): j = 2 .. k - 2, then k - 1, then 1. Only the two end terms hold an order
    k - 1 coefficient, the last one computed (a[k-1], b[k-1]; b is the operation's own
    column when it has one, computed after its operand a): the sum of the older terms is
    ready before order k - 1 ends, and the chain from order k - 1 to order k is two
    multiply-adds long rather than k - 1 (the sums are latency-bound)."""
    return list(range(2, k - 1)) + [k - 1]*(k >= 3) + [1]*(k >= 2)


def symmetric_terms(k):
    """The order of the terms j = 1 .. (k - 1)/2 of a square's halved history sum: down to
    j = 1, whose a[k-1] is the newest coefficient."""
    return list(range((k - 1)//2, 0, -1))


def history_loops(plain, sym, W, kind, two, ind, emit):
    """The lines of the loop version's history sums of order k (a variable; fk its real),
    the terms in the order of :func:`history_terms` and :func:`symmetric_terms`: plain,
    sym the recipes (h, left, right, weight) of the plain and symmetric sums; W(j,
    column) spells a coefficient, two the literal 2; emit(statements, indent) the lines of
    statements."""
    lines = []

    def terms(j, kj):
        return [f"{h} = {h} + " + (f"({wt}*real({j}, {kind}) - fk)*" if wt else "") +
                f"{W(j, lft)}*{W(kj, rgt)}" for h, lft, rgt, wt in plain]
    if plain:
        lines.append(f"{ind}    do j = 2, k - 2")
        lines += emit(terms("j", "k - j"), ind + "        ")
        lines += [f"{ind}    end do", f"{ind}    if (k >= 3) then"]
        lines += emit(terms("k - 1", "1"), ind + "        ")
        lines += [f"{ind}    end if", f"{ind}    if (k >= 2) then"]
        lines += emit(terms("1", "k - 1"), ind + "        ")
        lines.append(f"{ind}    end if")
    if sym:
        lines.append(f"{ind}    do j = (k - 1)/2, 1, -1")
        lines += emit([f"{h} = {h} + {W('j', lft)}*{W('k - j', lft)}"
                       for h, lft, _, _ in sym], ind + "        ")
        lines.append(f"{ind}    end do")
        lines += [f"{ind}    {h} = {two}*{h}" for h, _, _, _ in sym]
        lines.append(f"{ind}    if (mod(k, 2) == 0) then")
        lines += emit([f"{h} = {h} + {W('k/2', lft)}*{W('k/2', lft)}"
                       for h, lft, _, _ in sym], ind + "        ")
        lines.append(f"{ind}    end if")
    return lines


def _sum_seq(terms, zero):
    """The terms summed left to right: the order of the loop version's history sums
    (h = 0; h = h + term_j, j in the order of history_terms), so the written-out routine
    and the loop give the same coefficients to the last bit (compiled without
    -ffast-math)."""
    return " + ".join(terms) if terms else zero


def _history_sum(pp, k, lft, rgt, wt, W=None, terms_of=history_terms,
                 symmetric_of=symmetric_terms):
    """The history sum of order k written out (literal indices), the same operations in
    the same order as the loop version's (see body_lines), so the same bits. W(j, column)
    spells a coefficient (default: the printer's); terms_of(k) and symmetric_of(k) the
    order of the terms j of a plain sum and of a square's halved one (the loop's)."""
    W = pp.w if W is None else W
    zero = f"0.0_{pp.kind}"
    if wt is _SYM:
        terms = [f"{W(j, lft)}*{W(k - j, lft)}" for j in symmetric_of(k)]
        out = f"{pp.real(2)}*({_sum_seq(terms, zero)})" if terms else None
        if k % 2 == 0:
            mid = f"{W(k//2, lft)}*{W(k//2, lft)}"
            out = f"{out} + {mid}" if out else mid
        return out or zero
    weight = (lambda j: f"({wt}*{pp.real(j)} - {pp.real(k)})*") if wt else (lambda j: "")
    return _sum_seq([f"{weight(j)}{W(j, lft)}*{W(k - j, rgt)}" for j in terms_of(k)], zero)


def _pair_history(hist, dec):
    """Pairs of history sums of the same form, computed together as the two lanes of one
    2-wide vector (the written-out code): ([(i, j)] indices into `hist`, {column: (group,
    lane)}). Two sums pair when their weights agree and each operand position holds either
    one column in both (a broadcast scalar) or the two columns of a lane group in lane
    order, groups being made on the way. As a compiler's SLP vectorizer does, pairs of
    operations whose operands are made alike (the same kinds of operations down to a depth)
    are taken first, deeper likeness first, then any that fit, each tier greedy in the
    recipe's order: Kepler's x^2, y^2 make the group (x, y), and x P, y P pair with P
    broadcast; Arenstorf's two distances pair with each other, not with y^2. Each lane
    gets the scalar sum's operations in the same order, so the coefficients keep their
    bits."""
    made = {}
    for op in dec.ops:
        for c in op.out:
            made[c] = op
    jbase = {jc: c for c, jc in dec.jcol.items()}

    def sig(c, d):
        if c in jbase:
            return ("j", sig(jbase[c], d))
        op = made.get(c)
        if op is None:
            return ("x",)
        if d == 0:
            return (op.kind,)
        return (op.kind, op.out.index(c)) + tuple(sig(a, d - 1) for a in op.args
                                                  if a is not None)
    lanes, pairs, used = {}, [], set()
    ngroups = 0

    def fits(ops):
        trial, ng = dict(lanes), ngroups
        for a, b in ops:
            if a == b:
                continue
            la, lb = trial.get(a), trial.get(b)
            if la is None and lb is None:
                trial[a], trial[b] = (ng, 0), (ng, 1)
                ng += 1
            elif not (la is not None and lb is not None and la[0] == lb[0] and
                      la[1] == 0 and lb[1] == 1):
                return None
        return trial, ng
    def attempt(i, j, depth):
        """Sum i in lane 1 and sum j in lane 2, if they fit (then recorded)."""
        nonlocal lanes, ngroups
        _, l1, r1, w1 = hist[i]
        _, l2, r2, w2 = hist[j]
        if not (w1 is w2 or (w1 is not _SYM and w2 is not _SYM and w1 == w2)):
            return False
        ops = [(l1, l2)] if w1 is _SYM else [(l1, l2), (r1, r2)]
        if all(a == b for a, b in ops):
            return False             # the same sum twice (never made by the decomposition)
        if depth is not None and any(a != b and sig(a, depth) != sig(b, depth)
                                     for a, b in ops):
            return False
        got = fits(ops)
        if got is None:
            return False
        lanes, ngroups = got
        pairs.append((i, j))
        used.update((i, j))
        return True
    for depth in (4, 2, 1, 0, None):
        for i in range(len(hist)):
            for j in range(i + 1, len(hist)):
                if i in used:
                    break
                if j not in used and (attempt(i, j, depth) or attempt(j, i, depth)):
                    break
    return pairs, lanes


def _pair_outputs(rc, pairs, lanes):
    """The pairs (index m in `pairs`, i, j) of products or squares whose outputs can share a
    lane group too (made here in `lanes` if neither has one), so that their current-order
    statements run as one 2-lane statement (see _current_statements)."""
    out = []
    ng = max((v[0] for v in lanes.values()), default=-1) + 1
    for m, (i, j) in enumerate(pairs):
        op1, op2 = rc.acc_op.get(rc.hist[i][0]), rc.acc_op.get(rc.hist[j][0])
        if op1 is None or op2 is None or op1[0] != op2[0]:
            continue
        o1, o2 = op1[1], op2[1]
        l1, l2 = lanes.get(o1), lanes.get(o2)
        if l1 is None and l2 is None:
            lanes[o1], lanes[o2] = (ng, 0), (ng, 1)
            ng += 1
        elif not (l1 is not None and l2 is not None and l1[0] == l2[0] and l1[1] == 0 and
                  l2[1] == 1):
            continue
        out.append((m, i, j))
    return out


def _pair_derivatives(dec, lanes):
    """Pairs (i, j) of state components whose derivatives are one scaled column each with
    the same factor, y_i' = c u, y_j' = c v, where (u, v) and (y_i, y_j) are lane groups in
    lane order (made here when neither column has one): y^[k+1] of both in one 2-lane
    statement. Repeated until nothing changes (Kepler: x' = u, y' = v make the group
    (u, v); then u' = -m_x, v' = -m_y pair)."""
    def single(o):
        if o.c0 != 0 or len(o.terms) != 1:
            return None
        (c, v), = o.terms.items()
        return c, sp.sympify(v)

    def place(a, b, ng):
        la, lb = lanes.get(a), lanes.get(b)
        if la is None and lb is None:
            lanes[a], lanes[b] = (ng, 0), (ng, 1)
            return ng + 1
        if la is not None and lb is not None and la[0] == lb[0] and la[1] == 0 and \
                lb[1] == 1:
            return ng
        return None
    out, used = [], set()
    changed = True
    while changed:
        changed = False
        for i in range(dec.n):
            for j in range(dec.n):
                if i == j or i in used or j in used:
                    continue
                si, sj = single(dec.outputs[i]), single(dec.outputs[j])
                if si is None or sj is None or si[1] != sj[1]:
                    continue
                ng = max((v[0] for v in lanes.values()), default=-1) + 1
                saved = dict(lanes)
                for a, b in ((i + 1, j + 1), (si[0], sj[0])):
                    if a != b and ng is not None:
                        ng = place(a, b, ng)
                if ng is None:
                    lanes.clear()
                    lanes.update(saved)
                    continue
                out.append((i, j))
                used.update((i, j))
                changed = True
    return out


def _current_statements(pp, rc, k, stmts, vcur):
    """The current-order statements of order k, those of each pair in `vcur` as one 2-lane
    statement (a tuple: the text of lane ``ln``), placed where the later of the two was,
    unless a statement between them reads the earlier one's coefficient (then both stay
    scalar). Lane by lane the scalar statement's operations in its order: the same bits."""
    stmts = list(stmts)
    W = pp.w
    for m, i, j in vcur:
        kind, o1, a1, b1 = rc.acc_op[rc.hist[i][0]]
        _, o2, a2, b2 = rc.acc_op[rc.hist[j][0]]
        p1, p2 = rc.cur_at[o1], rc.cur_at[o2]
        lo, hi = min(p1, p2), max(p1, p2)
        tok = re.compile(r"(?<!\w)" + re.escape(W(k, o1 if p1 < p2 else o2)) + r"(?!\w)")
        if any(isinstance(stmts[q], str) and tok.search(stmts[q].split("=", 1)[1])
               for q in range(lo + 1, hi)):
            continue

        def V(kk, a, b):
            return W(kk, a) if a == b else f"g{pp.lanes[a][0] + 1}(ln, {kk})"
        lhs = f"g{pp.lanes[o1][0] + 1}(ln, {k}) = hv{m + 1}(ln) + "
        if kind == "mul":
            rhs = f"{V(0, a1, a2)}*{V(k, b1, b2)} + {V(k, a1, a2)}*{V(0, b1, b2)}"
        else:
            rhs = f"{pp.real(2)}*{V(0, a1, a2)}*{V(k, a1, a2)}"
        stmts[lo] = None
        stmts[hi] = (lhs + rhs,)
    return [x for x in stmts if x is not None]


def _history_sum_pair(pp, k, first, second):
    """The history sums of order k of a pair (see _pair_history) as the expression of lane
    ``ln``: lane by lane the operations of _history_sum, in its order."""
    _, lft, rgt, wt = first
    _, lft2, rgt2, _ = second
    partner = {lft: lft2, rgt: rgt2}

    def V(kk, a):
        b = partner[a]
        if a == b:
            return pp.w(kk, a)
        return f"g{pp.lanes[a][0] + 1}(ln, {kk})"
    return _history_sum(pp, k, lft, rgt, wt, V)
