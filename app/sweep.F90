!> Batch sweep over one parameter (or one initial-state component) of a built-in system.
!!
!! Each job integrates the system from y0 to t_end and records the final state, the first
!! return time to the section y(k) = y0(k) crossed in the initial direction (a period for
!! periodic motions), the number of evaluations and the status. Results are appended to the
!! CSV file as each job finishes (flushed), and a rerun with the same --out skips the jobs
!! already in the file, so an interrupted sweep resumes without losing or recomputing work.
!!
!! Threads: build with OpenMP (`fpm run sweep --flag -fopenmp -- ...`, OMP_NUM_THREADS).
!! Ranks: build with MPI (`fpm run sweep --compiler mpifort --flag "-DCONMECH_MPI" ...`,
!! then `mpirun -n 2 build/.../sweep ...`): rank r takes jobs r, r + size, ... and writes
!! OUT.rankR; rank 0 merges the parts into OUT (sorted by job) at the end.
!!
!!   sweep --system pendulum --params 9.81,1 --y0 0.1,0 --vary y0:1 --from 0.1 --to 3
!!         --count 100 --t-end 10 --section 2 --out sweep.csv [--rtol 1e-10 --atol 1e-10]
!!         [--method DOP853]
program sweep
    use conmech
    use app_events, only: section_events
    !$ use omp_lib
    implicit none
#ifdef CONMECH_MPI
    include "mpif.h"
    ! explicit interfaces for the few MPI calls (mpif.h declares none)
    interface
        subroutine mpi_init(ierror)
            integer, intent(out) :: ierror
        end subroutine mpi_init
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
    end interface
#endif

    character(len=64) :: sys_name = "pendulum", method_name = "DOP853"
    character(len=512) :: out_file = "sweep.csv", part_file
    real(dp), allocatable :: params(:), y0(:)
    character(len=32) :: vary = "y0:1"
    real(dp) :: vfrom = 0.1_dp, vto = 1.0_dp, t_end = 10.0_dp, rtol = 1.0e-10_dp
    real(dp) :: atol = 1.0e-10_dp
    integer :: count_ = 10, section = 0, n, i, u, ios, rank, nranks, ndone, nthreads
    logical, allocatable :: done(:)
    logical :: vary_param
    integer :: vary_index
    type(ode_options) :: opt
#ifdef CONMECH_MPI
    integer :: ierr
    call mpi_init(ierr)
    call mpi_comm_rank(mpi_comm_world, rank, ierr)
    call mpi_comm_size(mpi_comm_world, nranks, ierr)
#else
    rank = 0
    nranks = 1
