"""The Fortran procedures every Taylor library of a second-order system exports around its
recurrences (generalized systems M(q) q'' = Q and trees): the recurrences of the
first-order view y = [q; v] as ``prefix(t, order, w, p)``, ``prefix_info(info)`` (the
columns of w and the size 2n of the view) and ``prefix_rhs(t, y, dydt, p)``, the view's
right-hand side as the order-1 coefficient of the same recurrences."""

__all__ = ["core_part_lines", "first_order_procedures"]


def first_order_procedures(prefix, nw, m, npar, decl, body, ind="        ", rhs=True):
    """Fortran lines of the three procedures around the recurrences' declarations `decl`
    and statements `body` (w has `nw` columns, the state `m` entries, p `npar`); without
    `rhs` the first two only (a variational system's)."""
    lines = [f'    subroutine {prefix}(t, order, w, p) bind(C, name="{prefix}")',
             f"{ind}real(dp), value, intent(in) :: t",
             f"{ind}integer(c_int), value, intent(in) :: order",
             f"{ind}real(dp), intent(inout) :: w(0:order, {nw})",
             f"{ind}real(dp), intent(in) :: p({npar})"]
    lines += decl + body + [f"    end subroutine {prefix}", ""]
    lines += [f'    subroutine {prefix}_info(info) bind(C, name="{prefix}_info")',
              f"{ind}integer(c_int), intent(out) :: info(4)",
              f"{ind}info = [{nw}, 0, {m}, 0]",
              f"    end subroutine {prefix}_info", ""]
    if not rhs:
        return lines
    lines += [f'    subroutine {prefix}_rhs(t, y, dydt, p) bind(C, name="{prefix}_rhs")',
              f"{ind}real(dp), value, intent(in) :: t",
              f"{ind}real(dp), intent(in) :: y({m})",
              f"{ind}real(dp), intent(out) :: dydt({m})",
              f"{ind}real(dp), intent(in) :: p({npar})",
              f"{ind}real(dp) :: w(0:1, {nw})",
              f"{ind}w = 0.0_dp",
              f"{ind}w(0, 1:{m}) = y",
              f"{ind}call {prefix}(t, 1_c_int, w, p)",
              f"{ind}dydt = w(1, 1:{m})",
              f"    end subroutine {prefix}_rhs", ""]
    return lines


def core_part_lines(d, part, dec_cache, key, decompose, what, procedures):
    """(Fortran lines, entry names, reason) of one part of the Taylor library of a model whose
    recurrences run through its first-order view: the core only (the batch, quadruple
    precision and variational parts of a generalized system are generated apart, by
    conmech.symbolic.taylor_generalized and taylor_generalized_var). decompose(d) ->
    (*pieces, reason), pieces[0] None when the model is not supported, is kept in
    dec_cache[key] for the other parts; procedures(*pieces) writes the core; `what` names
    the kind of model in the refusal of another part."""
    if key not in dec_cache:
        dec_cache[key] = decompose(d)
    *pieces, why = dec_cache[key]
    if pieces[0] is None:
        return [], [], why
    if part != "core":
        return [], [], (f"the Taylor part {part!r} (ensembles, quadruple precision, the "
                        f"variational system) is not generated for {what}")
    return procedures(*pieces), ["taylor", "taylor_info", "taylor_rhs"], None
