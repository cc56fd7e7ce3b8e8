!> Registry of the built-in mechanical seed systems by name, with default initial states.
!!
!! Excessive coordinates (`make_constrained`), parameters in order:
!!   pendulum_xy: m, g, l | rod_two_masses: g, l | double_pendulum_xy: m1, m2, l1, l2, g |
!!   atwood_xy: m1, m2, g, L | pendulum_moving_xy: m, g, l, a, b, w |
!!   yoyo: m, r, I, g, ah, vh, h0 | skate: m, I, g, alpha | rolling_disk: m, R, I_roll, I_turn
!!   | pendulum_chain_xy: N (links, default 8), m, l, g | rolling_ball: m, R, I, g, alpha
!! Generalized coordinates (`make_generalized`):
!!   pendulum_angle: m, g, l | cart_pendulum: M, m, l, g | double_pendulum: m1, m2, l1, l2, g |
!!   atwood: m1, m2, g | spring_pendulum: m, k, l0, g |
!!   double_spring_pendulum: m1, m2, k1, k2, l1, l2, g | three_springs: m, k, l0 |
!!   bead_hoop: m, R, omega, g | polar_particle: m, mu | pendulum_moving: m, g, l, a, b, w |
!!   yoyo_angle: m, r, I, g, ah, vh, h0
!! Missing trailing parameters keep their defaults; more than a system has is an error
!! (conmech_systems_params).
module conmech_systems_mech
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_generalized, only: generalized_system, generalized_ode
    use conmech_constrained_system, only: constrained_system
    use conmech_systems_generalized
    use conmech_systems_constrained
    use conmech_systems_chain, only: pendulum_chain_xy, chain_initial_state
    use conmech_systems_ball, only: rolling_ball
    use conmech_ode_system, only: ode_system
    use conmech_systems_params, only: check_param_count
    implicit none
    private

    public :: make_constrained, make_generalized, make_generalized_ode
    public :: mech_initial_state, constrained_names, generalized_names

    !> Names of the built-in constrained systems (space separated).
    character(len=*), parameter :: constrained_names = "pendulum_xy rod_two_masses " &
        //"double_pendulum_xy atwood_xy pendulum_moving_xy yoyo skate rolling_disk " &
        //"pendulum_chain_xy rolling_ball"
    !> Names of the built-in generalized-coordinate systems.
    character(len=*), parameter :: generalized_names = "pendulum_angle cart_pendulum " &
        //"double_pendulum atwood spring_pendulum double_spring_pendulum three_springs " &
        //"bead_hoop polar_particle pendulum_moving yoyo_angle"

