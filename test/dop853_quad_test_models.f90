!> Right-hand sides in quadruple precision with the calling convention of the generated
!! quadruple-precision Taylor routines (t, order, w(0:order, nw), p behind C pointers), giving
!! the first coefficient w(1, :) = f(t, w(0, :)) only: all DOP853 needs.
module dop853_quad_test_models
    use, intrinsic :: iso_c_binding, only: c_int, c_ptr, c_f_pointer
    use, intrinsic :: iso_fortran_env, only: qp => real128
    implicit none
    private
    public :: kepler_qp, growth_qp

contains

    !> Kepler's problem x'' = -mu x/|x|^3, state (x, y, u, v), p = [mu].
    subroutine kepler_qp(tp, order, wp, pp) bind(c)
        type(c_ptr), value :: tp, wp, pp
        integer(c_int), value :: order
        real(qp), pointer :: w(:, :), p(:), t
        real(qp) :: r3
        call c_f_pointer(tp, t)
        call c_f_pointer(wp, w, [order + 1, 4])
        call c_f_pointer(pp, p, [1])
        r3 = sqrt(w(1, 1)**2 + w(1, 2)**2)**3
        w(2, 1:2) = w(1, 3:4)
        w(2, 3:4) = -p(1)*w(1, 1:2)/r3
    end subroutine kepler_qp

    !> y' = k y cos t (y = y0 exp(k sin t)), p = [k].
    subroutine growth_qp(tp, order, wp, pp) bind(c)
        type(c_ptr), value :: tp, wp, pp
        integer(c_int), value :: order
        real(qp), pointer :: w(:, :), p(:), t
        call c_f_pointer(tp, t)
        call c_f_pointer(wp, w, [order + 1, 1])
        call c_f_pointer(pp, p, [1])
        w(2, 1) = p(1)*w(1, 1)*cos(t)
    end subroutine growth_qp

end module dop853_quad_test_models
