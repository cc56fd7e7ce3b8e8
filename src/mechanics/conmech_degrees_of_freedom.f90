!> Degrees of freedom of a constrained mechanical system: n coordinates minus the number of
!! independent holonomic constraints (the lecture notes' n = 3N - R); Pfaffian
!! (non-holonomic) constraints do not reduce them, they reduce only the independent
!! velocities.
!!
!! Independence is the rank of the constraint Jacobians at a point of the constraint
!! manifold (LAPACK's SVD, singular values <= rank_tol sigma_max counted as zero):
!!
!!     rank_h = rank G(t, q),   rank_c = rank [G(t, q); A(t, q)],
!!     degrees of freedom = n - rank_h,   velocity degrees of freedom = n - rank_c,
!!
!! and rank_c - rank_h is the number of independent non-holonomic constraints. Redundant
!! constraints (a rank below the number of rows) are counted once. The rank is that at the
!! given configuration: at a singular configuration of a mechanism it can drop.
module conmech_degrees_of_freedom
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_constrained_system, only: constrained_system, project_position
    use conmech_rank, only: singular_values
    implicit none
    private

    public :: dof_result, degrees_of_freedom

    !> Result of `degrees_of_freedom`.
    type :: dof_result
        integer :: info = CM_BAD_INPUT
        character(len=:), allocatable :: message
        integer :: n = 0                  !! number of coordinates
        integer :: rank_h = 0             !! independent holonomic constraints
        integer :: rank_nh = 0            !! independent non-holonomic constraints
        integer :: dof = 0                !! n - rank_h
        integer :: velocity_dof = 0       !! n - rank_h - rank_nh
        real(dp), allocatable :: q(:)     !! the configuration the ranks were taken at
        real(dp) :: residual = 0.0_dp     !! max |phi(t, q)| there
    end type dof_result

contains

    !> Degrees of freedom at (t, q). With `project` (default true) q is first moved onto the
    !! constraint manifold phi = 0 by Gauss-Newton (project_position); a configuration that
    !! cannot reach it is an error (CM_NO_CONVERGENCE), as the ranks off the manifold need
    !! not be those on it. rank_tol: relative rank tolerance (default 1e-10).
    subroutine degrees_of_freedom(sys, t, q, res, project, rank_tol)
        class(constrained_system), intent(in) :: sys
        real(dp), intent(in) :: t
        real(dp), intent(in) :: q(:)
        type(dof_result), intent(out) :: res
        logical, intent(in), optional :: project
        real(dp), intent(in), optional :: rank_tol
        real(dp), allocatable :: c(:, :), b(:), s(:), ph(:)
        real(dp) :: rt
        integer :: n, mh, mn, iters, rc
        logical :: proj
        character(len=:), allocatable :: msg
        n = sys%n
        mh = sys%n_hol
        mn = sys%n_nh
        res%n = n
        proj = .true.
        if (present(project)) proj = project
        rt = 1.0e-10_dp
        if (present(rank_tol)) rt = rank_tol
        if (size(q) /= n .or. n < 1 .or. .not. (rt > 0.0_dp .and. rt < 1.0_dp)) then
            res%info = CM_BAD_INPUT
            res%message = "degrees_of_freedom: q must have n components, 0 < rank_tol < 1"
            return
        end if
        res%q = q
        if (mh > 0) then
            if (proj) then
                call project_position(sys, t, res%q, 1.0e-12_dp, 50, iters, res%info, msg, &
                                      newton=.true.)
                if (res%info /= CM_SUCCESS) then
                    res%message = "degrees_of_freedom: no point of the constraint manifold "// &
                                  "reached from q ("//msg//")"
                    return
                end if
            end if
            allocate (ph(mh))
            call sys%phi(t, res%q, ph)
            res%residual = maxval(abs(ph))
        end if
        allocate (c(mh + mn, n), b(max(mn, 1)))
        if (mh > 0) call sys%phi_jac(t, res%q, c(1:mh, :))
        if (mn > 0) call sys%nh_matrix(t, res%q, c(mh + 1:mh + mn, :), b(1:mn))
        res%rank_h = 0
        if (mh > 0) then
            allocate (s(min(mh, n)))
            call singular_values(c(1:mh, :), s, res%info)
            if (res%info /= CM_SUCCESS) then
                res%message = "degrees_of_freedom: SVD of G: "//status_message(res%info)
                return
            end if
            res%rank_h = count(s > rt*max(s(1), tiny(1.0_dp)))
            deallocate (s)
        end if
        rc = res%rank_h
        if (mn > 0) then
            allocate (s(min(mh + mn, n)))
            call singular_values(c, s, res%info)
            if (res%info /= CM_SUCCESS) then
                res%message = "degrees_of_freedom: SVD of [G; A]: "//status_message(res%info)
                return
            end if
            rc = count(s > rt*max(s(1), tiny(1.0_dp)))
        end if
        res%rank_nh = rc - res%rank_h
        res%dof = n - res%rank_h
        res%velocity_dof = n - rc
        res%info = CM_SUCCESS
        res%message = "success"
    end subroutine degrees_of_freedom

end module conmech_degrees_of_freedom
