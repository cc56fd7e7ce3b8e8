!> The energy (first integral) of a built-in or compiled first-order system at a state,
!! for every system that has one:
!!
!! - harmonic: (v^2 + omega^2 x^2)/2; pendulum: v^2/2 - (g/l) cos theta; kepler:
!!   |v|^2/2 - mu/r (their own `energy`);
!! - the rotating-frame problems, their Jacobi integral: arenstorf and cr3bp
!!   C = 2 Omega - |v|^2; hill and hill_spatial I = |v|^2 - 2 F;
!! - systems in generalized coordinates, y = [q, q'] (the built-in seed systems, compiled
!!   and symbolic Lagrangian systems with an energy entry): the mechanical system's
!!   energy T + U (the Jacobi integral for rheonomic or gyroscopic ones).
!!
!! Other systems (Van der Pol, a compiled first-order system) have none: info
!! CM_BAD_INPUT with a message naming the system.
module conmech_system_energy
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_generalized, only: generalized_ode
    use conmech_systems_basic, only: harmonic_oscillator, pendulum_theta, kepler_2d, arenstorf
    use conmech_hill, only: hill_problem
    use conmech_hill_spatial, only: hill_spatial
    use conmech_cr3bp, only: cr3bp, cr3bp_jacobi
    implicit none
    private
    public :: system_energy, system_has_energy

    integer, parameter :: NO_ENERGY = 0    !! `energy_of`: the system has no energy
    integer, parameter :: EVEN_SIZE = -1   !! `energy_of`: y = [q, q'] of any even size

contains

    !> Whether `sys` has an energy that `system_energy` evaluates.
    logical function system_has_energy(sys) result(has)
        class(ode_system), intent(in) :: sys
        real(dp) :: e, y(0)
        integer :: need
        e = energy_of(sys, 0.0_dp, y, need)
        has = need /= NO_ENERGY
    end function system_has_energy

    !> e = the energy of `sys` at (t, y) (see the module notes); info CM_BAD_INPUT if the
    !! system has none or y has the wrong size for it.
    subroutine system_energy(sys, t, y, e, info, msg)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: e
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: need
        e = energy_of(sys, t, y, need)
        info = CM_BAD_INPUT
        if (need == NO_ENERGY) then
            msg = "bad input: the system defines no energy (first integral)"
        else if (need == EVEN_SIZE .and. (mod(size(y), 2) /= 0 .or. size(y) == 0)) then
            msg = "bad input: a system in generalized coordinates has y = [q, q'] "// &
                  "(an even, positive size)"
        else if (need /= EVEN_SIZE .and. size(y) /= need) then
            msg = "bad input: y has the wrong size for the system"
        else
            info = CM_SUCCESS
            msg = "success"
        end if
    end subroutine system_energy

    !> The one table of the energies: the energy of `sys` at (t, y), or 0 when y does not
    !! have the size it takes; `need` is that size (EVEN_SIZE: any even size, y = [q, q']
    !! in generalized coordinates; NO_ENERGY: the system has none).
    function energy_of(sys, t, y, need) result(e)
        class(ode_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        integer, intent(out) :: need
        real(dp) :: e
        integer :: nd
        e = 0.0_dp
        need = NO_ENERGY
        select type (sys)
        type is (harmonic_oscillator)
            if (fits(2)) e = 0.5_dp*(y(2)**2 + sys%omega**2*y(1)**2)
        type is (pendulum_theta)
            if (fits(2)) e = sys%energy(y)
        type is (kepler_2d)
            if (fits(4)) e = sys%energy(y)
        type is (arenstorf)
            if (fits(4)) e = cr3bp_jacobi(sys%mu, [y(1), y(2), 0.0_dp, y(3), y(4), 0.0_dp])
        type is (hill_problem)
            if (fits(4)) e = sys%jacobi(y)
        type is (hill_spatial)
            if (fits(6)) e = sys%jacobi(y)
        type is (cr3bp)
            if (fits(6)) e = sys%jacobi(y)
        class is (generalized_ode)
            if (.not. sys%mech%has_energy()) return
            need = EVEN_SIZE
            nd = size(y)/2
            if (size(y) > 0 .and. 2*nd == size(y)) e = sys%mech%energy(t, y(1:nd), y(nd + 1:))
        end select
    contains
        !> The energy takes n components (recorded in `need`): does y have them?
        logical function fits(n)
            integer, intent(in) :: n
            need = n
            fits = size(y) == n
        end function fits
    end function energy_of

end module conmech_system_energy
