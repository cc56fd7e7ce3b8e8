"""The procedures of the generated code of a tree that run over the ancestor pairs: the
mass matrix (composite rigid bodies), the derivatives of inverse dynamics, the tree-sparse
L^T D L factorisation of M and its solve, the maps of absolute angles; as loops over the
parent array (:data:`FIXED`) or, for small trees, written out (:func:`straight_pairs`)."""
from .printer import _wrap
from .tree_print import IND as _IND

__all__ = ["FIXED", "straight_pairs"]


def straight_pairs(joints, nz, jac):
    """Straight-line forms of tree_mass_topo, tree_did, tree_ltdl and tree_ltdl_solve
    (keyed by the text that starts their doc comment), for small trees."""
    nb = len(joints)
    anc = []
    for k in range(nb):
        a, j = [], k
        while j >= 0:
            a.append(j)
            j = joints[j].parent
        anc.append(a)
    related = {(j, k) for k in range(nb) for j in anc[k]}
    related |= {(k, j) for j, k in related}
    I = _IND

    def dot(x, j, y, k, scale=""):
        cs = sorted(nz.get((x, j), set()) & nz.get((y, k), set()))
        terms = [f"w%{x}({c}, {j + 1})*w%{y}({c}, {k + 1})" for c in cs]
        return (scale + "(" + " + ".join(terms) + ")") if terms else ""

    def neg(*parts):
        parts = [x for x in parts if x]
        return "-(" + " + ".join(parts) + ")" if parts else "0.0_dp"
    out = {}
    # mass matrix
    lines = []
    for k in range(nb):
        for j in anc[k]:
            d = dot("sv", j, "al", k) or "0.0_dp"
            lines += _wrap(f"h({j + 1}, {k + 1}) = {d}", I)
            if j != k:
                lines.append(f"{I}h({k + 1}, {j + 1}) = h({j + 1}, {k + 1})")
    lines += [f"{I}h({i + 1}, {j + 1}) = 0.0_dp" for i in range(nb) for j in range(nb)
              if (i, j) not in related]
    out["M (relative"] = "\n".join([
        "M (relative coordinates, topological order), written out.",
        "    pure subroutine tree_mass_topo(w, h)",
        f"{I}type(tree_work), intent(in) :: w",
        f"{I}real(dp), intent(out) :: h(nb, nb)"] + lines + [
        "    end subroutine tree_mass_topo", ""])
    # derivatives of inverse dynamics
    lines = []
    if jac:
        for k in range(nb):
            for j in anc[k]:
                lines += _wrap(f"xt({j + 1}, {k + 1}) = " + neg(
                    dot("al", k, "cc", j), dot("et", k, "ps", j)), I)
                lines += _wrap(f"xt({nb + j + 1}, {k + 1}) = " + neg(
                    dot("al", k, "ps", j, "2.0_dp*"), dot("et", k, "sv", j)), I)
                if j != k:
                    lines += _wrap(f"xt({k + 1}, {j + 1}) = " + neg(dot("sv", j, "ph", k)), I)
                    lines += _wrap(f"xt({nb + k + 1}, {j + 1}) = "
                                   + neg(dot("sv", j, "om", k)), I)
        lines += [f"{I}xt({h + 1}, {i + 1}) = 0.0_dp" for i in range(nb) for j in range(nb)
                  if (j, i) not in related for h in (j, nb + j)]
    out["xt = -[d tau"] = "\n".join([
        "xt = -[d tau/d q, d tau/d qd]^T (relative, topological), written out.",
        "    pure subroutine tree_did(w, xt)",
        f"{I}type(tree_work), intent(in) :: w",
        f"{I}real(dp), intent(out) :: xt(2*nb, nb)"] + lines + [
        "    end subroutine tree_did", ""])
    # L^T D L
    lines = []
    for k in reversed(range(nb)):
        kk = k + 1
        lines.append(f"{I}if (.not. (h({kk}, {kk}) > 0.0_dp)) h({kk}, {kk}) = 0.0_dp")
        for i in anc[k][1:]:
            lines.append(f"{I}a = h({kk}, {i + 1})/h({kk}, {kk})")
            for j in anc[i]:
                lines.append(f"{I}h({i + 1}, {j + 1}) = h({i + 1}, {j + 1}) - "
                             f"a*h({kk}, {j + 1})")
            lines.append(f"{I}h({kk}, {i + 1}) = a")
        lines.append(f"{I}h({kk}, {kk}) = 1.0_dp/h({kk}, {kk})")
    out["M = L^T D L"] = "\n".join([
        "M = L^T D L in place (D stored inverted), written out.",
        "    pure subroutine tree_ltdl(h)",
        f"{I}real(dp), intent(inout) :: h(nb, nb)",
        f"{I}real(dp) :: a"] + lines + ["    end subroutine tree_ltdl", ""])
    lines = []
    for i in reversed(range(nb)):
        for j in anc[i][1:]:
            lines.append(f"{I}xt(:, {j + 1}) = xt(:, {j + 1}) - h({i + 1}, {j + 1})*"
                         f"xt(:, {i + 1})")
    for i in range(nb):
        lines.append(f"{I}xt(:, {i + 1}) = xt(:, {i + 1})*h({i + 1}, {i + 1})")
        for j in anc[i][1:]:
            lines.append(f"{I}xt(:, {i + 1}) = xt(:, {i + 1}) - h({i + 1}, {j + 1})*"
                         f"xt(:, {j + 1})")
    out["xt := xt M^-1"] = "\n".join([
        "xt := xt M^-1 (x = M^-1 x kept transposed), written out.",
        "    pure subroutine tree_ltdl_solve(h, xt)",
        f"{I}real(dp), intent(in) :: h(nb, nb)",
        f"{I}real(dp), intent(inout) :: xt(2*nb, nb)"] + lines + [
        "    end subroutine tree_ltdl_solve", ""])
    return out


