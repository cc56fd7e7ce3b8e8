!> Support of the flat layer for the general transverse linearisation (compiled, not
!! wrapped): the system and its transverse model from a built-in name or a compiled spec,
!! the model with a Python energy gradient (conmech_flat_adapters, re-exported), and the packing of a `transverse_frame` into the
!! flat routine's output arrays.
!!
!! Callback convention: egrad(t, y, g, n), real(c_double) t, y(n), g(n); integer(c_int) n.
module conmech_support_transverse_general
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t
    use conmech_kinds, only: dp, nan_dp
    use conmech_status
    use conmech_ode_system, only: ode_system
    use conmech_generalized, only: generalized_system, generalized_ode
    use conmech_constrained_system, only: constrained_system
    use conmech_flat_spec, only: spec_kind, spec_system, spec_generalized, spec_constrained, &
                                 KIND_BUILTIN, KIND_ODE, KIND_GENERALIZED, KIND_CONSTRAINED
    use conmech_transverse_model, only: transverse_model
    use conmech_hill, only: hill_problem, hill_grad_f
    use conmech_systems_basic, only: kepler_2d
    use conmech_transverse_mech, only: generalized_model, constrained_model, constrained_index1
    use conmech_transverse_general, only: transverse_frame, transverse_eval, transverse_hill
    use conmech_flat_adapters, only: callback_energy_model
    implicit none
    private
    public :: callback_energy_model, system_and_model, pack_frame

    !> The conserved quantity of a built-in first-order system: Hill's Jacobi integral,
    !! the Kepler energy.
    type, extends(transverse_model) :: builtin_energy_model
        class(ode_system), allocatable :: sys
    contains
        procedure :: has_energy => bem_has_energy
        procedure :: energy => bem_energy
        procedure :: energy_gradient => bem_energy_gradient
    end type builtin_energy_model

