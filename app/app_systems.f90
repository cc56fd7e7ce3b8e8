!> What the programs need to know about the built-in systems to check a command line:
!! their names and how many parameters each takes (in the order of `make_system`,
!! `make_generalized`, `make_constrained`; missing trailing parameters keep defaults).
module app_systems
    use conmech_systems_mech, only: constrained_names, generalized_names
    implicit none
    private
    public :: ode_names, constrained_names, generalized_names, param_count, param_help

    !> First-order built-ins of `make_system` (the generalized ones are also accepted).
    character(len=*), parameter :: ode_names = "harmonic pendulum kepler arenstorf " &
        //"vanderpol hill"

contains

    !> Number of parameters of a built-in system (-1 if unknown).
    integer function param_count(name) result(np)
        character(len=*), intent(in) :: name
        select case (trim(name))
        case ("harmonic", "kepler", "arenstorf", "vanderpol")
            np = 1
        case ("pendulum", "hill", "polar_particle", "rod_two_masses")
            np = 2
        case ("pendulum_angle", "atwood", "three_springs", "pendulum_xy")
            np = 3
        case ("cart_pendulum", "spring_pendulum", "bead_hoop", "atwood_xy", "skate", &
              "rolling_disk")
            np = 4
        case ("double_pendulum", "double_pendulum_xy")
            np = 5
        case ("pendulum_moving", "pendulum_moving_xy")
            np = 6
        case ("double_spring_pendulum", "yoyo_angle", "yoyo")
            np = 7
        case default
            np = -1
        end select
    end function param_count

    !> The parameters of a system, named in order (for error messages).
    function param_help(name) result(s)
        character(len=*), intent(in) :: name
        character(len=:), allocatable :: s
        select case (trim(name))
        case ("harmonic"); s = "omega"
        case ("pendulum"); s = "g, l"
        case ("kepler", "arenstorf", "vanderpol"); s = "mu"
        case ("hill"); s = "m, kappa"
        case ("pendulum_xy", "pendulum_angle"); s = "m, g, l"
        case ("rod_two_masses"); s = "g, l"
        case ("double_pendulum_xy", "double_pendulum"); s = "m1, m2, l1, l2, g"
        case ("atwood_xy"); s = "m1, m2, g, L"
        case ("pendulum_moving_xy", "pendulum_moving"); s = "m, g, l, a, b, w"
        case ("yoyo", "yoyo_angle"); s = "m, r, I, g, ah, vh, h0"
        case ("skate"); s = "m, I, g, alpha"
        case ("rolling_disk"); s = "m, R, I_roll, I_turn"
        case ("cart_pendulum"); s = "M, m, l, g"
        case ("atwood"); s = "m1, m2, g"
        case ("spring_pendulum"); s = "m, k, l0, g"
        case ("double_spring_pendulum"); s = "m1, m2, k1, k2, l1, l2, g"
        case ("three_springs"); s = "m, k, l0"
        case ("bead_hoop"); s = "m, R, omega, g"
        case ("polar_particle"); s = "m, mu"
        case default; s = ""
        end select
    end function param_help

end module app_systems
