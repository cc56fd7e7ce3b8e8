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

contains

    !> Whether `sys` has an energy that `system_energy` evaluates.
    logical function system_has_energy(sys) result(has)
        class(ode_system), intent(in) :: sys
        select type (sys)
        type is (harmonic_oscillator)
            has = .true.
        type is (pendulum_theta)
            has = .true.
        type is (kepler_2d)
            has = .true.
        type is (arenstorf)
            has = .true.
        type is (hill_problem)
            has = .true.
        type is (hill_spatial)
            has = .true.
        type is (cr3bp)
            has = .true.
        class is (generalized_ode)
            has = sys%mech%has_energy()
        class default
            has = .false.
        end select
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
        integer :: nd
        e = 0.0_dp
        info = CM_BAD_INPUT
        msg = "bad input: the system defines no energy (first integral)"
        select type (sys)
        type is (harmonic_oscillator)
            if (.not. size_ok(2)) return
            e = 0.5_dp*(y(2)**2 + sys%omega**2*y(1)**2)
        type is (pendulum_theta)
            if (.not. size_ok(2)) return
            e = sys%energy(y)
        type is (kepler_2d)
            if (.not. size_ok(4)) return
            e = sys%energy(y)
        type is (arenstorf)
            if (.not. size_ok(4)) return
            e = cr3bp_jacobi(sys%mu, [y(1), y(2), 0.0_dp, y(3), y(4), 0.0_dp])
        type is (hill_problem)
            if (.not. size_ok(4)) return
            e = sys%jacobi(y)
        type is (hill_spatial)
            if (.not. size_ok(6)) return
            e = sys%jacobi(y)
        type is (cr3bp)
            if (.not. size_ok(6)) return
            e = sys%jacobi(y)
        class is (generalized_ode)
            if (.not. sys%mech%has_energy()) return
            if (mod(size(y), 2) /= 0) then
                msg = "bad input: a system in generalized coordinates has y = [q, q'] "// &
                      "(an even size)"
                return
            end if
            nd = size(y)/2
            e = sys%mech%energy(t, y(1:nd), y(nd + 1:))
        class default
            return
        end select
        info = CM_SUCCESS
        msg = "success"
    contains
        logical function size_ok(n)
            integer, intent(in) :: n
            size_ok = size(y) == n
            if (.not. size_ok) msg = "bad input: y has the wrong size for the system"
        end function size_ok
    end subroutine system_energy

end module conmech_system_energy
