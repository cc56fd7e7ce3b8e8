!> Working precision and basic constants of conmech.
!!
!! `nan_dp` is the quiet NaN (the one ieee_value(1.0_dp, ieee_quiet_nan) gives) made from
!! its bits, and the library tests for NaN and Inf by comparisons (x /= x;
!! abs(x) <= huge(x) for a finite x): no scope of the library uses the intrinsic IEEE
!! modules, because gfortran saves and restores the whole floating-point environment
!! (about 0.2 us) on every call of a procedure that sees their names, which an external
!! procedure does through any module it uses that uses them (every entry of the flat
!! layer would pay it on each call). The comparison abs(x) <= huge(x) is an ordered one, so a NaN
!! checked by it raises the invalid flag (as the Taylor stepper's checks always did); x /= x
!! does not.
module conmech_kinds
    use, intrinsic :: iso_fortran_env, only: real64, int32, int64
    implicit none
    private
    public :: dp, ip, pi, eps_dp, nan_dp

    integer, parameter :: dp = real64   !! working real kind
    integer, parameter :: ip = int32    !! default integer kind
    real(dp), parameter :: pi = 3.14159265358979323846264338327950288_dp
    real(dp), parameter :: eps_dp = epsilon(1.0_dp)
    !> the quiet NaN, bits 0x7FF8000000000000
    real(dp), parameter :: nan_dp = transfer(9221120237041090560_int64, 1.0_dp)
end module conmech_kinds
