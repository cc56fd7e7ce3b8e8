!> Quadruple-precision values across the flat layer: a real128 number crosses the f2py
!! boundary as a pair of doubles (hi, lo) whose sum is the value (two doubles carry 106 of
!! its 113 significand bits exactly), and a generated real128 Taylor routine as its address.
module conmech_flat_quad_pairs
    use, intrinsic :: iso_c_binding, only: c_double, c_intptr_t, c_funptr, c_null_funptr, &
                                           c_f_procpointer
    use conmech_taylor_quad, only: qp, taylor_qp_fn
    implicit none
    private
    public :: from_pairs, from_pair, to_pairs, quad_routine

contains

    !> The values hi + lo of the columns of `a` (2, m).
    pure function from_pairs(a) result(q)
        real(c_double), intent(in) :: a(:, :)
        real(qp) :: q(size(a, 2))
        q = real(a(1, :), qp) + real(a(2, :), qp)
    end function from_pairs

    !> The value hi + lo of the pair `a`.
    pure function from_pair(a) result(q)
        real(c_double), intent(in) :: a(2)
        real(qp) :: q
        q = real(a(1), qp) + real(a(2), qp)
    end function from_pair

    !> Each q(i) as the pair (hi, lo): hi the double nearest q(i), lo the double nearest
    !! the rest.
    pure subroutine to_pairs(q, a)
        real(qp), intent(in) :: q(:)
        real(c_double), intent(out) :: a(2, size(q))
        a(1, :) = real(q, c_double)
        a(2, :) = real(q - real(a(1, :), qp), c_double)
    end subroutine to_pairs

    !> The generated real128 Taylor routine at the address `fnaddr` (nonzero).
    subroutine quad_routine(fnaddr, fn)
        integer(8), intent(in) :: fnaddr
        procedure(taylor_qp_fn), pointer, intent(out) :: fn
        type(c_funptr) :: fp
        fp = transfer(int(fnaddr, c_intptr_t), c_null_funptr)
        call c_f_procpointer(fp, fn)
    end subroutine quad_routine

end module conmech_flat_quad_pairs