contains

    logical function bem_has_energy(self)
        class(builtin_energy_model), intent(in) :: self
        bem_has_energy = .false.
        select type (s => self%sys)
        type is (hill_problem)
            bem_has_energy = .true.
        type is (kepler_2d)
            bem_has_energy = .true.
        end select
    end function bem_has_energy

    real(dp) function bem_energy(self, t, x) result(e)
        class(builtin_energy_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        e = 0.0_dp
        select type (s => self%sys)
        type is (hill_problem)
            e = s%jacobi(x)
        type is (kepler_2d)
            e = s%energy(x)
        end select
    end function bem_energy

    !> The exact gradient (Hill: C = |v|^2 - 2 F; Kepler: E = |v|^2/2 - mu/r).
    subroutine bem_energy_gradient(self, t, x, g)
        class(builtin_energy_model), intent(in) :: self
        real(dp), intent(in) :: t, x(:)
        real(dp), intent(out) :: g(:)
        real(dp) :: fx, fy, r3
        g = 0.0_dp
        select type (s => self%sys)
        type is (hill_problem)
            call hill_grad_f(s%m, s%kappa, x(1), x(2), fx, fy)
            g = [-2.0_dp*fx, -2.0_dp*fy, 2.0_dp*x(3), 2.0_dp*x(4)]
        type is (kepler_2d)
            r3 = sqrt(x(1)**2 + x(2)**2)**3
            g = [s%mu*x(1)/r3, s%mu*x(2)/r3, x(3), x(4)]
        end select
    end subroutine bem_energy_gradient

    !> The first-order system and its transverse model: a generalized system (built-in or
    !! compiled: its energy), a constrained one (index-1 form; its manifold normals and
    !! energy; rheonomic refused) or any other first-order system (no invariants).
    !! `kind` returns 0 (ode), 2 (generalized), 1 (constrained).
    subroutine system_and_model(name, params, nspec, spec, sys, model, kind, info, msg)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:)
        integer, intent(in) :: nspec
        integer(c_int64_t), intent(in) :: spec(:)
        class(ode_system), allocatable, intent(out) :: sys
        class(transverse_model), allocatable, intent(out) :: model
        integer, intent(out) :: kind, info
        character(len=:), allocatable, intent(out) :: msg
        class(generalized_system), allocatable :: gs
        class(constrained_system), allocatable :: cs
        integer :: sk
        sk = spec_kind(nspec, spec)
        kind = 0
        info = CM_BAD_INPUT
        if (sk == KIND_BUILTIN .or. sk == KIND_GENERALIZED) then
            call spec_generalized(name, params, nspec, spec, gs, info, msg)
            if (info == CM_SUCCESS) then
                kind = 2
                block
                    type(generalized_ode) :: w
                    type(generalized_model) :: gm
                    allocate (gm%mech, source=gs)
                    call move_alloc(gs, w%mech)
                    allocate (sys, source=w)
                    allocate (model, source=gm)
                end block
                return
            end if
        end if
        if (sk == KIND_BUILTIN .or. sk == KIND_CONSTRAINED) then
            call spec_constrained(name, params, nspec, spec, cs, info, msg)
            if (info == CM_SUCCESS) then
                kind = 1
                if (cs%rheonomic) then
                    info = CM_BAD_INPUT
                    msg = "transverse: a rheonomic (time-dependent) constrained system has "// &
                          "no periodic orbits in this sense"
                    return
                end if
                block
                    type(constrained_index1) :: w
                    type(constrained_model) :: cm
                    allocate (cm%mech, source=cs)
                    call move_alloc(cs, w%mech)
                    allocate (sys, source=w)
                    allocate (model, source=cm)
                end block
                return
            end if
        end if
        if (sk == KIND_BUILTIN .or. sk == KIND_ODE) then
            call spec_system(name, params, nspec, spec, sys, info, msg)
            if (info == CM_SUCCESS) then
                block
                    type(builtin_energy_model) :: bm
                    allocate (bm%sys, source=sys)
                    allocate (model, source=bm)
                end block
                return
            end if
        end if
        if (info == CM_SUCCESS) info = CM_BAD_INPUT
    end subroutine system_and_model

    !> The frame's results into the flat arrays (kmax >= k; unused entries zero).
    subroutine pack_frame(fr, nt, t, kmax, n, k, reduced, closure, drift, defect, mono, mr, &
                          mi, fmono, fr_re, fr_im, holo, xs, qs, as, phis, psis, nfev)
        type(transverse_frame), intent(in) :: fr
        integer, intent(in) :: nt, kmax, n
        real(c_double), intent(in) :: t(nt)
        integer(c_int), intent(out) :: k, reduced, nfev
        real(c_double), intent(out) :: closure, drift, defect
        real(c_double), intent(out) :: mono(kmax, kmax), mr(kmax), mi(kmax), holo(kmax, kmax)
        real(c_double), intent(out) :: fmono(n, n), fr_re(n), fr_im(n)
        real(c_double), intent(out) :: xs(n, nt), qs(n, kmax, nt), as(kmax, kmax, nt)
        real(c_double), intent(out) :: phis(nt), psis(nt)
        real(dp) :: bdum(max(fr%k, 1), 1)
        integer :: i, info
        k = fr%k
        reduced = merge(1, 0, fr%reduced)
        closure = fr%closure
        drift = fr%energy_drift
        defect = fr%frame_defect
        nfev = fr%nfev
        mono = 0.0_c_double
        mr = 0.0_c_double
        mi = 0.0_c_double
        holo = 0.0_c_double
        fmono = 0.0_c_double
        fr_re = 0.0_c_double
        fr_im = 0.0_c_double
        xs = 0.0_c_double
        qs = 0.0_c_double
        as = 0.0_c_double
        phis = 0.0_c_double
        psis = 0.0_c_double
        if (fr%info /= CM_SUCCESS .or. fr%k > kmax) return
        mono(1:k, 1:k) = fr%monodromy
        mr(1:k) = fr%mr
        mi(1:k) = fr%mi
        holo(1:k, 1:k) = fr%holonomy
        if (allocated(fr%full_monodromy)) then
            fmono = fr%full_monodromy
            fr_re = fr%fr
            fr_im = fr%fi
        end if
        do i = 1, nt
            call transverse_eval(fr, t(i), xs(:, i), qs(:, 1:k, i), as(1:k, 1:k, i), bdum, info)
            if (fr%reduced .and. n == 4 .and. k == 2) then
                call transverse_hill(fr, t(i), phis(i), psis(i), info)
                if (info /= CM_SUCCESS) then
                    phis(i) = nan_dp
                    psis(i) = phis(i)
                end if
            end if
        end do
    end subroutine pack_frame

end module conmech_support_transverse_general
