!> Batch sweep over one parameter (or one initial-state component) of a built-in system.
!!
!! Each job integrates the system from y0 to t_end and records the final state, the first
!! return time to the section y(k) = y0(k) crossed in the initial direction (a period for
!! periodic motions), the number of evaluations and the status. Rows are appended to the
!! CSV as jobs finish (flushed); a rerun with the same arguments resumes (OUT.args records
!! them; other arguments are refused, --force starts over). Threads: OpenMP (dynamic
!! schedule). Ranks: MPI (-DCONMECH_MPI), jobs handed out one at a time from a shared
!! counter (MPI_Fetch_and_op), each rank writing OUT.rankR; rank 0 merges them into OUT
!! (temporary file, fsync, rename, then the parts are deleted).
program sweep
    use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
    use conmech_kinds, only: nan_dp
    use conmech
    use app_events, only: section_events
    use app_cli
    use app_namelist, only: check_namelist
    use app_batch
    use app_systems, only: ode_names, generalized_names, param_count, param_help
    use app_output, only: results_file
    !$ use omp_lib
    implicit none
#ifdef CONMECH_MPI
    include "mpif.h"
    ! explicit interfaces for the MPI calls used (mpif.h declares none)
    interface
        subroutine mpi_init_thread(required, provided, ierror)
            integer, intent(in) :: required
            integer, intent(out) :: provided, ierror
        end subroutine mpi_init_thread
        subroutine mpi_finalize(ierror)
            integer, intent(out) :: ierror
        end subroutine mpi_finalize
        subroutine mpi_comm_rank(comm, rank, ierror)
            integer, intent(in) :: comm
            integer, intent(out) :: rank, ierror
        end subroutine mpi_comm_rank
        subroutine mpi_comm_size(comm, size, ierror)
            integer, intent(in) :: comm
            integer, intent(out) :: size, ierror
        end subroutine mpi_comm_size
        subroutine mpi_barrier(comm, ierror)
            integer, intent(in) :: comm
            integer, intent(out) :: ierror
        end subroutine mpi_barrier
        subroutine mpi_abort(comm, errorcode, ierror)
            integer, intent(in) :: comm, errorcode
            integer, intent(out) :: ierror
        end subroutine mpi_abort
        subroutine mpi_win_create(base, size, disp_unit, info, comm, win, ierror)
            import :: mpi_address_kind
            integer :: base
            integer(mpi_address_kind), intent(in) :: size
            integer, intent(in) :: disp_unit, info, comm
            integer, intent(out) :: win, ierror
        end subroutine mpi_win_create
        subroutine mpi_win_free(win, ierror)
            integer, intent(inout) :: win
            integer, intent(out) :: ierror
        end subroutine mpi_win_free
        subroutine mpi_win_lock(lock_type, rank, assert, win, ierror)
            integer, intent(in) :: lock_type, rank, assert, win
            integer, intent(out) :: ierror
        end subroutine mpi_win_lock
        subroutine mpi_win_unlock(rank, win, ierror)
            integer, intent(in) :: rank, win
            integer, intent(out) :: ierror
        end subroutine mpi_win_unlock
        subroutine mpi_fetch_and_op(origin, result, datatype, target_rank, target_disp, &
                                    op, win, ierror)
            import :: mpi_address_kind
            integer, intent(in) :: origin
            integer :: result
            integer, intent(in) :: datatype, target_rank, op, win
            integer(mpi_address_kind), intent(in) :: target_disp
            integer, intent(out) :: ierror
        end subroutine mpi_fetch_and_op
    end interface
    integer :: ierr, provided, win
    integer, target :: counter_cell
