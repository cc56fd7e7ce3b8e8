!> Hill's lunar problem: the variation orbit for a given m, its monodromy matrix, Floquet
!! multipliers, stability index and the perigee constant c.
!!
!!   fpm run hill -- --m 0.080848933808312 --csv orbit.csv --phi phi.csv
!!
!! --csv writes t,x,y,xd,yd along one period; --phi writes t,phi of the transverse Hill's
!! equation N'' + Phi(t) N = 0. Exit status 0 on success, 1 on failure, 2 on bad arguments.
program hill
    use, intrinsic :: iso_fortran_env, only: error_unit
    use conmech
    use app_cli
    use app_namelist, only: check_namelist
    use app_batch, only: file_exists, max_jobs
    implicit none
    character(len=*), parameter :: help = &
        "usage: hill [--m M] [--kappa K] [--csv FILE] [--phi FILE] [--npoints N] [--force]"// &
        new_line("a")//"The variation orbit of Hill's lunar problem for one m: initial "// &
        "state, period,"//new_line("a")//"Jacobi constant, monodromy matrix, Floquet "// &
        "multipliers, stability index and"//new_line("a")//"perigee constant c."// &
        new_line("a")//"Options:"//new_line("a")// &
        "  --m M             ratio of mean motions (default Hill's 0.080848933808312), > 0"// &
        new_line("a")//"  --kappa K         mass parameter (default 1), > 0"// &
        new_line("a")//"  --csv FILE        write t,x,y,xd,yd along one period"// &
        new_line("a")//"  --phi FILE        write t,phi of the transverse Hill equation"// &
        new_line("a")//"  --npoints N       points per period in the files (default 401, "// &
        "2..10000000)"//new_line("a")// &
        "  --force           overwrite existing --csv / --phi files"//new_line("a")// &
        "  --input FILE.nml  read the options from a namelist &hill ... / (see jobs/hill.nml)"// &
        new_line("a")//"  --help, --version"//new_line("a")// &
        "Exit status: 0 success, 1 the orbit was not found, 2 bad input."//new_line("a")// &
        "Example:"//new_line("a")// &
        "  hill --m 0.080848933808312 --csv orbit.csv --phi phi.csv"
    type(cli_parser) :: cli
    real(dp) :: m_, kappa_
    character(len=1024) :: csv_file, phi_file
    character(len=:), allocatable :: key
    integer :: i, npts, info, ucsv, uphi
    logical :: force_
    type(hill_orbit) :: orb
    type(hill_transverse_result) :: tr
    real(dp), allocatable :: t(:), states(:, :), phi_(:)

    call cli%start("hill", help)
    m_ = 0.080848933808312_dp
    kappa_ = 1.0_dp
    csv_file = ""
    phi_file = ""
    npts = 401
    force_ = .false.
    if (len(cli%input) > 0) call read_input()
    do while (cli%next(key))
        select case (key)
        case ("--m"); call cli%get_real(m_)
        case ("--kappa"); call cli%get_real(kappa_)
        case ("--csv"); call cli%get_string(csv_file)
        case ("--phi"); call cli%get_string(phi_file)
        case ("--npoints"); call cli%get_int(npts)
        case ("--force"); call cli%flag(); force_ = .true.
        case default; call cli%unknown()
        end select
    end do
    if (.not. (m_ > 0.0_dp .and. m_ <= huge(m_))) call cli%fail("--m must be positive and finite")
    if (.not. (kappa_ > 0.0_dp .and. kappa_ <= huge(kappa_))) &
        call cli%fail("--kappa must be positive and finite")
    if (npts < 2 .or. npts > max_jobs) call cli%fail("--npoints must be in 2..10000000")
    ! open the outputs before computing: a bad path is found at once
    ucsv = open_out(csv_file, "--csv")
    uphi = open_out(phi_file, "--phi")

    call hill_variation_orbit(m_, kappa_, orb)
    if (orb%info /= CM_SUCCESS) then
        write (error_unit, '(a)') "hill: error: "//orb%message
        call discard()
        stop 1, quiet=.true.
    end if
    write (*, '(a, es24.16, a, es24.16)') "m      =", m_, "   kappa =", kappa_
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

    if (ucsv /= 0 .or. uphi /= 0) then
        allocate (t(npts), states(4, npts), phi_(npts))
        do i = 1, npts
            t(i) = orb%period*real(i - 1, dp)/real(npts - 1, dp)
        end do
        call hill_orbit_sample(orb, t, states, phi_, info)
        if (info /= CM_SUCCESS) then
            write (error_unit, '(a)') "hill: error: sampling the orbit failed: "// &
                status_message(info)
            call discard()
            stop 1, quiet=.true.
        end if
        if (ucsv /= 0) then
            write (ucsv, '(a)') "t,x,y,xd,yd"
            do i = 1, npts
                write (ucsv, '(a)') fmt_real(t(i))//","//fmt_list(states(:, i))
            end do
            close (ucsv)
            write (*, '(a)') "wrote "//trim(csv_file)
        end if
        if (uphi /= 0) then
            write (uphi, '(a)') "t,phi"
            do i = 1, npts
                write (uphi, '(a)') fmt_real(t(i))//","//fmt_real(phi_(i))
            end do
            close (uphi)
            write (*, '(a)') "wrote "//trim(phi_file)
        end if
    end if
    if (allocated(t)) deallocate (t, states, phi_)
    deallocate (key)
    call cli%clear()

contains

    !> Open an output file (0 if none); an existing file needs --force.
    integer function open_out(name, opt) result(uu)
        character(len=*), intent(in) :: name, opt
        integer :: ios
        uu = 0
        if (len_trim(name) == 0) return
        if (file_exists(trim(name)) .and. .not. force_) call cli%fail(opt//" "//trim(name)// &
            " exists; use --force to overwrite it")
        open (newunit=uu, file=trim(name), status="replace", action="write", iostat=ios)
        if (ios /= 0) call cli%fail("cannot write "//opt//" "//trim(name))
    end function open_out

    !> Remove the (empty) outputs of a failed run.
    subroutine discard()
        if (ucsv /= 0) close (ucsv, status="delete")
        if (uphi /= 0) close (uphi, status="delete")
    end subroutine discard

    !> The options from a namelist &hill ... / (the command line overrides them).
    subroutine read_input()
        real(dp) :: m, kappa
        character(len=1024) :: csv, phi
        integer :: npoints, ios
        character(len=:), allocatable :: lines(:)
        logical :: force
        character(len=512) :: msg
        namelist /hill/ m, kappa, csv, phi, npoints, force
        m = m_; kappa = kappa_; csv = csv_file; phi = phi_file; npoints = npts
        force = force_
        call check_namelist(cli, cli%input, "hill", &
            "m:r kappa:r csv:s1024 phi:s1024 npoints:i force:l", lines)
        read (lines, nml=hill, iostat=ios, iomsg=msg)
        if (ios /= 0) call cli%fail("--input "//cli%input//": namelist &hill: "//trim(msg))
        m_ = m; kappa_ = kappa; csv_file = csv; phi_file = phi; npts = npoints
        force_ = force
    end subroutine read_input

end program hill
