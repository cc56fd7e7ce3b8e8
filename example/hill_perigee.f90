!> Hill's perigee constant in a few lines: the variation orbit of Hill's lunar problem at
!! Hill's m, its monodromy matrix and c (Hill 1877: c = 1.0715832774160).
!!
!!   fpm run --example hill_perigee
program hill_perigee
    use conmech
    implicit none
    type(hill_orbit) :: orb
    type(hill_orbit), allocatable :: fam(:)
    real(dp), allocatable :: ms(:)
    integer :: i

    call hill_variation_orbit(0.080848933808312_dp, 1.0_dp, orb)
    if (orb%info /= CM_SUCCESS) error stop orb%message
    write (*, '(a, 2f20.16)') "x0, v0          =", orb%y0(1), orb%y0(4)
    write (*, '(a, f20.16)') "stability index =", orb%stability_index
    write (*, '(a, f20.16)') "perigee c       =", orb%c

    ! the family over m by continuation, with its stability index
    ms = [(0.02_dp*i, i = 1, 8)]
    allocate (fam(size(ms)))
    call hill_family(ms, 1.0_dp, fam)
    do i = 1, size(ms)
        write (*, '(a, f6.3, a, f10.6, a, f14.10)') "m =", ms(i), "   S =", &
            fam(i)%stability_index, "   c =", fam(i)%c
    end do
end program hill_perigee