#endif
    character(len=*), parameter :: help = &
        "usage: sweep --system NAME --y0 Y1,Y2,.. --vary param:K|y0:K --from A --to B"// &
        new_line("a")//"             --count N --t-end T [options]"//new_line("a")// &
        "Integrate a built-in system once per value of one parameter or initial value"// &
        new_line("a")//"(a grid of --count values from --from to --to) and write one CSV"// &
        " row per job:"//new_line("a")// &
        "job,value,y1..yn (state at t_end),return_time,nfev,status."//new_line("a")// &
        "Options:"//new_line("a")// &
        "  --system NAME     "//ode_names//","//new_line("a")// &
        "                    or a generalized seed system (y = [q, v])"//new_line("a")// &
        "  --model LIB.so    instead of --system: a compiled user model (an ode or"// &
        new_line("a")//"                    generalized one, e.g. from python -m "// &
        "conmech.symbolic)"//new_line("a")// &
        "  --list            print the names of the built-in systems and exit"// &
        new_line("a")//"  --params P1,P2..  system parameters (at most as many as it has; "// &
        "the rest keep"//new_line("a")//"                    their defaults)"// &
        new_line("a")// &
        "  --y0 Y1,Y2,..     initial state (the system's dimension)"//new_line("a")// &
        "  --vary param:K | y0:K   what the grid varies (1-based index)"//new_line("a")// &
        "  --from A --to B --count N   the grid (N <= 10000000)"//new_line("a")// &
        "  --t-end T         end time of each integration (default 10)"//new_line("a")// &
        "  --section K       record the first return to y(K) = y0(K) (0: off, default)"// &
        new_line("a")//"  --rtol R --atol A tolerances (default 1e-10)"//new_line("a")// &
        "  --method M        DOP853 (default), DOPRI5, VERNER98"//new_line("a")// &
        "  --out FILE        results CSV (default sweep.csv in the current directory);"// &
        new_line("a")//"                    an existing FILE made by the same arguments is"// &
        " resumed"//new_line("a")// &
        "  --force           overwrite FILE made by other arguments"//new_line("a")// &
        "  --order job|completion   rows in job order (default; with threads the rows"// &
        new_line("a")//"                    finished early wait for the earlier ones, with"// &
        " ranks the"//new_line("a")//"                    final merge sorts) or as jobs"// &
        " finish"//new_line("a")// &
        "  --quiet           no progress line on stderr"//new_line("a")// &
        "  --input FILE.nml  read the options from a namelist &sweep ... / (the command"// &
        new_line("a")//"                    line overrides it); see jobs/sweep.nml"// &
        new_line("a")//"  --help, --version"//new_line("a")// &
        "Threads: fpm run sweep --flag -fopenmp; ranks: build with --compiler mpifort "// &
        "--flag -DCONMECH_MPI."//new_line("a")// &
        "Exit status: 0 all jobs succeeded, 1 some failed (counted), 2 bad input, 3 the"// &
        new_line("a")//"results could not be written (disk full, I/O error: rerun to resume)."// &
        new_line("a")//"Example:"//new_line("a")// &
        "  sweep --system pendulum --params 9.81,1 --y0 0.1,0 --vary y0:1 --from 0.1 "// &
        "--to 3 \"//new_line("a")// &
        "        --count 100 --t-end 10 --section 2 --out sweep.csv"

    type(cli_parser) :: cli
    character(len=64) :: sys_name, method_name, order_name
    character(len=1024) :: out_file, vary_spec, model_path
    type(model_library) :: model
    real(dp), allocatable :: pars(:), ystart(:)
    real(dp) :: vfrom, vto, tend, rtol_, atol_
    integer :: count_, isec, n, i, rank, nranks, nthreads, ntodo, next_free, nfail
    integer :: nfinished, vary_index, nrows
    logical :: vary_param, force_, quiet_, symmetric, have_y0, job_order, io_failed, in_order
    character(len=512) :: io_msg
    type(results_file) :: outf                 !! the results file (OUT, or OUT.rankR)
    logical :: ok_io
    character(len=:), allocatable :: why
    !> Rows finished ahead of an earlier job wait here (a ring indexed by todo position)
    !! so that a threaded run writes them in job order.
    integer, parameter :: ring = 65536
    type(row_t), allocatable :: pending(:)
    integer :: next_out
    logical, allocatable :: done(:)
    integer, allocatable :: todo(:)
    character(len=:), allocatable :: key, header, canon, part_file
    type(ode_options) :: opt
    type(progress_t) :: progress

    symmetric = .true.
