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
    use conmech
    implicit none
    character(len=:), allocatable :: name, proj_name, method_name, out, arg, val, msg
    real(dp), allocatable :: params(:), q0(:), v0(:), t_eval(:)
    real(dp) :: t_end, rtol, atol, step
    integer :: n_out, every, i, info, nargs, unit
    logical :: have_q0, have_v0, is_constrained
    class(constrained_system), allocatable :: cs
    class(generalized_system), allocatable :: gs

    name = ""
    proj_name = "position+velocity"
    method_name = "DOP853"
    out = ""
    t_end = 10.0_dp
    step = 1.0e-3_dp
    rtol = 1.0e-10_dp
    atol = 1.0e-10_dp
    n_out = 201
    every = 1
    allocate (params(0), q0(0), v0(0))
    have_q0 = .false.
    have_v0 = .false.

    nargs = command_argument_count()
    i = 1
    do while (i <= nargs)
        arg = get_arg(i)
        if (arg == "--list") then
            write (*, '(a)') "constrained (excessive coordinates): "//constrained_names
            write (*, '(a)') "generalized coordinates: "//generalized_names
            stop
        else if (arg == "--help" .or. arg == "-h") then
            call usage()
            stop
        end if
        if (i == nargs) call die("missing value after "//arg)
        val = get_arg(i + 1)
        select case (arg)
        case ("--system")
            name = val
        case ("--t-end")
            t_end = to_real(val, arg)
        case ("--projection")
            proj_name = val
        case ("--method")
            method_name = val
        case ("--step")
            step = to_real(val, arg)
        case ("--rtol")
            rtol = to_real(val, arg)
        case ("--atol")
            atol = to_real(val, arg)
        case ("--n-out")
            n_out = nint(to_real(val, arg))
        case ("--every")
            every = nint(to_real(val, arg))
        case ("--params")
            params = to_list(val, arg)
        case ("--q0")
            q0 = to_list(val, arg)
            have_q0 = .true.
        case ("--v0")
            v0 = to_list(val, arg)
            have_v0 = .true.
        case ("--out")
            out = val
        case default
            call die("unknown option "//arg)
        end select
        i = i + 2
    end do
    if (len(name) == 0) call die("--system NAME is required (see --list)")
    if (n_out < 2) call die("--n-out must be at least 2")
    if (method_from_name(method_name) == 0) call die("unknown method "//method_name)
    if (projection_from_name(proj_name) < 0) call die("unknown projection "//proj_name// &
        " (none, velocity, position+velocity, baumgarte)")

    call make_constrained(name, params, cs, info, msg)
    is_constrained = info == CM_SUCCESS
    if (.not. is_constrained) then
        call make_generalized(name, params, gs, info, msg)
        if (info /= CM_SUCCESS) call die("unknown system '"//name//"' (see --list)")
    end if
    block
        real(dp), allocatable :: qd(:), vd(:)
        call mech_initial_state(name, params, qd, vd, info)
        if (.not. have_q0) q0 = qd
        if (.not. have_v0) v0 = vd
    end block

    allocate (t_eval(n_out))
    do i = 1, n_out
        t_eval(i) = t_end*real(i - 1, dp)/real(n_out - 1, dp)
    end do

    if (is_constrained) then
        call run_constrained()
    else
        call run_generalized()
    end if

contains

    subroutine run_constrained()
        type(constrained_options) :: opt
        type(constrained_result) :: r
        integer :: j, m, n
        opt%ode%method = method_from_name(method_name)
        opt%ode%rtol = rtol
        opt%ode%atol = atol
        opt%ode%max_steps = 10000000
        if (opt%ode%method == METHOD_RK4) opt%ode%first_step = step
        opt%projection = projection_from_name(proj_name)
        opt%every = every
        call constrained_solve(cs, [0.0_dp, t_end], q0, v0, opt, r, t_eval)
        n = cs%n
        m = cs%n_hol + cs%n_nh
        if (len(out) > 0 .and. r%nt > 0) then
            open (newunit=unit, file=out, status="replace", action="write")
            write (unit, '(a)', advance="no") "t"
            call header(unit, "q", n)
            call header(unit, "v", n)
            call header(unit, "lambda", m)
            call header(unit, "reaction", n)
            write (unit, '(a)') ",res_pos,res_vel,energy,power"
            do j = 1, r%nt
                write (unit, '(es24.16e3,*(:,",",es24.16e3))') r%t(j), r%q(:, j), r%v(:, j), &
                    r%lam(:, j), r%reaction(:, j), r%res_pos(j), r%res_vel(j), r%energy(j), &
                    r%power(j)
            end do
            close (unit)
        end if
        write (*, '(a)') "system      : "//name//" (excessive coordinates)"
        write (*, '(a,i0,a,i0,a,i0,a,i0)') "coordinates : ", n, ", holonomic ", cs%n_hol, &
            ", non-holonomic ", cs%n_nh, ", rank ", r%rank
        write (*, '(a)') "method      : "//method_name//", projection "//proj_name
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
        if (len(out) > 0) write (*, '(a,i0,a)') "wrote       : "//out//" (", r%nt, " rows)"
        write (*, '(a)') "status      : "//r%message
        if (.not. r%success) stop 1
    end subroutine run_constrained

    subroutine run_generalized()
        type(ode_options) :: opt
        type(ode_result) :: r
        integer :: j, n
        real(dp), allocatable :: e(:)
        opt%method = method_from_name(method_name)
        opt%rtol = rtol
        opt%atol = atol
        opt%max_steps = 10000000
        if (opt%method == METHOD_RK4) opt%first_step = step
        call generalized_solve(gs, [0.0_dp, t_end], q0, v0, opt, r, t_eval)
        n = gs%ndof
        allocate (e(r%nt))
        do j = 1, r%nt
            e(j) = gs%energy(r%t(j), r%y(1:n, j), r%y(n + 1:, j))
        end do
        if (len(out) > 0 .and. r%nt > 0) then
            open (newunit=unit, file=out, status="replace", action="write")
            write (unit, '(a)', advance="no") "t"
            call header(unit, "q", n)
            call header(unit, "v", n)
            write (unit, '(a)') ",energy"
            do j = 1, r%nt
                write (unit, '(es24.16e3,*(:,",",es24.16e3))') r%t(j), r%y(:, j), e(j)
            end do
            close (unit)
        end if
        write (*, '(a)') "system      : "//name//" (generalized coordinates)"
        write (*, '(a,i0)') "coordinates : ", n
        write (*, '(a)') "method      : "//method_name
        write (*, '(a,i0,a,i0,a,i0)') "steps       : ", r%stats%naccept, " accepted, ", &
            r%stats%nreject, " rejected, nfev ", r%stats%nfev
        if (gs%has_energy() .and. r%nt > 0) write (*, '(a,es10.3)') "energy drift: ", &
            maxval(abs(e - e(1)))
        if (len(out) > 0) write (*, '(a,i0,a)') "wrote       : "//out//" (", r%nt, " rows)"
        write (*, '(a)') "status      : "//r%message
        if (.not. r%success) stop 1
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

    function get_arg(k) result(s)
        integer, intent(in) :: k
        character(len=:), allocatable :: s
        integer :: l
        call get_command_argument(k, length=l)
        allocate (character(len=l) :: s)
        call get_command_argument(k, s)
    end function get_arg

    real(dp) function to_real(s, what)
        character(len=*), intent(in) :: s, what
        integer :: ios
        read (s, *, iostat=ios) to_real
        if (ios /= 0) call die("bad number '"//s//"' after "//what)
    end function to_real

    function to_list(s, what) result(x)
        character(len=*), intent(in) :: s, what
        real(dp), allocatable :: x(:)
        integer :: k, j, ios
        k = 1
        do j = 1, len(s)
            if (s(j:j) == ",") k = k + 1
        end do
        allocate (x(k))
        read (s, *, iostat=ios) x
        if (ios /= 0) call die("bad list '"//s//"' after "//what)
    end function to_list

    subroutine usage()
        write (*, '(a)') "usage: seed --system NAME [--t-end T] [--projection none|velocity|"// &
            "position+velocity|baumgarte]"
        write (*, '(a)') "            [--method RK4|DOPRI5|DOP853] [--rtol R] [--atol A] "// &
            "[--step H] [--n-out N] [--every K]"
        write (*, '(a)') "            [--params p1,p2,..] [--q0 ..] [--v0 ..] [--out file.csv]"
        write (*, '(a)') "       seed --list"
    end subroutine usage

    subroutine die(text)
        character(len=*), intent(in) :: text
        write (*, '(a)') "seed: error: "//text
        stop 2
    end subroutine die

end program seed
