!> integrate_stm on linear systems y' = J y of every product kernel: n = 4 and 6 (constant
!! sizes), 5 and 8 (any n <= 16), 17 and 18 (dgemm), each in the first-order mechanical
!! form J = [0 I; A B] where n is even and in general form: the STM agrees with the
!! columns integrated one by one (the solution from e_j is column j of the STM), and the
!! state is Phi y0 to round-off (an RK step is linear in the state).
module variational_test_systems
    use conmech_kinds, only: dp
    use conmech_ode_system, only: ode_system
    implicit none
    private
    public :: linear_system

    !> y' = J y with a constant J (analytic Jacobian).
    type, extends(ode_system) :: linear_system
        real(dp), allocatable :: j(:, :)
    contains
        procedure :: rhs => lin_rhs
        procedure :: jacobian => lin_jac
        procedure :: has_jacobian => lin_has
    end type linear_system

contains

    subroutine lin_rhs(self, t, y, dydt)
        class(linear_system), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dydt(:)
        dydt = matmul(self%j, y)
    end subroutine lin_rhs

    subroutine lin_jac(self, t, y, dfdy)
        class(linear_system), intent(in) :: self
        real(dp), intent(in) :: t, y(:)
        real(dp), intent(out) :: dfdy(:, :)
        dfdy = self%j
    end subroutine lin_jac

    logical function lin_has(self)
        class(linear_system), intent(in) :: self
        lin_has = .true.
    end function lin_has

end module variational_test_systems

program test_variational
    use conmech
    use conmech_testing, only: test_suite
    use variational_test_systems, only: linear_system
    implicit none
    type(test_suite) :: ts
    integer, parameter :: sizes(6) = [4, 5, 6, 8, 17, 18]
    integer :: k, mech
    character(len=40) :: label

    ts%name = "test_variational"
    do k = 1, size(sizes)
        do mech = 0, 1
            if (mech == 1 .and. mod(sizes(k), 2) /= 0) cycle
            write (label, '(a,i0,a)') "n = ", sizes(k), merge(", [0 I; A B]", ",   general ", &
                                                              mech == 1)
            call check_size(sizes(k), mech == 1, trim(label))
        end do
    end do
    call ts%finish()

contains

    subroutine check_size(n, mechanical, label)
        integer, intent(in) :: n
        logical, intent(in) :: mechanical
        character(len=*), intent(in) :: label
        type(linear_system) :: sys
        type(ode_options) :: opt
        real(dp) :: y(n), phi(n, n), col(n), err
        integer :: i, j, info, m
        allocate (sys%j(n, n))
        ! a full, well-scaled J with eigenvalues of moderate size
        do j = 1, n
            do i = 1, n
                sys%j(i, j) = 0.3_dp*sin(1.7_dp*i + 0.9_dp*j**2)
            end do
        end do
        if (mechanical) then
            m = n/2
            sys%j(1:m, :) = 0.0_dp
            do i = 1, m
                sys%j(i, m + i) = 1.0_dp
            end do
        end if
        opt%method = METHOD_DOP853
        opt%rtol = 1.0e-11_dp
        opt%atol = 1.0e-11_dp
        y = [(cos(0.5_dp*i), i=1, n)]
        phi = 0.0_dp
        do i = 1, n
            phi(i, i) = 1.0_dp
        end do
        call integrate_stm(sys, 0.0_dp, 1.5_dp, y, phi, opt, info)
        call ts%check(info == CM_SUCCESS, label//": integrate_stm succeeds")
        err = 0.0_dp
        do j = 1, n
            col = 0.0_dp
            col(j) = 1.0_dp
            call ode_integrate(sys, 0.0_dp, 1.5_dp, col, opt, info)
            err = max(err, maxval(abs(phi(:, j) - col)))
        end do
        call ts%check_less(err, 1.0e-10_dp, label//": STM = columns integrated one by one")
        ! the state: the same linear map applied to y0
        col = [(cos(0.5_dp*i), i=1, n)]
        call ts%check_less(maxval(abs(y - matmul(phi, col))), 1.0e-12_dp, &
                           label//": y(t) = Phi y0")
    end subroutine check_size

end program test_variational
