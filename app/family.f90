!> Continue a family of periodic orbits of a built-in system in one of its parameters
!! (pseudo-arclength, special points located) and write the branch and its special points
!! as CSV. Resumable: rerun the same command after an interruption and the branch goes on
!! from its last row.
!!
!!   fpm run family -- --system vanderpol --params 1 --param 1 --y0 2,0 --period 6.6 \
!!       --p-max 3 --out branch.csv --special special.csv
!!
!! Exit status 0 on success, 1 when the continuation stopped early (the rows so far are
!! written; the message names the parameter value), 2 on bad input.
program family
    use, intrinsic :: iso_fortran_env, only: error_unit
    use conmech
    use app_cli
    use app_batch, only: file_exists
    implicit none
    character(len=*), parameter :: nl = new_line("a")
    character(len=*), parameter :: help = &
        "usage: family --system NAME --y0 LIST --period T [--params LIST] [--param K]"//nl// &
        "              [--free LIST --targets LIST [--period-factor F] [--free-time]]"//nl// &
        "              [--conservative] [--fixed-period] [--non-autonomous]"//nl// &
        "              [--ds S] [--ds-min S] [--ds-max S] [--p-min P] [--p-max P]"//nl// &
        "              [--max-points N] [--direction 1|-1] [--rtol R]"//nl// &
        "              [--out FILE] [--special FILE] [--force]"//nl// &
        "Pseudo-arclength continuation of the periodic orbit through y0 in parameter K"//nl// &
        "(1-based) of the built-in system, with folds, branch points, period doublings"//nl// &
        "and Neimark-Sacker points located. --free/--targets (1-based) select symmetric"//nl// &
        "shooting (tau = T/period-factor). The branch goes to --out (default"//nl// &
        "branch.csv: i,p,period,stability_index,stable,residual,iterations,y0_1..y0_n),"//nl// &
        "the special points to --special (default special.csv: kind,index,p,period,"//nl// &
        "stability_index,y0_1..). An existing --out is resumed from its last row"//nl// &
        "(--force starts afresh). Exit: 0 done, 1 stopped early, 2 bad input."//nl// &
        "Example (Hill's variation orbits in m, the loss of stability at m = 0.195...):"//nl// &
        "  family --system hill --params 0.15,1 --param 1 --y0 0.8,0,0,1"//nl// &
        "         --period 6.283185307179586 --free 1,4 --targets 1,4 --period-factor 4"//nl// &
        "         --conservative --p-max 0.25"
    type(cli_parser) :: cli
    character(len=64) :: sysname
    character(len=1024) :: out_file, sp_file
    character(len=:), allocatable :: key, msg
    real(dp), allocatable :: params(:), y0(:), freer(:), targr(:), last(:)
    real(dp) :: period, pf
    integer :: ipar, n, i, u, us, nrows, info, k
    logical :: force_, sym, tfree, resume
    type(cont_options) :: o
    type(builtin_param_system) :: sys
    type(branch) :: br

    call cli%start("family", help)
    sysname = ""
    out_file = "branch.csv"
    sp_file = "special.csv"
    period = -1.0_dp
    pf = 2.0_dp
    ipar = 1
    force_ = .false.
    tfree = .false.
    allocate (params(0), y0(0), freer(0), targr(0))
    do while (cli%next(key))
        select case (key)
        case ("--system"); call cli%get_string(sysname)
        case ("--params"); call cli%get_list(params)
        case ("--param"); call cli%get_int(ipar)
        case ("--y0"); call cli%get_list(y0)
        case ("--period"); call cli%get_real(period)
        case ("--free"); call cli%get_list(freer)
        case ("--targets"); call cli%get_list(targr)
        case ("--period-factor"); call cli%get_real(pf)
        case ("--free-time"); call cli%flag(); tfree = .true.
        case ("--conservative"); call cli%flag(); o%conservative = .true.
        case ("--fixed-period"); call cli%flag(); o%fixed_period = .true.
        case ("--non-autonomous"); call cli%flag(); o%autonomous = .false.
        case ("--ds"); call cli%get_real(o%ds)
        case ("--ds-min"); call cli%get_real(o%ds_min)
        case ("--ds-max"); call cli%get_real(o%ds_max)
        case ("--p-min"); call cli%get_real(o%p_min)
        case ("--p-max"); call cli%get_real(o%p_max)
        case ("--max-points"); call cli%get_int(o%max_points)
        case ("--direction"); call cli%get_int(o%direction)
        case ("--rtol"); call cli%get_real(o%rtol); o%atol = o%rtol
        case ("--out"); call cli%get_string(out_file)
        case ("--special"); call cli%get_string(sp_file)
        case ("--force"); call cli%flag(); force_ = .true.
        case default; call cli%unknown()
        end select
    end do
    if (len_trim(sysname) == 0) call cli%fail("--system is required")
    n = size(y0)
    if (n < 1) call cli%fail("--y0 is required")
    if (.not. (period > 0.0_dp)) call cli%fail("--period must be positive")
    if (o%max_points < 2) call cli%fail("--max-points must be >= 2")
    if (.not. (o%ds > 0.0_dp .and. o%ds_min > 0.0_dp .and. o%ds_max >= o%ds_min)) &
        call cli%fail("--ds, --ds-min, --ds-max must be positive (ds-max >= ds-min)")
    if (abs(o%direction) /= 1) call cli%fail("--direction must be 1 or -1")
    sym = size(freer) > 0 .or. size(targr) > 0
    if (sym .and. (size(freer) == 0 .or. size(targr) == 0)) &
        call cli%fail("--free and --targets go together")
    if (sym .and. (any(freer < 1) .or. any(freer > n) .or. any(targr < 1) .or. &
                   any(targr > n))) call cli%fail("--free/--targets: indices in 1..n")
    if (system_dimension(trim(sysname)) == 0) call cli%fail("unknown --system "//trim(sysname))
    if (system_dimension(trim(sysname)) /= n) &
        call cli%fail("--y0 must have "//itoa(system_dimension(trim(sysname)))//" values")
    if (size(params) == 0) call cli%fail("--params is required (the system's parameters)")
    call make_param_system(trim(sysname), params, ipar, sys, info, msg)
    if (info /= CM_SUCCESS) call cli%fail(msg)

    ! resume from the last row of an existing branch file
    nrows = 0
    resume = file_exists(trim(out_file)) .and. .not. force_
    if (resume) then
        call read_last(trim(out_file), n, nrows, last, o%direction)
        if (nrows > 0) then
            params(ipar) = last(1)
            period = last(2)
            y0 = last(3:)
            o%max_points = o%max_points - nrows + 1
            write (*, '(a, i0, a)') "family: resuming after ", nrows, " points of "// &
                trim(out_file)
            if (o%max_points < 2) then
                write (*, '(a)') "family: the branch is complete"
                stop
            end if
            call make_param_system(trim(sysname), params, ipar, sys, info, msg)
        end if
    end if
    if (nrows == 0) then
        open (newunit=u, file=trim(out_file), status="replace", action="write", iostat=info)
        if (info /= 0) call cli%fail("cannot write "//trim(out_file))
        write (u, '(a)', advance="no") "i,p,period,stability_index,stable,residual,iterations"
        do k = 1, n
            write (u, '(a)', advance="no") ",y0_"//itoa(k)
        end do
        write (u, '(a)') ""
        close (u)
        open (newunit=us, file=trim(sp_file), status="replace", action="write", iostat=info)
        if (info /= 0) call cli%fail("cannot write "//trim(sp_file))
        write (us, '(a)', advance="no") "kind,index,p,period,stability_index"
        do k = 1, n
            write (us, '(a)', advance="no") ",y0_"//itoa(k)
        end do
        write (us, '(a)') ""
        close (us)
    end if

    if (sym) then
        call continue_orbits(sys, set_builtin_param, params(ipar), y0, period, br, o, &
                             nint(freer), nint(targr), tfree, pf)
    else
        call continue_orbits(sys, set_builtin_param, params(ipar), y0, period, br, o)
    end if
    if (br%npoints == 0) then
        write (error_unit, '(a)') "family: error: "//br%message
        stop 1, quiet=.true.
    end if
    open (newunit=u, file=trim(out_file), status="old", position="append", action="write")
    do i = merge(2, 1, nrows > 0), br%npoints
        write (u, '(a)') itoa(nrows + i - merge(1, 0, nrows > 0))//","// &
            fmt_real(br%points(i)%p)//","//fmt_real(br%points(i)%period)//","// &
            fmt_real(br%points(i)%stability_index)//","//itoa(merge(1, 0, &
            stable(br%points(i))))//","//fmt_real(br%points(i)%residual)//","// &
            itoa(br%points(i)%iterations)//","//fmt_list(br%points(i)%y0)
    end do
    close (u)
    open (newunit=us, file=trim(sp_file), status="old", position="append", action="write")
    do i = 1, br%nspecial
        write (us, '(a)') trim(special_name(br%special(i)%kind))//","// &
            itoa(nrows + br%special(i)%index - merge(1, 0, nrows > 0))//","// &
            fmt_real(br%special(i)%point%p)//","//fmt_real(br%special(i)%point%period)// &
            ","//fmt_real(br%special(i)%point%stability_index)//","// &
            fmt_list(br%special(i)%point%y0)
        write (*, '(a, es24.16)') "family: "//special_name(br%special(i)%kind)//" at p =", &
            br%special(i)%point%p
    end do
    close (us)
    write (*, '(a, i0, a)') "family: ", br%npoints, " points, "//br%message
    if (br%info /= CM_SUCCESS) stop 1, quiet=.true.

contains

    logical function stable(pt)
        type(cont_point), intent(in) :: pt
        if (o%conservative .and. n == 4) then
            stable = abs(pt%stability_index) < 1.0_dp
        else
            stable = pt%stability_index < 1.0_dp
        end if
    end function stable

    function itoa(k) result(s)
        integer, intent(in) :: k
        character(len=:), allocatable :: s
        character(len=16) :: b
        write (b, '(i0)') k
        s = trim(b)
    end function itoa

    !> The number of complete rows and the last one's [p, period, y0]; the direction of
    !! the parameter over the last two rows.
    subroutine read_last(name, n, nrows, last, direction)
        character(len=*), intent(in) :: name
        integer, intent(in) :: n
        integer, intent(out) :: nrows
        real(dp), allocatable, intent(out) :: last(:)
        integer, intent(inout) :: direction
        character(len=4096) :: line
        real(dp) :: row(7 + n), prev
        integer :: uu, ios
        allocate (last(n + 2))
        nrows = 0
        prev = huge(1.0_dp)
        open (newunit=uu, file=name, status="old", action="read", iostat=ios)
        if (ios /= 0) return
        read (uu, '(a)', iostat=ios) line
        do
            read (uu, '(a)', iostat=ios) line
            if (ios /= 0) exit
            read (line, *, iostat=ios) row
            if (ios /= 0) exit
            if (nrows > 0) prev = last(1)
            nrows = nrows + 1
            last = [row(2), row(3), row(8:)]
        end do
        close (uu)
        if (nrows > 1 .and. prev /= last(1)) direction = merge(1, -1, last(1) > prev)
    end subroutine read_last

end program family
