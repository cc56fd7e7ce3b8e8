!> Degrees of freedom of the built-in constrained systems: coordinates minus independent
!! holonomic constraints (seed 002: n = 3N - R; non-holonomic constraints do not reduce it),
!! and the independent velocities (the rubber ball's 2, seed 001).
program test_degrees_of_freedom
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_constrained_system, only: constrained_system
    use conmech_systems_mech, only: make_constrained, mech_initial_state
    use conmech_degrees_of_freedom, only: dof_result, degrees_of_freedom
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    ts%name = "test_degrees_of_freedom"

    call check("pendulum_xy", 1, 1)
    call check("rod_two_masses", 3, 2)
    call check("double_pendulum_xy", 2, 2)
    call check("atwood_xy", 1, 1)
    call check("pendulum_moving_xy", 1, 1)
    call check("yoyo", 1, 1)
    call check("skate", 3, 2)
    call check("rolling_disk", 4, 2)
    call check("rolling_ball", 5, 2)
    call check_off_manifold()
    call ts%finish()

contains

    subroutine check(name, dof, vdof)
        character(len=*), intent(in) :: name
        integer, intent(in) :: dof, vdof
        class(constrained_system), allocatable :: sys
        type(dof_result) :: r
        real(dp), allocatable :: q0(:), v0(:)
        real(dp) :: none(0)
        integer :: info
        character(len=:), allocatable :: msg
        call make_constrained(name, none, sys, info, msg)
        call mech_initial_state(name, none, q0, v0, info)
        call degrees_of_freedom(sys, 0.0_dp, q0, r)
        call ts%check(r%info == CM_SUCCESS .and. r%dof == dof .and. r%velocity_dof == vdof &
                      .and. r%dof == sys%n - r%rank_h .and. r%residual <= 1.0e-12_dp, &
                      name//": degrees of freedom and independent velocities")
    end subroutine check

    !> A configuration off the manifold is projected first; without the projection the
    !! residual shows it.
    subroutine check_off_manifold()
        class(constrained_system), allocatable :: sys
        type(dof_result) :: r
        real(dp) :: none(0)
        integer :: info
        character(len=:), allocatable :: msg
        call make_constrained("double_pendulum_xy", none, sys, info, msg)
        call degrees_of_freedom(sys, 0.0_dp, [0.3_dp, -0.5_dp, 0.9_dp, -1.7_dp], r)
        call ts%check(r%info == CM_SUCCESS .and. r%dof == 2 .and. r%residual <= 1.0e-12_dp, &
                      "double pendulum: projected onto the manifold, 2 degrees of freedom")
        call degrees_of_freedom(sys, 0.0_dp, [0.3_dp, -0.5_dp, 0.9_dp, -1.7_dp], r, &
                                project=.false.)
        call ts%check(r%info == CM_SUCCESS .and. r%residual > 1.0e-3_dp, &
                      "double pendulum: unprojected, the residual is reported")
        call degrees_of_freedom(sys, 0.0_dp, [0.3_dp], r)
        call ts%check(r%info == CM_BAD_INPUT, "wrong size of q: bad input")
    end subroutine check_off_manifold

end program test_degrees_of_freedom
