!> The parameters of the built-in systems by name: how many each takes and their names in
!! the documented order (missing trailing parameters keep their defaults; more than the
!! system has is an error in every registry: `make_system`, `make_generalized`,
!! `make_constrained`, and so in the programs and the Python package).
module conmech_systems_params
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    implicit none
    private
    public :: builtin_param_count, builtin_param_names, check_param_count

contains

    !> Number of parameters of a built-in system (-1 if the name is unknown).
    pure integer function builtin_param_count(name) result(np)
        character(len=*), intent(in) :: name
        select case (trim(name))
        case ("harmonic", "kepler", "arenstorf", "vanderpol", "cr3bp")
            np = 1
        case ("pendulum", "hill", "hill_spatial", "polar_particle", "rod_two_masses")
            np = 2
        case ("pendulum_angle", "atwood", "three_springs", "pendulum_xy")
            np = 3
        case ("cart_pendulum", "spring_pendulum", "bead_hoop", "atwood_xy", "skate", &
              "rolling_disk", "pendulum_chain_xy")
            np = 4
        case ("double_pendulum", "double_pendulum_xy", "rolling_ball")
            np = 5
        case ("pendulum_moving", "pendulum_moving_xy")
            np = 6
        case ("double_spring_pendulum", "yoyo_angle", "yoyo")
            np = 7
        case default
            np = -1
        end select
    end function builtin_param_count

    !> The parameters of a built-in system, named in order ("" if unknown).
    pure function builtin_param_names(name) result(s)
        character(len=*), intent(in) :: name
        character(len=:), allocatable :: s
        select case (trim(name))
        case ("harmonic"); s = "omega"
        case ("pendulum"); s = "g, l"
        case ("kepler", "arenstorf", "vanderpol", "cr3bp"); s = "mu"
        case ("hill", "hill_spatial"); s = "m, kappa"
        case ("pendulum_xy", "pendulum_angle"); s = "m, g, l"
        case ("rod_two_masses"); s = "g, l"
        case ("double_pendulum_xy", "double_pendulum"); s = "m1, m2, l1, l2, g"
        case ("atwood_xy"); s = "m1, m2, g, L"
        case ("pendulum_moving_xy", "pendulum_moving"); s = "m, g, l, a, b, w"
        case ("yoyo", "yoyo_angle"); s = "m, r, I, g, ah, vh, h0"
        case ("skate"); s = "m, I, g, alpha"
        case ("rolling_disk"); s = "m, R, I_roll, I_turn"
        case ("pendulum_chain_xy"); s = "N, m, l, g"
        case ("rolling_ball"); s = "m, R, I, g, alpha"
        case ("cart_pendulum"); s = "M, m, l, g"
        case ("atwood"); s = "m1, m2, g"
        case ("spring_pendulum"); s = "m, k, l0, g"
        case ("double_spring_pendulum"); s = "m1, m2, k1, k2, l1, l2, g"
        case ("three_springs"); s = "m, k, l0"
        case ("bead_hoop"); s = "m, R, omega, g"
        case ("polar_particle"); s = "m, mu"
        case default; s = ""
        end select
    end function builtin_param_names

    !> info = CM_BAD_INPUT with a message naming the system and its parameters when more
    !! parameters are given than the built-in `name` has (unknown names pass: the
    !! registry reports them).
    subroutine check_param_count(name, nparams, info, msg)
        character(len=*), intent(in) :: name
        integer, intent(in) :: nparams
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: np
        character(len=12) :: a, b
        np = builtin_param_count(name)
        info = CM_SUCCESS
        msg = "success"
        if (np < 0 .or. nparams <= np) return
        write (a, '(i0)') nparams
        write (b, '(i0)') np
        info = CM_BAD_INPUT
        msg = "bad input: "//trim(a)//" parameters given for the system '"//trim(name)// &
              "', which has "//trim(b)//" ("//builtin_param_names(name)//")"
    end subroutine check_param_count

end module conmech_systems_params
