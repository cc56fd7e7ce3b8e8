!> What the two forms of a mechanical system have in common, the generalized coordinates
!! of conmech_generalized and the excessive coordinates with constraints of
!! conmech_constrained_system: the mass matrix M(t, q), the applied forces Q(t, q, q')
!! (velocity terms included) and, optionally, the energy, a first integral.
module conmech_mechanical_system
    use conmech_kinds, only: dp
    implicit none
    private

    public :: mechanical_system

    type, abstract :: mechanical_system
    contains
        procedure(mech_mass), deferred :: mass
        procedure(mech_forces), deferred :: forces
        procedure :: energy => mech_no_energy
        procedure :: has_energy => mech_no_energy_given
    end type mechanical_system

    abstract interface
        !> mm = M(t, q), symmetric positive definite (a row and a column per coordinate).
        subroutine mech_mass(self, t, q, mm)
            import :: mechanical_system, dp
            class(mechanical_system), intent(in) :: self
            real(dp), intent(in) :: t
            real(dp), intent(in) :: q(:)
            real(dp), intent(out) :: mm(:, :)
        end subroutine mech_mass
        !> f = Q(t, q, v): the applied forces, the velocity terms included.
        subroutine mech_forces(self, t, q, v, f)
            import :: mechanical_system, dp
            class(mechanical_system), intent(in) :: self
            real(dp), intent(in) :: t
            real(dp), intent(in) :: q(:), v(:)
            real(dp), intent(out) :: f(:)
        end subroutine mech_forces
    end interface

contains

    !> Default energy: not defined (returns 0; `has_energy` is false).
    function mech_no_energy(self, t, q, v) result(e)
        class(mechanical_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:), v(:)
        real(dp) :: e
        e = 0.0_dp
    end function mech_no_energy

    logical function mech_no_energy_given(self)
        class(mechanical_system), intent(in) :: self
        mech_no_energy_given = .false.
    end function mech_no_energy_given

end module conmech_mechanical_system