#endif
    allocate (params(0), y0(0))
    call parse_args()
    n = system_dimension(sys_name)
    if (n == 0) call die("unknown system '"//trim(sys_name)//"'")
    if (size(y0) /= n) call die("--y0 must have the system's dimension")
    if (count_ < 1) call die("--count must be positive")
    if (vary_param) then
        if (vary_index < 1 .or. vary_index > size(params)) &
            call die("--vary param:K needs K within --params")
    else
        if (vary_index < 1 .or. vary_index > n) call die("--vary y0:K needs K in 1..n")
    end if
    if (section > n) call die("--section must be a state index")
    opt%method = method_from_name(method_name)
    if (opt%method == 0) call die("unknown --method")
    opt%rtol = rtol
    opt%atol = atol
    opt%save_steps = .false.

    if (nranks > 1) then
        write (part_file, '(a,".rank",i0)') trim(out_file), rank
    else
        part_file = out_file
    end if
    ! ---- resume: mark the jobs already in this rank's file (and, for ranks, in OUT)
    allocate (done(0:count_ - 1))
    done = .false.
    call mark_done(part_file)
    if (nranks > 1) call mark_done(out_file)
    open (newunit=u, file=trim(part_file), position="append", action="write", iostat=ios)
    if (ios /= 0) call die("cannot open "//trim(part_file))
    ndone = count(done)
    if (ndone == 0 .and. rank == 0) write (u, '(a)') header()
    nthreads = 1
    !$ nthreads = omp_get_max_threads()
    if (rank == 0) write (*, '(a,i0,a,i0,a,i0,a,i0,a)') "sweep: ", count_, " jobs, ", ndone, &
        " already done, ", nranks, " rank(s) x ", nthreads, " thread(s)"

    !$omp parallel do schedule(dynamic) default(shared) private(i)
    do i = rank, count_ - 1, nranks
        if (done(i)) cycle
        call run_job(i)
    end do
    !$omp end parallel do
    close (u)

#ifdef CONMECH_MPI
    call mpi_barrier(mpi_comm_world, ierr)
    if (rank == 0 .and. nranks > 1) call merge_parts()
    call mpi_finalize(ierr)
#endif
    if (rank == 0) write (*, '(a)') "sweep: results in "//trim(out_file)

contains

    function header() result(h)
        character(len=:), allocatable :: h
        integer :: j
        character(len=16) :: b
        h = "job,value"
        do j = 1, n
            write (b, '(i0)') j
            h = h//",y"//trim(b)
        end do
        h = h//",return_time,nfev,status"
    end function header

    subroutine run_job(i)
        integer, intent(in) :: i
        class(ode_system), allocatable :: sys
        type(ode_result) :: res
        type(section_events) :: ev
        real(dp) :: p(size(params)), yi(n), v, tret
        integer :: info, j
        character(len=:), allocatable :: msg
        character(len=2048) :: line
        character(len=32) :: b
        if (count_ == 1) then
            v = vfrom
        else
            v = vfrom + (vto - vfrom)*real(i, dp)/real(count_ - 1, dp)
        end if
        p = params
        yi = y0
        if (vary_param) then
            p(vary_index) = v
        else
            yi(vary_index) = v
        end if
        call make_system(sys_name, p, sys, info, msg)
        tret = -1.0_dp
        if (section > 0) then
            allocate (ev%direction(1), ev%terminal(1))
            ev%k = section
            ev%c = yi(section)
            ! crossing in the same direction as the initial motion through the section
            block
                real(dp) :: f(n)
                call sys%rhs(0.0_dp, yi, f)
                ev%direction = int(sign(1.0_dp, f(section)))
            end block
            ev%terminal = .false.
            call ode_solve(sys, [0.0_dp, t_end], yi, opt, res, events=ev)
            ! the first crossing after the start (the start itself is not a crossing)
            if (res%nev > 0) tret = res%ev_t(1)
        else
            call ode_solve(sys, [0.0_dp, t_end], yi, opt, res)
        end if
        write (line, '(i0,",",es24.16)') i, v
        do j = 1, n
            write (b, '(es24.16)') res%y(j, res%nt)
            line = trim(line)//","//trim(adjustl(b))
        end do
        write (b, '(es24.16)') tret
        line = trim(line)//","//trim(adjustl(b))
        write (b, '(i0,",",i0)') res%stats%nfev, res%status
        line = trim(line)//","//trim(b)
        !$omp critical (sweep_output)
        write (u, '(a)') trim(line)
        flush (u)
        !$omp end critical (sweep_output)
    end subroutine run_job

    subroutine mark_done(file)
        character(len=*), intent(in) :: file
        integer :: uu, ios2, job
        character(len=2048) :: line
        open (newunit=uu, file=trim(file), status="old", action="read", iostat=ios2)
        if (ios2 /= 0) return
        do
            read (uu, '(a)', iostat=ios2) line
            if (ios2 /= 0) exit
            read (line, *, iostat=ios2) job
            if (ios2 == 0 .and. job >= 0 .and. job < count_) done(job) = .true.
        end do
        close (uu)
    end subroutine mark_done

#ifdef CONMECH_MPI
    !> Rank 0: merge OUT (earlier runs) and every OUT.rankR into OUT, one line per job.
    subroutine merge_parts()
        character(len=2048), allocatable :: lines(:)
        logical, allocatable :: have(:)
        character(len=2048) :: line
        character(len=512) :: f
        integer :: r, uu, ios2, job
        allocate (lines(0:count_ - 1), have(0:count_ - 1))
        have = .false.
        do r = -1, nranks - 1
            if (r < 0) then
                f = out_file
            else
                write (f, '(a,".rank",i0)') trim(out_file), r
            end if
            open (newunit=uu, file=trim(f), status="old", action="read", iostat=ios2)
            if (ios2 /= 0) cycle
            do
                read (uu, '(a)', iostat=ios2) line
                if (ios2 /= 0) exit
                read (line, *, iostat=ios2) job
                if (ios2 == 0 .and. job >= 0 .and. job < count_) then
                    lines(job) = line
                    have(job) = .true.
                end if
            end do
            if (r >= 0) then
                close (uu, status="delete")
            else
                close (uu)
            end if
        end do
        open (newunit=uu, file=trim(out_file), status="replace", action="write")
        write (uu, '(a)') header()
        do job = 0, count_ - 1
            if (have(job)) write (uu, '(a)') trim(lines(job))
        end do
        close (uu)
    end subroutine merge_parts
#endif

    subroutine parse_args()
        integer :: k, nargs
        character(len=512) :: key, val
        nargs = command_argument_count()
        k = 1
        vary_param = .false.
        vary_index = 1
        do while (k <= nargs)
            call get_command_argument(k, key)
            if (trim(key) == "--help" .or. trim(key) == "-h") then
                if (rank == 0) write (*, '(a)') "usage: sweep --system NAME --params P1,P2 " // &
                    "--y0 Y1,Y2,.. --vary param:K|y0:K --from A --to B --count N " // &
                    "--t-end T [--section K] [--rtol R] [--atol A] [--method M] [--out F]"
                call finish_ok()
            end if
            if (k == nargs) call die("missing value after "//trim(key))
            call get_command_argument(k + 1, val)
            ios = 0
            select case (trim(key))
            case ("--system")
                sys_name = val
            case ("--method")
                method_name = val
            case ("--params")
                call parse_list(val, params)
            case ("--y0")
                call parse_list(val, y0)
            case ("--vary")
                if (val(1:6) == "param:") then
                    vary_param = .true.
                    read (val(7:), *, iostat=ios) vary_index
                else if (val(1:3) == "y0:") then
                    read (val(4:), *, iostat=ios) vary_index
                else
                    call die("--vary must be param:K or y0:K")
                end if
            case ("--from")
                read (val, *, iostat=ios) vfrom
            case ("--to")
                read (val, *, iostat=ios) vto
            case ("--count")
                read (val, *, iostat=ios) count_
            case ("--t-end")
                read (val, *, iostat=ios) t_end
            case ("--section")
                read (val, *, iostat=ios) section
            case ("--rtol")
                read (val, *, iostat=ios) rtol
            case ("--atol")
                read (val, *, iostat=ios) atol
            case ("--out")
                out_file = val
            case default
                call die("unknown option "//trim(key))
            end select
            if (ios /= 0) call die("cannot read the value of "//trim(key))
            k = k + 2
        end do
    end subroutine parse_args

    subroutine parse_list(s, v)
        character(len=*), intent(in) :: s
        real(dp), allocatable, intent(out) :: v(:)
        integer :: m, j, ios2
        m = 1
        do j = 1, len_trim(s)
            if (s(j:j) == ",") m = m + 1
        end do
        allocate (v(m))
        read (s, *, iostat=ios2) v
        if (ios2 /= 0) call die("cannot read the list '"//trim(s)//"'")
    end subroutine parse_list

    subroutine die(msg)
        character(len=*), intent(in) :: msg
        if (rank == 0) write (*, '(a)') "sweep: error: "//msg
#ifdef CONMECH_MPI
        call mpi_abort(mpi_comm_world, 2, ierr)
#endif
        stop 2
    end subroutine die

    subroutine finish_ok()
#ifdef CONMECH_MPI
        call mpi_finalize(ierr)
#endif
        stop
    end subroutine finish_ok

end program sweep
