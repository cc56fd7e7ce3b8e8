"""Taylor's method for ensembles of a tree (``planar_tree``, ``spatial_tree``,
``from_urdf``) in SIMD lanes: the batch coefficient routine of the recurrences of its
articulated-body chain (:mod:`conmech.symbolic.taylor_tree`) and the propagator of
:mod:`conmech.symbolic.taylor_batch`.

The chain's decomposition is an ode system's (the first-order view y = [q; v] as the
state, the definitions of the chain as intermediates), so its batch coefficient routine
is the ode systems' (:func:`conmech.symbolic.taylor_batch.coefficient_routine`: the
statements of the scalar loop version with a lane dimension first, the same operations in
the same order, each lane the scalar routine's coefficients to the last bit). The scalar
routine checks the pivots D_i (the articulated inertias) at order 0 and returns NaN
coefficients when one is not positive; here each lane's pivots are checked after its
expansion (their order-0 values stay in w) and a lane whose pivot is not positive gets
NaN coefficients of orders 1.. as the scalar routine gives, so the propagator reports
that member as failed, the other lanes unaffected."""
from .printer import quiet_nan
from .taylor import _Printer, _wrap
from .taylor_batch import coefficient_routine, run_routine
from .taylor_tree import kept_tree_decomposition

__all__ = ["tree_batch_lines"]


def tree_coefficient_routine(dec, pivots, names, lanes, cname="conmech_taylor_batch"):
    """Fortran lines of the bind(C) routine ``cname(t, order, w, p)`` of `lanes` members
    of the tree of the decomposition `dec` with the pivot forms `pivots`."""
    lines = coefficient_routine(dec, names, lanes, cname)
    checked = [lin for lin in pivots if lin.terms]   # constants: checked at the build
    if not checked:
        return lines
    ind = "        "
    pp = _Printer(dec, names, False, "dp")
    pp.w = lambda k, c: f"w(l, {k}, {c})"
    test = " .and. ".join(f"({pp.lin_at(lin, 0, True)}) > 0.0_dp" for lin in checked)
    tail = [f"{ind}do l = 1, nl"]
    tail += _wrap(f"if (.not. ({test})) w(l, 1:order, :) = qnan", ind + "    ")
    tail.append(f"{ind}end do")
    end = lines.index(f"    end subroutine {cname}")
    first = lines.index(f"{ind}if (order < 1) return")
    # a quiet NaN by its bits (printer.quiet_nan; the batch library is also compiled
    # without the compiler's module directory, so without ieee_arithmetic)
    nan = [f"{ind}real(dp), parameter :: qnan = {quiet_nan()}"]
    return lines[:first] + nan + lines[first:end] + tail + lines[end:]


def tree_batch_lines(d, names, lanes, fixed, dec_cache, codes):
    """(Fortran lines, entry names, reason) of the batch part of a tree model's Taylor
    library with `lanes` lanes: the coefficient routine and the propagator
    ``conmech_taylor_batch_run`` over the 2n states of the first-order view; codes: the
    propagator's status codes. No routine written out for one order (`fixed`): refused
    with the reason."""
    dec, pivots, why = kept_tree_decomposition(d, dec_cache)
    if dec is None:
        return [], [], why
    if fixed is not None:
        return [], [], ("the batch recurrences of a tree are not written out for one "
                        "order (the loop version serves every order)")
    npar = max(len(dec.params), 1)
    return tree_coefficient_routine(dec, pivots, names, lanes) + \
        run_routine(dec.n, dec.ncol, npar, lanes, codes), \
        ["taylor_batch", "taylor_batch_run"], None
