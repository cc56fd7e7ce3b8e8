!> The step of a central difference quotient at x: h = eps^(1/3) max(|x|, 1), which
!! balances the truncation error O(h^2) of the quotient against its rounding error
!! O(eps/h), relative to the scale max(|x|, 1). The finite-difference defaults of the
!! systems' Jacobians and the Newton matrices of shooting and continuation use it.
module conmech_central_step
    use conmech_kinds, only: dp
    implicit none
    private

    public :: central_step

contains

    elemental real(dp) function central_step(x) result(h)
        real(dp), intent(in) :: x
        h = epsilon(1.0_dp)**(1.0_dp/3.0_dp)*max(abs(x), 1.0_dp)
    end function central_step

end module conmech_central_step
