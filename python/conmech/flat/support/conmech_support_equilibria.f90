!> Support of flat_equilibria.f90: an equilibrium_result copied into the flat arguments.
module conmech_support_equilibria
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_equilibria, only: equilibrium_result
    implicit none
    private
    public :: unpack_structure

contains

    !> The fields of `e` into plain arrays (family and drift padded to n x n with zeros).
    subroutine unpack_structure(e, n, jac, wr, wi, kind, saddle, residual, analytic, &
                                zero_mult, largest_block, secular_freq, family_dim, family, &
                                ndrift, drift, info, message)
        type(equilibrium_result), intent(in) :: e
        integer(c_int), intent(in) :: n
        real(c_double), intent(out) :: jac(n, n), wr(n), wi(n), residual, secular_freq
        real(c_double), intent(out) :: family(n, n), drift(n, n)
        integer(c_int), intent(out) :: kind, saddle, analytic, zero_mult, largest_block
        integer(c_int), intent(out) :: family_dim, ndrift, info
        character(len=256), intent(out) :: message
        info = e%info
        message = ""
        if (allocated(e%message)) message = e%message
        jac = 0.0_c_double
        wr = 0.0_c_double
        wi = 0.0_c_double
        family = 0.0_c_double
        drift = 0.0_c_double
        family_dim = 0
        ndrift = 0
        if (allocated(e%jacobian)) then
            if (size(e%jacobian, 1) == n) jac = e%jacobian
        end if
        if (allocated(e%wr)) wr = e%wr
        if (allocated(e%wi)) wi = e%wi
        if (allocated(e%family)) then
            family_dim = size(e%family, 2)
            if (family_dim > 0) family(:, 1:family_dim) = e%family
        end if
        if (allocated(e%drift)) then
            ndrift = size(e%drift, 2)
            if (ndrift > 0) drift(:, 1:ndrift) = e%drift
        end if
        kind = e%kind
        saddle = merge(1, 0, e%saddle)
        analytic = merge(1, 0, e%analytic)
        residual = e%residual
        zero_mult = e%zero_multiplicity
        largest_block = e%largest_block
        secular_freq = e%secular_frequency
    end subroutine unpack_structure

end module conmech_support_equilibria
