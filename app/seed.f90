!> Run a named seed system and write its motion as CSV.
!!
!!     fpm run seed -- --system NAME [--t-end T] [--projection P] [--method M]
!!                     [--rtol R] [--atol A] [--step H (RK4)] [--n-out N] [--every K]
!!                     [--params p1,p2,...] [--q0 ...] [--v0 ...] [--out file.csv]
!!     fpm run seed -- --list
!!
!! Constrained systems (excessive coordinates) write t, q_i, v_i, lambda_j, reaction_i,
!! res_pos, res_vel, energy, power; generalized-coordinate systems write t, q_i, v_i,
!! energy. Without --out only the summary is printed. Exit code 0 on success, 1 when the
!! integration fails, 2 on bad arguments.
program seed
    use, intrinsic :: iso_fortran_env, only: error_unit
    use conmech
    use app_cli
    use app_namelist, only: check_namelist
    use app_batch, only: file_exists, max_jobs
    use app_systems, only: param_count, param_help
    implicit none
    character(len=*), parameter :: help = &
        "usage: seed --system NAME [options]     (seed --list: the systems)"//new_line("a")// &
        "Integrate a seed system of the lecture notes and write its motion as CSV: "// &
        "t, q_i, v_i,"//new_line("a")//"lambda_j, reaction_i, res_pos, res_vel, energy,"// &
        " power (constrained, excessive"//new_line("a")//"coordinates) or t, q_i, v_i, "// &
        "energy (generalized coordinates)."//new_line("a")//"Options:"//new_line("a")// &
        "  --system NAME     see --list"//new_line("a")// &
        "  --list            print the system names and exit"//new_line("a")// &
        "  --t-end T         end time (default 10)"//new_line("a")// &
        "  --projection P    none, velocity, position+velocity (default), baumgarte"// &
        new_line("a")//"  --method M        DOP853 (default), DOPRI5, VERNER98, RK4"// &
        new_line("a")//"  --rtol R --atol A tolerances (default 1e-10)"//new_line("a")// &
        "  --step H          step of RK4 (default 1e-3)"//new_line("a")// &
        "  --n-out N         output points (default 201, 2..10000000)"//new_line("a")// &
        "  --every K         project every K steps (default 1)"//new_line("a")// &
        "  --params P1,..    system parameters (at most as many as it has)"//new_line("a")// &
        "  --q0 Q1,.. --v0 V1,..   initial state (default: the system's own)"// &
        new_line("a")//"  --out FILE        write the CSV (none: summary only); an existing"// &
        " FILE needs --force"//new_line("a")// &
        "  --force           overwrite --out"//new_line("a")// &
        "  --input FILE.nml  read the options from a namelist &seed ... / (see jobs/seed.nml)"// &
        new_line("a")//"  --help, --version"//new_line("a")// &
        "Exit status: 0 success, 1 the integration failed, 2 bad input."//new_line("a")// &
        "Example:"//new_line("a")//"  seed --system pendulum_xy --t-end 20 --out pendulum.csv"
    type(cli_parser) :: cli
    character(len=64) :: name, proj_name, method_name
    character(len=1024) :: out_file
    character(len=:), allocatable :: key, msg
    real(dp), allocatable :: pars(:), qstart(:), vstart(:), t_eval(:)
    real(dp) :: tend, rtol_, atol_, h_rk4
    integer :: nout, every_k, i, info, unit, np
    logical :: have_q0, have_v0, is_constrained, force_, list
    class(constrained_system), allocatable :: cs
    class(generalized_system), allocatable :: gs

    call cli%start("seed", help)
    name = ""
    proj_name = "position+velocity"
    method_name = "DOP853"
    out_file = ""
    tend = 10.0_dp
    h_rk4 = 1.0e-3_dp
    rtol_ = 1.0e-10_dp
    atol_ = 1.0e-10_dp
    nout = 201
    every_k = 1
    allocate (pars(0), qstart(0), vstart(0))
    have_q0 = .false.
    have_v0 = .false.
    force_ = .false.
    list = .false.
    if (len(cli%input) > 0) call read_input()
    do while (cli%next(key))
        select case (key)
        case ("--list"); call cli%flag(); list = .true.
        case ("--system"); call cli%get_string(name)
        case ("--t-end"); call cli%get_real(tend)
        case ("--projection"); call cli%get_string(proj_name)
        case ("--method"); call cli%get_string(method_name)
        case ("--step"); call cli%get_real(h_rk4)
        case ("--rtol"); call cli%get_real(rtol_)
        case ("--atol"); call cli%get_real(atol_)
        case ("--n-out"); call cli%get_int(nout)
        case ("--every"); call cli%get_int(every_k)
        case ("--params"); call cli%get_list(pars)
        case ("--q0")
            call cli%get_list(qstart)
            have_q0 = .true.
        case ("--v0")
            call cli%get_list(vstart)
            have_v0 = .true.
        case ("--out"); call cli%get_string(out_file)
        case ("--force"); call cli%flag(); force_ = .true.
        case default; call cli%unknown()
        end select
    end do
    if (list) then
        write (*, '(a)') "constrained (excessive coordinates): "//constrained_names
        write (*, '(a)') "generalized coordinates: "//generalized_names
        stop 0, quiet=.true.
    end if
    if (len_trim(name) == 0) call cli%fail("--system NAME is required; valid: "// &
                                           constrained_names//" "//generalized_names)
    if (.not. (word_in(name, constrained_names) .or. word_in(name, generalized_names))) &
        call cli%bad_name("system", name, constrained_names//" "//generalized_names)
    np = param_count(name)
    if (size(pars) > np) call cli%fail("--params: "//trim(name)//" has "//itoa(np)// &
        " parameter(s) ("//param_help(name)//"), got "//itoa(size(pars)))
    if (nout < 2 .or. nout > max_jobs) call cli%fail("--n-out must be in 2..10000000")
    if (every_k < 1) call cli%fail("--every must be at least 1")
    if (.not. (tend > 0.0_dp .and. tend <= huge(tend))) &
        call cli%fail("--t-end must be positive and finite")
    if (.not. (rtol_ > 0.0_dp .and. rtol_ < 1.0_dp)) call cli%fail("--rtol must be in (0, 1)")
    if (.not. (atol_ > 0.0_dp .and. atol_ <= huge(atol_))) &
        call cli%fail("--atol must be positive and finite")
    if (.not. (h_rk4 > 0.0_dp .and. h_rk4 <= huge(h_rk4))) &
        call cli%fail("--step must be positive and finite")
    if (method_from_name(method_name) == 0) call cli%bad_name("method", method_name, &
                                                              "DOP853 DOPRI5 VERNER98 RK4")
    if (projection_from_name(proj_name) < 0) call cli%bad_name("projection", proj_name, &
        "none velocity position+velocity baumgarte")

    call make_constrained(name, pars, cs, info, msg)
    is_constrained = info == CM_SUCCESS
    if (.not. is_constrained) then
        call make_generalized(name, pars, gs, info, msg)
        if (info /= CM_SUCCESS) call cli%fail(msg)
    end if
    block
        real(dp), allocatable :: qd(:), vd(:)
        call mech_initial_state(name, pars, qd, vd, info)
        if (.not. have_q0) qstart = qd
        if (.not. have_v0) vstart = vd
        if (size(qstart) /= size(qd)) call cli%fail("--q0: "//trim(name)//" has "// &
            itoa(size(qd))//" coordinates, got "//itoa(size(qstart)))
        if (size(vstart) /= size(vd)) call cli%fail("--v0: "//trim(name)//" has "// &
            itoa(size(vd))//" velocities, got "//itoa(size(vstart)))
    end block
    ! open the output before computing: a bad path or an existing file is found at once
    unit = 0
    if (len_trim(out_file) > 0) then
        if (file_exists(trim(out_file)) .and. .not. force_) call cli%fail("--out "// &
            trim(out_file)//" exists; use --force to overwrite it")
        open (newunit=unit, file=trim(out_file), status="replace", action="write", iostat=info)
        if (info /= 0) call cli%fail("cannot write --out "//trim(out_file))
    end if

    allocate (t_eval(nout))
    do i = 1, nout
        t_eval(i) = tend*real(i - 1, dp)/real(nout - 1, dp)
    end do

    if (is_constrained) then
        call run_constrained()
    else
        call run_generalized()
    end if
    if (allocated(cs)) deallocate (cs)
    if (allocated(gs)) deallocate (gs)
    deallocate (key, pars, qstart, vstart, t_eval)
    if (allocated(msg)) deallocate (msg)
    call cli%clear()

contains

    subroutine run_constrained()
        type(constrained_options) :: opt
        type(constrained_result) :: r
        integer :: j, m, n
        opt%ode%method = method_from_name(method_name)
        opt%ode%rtol = rtol_
        opt%ode%atol = atol_
        opt%ode%max_steps = 10000000
        if (opt%ode%method == METHOD_RK4) opt%ode%first_step = h_rk4
        opt%projection = projection_from_name(proj_name)
        opt%every = every_k
        call constrained_solve(cs, [0.0_dp, tend], qstart, vstart, opt, r, t_eval)
        n = cs%n
        m = cs%n_hol + cs%n_nh
        if (unit /= 0) then
            write (unit, '(a)', advance="no") "t"
            call header(unit, "q", n)
            call header(unit, "v", n)
            call header(unit, "lambda", m)
            call header(unit, "reaction", n)
            write (unit, '(a)') ",res_pos,res_vel,energy,power"
            do j = 1, r%nt
                write (unit, '(a)') fmt_real(r%t(j))//","//fmt_list(r%q(:, j))//","// &
                    fmt_list(r%v(:, j))//trim_comma(fmt_list(r%lam(:, j)))//","// &
                    fmt_list(r%reaction(:, j))//","//fmt_list([r%res_pos(j), r%res_vel(j), &
                    r%energy(j), r%power(j)])
            end do
            close (unit)
        end if
        write (*, '(a)') "system      : "//trim(name)//" (excessive coordinates)"
        write (*, '(a,i0,a,i0,a,i0,a,i0)') "coordinates : ", n, ", holonomic ", cs%n_hol, &
            ", non-holonomic ", cs%n_nh, ", rank ", r%rank
        write (*, '(a)') "method      : "//trim(method_name)//", projection "//trim(proj_name)
        write (*, '(a,i0,a,i0,a,i0,a,i0)') "steps       : ", r%naccept, " accepted, ", &
            r%nreject, " rejected, nfev ", r%nfev, ", projections ", r%nproj
        write (*, '(a,es10.3,a,es10.3)') "initial fix : |dq0| = ", r%dq0, ", |dv0| = ", r%dv0
        if (r%nt > 0) then
            write (*, '(a,es10.3,a,es10.3)') "max resid.  : |phi| ", maxval(r%res_pos), &
                ", |C v + c0| ", maxval(r%res_vel)
            if (cs%has_energy()) write (*, '(a,es10.3)') "energy drift: ", &
                maxval(abs(r%energy - r%energy(1)))
            write (*, '(a,es10.3)') "max |power| : ", maxval(abs(r%power))
        end if
        if (unit /= 0) write (*, '(a,i0,a)') "wrote       : "//trim(out_file)//" (", r%nt, " rows)"
        write (*, '(a)') "status      : "//r%message
        if (unit /= 0) close (unit)
        if (.not. r%success) then
            write (error_unit, '(a)') "seed: error: "//r%message
            stop 1, quiet=.true.
        end if
    end subroutine run_constrained

    subroutine run_generalized()
        type(ode_options) :: opt
        type(ode_result) :: r
        integer :: j, n
        real(dp), allocatable :: e(:)
        opt%method = method_from_name(method_name)
        opt%rtol = rtol_
        opt%atol = atol_
        opt%max_steps = 10000000
        if (opt%method == METHOD_RK4) opt%first_step = h_rk4
        call generalized_solve(gs, [0.0_dp, tend], qstart, vstart, opt, r, t_eval)
        n = gs%ndof
        allocate (e(r%nt))
        do j = 1, r%nt
            e(j) = gs%energy(r%t(j), r%y(1:n, j), r%y(n + 1:, j))
        end do
        if (unit /= 0) then
            write (unit, '(a)', advance="no") "t"
            call header(unit, "q", n)
            call header(unit, "v", n)
            write (unit, '(a)') ",energy"
            do j = 1, r%nt
                write (unit, '(a)') fmt_real(r%t(j))//","//fmt_list(r%y(:, j))//","// &
                    fmt_real(e(j))
            end do
            close (unit)
        end if
        write (*, '(a)') "system      : "//trim(name)//" (generalized coordinates)"
        write (*, '(a,i0)') "coordinates : ", n
        write (*, '(a)') "method      : "//trim(method_name)
        write (*, '(a,i0,a,i0,a,i0)') "steps       : ", r%stats%naccept, " accepted, ", &
            r%stats%nreject, " rejected, nfev ", r%stats%nfev
        if (gs%has_energy() .and. r%nt > 0) write (*, '(a,es10.3)') "energy drift: ", &
            maxval(abs(e - e(1)))
        if (unit /= 0) write (*, '(a,i0,a)') "wrote       : "//trim(out_file)//" (", r%nt, " rows)"
        write (*, '(a)') "status      : "//r%message
        if (unit /= 0) close (unit)
        if (.not. r%success) then
            write (error_unit, '(a)') "seed: error: "//r%message
            stop 1, quiet=.true.
        end if
    end subroutine run_generalized

    subroutine header(u, base, k)
        integer, intent(in) :: u, k
        character(len=*), intent(in) :: base
        integer :: j
        character(len=16) :: b
        do j = 1, k
            write (b, '(i0)') j
            write (u, '(a)', advance="no") ","//base//trim(b)
        end do
    end subroutine header

    function itoa(k) result(s)
        integer, intent(in) :: k
        character(len=:), allocatable :: s
        character(len=16) :: b
        write (b, '(i0)') k
        s = trim(b)
    end function itoa

    !> "," // s, or "" for an empty list.
    function trim_comma(s) result(r)
        character(len=*), intent(in) :: s
        character(len=:), allocatable :: r
        r = ""
        if (len(s) > 0) r = ","//s
    end function trim_comma

    !> The options from a namelist &seed ... / (the command line overrides them).
    subroutine read_input()
        character(len=64) :: system, projection, method
        character(len=1024) :: out
        real(dp) :: t_end, step, rtol, atol, params(64), q0(64), v0(64)
        integer :: n_out, every, ios
        character(len=:), allocatable :: lines(:)
        logical :: force
        character(len=512) :: iomsg_
        namelist /seed/ system, projection, method, t_end, step, rtol, atol, n_out, every, &
            params, q0, v0, out, force
        system = name; projection = proj_name; method = method_name; out = out_file
        t_end = tend; step = h_rk4; rtol = rtol_; atol = atol_; n_out = nout
        every = every_k; force = force_
        params = unset; q0 = unset; v0 = unset
        call check_namelist(cli, cli%input, "seed", &
            "system:s64 projection:s64 method:s64 t_end:r step:r rtol:r atol:r n_out:i "// &
            "every:i params:r64 q0:r64 v0:r64 out:s1024 force:l", lines)
        read (lines, nml=seed, iostat=ios, iomsg=iomsg_)
        if (ios /= 0) call cli%fail("--input "//cli%input//": namelist &seed: "// &
                                    trim(iomsg_))
        name = system; proj_name = projection; method_name = method; out_file = out
        tend = t_end; h_rk4 = step; rtol_ = rtol; atol_ = atol; nout = n_out
        every_k = every; force_ = force
        pars = nml_list(cli, params, "params")
        qstart = nml_list(cli, q0, "q0")
        vstart = nml_list(cli, v0, "v0")
        have_q0 = size(qstart) > 0
        have_v0 = size(vstart) > 0
    end subroutine read_input

end program seed
