!> A fill-reducing order for sparse LU: reverse Cuthill-McKee (Cuthill and McKee, Proc. 24th
!! ACM National Conference (1969) 157-172; George's reversal, 1971) on the pattern of
!! A + A^T, from a pseudo-peripheral start node of each connected component (George and
!! Liu's search). It reduces the profile of the matrix; for the Jacobians of discretised
!! one-dimensional (and thin two-dimensional) problems, whatever the numbering of the
!! unknowns, the factors then stay within the reduced band. Applied symmetrically (rows and
!! columns; conmech_sparse_lu keeps a dominant diagonal as pivot), it is the choice of
!! banded solvers; a minimum-degree order fills less on wide two- and three-dimensional
!! meshes, at the cost of a more elaborate symbolic phase.
module conmech_sparse_order
    implicit none
    private

    public :: rcm_order

contains

    !> q: the reverse Cuthill-McKee order of the pattern of A + A^T (A: n x n, compressed by
    !! columns, 1-based rows ai(ap(j) : ap(j + 1) - 1) of column j); the diagonal and
    !! duplicate entries are ignored.
    subroutine rcm_order(n, ap, ai, q)
        integer, intent(in) :: n
        integer, intent(in) :: ap(:), ai(:)
        integer, intent(out) :: q(:)
        integer, allocatable :: deg(:), xadj(:), adj(:), fill(:), mark(:), order(:)
        integer :: i, j, p, pos, start, ecc, ecc_new, nlev, last, k, nlast
        allocate (deg(n), xadj(n + 1), mark(n), order(n))
        ! the symmetric adjacency, duplicates removed
        deg = 0
        do j = 1, n
            do p = ap(j), ap(j + 1) - 1
                i = ai(p)
                if (i == j) cycle
                deg(i) = deg(i) + 1
                deg(j) = deg(j) + 1
            end do
        end do
        xadj(1) = 1
        do i = 1, n
            xadj(i + 1) = xadj(i) + deg(i)
        end do
        allocate (adj(max(xadj(n + 1) - 1, 1)), fill(n))
        fill = xadj(1:n)
        do j = 1, n
            do p = ap(j), ap(j + 1) - 1
                i = ai(p)
                if (i == j) cycle
                adj(fill(i)) = j
                fill(i) = fill(i) + 1
                adj(fill(j)) = i
                fill(j) = fill(j) + 1
            end do
        end do
        mark = 0
        do i = 1, n
            k = xadj(i)
            do p = xadj(i), fill(i) - 1
                if (mark(adj(p)) == i) cycle
                mark(adj(p)) = i
                adj(k) = adj(p)
                k = k + 1
            end do
            deg(i) = k - xadj(i)
        end do
        ! component by component: a pseudo-peripheral node, then Cuthill-McKee from it
        mark = 0
        pos = 0
        do while (pos < n)
            start = 0
            do i = 1, n
                if (mark(i) /= 0) cycle
                if (start == 0) then
                    start = i
                else if (deg(i) < deg(start)) then
                    start = i
                end if
            end do
            call bfs(start, pos, ecc, last)
            do
                call unmark(pos)
                call bfs(last, pos, ecc_new, nlev)
                if (ecc_new <= ecc) then
                    call unmark(pos)
                    exit
                end if
                start = last
                ecc = ecc_new
                last = nlev
            end do
            call bfs(start, pos, ecc, last)
            pos = pos + count_component(pos)
        end do
        do k = 1, n
            q(k) = order(n + 1 - k)
        end do

    contains

        !> Cuthill-McKee from s into order(pos0 + 1 :), neighbours by increasing degree;
        !! e: the number of levels, lastnode: a node of least degree in the last level;
        !! the component ends at order(nlast).
        subroutine bfs(s, pos0, e, lastnode)
            integer, intent(in) :: s, pos0
            integer, intent(out) :: e, lastnode
            integer :: head, tail, v, w, pp, a, b, tmp, lev_start, lev_end
            head = pos0 + 1
            tail = pos0 + 1
            order(tail) = s
            mark(s) = 1
            e = 1
            lev_start = tail
            lev_end = tail
            do while (head <= tail)
                v = order(head)
                a = tail + 1
                do pp = xadj(v), xadj(v) + deg(v) - 1
                    w = adj(pp)
                    if (mark(w) /= 0) cycle
                    mark(w) = 1
                    tail = tail + 1
                    order(tail) = w
                end do
                ! insertion sort of the new nodes by degree
                do b = a + 1, tail
                    tmp = order(b)
                    pp = b - 1
                    do while (pp >= a)
                        if (deg(order(pp)) <= deg(tmp)) exit
                        order(pp + 1) = order(pp)
                        pp = pp - 1
                    end do
                    order(pp + 1) = tmp
                end do
                if (head == lev_end .and. tail > lev_end) then
                    e = e + 1
                    lev_start = lev_end + 1
                    lev_end = tail
                end if
                head = head + 1
            end do
            lastnode = order(lev_start)
            do pp = lev_start, lev_end
                if (deg(order(pp)) < deg(lastnode)) lastnode = order(pp)
            end do
            nlast = tail
        end subroutine bfs

        subroutine unmark(pos0)
            integer, intent(in) :: pos0
            integer :: pp
            do pp = pos0 + 1, nlast
                mark(order(pp)) = 0
            end do
        end subroutine unmark

        integer function count_component(pos0)
            integer, intent(in) :: pos0
            count_component = nlast - pos0
        end function count_component

    end subroutine rcm_order

end module conmech_sparse_order
