"""The recipe of a decomposition's Taylor recurrences (:mod:`conmech.symbolic.taylor`'s
table), independent of how the orders are run: every operation's order-0 statements, the
terms of its history sum over the coefficients of orders 1..k-1 and its current-order
statements. The double, quadruple-precision, batch, written-out and generalized-system
emitters all print their loops from one recipe, so a recurrence is written once."""
import sympy as sp

from .taylor_decompose import TaylorUnsupported
from .taylor_lanes import _SYM

__all__ = ["Recipe"]


class Recipe:
    """The statements of one decomposition, independent of how the orders are run: the
    order-0 statements, the history terms (accumulator, left column, right column, weight:
    the term w(j, left) w(k - j, right), j = 1 .. k - 1; weight None: unweighted, _SYM: a
    symmetric sum (left = right, see _SYM), else the Fortran text of (r + 1) for the
    power weight ((r + 1) j - k)) and the current-order statements (functions of E: the
    order index k, its real fk and reciprocal rk as Fortran text)."""

    def __init__(self, pp, given=False, order_name="order"):
        self.pp = pp
        d = pp.d
        K = pp.kind
        W = pp.w
        one = pp.real(1)
        self.consts = [(pp.const_names[s], pp.pr._print(e)) for s, e in d.consts]
        s0, hist, cur, accs, invs = [], [], [], [], []
        # products and squares: accumulator -> (kind, out, a, b); out -> its index in cur
        self.acc_op, self.cur_at = {}, {}

        def JC(c):
            return d.jcol[c]

        def jset(c):
            if c in d.jcol:
                cur.append(lambda E, c=c: f"{W(E['k'], JC(c))} = {E['fk']}*{W(E['k'], c)}")
        if d.t_col is not None and isinstance(order_name, int):     # written out
            c = d.t_col
            s0.append(f"{W(0, c)} = t")
            for cc in [c] + ([JC(c)] if c in d.jcol else []):
                s0 += [f"{W(k, cc)} = {one if k == 1 else '0.0_' + K}"
                       for k in range(1, order_name + 1)]
        elif d.t_col is not None:
            c = d.t_col
            s0.append(f"{W(0, c)} = t")
            s0.append(f"if ({order_name} >= 1) {W(1, c)} = {one}")
            s0.append(f"if ({order_name} >= 2) {W(f'2:{order_name}', c)} = 0.0_{K}")
            if c in d.jcol:
                s0.append(f"if ({order_name} >= 1) {W(1, JC(c))} = {one}")
                s0.append(f"if ({order_name} >= 2) {W(f'2:{order_name}', JC(c))} = 0.0_{K}")

        def acc():
            h = f"h{len(accs) + 1}"
            accs.append(h)
            return h

        def inv():
            v = f"iv{len(invs) + 1}"
            invs.append(v)
            return v
        for op in d.ops:
            kind = op.kind
            if kind == "time":
                continue
            o = op.out[0]
            a = op.args[0] if op.args else None
            if kind == "lin":
                lin = op.data["lin"]
                s0.append(f"{W(0, o)} = {pp.lin_at(lin, 0, True)}")
                cur.append(lambda E, o=o, lin=lin: f"{W(E['k'], o)} = "
                           f"{pp.lin_at(lin, E['k'], False)}")
            elif kind == "mul":
                b = op.args[1]
                h = acc()
                s0.append(f"{W(0, o)} = {W(0, a)}*{W(0, b)}")
                hist.append((h, a, b, None))
                self.acc_op[h] = ("mul", o, a, b)
                self.cur_at[o] = len(cur)
                cur.append(lambda E, o=o, a=a, b=b, h=h: f"{W(E['k'], o)} = {h} + "
                           f"{W(0, a)}*{W(E['k'], b)} + {W(E['k'], a)}*{W(0, b)}")
            elif kind == "sq":
                h = acc()
                s0.append(f"{W(0, o)} = {W(0, a)}**2")
                hist.append((h, a, a, _SYM))
                two = pp.real(2)
                self.acc_op[h] = ("sq", o, a, a)
                self.cur_at[o] = len(cur)
                cur.append(lambda E, o=o, a=a, h=h, two=two: f"{W(E['k'], o)} = {h} + "
                           f"{two}*{W(0, a)}*{W(E['k'], a)}")
            elif kind in ("div", "recip"):
                b = op.args[1] if kind == "div" else op.args[0]
                h, iv = acc(), inv()
                s0.append(f"{iv} = {one}/{W(0, b)}")
                num0 = W(0, a) if kind == "div" else pp.num(op.data["c"])
                s0.append(f"{W(0, o)} = {num0}*{iv}")
                hist.append((h, b, o, None))
                cur.append(lambda E, o=o, a=a, b=b, h=h, iv=iv, dv=kind == "div":
                           f"{W(E['k'], o)} = ({W(E['k'], a) + ' - ' if dv else '-'}{h} - "
                           f"{W(E['k'], b)}*{W(0, o)})*{iv}")
            elif kind == "sqrt":
                h, iv = acc(), inv()
                s0.append(f"{W(0, o)} = sqrt({W(0, a)})")
                s0.append(f"{iv} = {pp.real(0.5)}/{W(0, o)}")
                hist.append((h, o, o, _SYM))
                cur.append(lambda E, o=o, a=a, h=h, iv=iv:
                           f"{W(E['k'], o)} = ({W(E['k'], a)} - {h})*{iv}")
            elif kind == "pow":
                r = op.data["r"]
                h, iv = acc(), inv()
                s0.append(f"{W(0, o)} = {pp.pow_order0(W(0, a), r)}")
                s0.append(f"{iv} = {one}/{W(0, a)}")
                rs = pp.num(r)
                rp1 = pp.num(sp.sympify(r) + 1) if sp.sympify(r).is_Number else \
                    f"({rs} + {one})"
                # k a0 c[k] = sum_{j=1..k} ((r + 1) j - k) a[j] c[k-j]: the terms j < k in
                # one weighted history sum, the term j = k (weight r k) current
                hist.append((h, a, o, f"({rp1})"))
                cur.append(lambda E, o=o, a=a, h=h, iv=iv, rs=rs:
                           f"{W(E['k'], o)} = ({h}*{E['rk']} + "
                           f"{rs}*{W(E['k'], a)}*{W(0, o)})*{iv}")
            elif kind == "exp":
                h = acc()
                s0.append(f"{W(0, o)} = exp({W(0, a)})")
                hist.append((h, JC(a), o, None))
                cur.append(lambda E, o=o, a=a, h=h: f"{W(E['k'], o)} = {h}*{E['rk']} + "
                           f"{W(E['k'], a)}*{W(0, o)}")
            elif kind in ("sincos", "sinhcosh"):
                sn, cs = op.out
                hy = kind == "sinhcosh"
                h, h2 = acc(), acc()
                s0.append(f"{W(0, sn)} = {'sinh' if hy else 'sin'}({W(0, a)})")
                s0.append(f"{W(0, cs)} = {'cosh' if hy else 'cos'}({W(0, a)})")
                hist += [(h, JC(a), cs, None), (h2, JC(a), sn, None)]
                sg = "" if hy else "-"
                cur.append(lambda E, sn=sn, cs=cs, a=a, h=h: f"{W(E['k'], sn)} = "
                           f"{h}*{E['rk']} + {W(E['k'], a)}*{W(0, cs)}")
                cur.append(lambda E, sn=sn, cs=cs, a=a, h2=h2, sg=sg: f"{W(E['k'], cs)} = "
                           f"{sg}({h2}*{E['rk']} + {W(E['k'], a)}*{W(0, sn)})")
            elif kind in ("tan", "tanh"):
                g = op.args[1]
                h = acc()
                s0.append(f"{W(0, o)} = {kind}({W(0, a)})")
                hist.append((h, JC(a), g, None))
                cur.append(lambda E, o=o, a=a, g=g, h=h: f"{W(E['k'], o)} = "
                           f"{h}*{E['rk']} + {W(E['k'], a)}*{W(0, g)}")
            elif kind.startswith("inv_"):
                u = op.args[1]
                h, iv = acc(), inv()
                s0.append(f"{W(0, o)} = {kind[4:]}({W(0, a)})")
                s0.append(f"{iv} = {one}/{W(0, u)}")
                hist.append((h, JC(o), u, None))
                cur.append(lambda E, o=o, a=a, h=h, iv=iv: f"{W(E['k'], o)} = "
                           f"({W(E['k'], a)} - {h}*{E['rk']})*{iv}")
            else:
                raise TaylorUnsupported(f"unknown operation {kind}")
            for c in op.out:
                jset(c)
        self.s0, self.hist, self.cur, self.accs, self.invs = s0, hist, cur, accs, invs