contains

    !> p(i) if present, else the default d.
    pure real(dp) function par(p, i, d)
        real(dp), intent(in) :: p(:)
        integer, intent(in) :: i
        real(dp), intent(in) :: d
        par = d
        if (size(p) >= i) par = p(i)
    end function par

    !> Allocate the built-in constrained system `name` (n, n_hol, n_nh set).
    subroutine make_constrained(name, params, sys, info, msg)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        class(constrained_system), allocatable, intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        call check_param_count(name, size(params), info, msg)
        if (info /= CM_SUCCESS) return
        select case (trim(name))
        case ("pendulum_xy")
            block
                type(pendulum_xy) :: s
                s%m = par(params, 1, s%m); s%g = par(params, 2, s%g); s%l = par(params, 3, s%l)
                s%n = 2; s%n_hol = 1
                s%diagonal_mass = .true.
                allocate (sys, source=s)
            end block
        case ("rod_two_masses")
            block
                type(rod_two_masses) :: s
                s%g = par(params, 1, s%g); s%l = par(params, 2, s%l)
                s%n = 4; s%n_hol = 1; s%n_nh = 1
                s%diagonal_mass = .true.
                allocate (sys, source=s)
            end block
        case ("double_pendulum_xy")
            block
                type(double_pendulum_xy) :: s
                s%m1 = par(params, 1, s%m1); s%m2 = par(params, 2, s%m2)
                s%l1 = par(params, 3, s%l1); s%l2 = par(params, 4, s%l2)
                s%g = par(params, 5, s%g)
                s%n = 4; s%n_hol = 2
                s%diagonal_mass = .true.
                allocate (sys, source=s)
            end block
        case ("atwood_xy")
            block
                type(atwood_xy) :: s
                s%m1 = par(params, 1, s%m1); s%m2 = par(params, 2, s%m2)
                s%g = par(params, 3, s%g); s%len = par(params, 4, s%len)
                s%n = 2; s%n_hol = 1
                s%diagonal_mass = .true.
                allocate (sys, source=s)
            end block
        case ("pendulum_moving_xy")
            block
                type(pendulum_moving_xy) :: s
                s%m = par(params, 1, s%m); s%g = par(params, 2, s%g); s%l = par(params, 3, s%l)
                s%a = par(params, 4, s%a); s%b = par(params, 5, s%b); s%w = par(params, 6, s%w)
                s%n = 2; s%n_hol = 1; s%rheonomic = .true.
                s%diagonal_mass = .true.
                allocate (sys, source=s)
            end block
        case ("yoyo")
            block
                type(yoyo) :: s
                s%m = par(params, 1, s%m); s%r = par(params, 2, s%r); s%i = par(params, 3, s%i)
                s%g = par(params, 4, s%g); s%ah = par(params, 5, s%ah)
                s%vh = par(params, 6, s%vh); s%h0 = par(params, 7, s%h0)
                s%n = 2; s%n_hol = 1; s%rheonomic = .true.
                s%diagonal_mass = .true.
                allocate (sys, source=s)
            end block
        case ("skate")
            block
                type(skate) :: s
                s%m = par(params, 1, s%m); s%i = par(params, 2, s%i); s%g = par(params, 3, s%g)
                s%alpha = par(params, 4, s%alpha)
                s%n = 3; s%n_nh = 1
                s%diagonal_mass = .true.
                allocate (sys, source=s)
            end block
        case ("rolling_disk")
            block
                type(rolling_disk) :: s
                s%m = par(params, 1, s%m); s%r = par(params, 2, s%r)
                s%i_roll = par(params, 3, s%i_roll); s%i_turn = par(params, 4, s%i_turn)
                s%n = 4; s%n_nh = 2
                s%diagonal_mass = .true.
                allocate (sys, source=s)
            end block
        case ("pendulum_chain_xy")
            block
                type(pendulum_chain_xy) :: s
                real(dp) :: nl
                nl = par(params, 1, 8.0_dp)
                if (.not. (nl >= 1.0_dp .and. nl <= 1.0e5_dp .and. nl == aint(nl))) then
                    info = CM_BAD_INPUT
                    msg = "bad input: pendulum_chain_xy needs a whole number of links N " &
                          //"(1 <= N <= 100000) as its first parameter"
                    return
                end if
                s%m = par(params, 2, s%m); s%l = par(params, 3, s%l); s%g = par(params, 4, s%g)
                s%n = 2*nint(nl); s%n_hol = nint(nl)
                s%diagonal_mass = .true.
                s%jac_width = min(4, s%n)
                allocate (sys, source=s)
            end block
        case ("rolling_ball")
            block
                type(rolling_ball) :: s
                s%m = par(params, 1, s%m); s%r = par(params, 2, s%r); s%i = par(params, 3, s%i)
                s%g = par(params, 4, s%g); s%alpha = par(params, 5, s%alpha)
                s%n = 6; s%n_hol = 1; s%n_nh = 3
                s%constant_mass = .true.; s%diagonal_mass = .true.
                allocate (sys, source=s)
            end block
        case default
            info = CM_BAD_INPUT
            msg = "bad input: unknown constrained system '"//trim(name)//"' (known: " &
                  //constrained_names//")"
        end select
    end subroutine make_constrained

    !> Allocate the built-in generalized-coordinate system `name` (ndof set).
    subroutine make_generalized(name, params, mech, info, msg)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        class(generalized_system), allocatable, intent(out) :: mech
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        call check_param_count(name, size(params), info, msg)
        if (info /= CM_SUCCESS) return
        select case (trim(name))
        case ("pendulum_angle")
            block
                type(gen_pendulum) :: s
                s%m = par(params, 1, s%m); s%g = par(params, 2, s%g); s%l = par(params, 3, s%l)
                s%ndof = 1
                allocate (mech, source=s)
            end block
        case ("cart_pendulum")
            block
                type(cart_pendulum) :: s
                s%mc = par(params, 1, s%mc); s%m = par(params, 2, s%m)
                s%l = par(params, 3, s%l); s%g = par(params, 4, s%g)
                s%ndof = 2
                allocate (mech, source=s)
            end block
        case ("double_pendulum")
            block
                type(gen_double_pendulum) :: s
                s%m1 = par(params, 1, s%m1); s%m2 = par(params, 2, s%m2)
                s%l1 = par(params, 3, s%l1); s%l2 = par(params, 4, s%l2)
                s%g = par(params, 5, s%g)
                s%ndof = 2
                allocate (mech, source=s)
            end block
        case ("atwood")
            block
                type(gen_atwood) :: s
                s%m1 = par(params, 1, s%m1); s%m2 = par(params, 2, s%m2)
                s%g = par(params, 3, s%g)
                s%ndof = 1
                allocate (mech, source=s)
            end block
        case ("spring_pendulum")
            block
                type(spring_pendulum) :: s
                s%m = par(params, 1, s%m); s%k = par(params, 2, s%k)
                s%l0 = par(params, 3, s%l0); s%g = par(params, 4, s%g)
                s%ndof = 2
                allocate (mech, source=s)
            end block
        case ("double_spring_pendulum")
            block
                type(double_spring_pendulum) :: s
                s%m1 = par(params, 1, s%m1); s%m2 = par(params, 2, s%m2)
                s%k1 = par(params, 3, s%k1); s%k2 = par(params, 4, s%k2)
                s%l1 = par(params, 5, s%l1); s%l2 = par(params, 6, s%l2)
                s%g = par(params, 7, s%g)
                s%ndof = 4
                allocate (mech, source=s)
            end block
        case ("three_springs")
            block
                type(three_springs) :: s
                s%m = par(params, 1, s%m); s%k = par(params, 2, s%k)
                s%l0 = par(params, 3, s%l0)
                s%ndof = 6
                allocate (mech, source=s)
            end block
        case ("bead_hoop")
            block
                type(bead_hoop) :: s
                s%m = par(params, 1, s%m); s%r = par(params, 2, s%r)
                s%omega = par(params, 3, s%omega); s%g = par(params, 4, s%g)
                s%ndof = 1
                allocate (mech, source=s)
            end block
        case ("polar_particle")
            block
                type(polar_particle) :: s
                s%m = par(params, 1, s%m); s%mu = par(params, 2, s%mu)
                s%ndof = 2
                allocate (mech, source=s)
            end block
        case ("pendulum_moving")
            block
                type(gen_pendulum_moving) :: s
                s%m = par(params, 1, s%m); s%g = par(params, 2, s%g); s%l = par(params, 3, s%l)
                s%a = par(params, 4, s%a); s%b = par(params, 5, s%b); s%w = par(params, 6, s%w)
                s%ndof = 1
                allocate (mech, source=s)
            end block
        case ("yoyo_angle")
            block
                type(gen_yoyo) :: s
                s%m = par(params, 1, s%m); s%r = par(params, 2, s%r); s%i = par(params, 3, s%i)
                s%g = par(params, 4, s%g); s%ah = par(params, 5, s%ah)
                s%vh = par(params, 6, s%vh); s%h0 = par(params, 7, s%h0)
                s%ndof = 1
                allocate (mech, source=s)
            end block
        case default
            info = CM_BAD_INPUT
            msg = "bad input: unknown generalized system '"//trim(name)//"' (known: " &
                  //generalized_names//")"
        end select
    end subroutine make_generalized

    !> A built-in generalized system as a first-order ode_system (y = [q, v]).
    subroutine make_generalized_ode(name, params, sys, info, msg)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        class(ode_system), allocatable, intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(generalized_ode) :: w
        call make_generalized(name, params, w%mech, info, msg)
        if (info /= CM_SUCCESS) return
        allocate (sys, source=w)
    end subroutine make_generalized_ode

    !> A default initial state (q0, v0) of a built-in system (constrained or generalized),
    !! consistent with its constraints for the given parameters.
    subroutine mech_initial_state(name, params, q0, v0, info)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        real(dp), allocatable, intent(out) :: q0(:), v0(:)
        integer, intent(out) :: info
        real(dp) :: l, l1, l2, th
        info = CM_SUCCESS
        th = 1.0_dp
        select case (trim(name))
        case ("pendulum_xy")
            l = par(params, 3, 1.0_dp)
            q0 = [l*sin(th), -l*cos(th)]; v0 = [0.0_dp, 0.0_dp]
        case ("rod_two_masses")
            l = par(params, 2, 1.0_dp)
            q0 = [0.0_dp, 0.0_dp, l*cos(0.5_dp), l*sin(0.5_dp)]
            ! centre velocity (1 along the rod) and rotation: consistent with both constraints
            v0 = [cos(0.5_dp) + 0.3_dp*sin(0.5_dp), sin(0.5_dp) - 0.3_dp*cos(0.5_dp), &
                  cos(0.5_dp) - 0.3_dp*sin(0.5_dp), sin(0.5_dp) + 0.3_dp*cos(0.5_dp)]
        case ("double_pendulum_xy")
            l1 = par(params, 3, 1.0_dp); l2 = par(params, 4, 1.0_dp)
            q0 = [l1*sin(th), -l1*cos(th), l1*sin(th) + l2*sin(0.5_dp), &
                  -l1*cos(th) - l2*cos(0.5_dp)]
            v0 = [0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp]
        case ("atwood_xy")
            l = par(params, 4, 2.0_dp)
            q0 = [0.5_dp*l, 0.5_dp*l]; v0 = [0.0_dp, 0.0_dp]
        case ("pendulum_moving_xy")
            l = par(params, 3, 1.0_dp)
            q0 = [l*sin(0.5_dp), -l*cos(0.5_dp)]; v0 = [0.0_dp, 0.0_dp]
            v0(1) = par(params, 5, 0.1_dp)*par(params, 6, 3.0_dp)   ! moving with the support
        case ("yoyo")
            q0 = [par(params, 7, 0.0_dp), 0.0_dp]; v0 = [par(params, 6, 0.0_dp), 0.0_dp]
        case ("skate")
            q0 = [0.0_dp, 0.0_dp, 0.0_dp]; v0 = [0.0_dp, 0.0_dp, 2.0_dp]
        case ("pendulum_chain_xy")
            l = par(params, 3, 1.0_dp)
            th = par(params, 1, 8.0_dp)
            if (.not. (th >= 1.0_dp .and. th <= 1.0e5_dp .and. th == aint(th))) then
                info = CM_BAD_INPUT
                allocate (q0(0), v0(0))
                return
            end if
            call chain_initial_state(nint(th), l, q0, v0)
        case ("rolling_disk")
            q0 = [0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp]
            v0 = [par(params, 2, 1.0_dp)*2.0_dp, 0.0_dp, 0.5_dp, 2.0_dp]
        case ("rolling_ball")
            ! identity orientation, centre velocity (1, 0.5): e' = [0, -y'/(2R), x'/(2R), 0]
            l = par(params, 2, 1.0_dp)
            q0 = [0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp]
            v0 = [1.0_dp, 0.5_dp, 0.0_dp, -0.25_dp/l, 0.5_dp/l, 0.0_dp]
        case ("pendulum_angle", "pendulum_moving")
            q0 = [th]; v0 = [0.0_dp]
        case ("cart_pendulum")
            q0 = [0.0_dp, 3.0_dp]; v0 = [0.0_dp, 0.0_dp]
        case ("double_pendulum")
            q0 = [th, 0.5_dp]; v0 = [0.0_dp, 0.0_dp]
        case ("atwood", "yoyo_angle")
            q0 = [0.0_dp]; v0 = [0.0_dp]
        case ("spring_pendulum")
            q0 = [1.2_dp, 0.8_dp]; v0 = [0.0_dp, 0.0_dp]
        case ("double_spring_pendulum")
            q0 = [0.8_dp, -0.8_dp, 1.5_dp, -1.6_dp]; v0 = [0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp]
        case ("three_springs")
            q0 = [0.0_dp, 0.0_dp, 1.2_dp, 0.0_dp, 0.5_dp, 0.9_dp]
            v0 = [0.0_dp, 0.1_dp, 0.0_dp, -0.2_dp, 0.3_dp, 0.1_dp]
        case ("bead_hoop")
            q0 = [0.5_dp]; v0 = [0.0_dp]
        case ("polar_particle")
            q0 = [1.0_dp, 0.0_dp]; v0 = [0.0_dp, 1.2_dp]
        case default
            info = CM_BAD_INPUT
            allocate (q0(0), v0(0))
        end select
    end subroutine mech_initial_state

end module conmech_systems_mech