#ifdef CONMECH_MPI
    call mpi_init_thread(MPI_THREAD_SERIALIZED, provided, ierr)
    call mpi_comm_rank(mpi_comm_world, rank, ierr)
    call mpi_comm_size(mpi_comm_world, nranks, ierr)
#else
    rank = 0
    nranks = 1
#endif
    call cli%start("sweep", help, talk=rank == 0, cleanup=cleanup)
    sys_name = ""
    model_path = ""
    method_name = "DOP853"
    order_name = "job"
    io_failed = .false.
    io_msg = ""
    out_file = "sweep.csv"
    vary_spec = ""
    vfrom = 0.0_dp
    vto = 1.0_dp
    tend = 10.0_dp
    rtol_ = 1.0e-10_dp
    atol_ = 1.0e-10_dp
    count_ = 10
    isec = 0
    force_ = .false.
    quiet_ = .false.
    have_y0 = .false.
    allocate (pars(0), ystart(0))
    if (len(cli%input) > 0) call read_input()
    do while (cli%next(key))
        select case (key)
        case ("--system"); call cli%get_string(sys_name)
        case ("--list")
            call cli%flag()
            if (rank == 0) write (*, '(a)') "built-in systems: "//ode_names//" "// &
                generalized_names
            call cli%done()
        case ("--model"); call cli%get_string(model_path)
        case ("--method"); call cli%get_string(method_name)
        case ("--params"); call cli%get_list(pars)
        case ("--y0")
            call cli%get_list(ystart)
            have_y0 = .true.
        case ("--vary"); call cli%get_string(vary_spec)
        case ("--from"); call cli%get_real(vfrom)
        case ("--to"); call cli%get_real(vto)
        case ("--count"); call cli%get_int(count_)
        case ("--t-end"); call cli%get_real(tend)
        case ("--section"); call cli%get_int(isec)
        case ("--rtol"); call cli%get_real(rtol_)
        case ("--atol"); call cli%get_real(atol_)
        case ("--out"); call cli%get_string(out_file)
        case ("--force"); call cli%flag(); force_ = .true.
        case ("--quiet"); call cli%flag(); quiet_ = .true.
        case ("--order"); call cli%get_string(order_name)
        case default; call cli%unknown()
        end select
    end do
    call validate()
    header = csv_header()
    canon = trim(merge("model= ", "system=", len_trim(model_path) > 0))// &
        trim(sys_name)//trim(model_path)//" params="//fmt_list(pars)//" y0="// &
        fmt_list(ystart)//" vary="//trim(vary_spec)//" from="//fmt_real(vfrom)//" to="// &
        fmt_real(vto)//" count="//itoa(count_)//" t_end="//fmt_real(tend)//" section="// &
        itoa(isec)//" rtol="//fmt_real(rtol_)//" atol="//fmt_real(atol_)//" method="// &
        trim(method_name)

    ! ---- resume: check OUT (and the rank parts) before the first job
    allocate (done(0:count_ - 1))
    done = .false.
    symmetric = .false.
    if (rank == 0) call prepare_output()
#ifdef CONMECH_MPI
    call mpi_barrier(mpi_comm_world, ierr)
    if (rank /= 0) call mark_done(.false.)
