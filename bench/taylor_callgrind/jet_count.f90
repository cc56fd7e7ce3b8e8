!> Instructions of one expansion of the recurrences written out for one order (the module
!! conmech_symbolic_taylor_fixed that conmech.symbolic.taylor.fixed_order_source writes):
!!   jet_count ORDER NW REPS P
!! expands REPS times about the state (0.994, 0.01, 0.02, -2.0) with the parameter P;
!! for callgrind (bench/callgrind_taylor_jet.sh): per expansion = (count at REPS = 11 -
!! count at REPS = 1)/10. Prints a checksum of the coefficients (so that no expansion is
!! optimised away, and paired and unpaired sources can be compared).
program jet_count
    use, intrinsic :: iso_c_binding, only: c_double, c_int
    use conmech_symbolic_taylor_fixed, only: conmech_taylor_fixed
    implicit none
    integer, parameter :: dp = c_double
    integer :: order, nw, reps, r
    real(dp), allocatable :: w(:, :)
    real(dp) :: p(1), acc
    character(len=32) :: a
    call get_command_argument(1, a)
    read (a, *) order
    call get_command_argument(2, a)
    read (a, *) nw
    call get_command_argument(3, a)
    read (a, *) reps
    call get_command_argument(4, a)
    read (a, *) p(1)
    allocate (w(0:order, nw))
    w = 0.0_dp
    acc = 0.0_dp
    do r = 1, reps
        w(0, 1:4) = [0.994_dp, 0.01_dp, 0.02_dp, -2.0_dp + 1.0e-3_dp*r]
        call conmech_taylor_fixed(0.0_dp, int(order, c_int), w, p)
        acc = acc + sum(w(:, 1:4))
    end do
    print '(es24.16)', acc
end program jet_count
