!> Hill's lunar problem: the variation orbit for a given m, its monodromy matrix, Floquet
!! multipliers, stability index and the perigee constant c.
!!
!!   fpm run hill -- --m 0.080848933808312 [--kappa 1] [--csv orbit.csv] [--phi phi.csv]
!!                   [--npoints 401]
!!
!! --csv writes t,x,y,xd,yd along one period; --phi writes t,phi of the transverse Hill's
!! equation N'' + Phi(t) N = 0. Exit status 0 on success, 1 on failure, 2 on bad arguments.
program hill
    use conmech
    implicit none
    real(dp) :: m, kappa
    character(len=:), allocatable :: csv, phicsv
    character(len=256) :: arg, val
    integer :: i, narg, npts, ios, info, u
    type(hill_orbit) :: orb
    type(hill_transverse_result) :: tr
    real(dp), allocatable :: t(:), states(:, :), phi(:)

    m = 0.080848933808312_dp
    kappa = 1.0_dp
    csv = ""
    phicsv = ""
    npts = 401
    narg = command_argument_count()
    i = 1
    do while (i <= narg)
        call get_command_argument(i, arg)
        if (trim(arg) == "-h" .or. trim(arg) == "--help") then
            write (*, '(a)') "usage: hill [--m M] [--kappa K] [--csv FILE] [--phi FILE] "// &
                "[--npoints N]"
            stop
        end if
        if (i == narg) call usage_error("missing value after "//trim(arg))
        call get_command_argument(i + 1, val)
        select case (trim(arg))
        case ("--m")
            read (val, *, iostat=ios) m
        case ("--kappa")
            read (val, *, iostat=ios) kappa
        case ("--csv")
            csv = trim(val)
            ios = 0
        case ("--phi")
            phicsv = trim(val)
            ios = 0
        case ("--npoints")
            read (val, *, iostat=ios) npts
            if (npts < 2) ios = 1
        case default
            call usage_error("unknown option "//trim(arg))
        end select
        if (ios /= 0) call usage_error("bad value for "//trim(arg)//": "//trim(val))
        i = i + 2
    end do

    call hill_variation_orbit(m, kappa, orb)
    if (orb%info /= CM_SUCCESS) then
        write (*, '(a)') "error: "//orb%message
        error stop 1
    end if
    write (*, '(a, es24.16, a, es24.16)') "m      =", m, "   kappa =", kappa
    write (*, '(a, 4es24.16)') "y0     =", orb%y0
    write (*, '(a, es24.16)') "period =", orb%period
    write (*, '(a, es24.16)') "jacobi =", orb%jacobi
    write (*, '(a, i0, a, i0)') "newton iterations = ", orb%iterations, &
        ", rhs evaluations = ", orb%nfev
    write (*, '(a)') "monodromy matrix:"
    do i = 1, 4
        write (*, '(4es24.16)') orb%monodromy(i, :)
    end do
    write (*, '(a)') "Floquet multipliers (dgeev; the trivial pair is a Jordan block, "// &
        "accurate only to ~sqrt(eps)):"
    do i = 1, 4
        write (*, '(2es24.16, a, es12.4)') orb%mr(i), orb%mi(i), "   |mu| =", &
            hypot(orb%mr(i), orb%mi(i))
    end do
    write (*, '(a, es24.16)') "det M  =", la_det(orb%monodromy)
    write (*, '(a, es24.16, a)') "stability index S = (tr M - 2)/2 =", orb%stability_index, &
        merge(" (stable)  ", " (unstable)", abs(orb%stability_index) < 1.0_dp)
    write (*, '(a, f20.16)') "perigee constant c =", orb%c
    call hill_transverse(orb, tr)
    if (tr%info == CM_SUCCESS) then
        write (*, '(a, f20.16)') "c from the transverse Hill equation =", tr%c
    end if

    if (len(csv) > 0 .or. len(phicsv) > 0) then
        allocate (t(npts), states(4, npts), phi(npts))
        do i = 1, npts
            t(i) = orb%period*real(i - 1, dp)/real(npts - 1, dp)
        end do
        call hill_orbit_sample(orb, t, states, phi, info)
        if (info /= CM_SUCCESS) then
            write (*, '(a)') "error: sampling the orbit failed: "//status_message(info)
            error stop 1
        end if
        if (len(csv) > 0) then
            open (newunit=u, file=csv, status="replace", action="write", iostat=ios)
            if (ios /= 0) call fail_io(csv)
            write (u, '(a)') "t,x,y,xd,yd"
            do i = 1, npts
                write (u, '(es24.16, 4(",", es24.16))') t(i), states(:, i)
            end do
            close (u)
            write (*, '(a)') "wrote "//csv
        end if
        if (len(phicsv) > 0) then
            open (newunit=u, file=phicsv, status="replace", action="write", iostat=ios)
            if (ios /= 0) call fail_io(phicsv)
            write (u, '(a)') "t,phi"
            do i = 1, npts
                write (u, '(es24.16, ",", es24.16)') t(i), phi(i)
            end do
            close (u)
            write (*, '(a)') "wrote "//phicsv
        end if
    end if

contains

    subroutine usage_error(msg)
        character(len=*), intent(in) :: msg
        write (*, '(a)') "error: "//msg
        write (*, '(a)') "usage: hill [--m M] [--kappa K] [--csv FILE] [--phi FILE] [--npoints N]"
        error stop 2
    end subroutine usage_error

    subroutine fail_io(name)
        character(len=*), intent(in) :: name
        write (*, '(a)') "error: cannot open "//name
        error stop 1
    end subroutine fail_io

end program hill
