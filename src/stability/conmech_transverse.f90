!> Transverse linearisation (as in the lecture notes) of a periodic orbit of any autonomous
!! two-degree-of-freedom system of the form
!!
!!     q'' = -grad V(q) + 2 Omega J q',   J = [0 -1; 1 0],   E = |q'|^2/2 + V(q)
!!
!! (a natural system, optionally in a frame rotating at a constant rate: gyroscopic term
!! 2 Omega J q'; Hill's problem is V = -F, Omega = -m; Henon-Heiles is Omega = 0).
!! Along the orbit, with the unit tangent tau = q'/|q'|, the normal n = J tau and the
!! turning rate of the tangent phi' = -n . grad V/|q'| + 2 Omega, the normal deviation N of
!! an isoenergetic perturbation (delta E = 0) obeys Hill's equation
!!
!!     N'' + Phi(t) N = 0,   Phi = n^T (Hess V) n + 3 (phi' - Omega)^2 + Omega^2,
!!
!! (for Omega = 0 the classical n^T V'' n + 3 (n . grad V)^2/|q'|^2; for Hill's problem the
!! seed's 3 (omega + m)^2 + m^2 - n^T F'' n). The 2 x 2 monodromy of this equation over the
!! period has the non-trivial multipliers of the 4 x 4 monodromy (the trivial pair belongs
!! to the phase along the orbit and to the energy). The orbit must not stop (|q'| > 0).
!!
!! A system is an extension of `planar_natural_system` that provides `potential` (V, its
!! gradient and Hessian) and sets `omega`; its right-hand side and analytic Jacobian are
!! generic, so the same object runs in every integrator and in the shooting methods.
module conmech_transverse
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_ode_options, only: tolerance_options
    use conmech_ode_solver, only: ode_options, ode_integrate, METHOD_DOP853
    use conmech_floquet, only: multipliers_2x2
    implicit none
    private

    public :: planar_natural_system, transverse_result, transverse_monodromy, transverse_phi

    !> q'' = -grad V + 2 omega J q' with y = [q1, q2, q1', q2'].
    type, abstract, extends(ode_system) :: planar_natural_system
        real(dp) :: omega = 0.0_dp   !! rotation rate of the frame (gyroscopic term)
    contains
        procedure(potential_proc), deferred :: potential
        procedure :: rhs => pn_rhs
        procedure :: jacobian => pn_jac
        procedure :: has_jacobian => pn_has_jac
        procedure :: energy => pn_energy
    end type planar_natural_system

    abstract interface
        !> V(q), its gradient g and Hessian h.
        subroutine potential_proc(self, q, v, g, h)
            import :: planar_natural_system, dp
            class(planar_natural_system), intent(in) :: self
            real(dp), intent(in) :: q(2)
            real(dp), intent(out) :: v, g(2), h(2, 2)
        end subroutine potential_proc
    end interface

    !> Result of `transverse_monodromy`.
    type :: transverse_result
        integer :: info = CM_BAD_INPUT
        character(len=:), allocatable :: message
        real(dp) :: monodromy(2, 2) = 0.0_dp  !! of N'' + Phi N = 0 over the period
        real(dp) :: half_trace = 0.0_dp       !! (M11 + M22)/2 = S of the 4 x 4 monodromy
        real(dp) :: det = 0.0_dp              !! 1 up to the integration error
        real(dp) :: mr(2) = 0.0_dp, mi(2) = 0.0_dp  !! its multipliers
        real(dp) :: closure = 0.0_dp          !! max |y(T) - y0| of the orbit integrated
    end type transverse_result

    !> The orbit with two solutions of N'' + Phi N = 0 appended (internal).
    type, extends(ode_system) :: transverse_ode
        class(planar_natural_system), allocatable :: base
    contains
        procedure :: rhs => tr_rhs
    end type transverse_ode

contains

    subroutine pn_rhs(self, t, y, dydt)
        class(planar_natural_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: v, g(2), h(2, 2)
        call self%potential(y(1:2), v, g, h)
        dydt(1) = y(3)
        dydt(2) = y(4)
        dydt(3) = -g(1) - 2.0_dp*self%omega*y(4)
        dydt(4) = -g(2) + 2.0_dp*self%omega*y(3)
    end subroutine pn_rhs

    subroutine pn_jac(self, t, y, dfdy)
        class(planar_natural_system), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dfdy(:, :)
        real(dp) :: v, g(2), h(2, 2)
        call self%potential(y(1:2), v, g, h)
        dfdy = 0.0_dp
        dfdy(1, 3) = 1.0_dp
        dfdy(2, 4) = 1.0_dp
        dfdy(3:4, 1:2) = -h
        dfdy(3, 4) = -2.0_dp*self%omega
        dfdy(4, 3) = 2.0_dp*self%omega
    end subroutine pn_jac

    logical function pn_has_jac(self)
        class(planar_natural_system), intent(in) :: self
        pn_has_jac = .true.
    end function pn_has_jac

    !> E = |q'|^2/2 + V(q).
    real(dp) function pn_energy(self, y) result(e)
        class(planar_natural_system), intent(in) :: self
        real(dp), intent(in) :: y(:)
        real(dp) :: v, g(2), h(2, 2)
        call self%potential(y(1:2), v, g, h)
        e = 0.5_dp*(y(3)**2 + y(4)**2) + v
    end function pn_energy

    !> Phi at the orbit point s = [q, q'] (see the module notes).
    real(dp) function transverse_phi(sys, s) result(p)
        class(planar_natural_system), intent(in) :: sys
        real(dp), intent(in) :: s(4)
        real(dp) :: sp, n(2), v, g(2), h(2, 2), turn
        sp = sqrt(s(3)**2 + s(4)**2)
        n = [-s(4), s(3)]/sp
        call sys%potential(s(1:2), v, g, h)
        turn = -dot_product(n, g)/sp + 2.0_dp*sys%omega
        p = dot_product(n, matmul(h, n)) + 3.0_dp*(turn - sys%omega)**2 + sys%omega**2
    end function transverse_phi

    subroutine tr_rhs(self, t, y, dydt)
        class(transverse_ode), intent(in) :: self
        real(dp), intent(in) :: t
        real(dp), intent(in) :: y(:)
        real(dp), intent(out) :: dydt(:)
        real(dp) :: p
        call self%base%rhs(t, y(1:4), dydt(1:4))
        p = transverse_phi(self%base, y(1:4))
        dydt(5) = y(6)
        dydt(6) = -p*y(5)
        dydt(7) = y(8)
        dydt(8) = -p*y(7)
    end subroutine tr_rhs

    !> Integrate the orbit through y0 with N'' + Phi(t) N = 0 over `period` (DOP853 at
    !! rtol = atol = `rtol`, default 1e-12) and return the 2 x 2 monodromy and its
    !! multipliers. info CM_BAD_INPUT for a bad orbit (non-positive period, |q'| = 0).
    subroutine transverse_monodromy(sys, y0, period, res, rtol)
        class(planar_natural_system), intent(in) :: sys
        real(dp), intent(in) :: y0(4), period
        type(transverse_result), intent(out) :: res
        real(dp), intent(in), optional :: rtol
        type(transverse_ode) :: ts
        type(ode_options) :: opt
        real(dp) :: z(8)
        character(len=:), allocatable :: msg
        if (.not. (period > 0.0_dp) .or. .not. all(abs(y0) <= huge(1.0_dp)) .or. &
            .not. (y0(3)**2 + y0(4)**2 > 0.0_dp)) then
            res%info = CM_BAD_INPUT
            res%message = "transverse_monodromy: need period > 0, finite y0, |q'| > 0"
            return
        end if
        opt = tolerance_options(1.0e-12_dp, rtol)
        opt%method = METHOD_DOP853
        if (.not. (opt%rtol > 0.0_dp .and. opt%rtol < 1.0_dp)) then
            res%info = CM_BAD_INPUT
            res%message = "transverse_monodromy: rtol must be in (0, 1)"
            return
        end if
        allocate (ts%base, source=sys)
        z = [y0, 1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp]
        call ode_integrate(ts, 0.0_dp, period, z, opt, res%info, message=msg)
        res%message = msg
        if (res%info < 0) return
        if (.not. all(abs(z) <= huge(1.0_dp))) then
            res%info = CM_NONFINITE
            res%message = "transverse_monodromy: non-finite values (the orbit stops?)"
            return
        end if
        res%monodromy = reshape(z(5:8), [2, 2])
        res%half_trace = 0.5_dp*(z(5) + z(8))
        res%det = z(5)*z(8) - z(6)*z(7)
        res%closure = maxval(abs(z(1:4) - y0))
        call multipliers_2x2(res%half_trace, res%det, res%mr, res%mi)
        res%info = CM_SUCCESS
        res%message = "success"
    end subroutine transverse_monodromy

end module conmech_transverse