#endif
    if (nranks > 1) then
        part_file = trim(out_file)//".rank"//itoa(rank)
        call outf%open(part_file, "w", ok_io, why)
        if (.not. ok_io) call cli%fail("cannot write "//part_file//": "//why)
        call outf%put(header, ok_io, why)
        if (ok_io) call outf%flush(ok_io, why)
        if (.not. ok_io) call cli%fail_io("cannot write "//part_file//": "//why)
    else
        part_file = trim(out_file)
        call outf%open(part_file, "a", ok_io, why)
        if (.not. ok_io) call cli%fail("cannot append to "//part_file//": "//why)
    end if
    allocate (pending(0:ring - 1))
    next_out = 0
    ntodo = count(.not. done)
    todo = pack([(i, i=0, count_ - 1)], .not. done)
    nthreads = 1
    !$ nthreads = omp_get_max_threads()
    if (rank == 0) write (*, '(a,i0,a,i0,a,i0,a,i0,a)') "sweep: ", count_, " jobs, ", &
        count_ - ntodo, " already done, ", nranks, " rank(s) x ", nthreads, " thread(s)"
    flush (output_unit)
    call progress%begin("sweep", count_, count_ - ntodo, on=rank == 0 .and. .not. quiet_)

#ifdef CONMECH_MPI
    counter_cell = 0
    call mpi_win_create(counter_cell, int(merge(4, 0, rank == 0), mpi_address_kind), 4, &
                        mpi_info_null, mpi_comm_world, win, ierr)
#endif
    next_free = 0
    nfinished = count_ - ntodo
    !$omp parallel default(shared) private(i)
    do
        !$omp critical (sweep_next)
        i = next_job()
        ! with ranks, rank 0 reports the jobs handed out so far (all ranks)
        if (nranks > 1) call progress%tick(count_ - ntodo + min(i, ntodo))
        !$omp end critical (sweep_next)
        if (i >= ntodo) exit
        call run_job(todo(i + 1), i)
    end do
    !$omp end parallel
    i = 0
    if (.not. io_failed) call flush_ring(ntodo, i)     ! nothing left normally
    if (i /= 0) io_failed = .true.
    if (.not. io_failed) then
        call outf%close(ok_io, why)
        if (.not. ok_io) io_msg = why
        if (.not. ok_io) i = 1
    end if
    if (io_failed .or. i /= 0) then
        ! a full disk or an I/O error is not a failed job: say what it is
        call cli%fail_io("cannot write "//part_file//": "//trim(io_msg))
    end if
    if (nranks > 1) write (*, '(a,i0,a,i0,a)') "sweep: rank ", rank, " ran ", &
        nfinished - (count_ - ntodo), " job(s)"

#ifdef CONMECH_MPI
    call mpi_win_free(win, ierr)
    call mpi_barrier(mpi_comm_world, ierr)
    if (rank == 0 .and. nranks > 1) call merge_parts(.true.)
#endif
    if (rank == 0) then
        call count_results(nrows, nfail, in_order)
        ! job order: rows that finished out of order (a resumed completion-order file, a
        ! ring overflow) are sorted now
        if (job_order .and. .not. in_order) call merge_parts(.true.)
        if (nrows < count_) then
            write (error_unit, '(a,i0,a,i0,a)') "sweep: only ", nrows, " of ", count_, &
                " jobs in "//trim(out_file)
            nfail = max(nfail, 1)
        end if
        write (*, '(a)') "sweep: results in "//trim(out_file)
        if (nfail > 0) write (error_unit, '(a,i0,a,i0,a)') "sweep: ", nfail, " of ", &
            count_, " jobs failed (status /= 0 in the CSV)"
    end if
#ifdef CONMECH_MPI
    call mpi_finalize(ierr)
#endif
    deallocate (pars, ystart, done, todo, key, header, canon, part_file, pending)
    if (allocated(why)) deallocate (why)
    if (allocated(outf%name)) deallocate (outf%name)
    call cli%clear()
    call progress%clear()
    if (rank == 0 .and. nfail > 0) stop 1, quiet=.true.

contains

    function itoa(k) result(s)
        integer, intent(in) :: k
        character(len=:), allocatable :: s
        character(len=16) :: b
        write (b, '(i0)') k
        s = trim(b)
    end function itoa

    !> The options from a namelist file (&sweep ... /, names as the options with _ for -),
    !! read before the command line (which overrides them).
    subroutine read_input()
        character(len=64) :: system, method, order
        character(len=1024) :: out, vary, model
        real(dp) :: params(64), y0(64), from, to, t_end, rtol, atol
        integer :: count, section, ios
        character(len=:), allocatable :: lines(:)
        logical :: force, quiet
        character(len=512) :: msg
        namelist /sweep/ system, model, method, params, y0, vary, from, to, count, t_end, &
            section, rtol, atol, out, force, quiet, order
        system = sys_name; method = method_name; out = out_file; vary = vary_spec
        order = order_name
        model = model_path
        params = unset; y0 = unset
        from = vfrom; to = vto; t_end = tend; rtol = rtol_; atol = atol_
        count = count_; section = isec; force = force_; quiet = quiet_
        call check_namelist(cli, cli%input, "sweep", &
            "system:s64 model:s1024 method:s64 params:r64 y0:r64 vary:s1024 from:r to:r "// &
            "count:i t_end:r section:i rtol:r atol:r out:s1024 force:l quiet:l order:s64", &
            lines)
        read (lines, nml=sweep, iostat=ios, iomsg=msg)
        if (ios /= 0) call cli%fail("--input "//cli%input//": namelist &sweep: "//trim(msg))
        sys_name = system; method_name = method; out_file = out; vary_spec = vary
        order_name = order
        model_path = model
        pars = nml_list(cli, params, "params")
        ystart = nml_list(cli, y0, "y0")
        have_y0 = size(ystart) > 0
        vfrom = from; vto = to; tend = t_end; rtol_ = rtol; atol_ = atol
        count_ = count; isec = section; force_ = force; quiet_ = quiet
    end subroutine read_input

    subroutine validate()
        integer :: np
        logical :: ok
        if (len_trim(model_path) > 0) then
            call check_model()
        else
            if (len_trim(sys_name) == 0) call cli%fail("--system NAME (or --model LIB.so) "// &
                "is required; valid names: "//ode_names//" "//generalized_names)
            n = system_dimension(sys_name)
            if (n == 0) call cli%bad_name("system", sys_name, ode_names//" "// &
                                          generalized_names)
            np = param_count(sys_name)
            if (np >= 0 .and. size(pars) > np) call cli%fail("--params: "//trim(sys_name)// &
                " has "//itoa(np)//" parameter(s) ("//param_help(sys_name)//"), got "// &
                itoa(size(pars)))
        end if
        if (.not. have_y0) call cli%fail("--y0 is required ("//itoa(n)//" values for "// &
                                         trim(sys_name)//")")
        if (size(ystart) /= n) call cli%fail("--y0: "//trim(sys_name)//" has dimension "// &
            itoa(n)//", got "//itoa(size(ystart))//" value(s)")
        if (count_ < 1 .or. count_ > max_jobs) call cli%fail("--count must be in 1.."// &
            itoa(max_jobs)//", got "//itoa(count_))
        if (len_trim(vary_spec) == 0) call cli%fail("--vary param:K or y0:K is required")
        vary_param = .false.
        ok = .false.
        if (len_trim(vary_spec) > 6) then
            if (vary_spec(1:6) == "param:") then
                vary_param = .true.
                call parse_int(vary_spec(7:), vary_index, ok)
                ok = ok .and. vary_index >= 1 .and. vary_index <= size(pars)
                if (.not. ok) call cli%fail("--vary "//trim(vary_spec)//": K must be in 1.."// &
                    itoa(size(pars))//" (the entries of --params)")
            end if
        end if
        if (.not. vary_param) then
            if (len_trim(vary_spec) > 3) then
                if (vary_spec(1:3) == "y0:") then
                    call parse_int(vary_spec(4:), vary_index, ok)
                    ok = ok .and. vary_index >= 1 .and. vary_index <= n
                    if (.not. ok) call cli%fail("--vary "//trim(vary_spec)//": K must be in 1.."//&
                        itoa(n))
                end if
            end if
            if (.not. ok) call cli%fail("--vary must be param:K or y0:K, got '"// &
                                        trim(vary_spec)//"'")
        end if
        if (.not. (tend /= 0.0_dp .and. abs(tend) <= huge(tend))) &
            call cli%fail("--t-end must be finite and nonzero")
        if (.not. (abs(vfrom) <= huge(vfrom) .and. abs(vto) <= huge(vto))) &
            call cli%fail("--from and --to must be finite")
        if (isec < 0 .or. isec > n) call cli%fail("--section must be in 0.."//itoa(n))
        if (.not. (rtol_ > 0.0_dp .and. rtol_ < 1.0_dp)) call cli%fail("--rtol must be in (0, 1)")
        if (.not. (atol_ > 0.0_dp .and. atol_ <= huge(atol_))) &
            call cli%fail("--atol must be positive and finite")
        opt%method = method_from_name(method_name)
        if (opt%method == 0) call cli%bad_name("method", method_name, &
                                               "DOP853 DOPRI5 RK45 VERNER98")
        if (opt%method == METHOD_RK4) call cli%fail("--method RK4 has no error control; "// &
            "use DOP853, DOPRI5 or VERNER98")
        opt%rtol = rtol_
        opt%atol = atol_
        opt%save_steps = .false.
        if (len_trim(out_file) == 0) call cli%fail("--out must not be empty")
        select case (trim(order_name))
        case ("job"); job_order = .true.
        case ("completion"); job_order = .false.
        case default; call cli%bad_name("--order", order_name, "job completion")
        end select
    end subroutine validate

    !> --model: load the library, check its kind and the parameters (missing trailing ones
    !! take the model's defaults).
    subroutine check_model()
        integer :: info, np
        character(len=:), allocatable :: msg
        if (len_trim(sys_name) > 0) call cli%fail("give --system or --model, not both")
        call load_model(trim(model_path), model, info, msg)
        if (info /= CM_SUCCESS) call cli%fail("--model: "//msg)
        select case (model%kind)
        case (MODEL_KIND_ODE)
            n = model%n
        case (MODEL_KIND_GENERALIZED)
            n = 2*model%n
        case default
            call cli%fail("--model "//trim(model_path)//" is a constrained model; sweep "// &
                          "needs an ode or generalized one")
        end select
        np = size(model%defaults)
        if (size(pars) > np) call cli%fail("--params: the model has "//itoa(np)// &
            " parameter(s) ("//model%param_names//"), got "//itoa(size(pars)))
        pars = [pars, model%defaults(size(pars) + 1:)]
    end subroutine check_model

    function csv_header() result(h)
        character(len=:), allocatable :: h
        integer :: j
        h = "job,value"
        do j = 1, n
            h = h//",y"//itoa(j)
        end do
        h = h//",return_time,nfev,status"
    end function csv_header

    !> Rank 0, before any job: check the arguments file, repair or merge what is there.
    subroutine prepare_output()
        logical :: fresh, ok
        integer :: r
        type(results_file) :: f
        character(len=:), allocatable :: msg
        if (force_) then
            r = 0
            do while (file_exists(trim(out_file)//".rank"//itoa(r)))
                call delete_file(trim(out_file)//".rank"//itoa(r))
                r = r + 1
            end do
        end if
        call check_args_file(cli, trim(out_file), canon, force_, fresh)
        if (fresh .and. file_exists(trim(out_file)//".rank0")) call cli%fail( &
            trim(out_file)//".rank0 exists without "//trim(out_file)//".args; use --force")
        call write_args_file(cli, trim(out_file), canon)
        if (fresh .or. file_size(trim(out_file)) <= 0) then
            call f%open(trim(out_file), "w", ok, msg)
            if (.not. ok) call cli%fail("cannot write "//trim(out_file)//": "//msg)
            call f%put(header, ok, msg)
            if (ok) call f%close(ok, msg)
            if (.not. ok) call cli%fail_io("cannot write "//trim(out_file)//": "//msg)
        end if
        ! parts of an earlier MPI run (even when this run has one rank): merge them first
        if (nranks > 1 .or. file_exists(trim(out_file)//".rank0")) then
            call merge_parts(.false.)
            call mark_done(.false.)
            return
        end if
        call mark_done(.true.)
    end subroutine prepare_output

    !> done(job) from OUT (repair: cut a torn last line).
    subroutine mark_done(repair)
        logical, intent(in) :: repair
        integer :: nr
        call load_rows(cli, trim(out_file), header, n + 5, 0, count_ - 1, .false., repair, &
                       done, nr)
    end subroutine mark_done

    !> Rows and failed jobs (status /= 0) in OUT; whether they are in job order.
    subroutine count_results(nr, nf, sorted)
        integer, intent(out) :: nr, nf
        logical, intent(out) :: sorted
        logical, allocatable :: have(:)
        allocate (have(0:count_ - 1))
        have = .false.
        call load_rows(cli, trim(out_file), header, n + 5, 0, count_ - 1, .false., .false., &
                       have, nr, status_col=n + 5, nfail=nf, in_order=sorted)
        nr = count(have)
    end subroutine count_results

    !> Index (0-based) into todo of the next job to run, shared by all threads and ranks.
    integer function next_job() result(k)
        if (io_failed) then
            k = ntodo
            return
        end if
#ifdef CONMECH_MPI
        call mpi_win_lock(MPI_LOCK_SHARED, 0, 0, win, ierr)
        call mpi_fetch_and_op(1, k, MPI_INTEGER, 0, 0_mpi_address_kind, MPI_SUM, win, ierr)
        call mpi_win_unlock(0, win, ierr)
#else
        k = next_free
        next_free = next_free + 1
#endif
    end function next_job

    subroutine run_job(i, pos)
        integer, intent(in) :: i      !! the job
        integer, intent(in) :: pos    !! its position in todo (0-based)
        class(ode_system), allocatable :: sys
        type(ode_result) :: res
        type(section_events) :: ev
        real(dp) :: p(size(pars)), yi(n), v, tret, yend(n), nan
        integer :: info
        character(len=:), allocatable :: msg, line
        nan = nan_dp
        if (count_ == 1) then
            v = vfrom
        else
            v = vfrom + (vto - vfrom)*real(i, dp)/real(count_ - 1, dp)
        end if
        p = pars
        yi = ystart
        if (vary_param) then
            p(vary_index) = v
        else
            yi(vary_index) = v
        end if
        tret = nan
        yend = nan
        if (len_trim(model_path) > 0) then
            call model_system(model, p, sys, info, msg)
        else
            call make_system(sys_name, p, sys, info, msg)
        end if
        if (info == CM_SUCCESS) then
            if (isec > 0) then
                allocate (ev%direction(1), ev%terminal(1))
                ev%k = isec
                ev%c = yi(isec)
                ! crossing in the same direction as the initial motion through the section
                block
                    real(dp) :: f(n)
                    call sys%rhs(0.0_dp, yi, f)
                    ev%direction = int(sign(1.0_dp, f(isec)))
                end block
                ev%terminal = .false.
                call ode_solve(sys, [0.0_dp, tend], yi, opt, res, events=ev)
                ! the first crossing after the start (the start itself is not a crossing)
                if (res%nev > 0) tret = res%ev_t(1)
            else
                call ode_solve(sys, [0.0_dp, tend], yi, opt, res)
            end if
            info = res%status
            ! a run that failed before its first output point has no final state
            if (res%nt >= 1 .and. allocated(res%y)) yend = res%y(:, res%nt)
        end if
        ! formatted inside the critical section: concurrent internal writes corrupted rows
        ! (libgfortran 12, OpenMP)
        !$omp critical (sweep_output)
        line = itoa(i)//","//fmt_real(v)//","//fmt_list(yend)//","//fmt_real(tret)//","// &
            itoa(res%stats%nfev)//","//itoa(info)
        call emit_row(pos, line)
        nfinished = nfinished + 1
        if (nranks == 1) call progress%tick(nfinished)
        !$omp end critical (sweep_output)
    end subroutine run_job

    !> Write the row of the job at todo position `pos` (inside the output critical
    !! section). In job order with one rank, a row finished ahead of an earlier job waits
    !! in the ring until the rows before it are written; a job slower than `ring` later
    !! ones lets them through (the ring is flushed in order and the slow row written when
    !! it comes) and the file is sorted at the end. A write error stops the run.
    subroutine emit_row(pos, line)
        integer, intent(in) :: pos
        character(len=*), intent(in) :: line
        integer :: ios
        logical :: ok
        character(len=:), allocatable :: msg
        if (io_failed) return
        ios = 0
        if (.not. job_order .or. nranks > 1 .or. pos < next_out) then
            call outf%put(line, ok, msg)
            if (.not. ok) ios = 1
            if (.not. ok) io_msg = msg
        else
            if (pos - next_out >= ring) call flush_ring(pos - ring + 1, ios)
            pending(mod(pos, ring))%s = line
            if (ios == 0) call flush_ring(next_out, ios)
        end if
        if (ios == 0) then
            call outf%flush(ok, msg)
            if (.not. ok) ios = 1
            if (.not. ok) io_msg = msg
        end if
        if (ios /= 0) io_failed = .true.
    end subroutine emit_row

    !> Write the waiting rows in order: every one before position `upto` (skipping the
    !! gaps), then the contiguous ones from there; next_out moves past them.
    subroutine flush_ring(upto, ios)
        integer, intent(in) :: upto
        integer, intent(inout) :: ios
        integer :: slot
        logical :: ok
        character(len=:), allocatable :: msg
        do
            slot = mod(next_out, ring)
            if (next_out >= upto .and. .not. allocated(pending(slot)%s)) exit
            if (next_out >= ntodo) exit
            if (allocated(pending(slot)%s)) then
                call outf%put(pending(slot)%s, ok, msg)
                deallocate (pending(slot)%s)
                if (.not. ok) then
                    ios = 1
                    io_msg = msg
                    return
                end if
            end if
            next_out = next_out + 1
        end do
    end subroutine flush_ring

    !> Rank 0: OUT and every OUT.rankR into OUT (sorted by job, first copy of a job wins),
    !! written to OUT.tmp, fsync'ed and renamed; only then are the parts deleted.
    subroutine merge_parts(at_end)
        logical, intent(in) :: at_end
        type(row_t), allocatable :: rows(:)
        logical, allocatable :: have(:)
        integer :: r, job, nr, nparts
        logical :: ok, ok2
        character(len=:), allocatable :: tmp, msg, msg2
        type(results_file) :: f
        allocate (rows(0:count_ - 1), have(0:count_ - 1))
        have = .false.
        call load_rows(cli, trim(out_file), header, n + 5, 0, count_ - 1, .false., .false., &
                       have, nr, rows)
        nparts = 0
        do while (file_exists(trim(out_file)//".rank"//itoa(nparts)))
            call load_rows(cli, trim(out_file)//".rank"//itoa(nparts), header, n + 5, 0, &
                           count_ - 1, .false., .false., have, nr, rows)
            nparts = nparts + 1
        end do
        if (nparts == 0 .and. .not. at_end) return
        tmp = trim(out_file)//".tmp"
        call f%open(tmp, "w", ok, msg)
        if (.not. ok) call cli%fail_io("cannot write "//tmp//": "//msg)
        call f%put(header, ok, msg)
        do job = 0, count_ - 1
            if (.not. ok) exit
            if (have(job)) call f%put(rows(job)%s, ok, msg)
        end do
        if (ok) then
            call f%close(ok, msg)
        else
            call f%close(ok2, msg2)
        end if
        if (.not. ok) then
            call delete_file(tmp)
            call cli%fail_io("cannot write "//tmp//": "//msg//" (the results so far are in "// &
                             trim(out_file)//merge(" and its .rank parts", "                    ", &
                             nparts > 0))
        end if
        call durable_rename(tmp, trim(out_file), ok)
        if (.not. ok) call cli%fail_io("cannot replace "//trim(out_file)//" by "//tmp)
        do r = 0, nparts - 1
            call delete_file(trim(out_file)//".rank"//itoa(r))
        end do
    end subroutine merge_parts

    !> Before an exit from the command-line layer: MPI finalize (same on every rank) or
    !! abort (an error found by rank 0 alone).
    subroutine cleanup(code)
        integer, intent(in) :: code
#ifdef CONMECH_MPI
        if (code == 0 .or. symmetric) then
            call mpi_finalize(ierr)
        else
            call mpi_abort(mpi_comm_world, code, ierr)
        end if
#else
        if (code < 0) write (error_unit, '(a)') "sweep: cleanup"
#endif
    end subroutine cleanup

end program sweep
