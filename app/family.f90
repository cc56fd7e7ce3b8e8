!> Continue a family of periodic orbits of a built-in system in one of its parameters
!! (pseudo-arclength, special points located) and write the branch and its special points
!! as CSV. Resumable: rerun the same command after an interruption and the branch goes on
!! from its last row.
!!
!!   fpm run family -- --system vanderpol --params 1 --param 1 --y0 2,0 --period 6.6 \
!!       --p-max 3 --out branch.csv --special special.csv
!!
!! With `--switch K` it then switches at the K-th bifurcation point of that branch (branch
!! point or period doubling) and continues the branch born there into `--switch-out`.
!! `--model LIB.so` continues a compiled user model instead of a built-in system.
!!
!! Exit status 0 on success, 1 when the continuation stopped early (the rows so far are
!! written; the message names the parameter value) or there is no K-th bifurcation point,
!! 2 on bad input.
program family
    use, intrinsic :: iso_fortran_env, only: error_unit
    use conmech
    use app_cli
    use app_namelist, only: check_namelist
    use app_batch, only: file_exists, row_t
    use app_output, only: results_file
    implicit none
    character(len=*), parameter :: nl = new_line("a")
    character(len=*), parameter :: help = &
        "usage: family (--system NAME | --model LIB.so) --y0 LIST --period T"//nl// &
        "              [--params LIST] [--param K]"//nl// &
        "              [--free LIST --targets LIST [--period-factor F] [--free-time]]"//nl// &
        "              [--conservative] [--fixed-period] [--non-autonomous]"//nl// &
        "              [--ds S] [--ds-min S] [--ds-max S] [--p-min P] [--p-max P]"//nl// &
        "              [--max-points N] [--direction 1|-1] [--rtol R]"//nl// &
        "              [--out FILE] [--special FILE] [--force]"//nl// &
        "              [--switch K [--switch-direction 1|-1] [--switch-points N]"//nl// &
        "               [--switch-out FILE] [--switch-special FILE]]"//nl// &
        "Pseudo-arclength continuation of the periodic orbit through y0 in parameter K"//nl// &
        "(1-based) of the built-in system, with folds, branch points, period doublings"//nl// &
        "and Neimark-Sacker points located. --free/--targets (1-based) select symmetric"//nl// &
        "shooting (tau = T/period-factor). The branch goes to --out (default"//nl// &
        "branch.csv: i,p,period,stability_index,stable,residual,iterations,y0_1..y0_n),"//nl// &
        "the special points to --special (default special.csv: kind,index,p,period,"//nl// &
        "stability_index,y0_1..). An existing --out is resumed from its last row"//nl// &
        "(--force starts afresh). --model LIB.so: a compiled ode or generalized model"//nl// &
        "(conmech_model_library; --params default to the model's)."//nl// &
        "Branch switching: --switch K takes the K-th bifurcation point of the branch"//nl// &
        "(counting only branch points and period doublings, in the order of --special),"//nl// &
        "continues the branch born there (period doubling: the orbits of twice the"//nl// &
        "period) on the side --switch-direction (default 1) for --switch-points points"//nl// &
        "(default --max-points) and writes it to --switch-out (default switched.csv, the"//nl// &
        "columns of --out, row 1 = the bifurcation point); its special points are printed"//nl// &
        "and, with --switch-special FILE, written there. General shooting only (not"//nl// &
        "with --free/--targets, --conservative, --fixed-period); no resume: an existing"//nl// &
        "--out or --switch-out needs --force."//nl// &
        "--input FILE.nml: the options from a namelist &family ... / (names as the"//nl// &
        "options, '-' -> '_'; switch = K; see jobs/family.nml); the command line"//nl// &
        "overrides them."//nl// &
        "Exit: 0 done, 1 stopped early or no K-th bifurcation point, 2 bad input, 3 an"//nl// &
        "output could not be written (disk full, I/O error)."//nl// &
        "Example: Hill's variation orbits in m, the loss of stability at m = 0.195..."//nl// &
        "  family --system hill --params 0.15,1 --param 1 --y0 0.8,0,0,1"//nl// &
        "         --period 6.283185307179586 --free 1,4 --targets 1,4 --period-factor 4"//nl// &
        "         --conservative --p-max 0.25"
    type(cli_parser) :: cli
    character(len=64) :: sysname
    character(len=1024) :: out_file, sp_file, model_path, sw_file, sw_sp_file
    character(len=:), allocatable :: key, msg, sw_opt
    real(dp), allocatable :: params(:), y0(:), freer(:), targr(:), last(:)
    real(dp) :: period, pf
    integer :: ipar, n, u, us, nrows, info, k, kswitch, sw_dir, sw_points
    logical :: force_, sym, tfree, resume
    type(cont_options) :: o
    type(builtin_param_system) :: sys
    type(model_library) :: model
    type(branch) :: br

    call cli%start("family", help)
    sysname = ""
    model_path = ""
    out_file = "branch.csv"
    sp_file = "special.csv"
    sw_file = "switched.csv"
    sw_sp_file = ""          ! the switched branch's special points: only when asked
    period = -1.0_dp
    pf = 2.0_dp
    ipar = 1
    kswitch = 0
    sw_dir = 1
    sw_points = -1
    sw_opt = ""
    force_ = .false.
    tfree = .false.
    o%direction = 1     ! the program's documented default (the library's is automatic)
    allocate (params(0), y0(0), freer(0), targr(0))
    if (len(cli%input) > 0) call read_input(params, y0, period)
    do while (cli%next(key))
        select case (key)
        case ("--system"); call cli%get_string(sysname)
        case ("--model"); call cli%get_string(model_path)
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
        case ("--switch"); call cli%get_int(kswitch)
            if (kswitch < 1) call cli%fail("--switch must be >= 1 (the K-th bifurcation "// &
                                           "point of the branch)")
        case ("--switch-direction"); call cli%get_int(sw_dir); sw_opt = key
        case ("--switch-points"); call cli%get_int(sw_points); sw_opt = key
        case ("--switch-out"); call cli%get_string(sw_file); sw_opt = key
        case ("--switch-special"); call cli%get_string(sw_sp_file); sw_opt = key
        case default; call cli%unknown()
        end select
    end do
    if (len_trim(sysname) == 0 .and. len_trim(model_path) == 0) &
        call cli%fail("--system (or --model) is required")
    if (len_trim(sysname) > 0 .and. len_trim(model_path) > 0) &
        call cli%fail("give --system or --model, not both")
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
    call check_switch()
    if (len_trim(model_path) > 0) then
        call check_model()
    else
        if (system_dimension(trim(sysname)) == 0) &
            call cli%fail("unknown --system "//trim(sysname))
        if (system_dimension(trim(sysname)) /= n) &
            call cli%fail("--y0 must have "//itoa(system_dimension(trim(sysname)))//" values")
        if (size(params) == 0) call cli%fail("--params is required (the system's parameters)")
        call make_param_system(trim(sysname), params, ipar, sys, info, msg)
        if (info /= CM_SUCCESS) call cli%fail(msg)
    end if

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
            call set_builtin_param(sys, params(ipar))
        end if
    end if
    if (nrows == 0) call write_headers(out_file, sp_file)

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
    call write_branch(out_file, sp_file, br, nrows)
    write (*, '(a, i0, a)') "family: ", br%npoints, " points, "//br%message
    if (kswitch > 0) call switch_branch(br)
    if (br%info /= CM_SUCCESS) stop 1, quiet=.true.
    call release()

contains

    !> Free what the program holds before its normal end (it ends valgrind-clean).
    subroutine release()
        call cli%clear()
        deallocate (params, y0, freer, targr)
        if (allocated(last)) deallocate (last)
        if (allocated(key)) deallocate (key)
        if (allocated(msg)) deallocate (msg)
        if (allocated(sw_opt)) deallocate (sw_opt)
        if (allocated(sys%inner)) deallocate (sys%inner)
        if (allocated(sys%name)) deallocate (sys%name)
        if (allocated(sys%params)) deallocate (sys%params)
        if (allocated(br%points)) deallocate (br%points)
        if (allocated(br%special)) deallocate (br%special)
        if (allocated(br%message)) deallocate (br%message)
        if (allocated(model%path)) deallocate (model%path)
        if (allocated(model%defaults)) deallocate (model%defaults)
        if (allocated(model%param_names)) deallocate (model%param_names)
    end subroutine release

    !> The options of branch switching, checked before any computation.
    subroutine check_switch()
        if (kswitch == 0) then
            if (len(sw_opt) > 0) call cli%fail(sw_opt//" needs --switch K")
            return
        end if
        if (abs(sw_dir) /= 1) call cli%fail("--switch-direction must be 1 or -1")
        if (sw_points == -1) sw_points = o%max_points
        if (sw_points < 2) call cli%fail("--switch-points must be >= 2")
        if (sym) call cli%fail("--switch needs general shooting, not --free/--targets "// &
                               "(symmetric shooting excludes the asymmetric branch)")
        if (o%conservative) call cli%fail("--switch is not available for a conservative "// &
                                          "family (--conservative)")
        if (o%fixed_period .and. o%autonomous) call cli%fail("--switch is not available "// &
            "with --fixed-period for an autonomous system")
        if (same_file(sw_file, out_file) .or. same_file(sw_file, sp_file) .or. &
            same_file(sw_sp_file, out_file) .or. same_file(sw_sp_file, sp_file) .or. &
            same_file(sw_file, sw_sp_file)) call cli%fail("--switch-out and "// &
            "--switch-special must differ from each other and from --out and --special")
        if (.not. force_) then
            if (file_exists(trim(out_file))) call cli%fail("--switch computes the branch "// &
                "afresh: "//trim(out_file)//" exists (--force replaces it)")
            if (file_exists(trim(sw_file))) call cli%fail("--switch-out "//trim(sw_file)// &
                " exists (--force replaces it)")
        end if
    end subroutine check_switch

    logical function same_file(a, b)
        character(len=*), intent(in) :: a, b
        same_file = len_trim(a) > 0 .and. trim(a) == trim(b)
    end function same_file

    !> --model: load the library, check its kind, y0 and the parameters (missing trailing
    !! ones take the model's defaults), and wrap it for the continuation.
    subroutine check_model()
        class(ode_system), allocatable :: inner
        integer :: nm, np
        call load_model(trim(model_path), model, info, msg)
        if (info /= CM_SUCCESS) call cli%fail("--model: "//msg)
        select case (model%kind)
        case (MODEL_KIND_ODE)
            nm = model%n
        case (MODEL_KIND_GENERALIZED)
            nm = 2*model%n
        case default
            call cli%fail("--model "//trim(model_path)//" is a constrained model; family "// &
                          "needs an ode or generalized one")
        end select
        if (n /= nm) call cli%fail("--y0 must have "//itoa(nm)//" values (the model's "// &
                                   "dimension)")
        np = size(model%defaults)
        if (size(params) > np) call cli%fail("--params: the model has "//itoa(np)// &
            " parameter(s) ("//model%param_names//"), got "//itoa(size(params)))
        params = [params, model%defaults(size(params) + 1:)]
        if (ipar < 1 .or. ipar > np) call cli%fail("--param must be in 1.."//itoa(np)// &
            " (the model's parameters: "//model%param_names//")")
        call model_system(model, params, inner, info, msg)
        if (info /= CM_SUCCESS) call cli%fail("--model: "//msg)
        call make_compiled_param_system(inner, params, ipar, sys, info, msg)
        if (info /= CM_SUCCESS) call cli%fail("--model: "//msg)
    end subroutine check_model

    !> New branch and special-point files with their header lines (no special-point file
    !! when `sfile` is empty).
    subroutine write_headers(bfile, sfile)
        character(len=*), intent(in) :: bfile, sfile
        character(len=:), allocatable :: cols
        integer :: j
        cols = ""
        do j = 1, n
            cols = cols//",y0_"//itoa(j)
        end do
        call write_header(bfile, "i,p,period,stability_index,stable,residual,iterations"//cols)
        if (len_trim(sfile) > 0) call write_header(sfile, "kind,index,p,period,"// &
                                                   "stability_index"//cols)
    end subroutine write_headers

    !> A new file holding one header line, written through C stdio so that a full disk
    !! or an I/O error is reported (exit 3), not lost.
    subroutine write_header(file, line)
        character(len=*), intent(in) :: file, line
        type(results_file) :: f
        logical :: ok, ok2
        character(len=:), allocatable :: why, why2
        call f%open(trim(file), "w", ok, why)
        if (.not. ok) call cli%fail("cannot write "//trim(file)//": "//why)
        call f%put(line, ok, why)
        if (ok) then
            call f%close(ok, why)
        else
            call f%close(ok2, why2)
        end if
        if (.not. ok) call cli%fail_io("cannot write "//trim(file)//": "//why)
    end subroutine write_header

    !> Append the points of `b` (after `nr` rows already there, whose last is b's first)
    !! and its special points; name the special points on stdout.
    subroutine write_branch(bfile, sfile, b, nr)
        character(len=*), intent(in) :: bfile, sfile
        type(branch), intent(in) :: b
        integer, intent(in) :: nr
        integer :: j, off
        type(row_t), allocatable :: rows(:)
        off = merge(1, 0, nr > 0)
        allocate (rows(max(b%npoints - off, 0)))
        do j = 1 + off, b%npoints
            rows(j - off)%s = itoa(nr + j - off)//","// &
                fmt_real(b%points(j)%p)//","//fmt_real(b%points(j)%period)//","// &
                fmt_real(b%points(j)%stability_index)//","//itoa(merge(1, 0, &
                stable(b%points(j))))//","//fmt_real(b%points(j)%residual)//","// &
                itoa(b%points(j)%iterations)//","//fmt_list(b%points(j)%y0)
        end do
        call append_rows(bfile, rows)
        deallocate (rows)
        allocate (rows(b%nspecial))
        do j = 1, b%nspecial
            rows(j)%s = trim(special_name(b%special(j)%kind))//","// &
                itoa(nr + b%special(j)%index - off)//","// &
                fmt_real(b%special(j)%point%p)//","//fmt_real(b%special(j)%point%period)// &
                ","//fmt_real(b%special(j)%point%stability_index)//","// &
                fmt_list(b%special(j)%point%y0)
            write (*, '(a, es24.16)') "family: "//special_name(b%special(j)%kind)// &
                " at p =", b%special(j)%point%p
        end do
        if (len_trim(sfile) > 0) call append_rows(sfile, rows)
    end subroutine write_branch

    !> Append rows to a file (C stdio: a write error is reported, exit 3).
    subroutine append_rows(file, rows)
        character(len=*), intent(in) :: file
        type(row_t), intent(in) :: rows(:)
        type(results_file) :: f
        logical :: ok, ok2
        character(len=:), allocatable :: why, why2
        integer :: j
        call f%open(trim(file), "a", ok, why)
        if (.not. ok) call cli%fail_io("cannot append to "//trim(file)//": "//why)
        do j = 1, size(rows)
            call f%put(rows(j)%s, ok, why)
            if (.not. ok) exit
        end do
        if (ok) then
            call f%close(ok, why)
        else
            call f%close(ok2, why2)
        end if
        if (.not. ok) call cli%fail_io("cannot write "//trim(file)//": "//why)
    end subroutine append_rows

    !> --switch: the branch born at the K-th bifurcation point (branch point or period
    !! doubling) of `b`, written to --switch-out / --switch-special.
    subroutine switch_branch(b)
        type(branch), intent(in) :: b
        type(branch) :: b2
        type(cont_options) :: o2
        real(dp) :: ratio
        integer :: j, nb, js, i
        character(len=:), allocatable :: at
        nb = 0
        js = 0
        do j = 1, b%nspecial
            if (b%special(j)%kind == SP_BP .or. b%special(j)%kind == SP_PD) then
                nb = nb + 1
                if (nb == kswitch) js = j
            end if
        end do
        if (js == 0) then
            write (error_unit, '(a)') "family: error: --switch "//itoa(kswitch)// &
                ": the branch has "//itoa(nb)//" bifurcation point(s) (branch points or "// &
                "period doublings; see "//trim(sp_file)//")"
            stop 1, quiet=.true.
        end if
        o2 = o
        o2%direction = sw_dir
        o2%max_points = sw_points
        i = b%special(js)%index
        at = " at p = "//fmt_real(b%special(js)%point%p)//" (between rows "//itoa(i)// &
                " and "//itoa(i + 1)//" of "//trim(out_file)//")"
        if (b%special(js)%kind == SP_PD) then
            if (.not. o%autonomous) then
                write (error_unit, '(a)') "family: error: --switch "//itoa(kswitch)// &
                    ": switching at a period doubling needs an autonomous system"
                stop 1, quiet=.true.
            end if
            call switch_period_doubling(sys, set_builtin_param, b%special(js), b2, o2)
            write (*, '(a)') "family: switching at the period doubling"//at
        else
            if (i < 1 .or. i + 1 > b%npoints) then
                write (error_unit, '(a)') "family: error: --switch "//itoa(kswitch)// &
                    ": the branch point is at the end of the branch (no tangent there)"
                stop 1, quiet=.true.
            end if
            call switch_branch_point(sys, set_builtin_param, b%special(js), &
                                     branch_secant(b%points(i), b%points(i + 1), &
                                                   o%autonomous), b2, o2, ratio)
            write (*, '(a, es10.3, a)') "family: switching at the branch point"//at// &
                ", kernel ratio", ratio, " (small at a genuine branch point)"
        end if
        if (b2%npoints == 0) then
            write (error_unit, '(a)') "family: error: --switch "//itoa(kswitch)//": "// &
                b2%message
            stop 1, quiet=.true.
        end if
        call write_headers(sw_file, sw_sp_file)
        call write_branch(sw_file, sw_sp_file, b2, 0)
        write (*, '(a, i0, a)') "family: new branch: ", b2%npoints, " points in "// &
            trim(sw_file)//", "//b2%message
        if (b2%info /= CM_SUCCESS) stop 1, quiet=.true.
    end subroutine switch_branch

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

    !> The options from a namelist &family ... / (the command line overrides them); the
    !! dummies are the host's params, y0, period (their names are the namelist's here).
    subroutine read_input(params_h, y0_h, period_h)
        real(dp), allocatable, intent(inout) :: params_h(:), y0_h(:)
        real(dp), intent(inout) :: period_h
        character(len=64) :: system
        character(len=1024) :: model, out, special, switch_out, switch_special
        real(dp) :: params(64), y0(64), free(64), targets(64)
        real(dp) :: period, period_factor, ds, ds_min, ds_max, p_min, p_max, rtol
        integer :: param, max_points, direction, switch, switch_direction, switch_points
        logical :: free_time, conservative, fixed_period, non_autonomous, force
        integer :: ios
        character(len=512) :: iomsg_
        character(len=:), allocatable :: lines(:)
        namelist /family/ system, model, params, param, y0, period, free, targets, &
            period_factor, free_time, conservative, fixed_period, non_autonomous, ds, &
            ds_min, ds_max, p_min, p_max, max_points, direction, rtol, out, special, force, &
            switch, switch_direction, switch_points, switch_out, switch_special
        system = sysname; model = model_path; out = out_file; special = sp_file
        switch_out = sw_file; switch_special = sw_sp_file
        params = unset; y0 = unset; free = unset; targets = unset
        param = ipar; period = period_h; period_factor = pf; free_time = tfree
        conservative = o%conservative; fixed_period = o%fixed_period
        non_autonomous = .not. o%autonomous; ds = o%ds; ds_min = o%ds_min
        ds_max = o%ds_max; p_min = o%p_min; p_max = o%p_max; max_points = o%max_points
        direction = o%direction; rtol = o%rtol; force = force_; switch = kswitch
        switch_direction = sw_dir; switch_points = sw_points
        call check_namelist(cli, cli%input, "family", &
            "system:s64 model:s1024 params:r64 param:i y0:r64 period:r free:r64 "// &
            "targets:r64 period_factor:r free_time:l conservative:l fixed_period:l "// &
            "non_autonomous:l ds:r ds_min:r ds_max:r p_min:r p_max:r max_points:i "// &
            "direction:i rtol:r out:s1024 special:s1024 force:l switch:i "// &
            "switch_direction:i switch_points:i switch_out:s1024 switch_special:s1024", lines)
        read (lines, nml=family, iostat=ios, iomsg=iomsg_)
        if (ios /= 0) call cli%fail("--input "//cli%input//": namelist &family: "// &
                                    trim(iomsg_))
        if (switch < 0) call cli%fail("--input "//cli%input//": switch must be >= 1 "// &
                                      "(0 or absent: no switching)")
        if (switch_direction /= sw_dir .or. switch_points /= sw_points .or. &
            switch_out /= sw_file .or. switch_special /= sw_sp_file) &
            sw_opt = "switch_* of --input "//cli%input
        sysname = system; model_path = model; out_file = out; sp_file = special
        sw_file = switch_out; sw_sp_file = switch_special
        params_h = nml_list(cli, params, "params")
        y0_h = nml_list(cli, y0, "y0")
        freer = nml_list(cli, free, "free")
        targr = nml_list(cli, targets, "targets")
        ipar = param; period_h = period; pf = period_factor; tfree = free_time
        o%conservative = conservative; o%fixed_period = fixed_period
        o%autonomous = .not. non_autonomous; o%ds = ds; o%ds_min = ds_min
        o%ds_max = ds_max; o%p_min = p_min; o%p_max = p_max; o%max_points = max_points
        o%direction = direction; o%rtol = rtol; o%atol = rtol; force_ = force
        kswitch = switch; sw_dir = switch_direction; sw_points = switch_points
    end subroutine read_input

end program family
