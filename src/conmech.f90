!> The umbrella module of conmech, mechanical systems with constraints and the stability of
!! their motions.
!!
!! `use conmech` gives the public API of every layer.
module conmech
    use conmech_kinds
    use conmech_status
    use conmech_lapack, only: la_solve, la_eig, la_sym_eig, la_det
    use conmech_ode_system
    use conmech_ode_solver
    use conmech_systems_basic
    use conmech_systems
    use conmech_generalized
    use conmech_c_system
    use conmech_c_mechanics
    use conmech_constrained_system
    use conmech_constrained_solver
    use conmech_rattle
    use conmech_rattle_stepper
    use conmech_radau
    use conmech_radau_stepper
    use conmech_gauss
    use conmech_systems_generalized
    use conmech_systems_constrained
    use conmech_systems_mech
    use conmech_model_library
    use conmech_hill
    use conmech_equilibria
    use conmech_jordan
    use conmech_relative_equilibria
    use conmech_degrees_of_freedom
    use conmech_variational
    use conmech_floquet
    use conmech_shooting
    use conmech_hill_orbit
    use conmech_ensemble
    use conmech_hill_family
    use conmech_continuation
    use conmech_transverse
    use conmech_rotation_log
    use conmech_transverse_model
    use conmech_transverse_mech
    use conmech_transverse_general
    use conmech_control_system
    use conmech_mech_plant
    use conmech_vhc
    use conmech_periodic_riccati
    use conmech_transverse_lqr
    use conmech_orbital_stabilisation
    use conmech_param_system
    use conmech_branch_switch
    use conmech_cr3bp
    use conmech_hill_spatial
    use conmech_system_energy
    use conmech_hopf
    use conmech_equilibrium_continuation
    use conmech_periodic_multipliers
    use conmech_periodic_schur
    use conmech_block_chain
    use conmech_taylor_stepper
    implicit none
    public
end module conmech
