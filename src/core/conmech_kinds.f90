!> Working precision and basic constants of conmech.
module conmech_kinds
    use, intrinsic :: iso_fortran_env, only: real64, int32
    implicit none
    private
    public :: dp, ip, pi, eps_dp

    integer, parameter :: dp = real64   !! working real kind
    integer, parameter :: ip = int32    !! default integer kind
    real(dp), parameter :: pi = 3.14159265358979323846264338327950288_dp
    real(dp), parameter :: eps_dp = epsilon(1.0_dp)
end module conmech_kinds