# fixed procedures: mass matrix (composite rigid bodies), derivatives of inverse dynamics
# over the ancestor pairs, L^T D L factorisation of M and its solve (Featherstone, Rigid
# Body Dynamics Algorithms, 6.5: the sparsity of the tree), maps of absolute angles. The
# Jacobians are kept transposed, xt(variable, equation) with the variables [q; v] and the
# equations in topological order, so that the row operations of the solve are contiguous.
FIXED = """
    !> M (relative coordinates, topological order): M_jk = S_j . alpha_k, j an ancestor
    !! of k or k.
    pure subroutine tree_mass_topo(w, h)
        type(tree_work), intent(in) :: w
        real(dp), intent(out) :: h(nb, nb)
        integer :: c, j, k
        real(dp) :: s, ak(na)
ZEROH
        do k = 1, nb
            ak = w%al(:, k)
            j = k
            do while (j > 0)
                s = 0.0_dp
                do c = 1, na
                    s = s + w%sv(c, j)*ak(c)
                end do
                h(j, k) = s
                h(k, j) = s
                j = par(j)
            end do
        end do
    end subroutine tree_mass_topo

    !> xt = -[d tau/d q, d tau/d qd]^T of inverse dynamics (relative, topological).
    pure subroutine tree_did(w, xt)
        type(tree_work), intent(in) :: w
        real(dp), intent(out) :: xt(2*nb, nb)
        integer :: c, j, k
        real(dp) :: ak(na), ek(na), pk(na), ok(na), s1, s2, s3, s4
ZEROX
        do k = 1, nb
            ak = w%al(:, k)
            ek = w%et(:, k)
            pk = w%ph(:, k)
            ok = w%om(:, k)
            s1 = 0.0_dp
            s2 = 0.0_dp
            do c = 1, na
                s1 = s1 + ak(c)*w%cc(c, k) + ek(c)*w%ps(c, k)
                s2 = s2 + 2.0_dp*ak(c)*w%ps(c, k) + ek(c)*w%sv(c, k)
            end do
            xt(k, k) = -s1
            xt(nb + k, k) = -s2
            j = par(k)
            do while (j > 0)
                s1 = 0.0_dp
                s2 = 0.0_dp
                s3 = 0.0_dp
                s4 = 0.0_dp
                do c = 1, na
                    s1 = s1 + ak(c)*w%cc(c, j) + ek(c)*w%ps(c, j)
                    s2 = s2 + 2.0_dp*ak(c)*w%ps(c, j) + ek(c)*w%sv(c, j)
                    s3 = s3 + w%sv(c, j)*pk(c)
                    s4 = s4 + w%sv(c, j)*ok(c)
                end do
                xt(j, k) = -s1
                xt(nb + j, k) = -s2
                xt(k, j) = -s3
                xt(nb + k, j) = -s4
                j = par(j)
            end do
        end do
    end subroutine tree_did

    !> M = L^T D L in place (L unit lower triangular with the tree's sparsity, D on the
    !! diagonal, stored inverted); a pivot that is not positive makes the factor NaN.
    pure subroutine tree_ltdl(h)
        real(dp), intent(inout) :: h(nb, nb)
        integer :: i, j, k
        real(dp) :: a
        do k = nb, 1, -1
            if (.not. (h(k, k) > 0.0_dp)) h(k, k) = 0.0_dp
            i = par(k)
            do while (i > 0)
                a = h(k, i)/h(k, k)
                j = i
                do while (j > 0)
                    h(i, j) = h(i, j) - a*h(k, j)
                    j = par(j)
                end do
                h(k, i) = a
                i = par(i)
            end do
            h(k, k) = 1.0_dp/h(k, k)
        end do
    end subroutine tree_ltdl

    !> xt := xt M^-1 (the rows of x = M^-1 x, x kept transposed), M from tree_ltdl.
    pure subroutine tree_ltdl_solve(h, xt)
        real(dp), intent(in) :: h(nb, nb)
        real(dp), intent(inout) :: xt(2*nb, nb)
        integer :: c, i, j
        real(dp) :: f
        do i = nb, 1, -1
            j = par(i)
            do while (j > 0)
                f = h(i, j)
                do c = 1, 2*nb
                    xt(c, j) = xt(c, j) - f*xt(c, i)
                end do
                j = par(j)
            end do
        end do
        do i = 1, nb
            f = h(i, i)
            do c = 1, 2*nb
                xt(c, i) = xt(c, i)*f
            end do
            j = par(i)
            do while (j > 0)
                f = h(i, j)
                do c = 1, 2*nb
                    xt(c, i) = xt(c, i) - f*xt(c, j)
                end do
                j = par(j)
            end do
        end do
    end subroutine tree_ltdl_solve

    !> x := T^T x on the equations (rows of x: columns of xt) and := x T on the variables
    !! (both halves), T mapping absolute to relative angles.
    pure subroutine tree_abs_r(xt)
        real(dp), intent(inout) :: xt(2*nb, nb)
        real(dp) :: y(2*nb, nb)
        integer :: k
        y = xt
        do k = 1, nb
            if (ka(k) > 0) xt(:, ka(k)) = xt(:, ka(k)) - y(:, k)
        end do
        y = xt
        do k = 1, nb
            if (ka(k) > 0) then
                xt(ka(k), :) = xt(ka(k), :) - y(k, :)
                xt(nb + ka(k), :) = xt(nb + ka(k), :) - y(nb + k, :)
            end if
        end do
    end subroutine tree_abs_r

    !> M in the user's coordinates and order.
    pure subroutine tree_mass_user(w, mm)
        type(tree_work), intent(in) :: w
        real(dp), intent(out) :: mm(nb, nb)
        real(dp) :: h(nb, nb), y(nb, nb)
        integer :: i, j, k
        call tree_mass_topo(w, h)
        if (any(ka > 0)) then
            y = h
            do k = 1, nb
                if (ka(k) > 0) h(ka(k), :) = h(ka(k), :) - y(k, :)
            end do
            y = h
            do k = 1, nb
                if (ka(k) > 0) h(:, ka(k)) = h(:, ka(k)) - y(:, k)
            end do
        end if
        do j = 1, nb
            do i = 1, nb
                mm(col(i), col(j)) = h(i, j)
            end do
        end do
    end subroutine tree_mass_user

    !> Q = fu - T^T tau in the user's order.
    pure subroutine tree_q_user(w, fu, f)
        type(tree_work), intent(in) :: w
        real(dp), intent(in) :: fu(nb)
        real(dp), intent(out) :: f(nb)
        real(dp) :: y(nb)
        integer :: i, k
        y = w%tau
        do k = 1, nb
            if (ka(k) > 0) y(ka(k)) = y(ka(k)) - w%tau(k)
        end do
        do i = 1, nb
            f(col(i)) = fu(col(i)) - y(i)
        end do
    end subroutine tree_q_user

    !> An n x 2n matrix in the user's order from its transpose in topological order.
    pure subroutine tree_untranspose(xt, r)
        real(dp), intent(in) :: xt(2*nb, nb)
        real(dp), intent(out) :: r(nb, 2*nb)
        integer :: i, j
UNTRANSPOSE
    end subroutine tree_untranspose

    !> xt := (M^-1 R)^T with M^-1 = T^-1 M_rel^-1 T^-T (absolute angles), h from tree_ltdl.
    pure subroutine tree_solve_r(h, xt)
        real(dp), intent(in) :: h(nb, nb)
        real(dp), intent(inout) :: xt(2*nb, nb)
        integer :: k
        if (any(ka > 0)) then
            do k = nb, 1, -1
                if (ka(k) > 0) xt(:, ka(k)) = xt(:, ka(k)) + xt(:, k)
            end do
        end if
        call tree_ltdl_solve(h, xt)
        if (any(ka > 0)) then
            do k = 1, nb
                if (ka(k) > 0) xt(:, k) = xt(:, k) + xt(:, ka(k))
            end do
        end if
    end subroutine tree_solve_r
"""
