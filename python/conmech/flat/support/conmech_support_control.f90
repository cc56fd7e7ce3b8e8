!> Support of the flat layer for control (compiled, not wrapped): plants, virtual
!! constraints and feedback laws from plain arrays.
!!
!! A plant: a generalized system (built-in `name` or compiled `spec`), ndof = nd, m inputs,
!! a constant input matrix bmat (nd, m) or, when baddr /= 0, a compiled function
!! void B(double t, const double *q, double *b, const double *p) with parameters bpar.
!!
!! A law from (ilaw(:) int64, rlaw(:) real, pylaw):
!!   ilaw(1) kind: 0 zero, 1 Python pylaw(t, x, u, n, m), 2 compiled
!!               void law(double t, const double *x, double *u, const double *p)
!!               (ilaw(3) its address, rlaw its parameters), 3 virtual-constraint feedback,
!!               4 transverse LQR around a nominal law
!!   ilaw(2) m (the number of inputs)
!!   kind 3: ilaw(3:5) = [ip, vkind, ncoef]; rlaw = [a, b, sgn, c(n-1, ncoef), kp(n-1),
!!           kd(n-1)]
!!   kind 4: ilaw(3:5) = [n, k, ng], ilaw(6:) the nominal law's ilaw; rlaw = [period,
!!           xs(n, ng+1), fs, as, qs(n, k, ng+1), qd, ks(m, k, ng+1), km, then the
!!           nominal's rlaw]
module conmech_support_control
    use, intrinsic :: iso_c_binding, only: c_int, c_int64_t, c_null_funptr, c_intptr_t
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_generalized, only: generalized_system
    use conmech_flat_spec, only: spec_generalized
    use conmech_flat_adapters, only: callback_law, c_law, zero_law
    use conmech_control_system, only: feedback_law
    use conmech_mech_plant, only: mech_plant
    use conmech_vhc, only: vhc, vhc_law
    use conmech_transverse_lqr, only: transverse_lqr_law
    use conmech_periodic_riccati, only: periodic_lq, riccati_result, riccati_gain
    implicit none
    private
    public :: callback_law, c_law, zero_law, build_plant, build_vhc, build_law, law_rsize
    public :: project_states, build_plant_law, pack_riccati


contains

    !> The plant (see the module notes). info /= 0 with the flat routine's `message` if the
    !! system is not a generalized one or the sizes do not match.
    subroutine build_plant(name, params, nspec, spec, nd, m, bmat, baddr, bpar, plant, info, &
                           message)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:), bmat(:, :), bpar(:)
        integer, intent(in) :: nspec, nd, m
        integer(c_int64_t), intent(in) :: spec(:), baddr
        type(mech_plant), intent(out) :: plant
        integer, intent(out) :: info
        character(len=*), intent(out) :: message
        class(generalized_system), allocatable :: gs
        character(len=:), allocatable :: msg
        call spec_generalized(name, params, nspec, spec, gs, info, msg)
        if (info /= CM_SUCCESS) then
            message = "control: the plant must be a system in generalized coordinates ("// &
                      msg//")"
            return
        end if
        if (gs%ndof /= nd .or. m < 1) then
            info = CM_BAD_INPUT
            message = "control: the input matrix does not match the plant's coordinates"
            return
        end if
        call move_alloc(gs, plant%mech)
        plant%n_inputs = m
        plant%b = bmat
        if (baddr /= 0) plant%bfun = transfer(int(baddr, c_intptr_t), c_null_funptr)
        plant%p = bpar
        info = CM_SUCCESS
        message = "success"
    end subroutine build_plant

    !> The plant and the feedback law of one flat control argument set (the plant by
    !! build_plant, the law by build_law): info and the message of the first that fails.
    subroutine build_plant_law(name, params, nspec, spec, nd, m, bmat, baddr, bpar, ilaw, &
                               rlaw, nrl, pylaw, n, plant, law, info, message)
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: params(:), bmat(:, :), bpar(:)
        integer, intent(in) :: nspec, nd, m
        integer(c_int64_t), intent(in) :: spec(:), baddr
        integer(c_int64_t), intent(in) :: ilaw(:)
        real(dp), intent(in) :: rlaw(:)
        integer, intent(in) :: nrl, n
        external :: pylaw
        type(mech_plant), intent(out) :: plant
        class(feedback_law), allocatable, intent(out) :: law
        integer, intent(out) :: info
        character(len=*), intent(out) :: message
        character(len=:), allocatable :: msg
        call build_plant(name, params, nspec, spec, nd, m, bmat, baddr, bpar, plant, info, &
                         message)
        if (info /= CM_SUCCESS) return
        call build_law(ilaw, rlaw, nrl, pylaw, plant, n, law, info, msg)
        message = msg
    end subroutine build_plant_law

    !> The virtual constraint of a kind-3 law (ilaw(3:5), rlaw from its start).
    subroutine build_vhc(ilaw, rlaw, n, con, used)
        integer(c_int64_t), intent(in) :: ilaw(:)
        real(dp), intent(in) :: rlaw(:)
        integer, intent(in) :: n
        type(vhc), intent(out) :: con
        integer, intent(out) :: used   !! entries of rlaw taken (without the gains)
        con%n = n
        con%ip = int(ilaw(3))
        con%kind = int(ilaw(4))
        con%ncoef = int(ilaw(5))
        con%a = rlaw(1)
        con%b = rlaw(2)
        con%sgn = rlaw(3)
        con%c = reshape(rlaw(4:3 + (n - 1)*con%ncoef), [n - 1, con%ncoef])
        used = 3 + (n - 1)*con%ncoef
    end subroutine build_vhc

    !> Number of rlaw entries a law takes (recursively for kind 4); n = state dimension.
    recursive integer function law_rsize(ilaw, n) result(sz)
        integer(c_int64_t), intent(in) :: ilaw(:)
        integer, intent(in) :: n
        integer :: k, ng, m
        m = int(ilaw(2))
        select case (int(ilaw(1)))
        case (3)
            sz = 3 + (n/2 - 1)*int(ilaw(5)) + 2*(n/2 - 1)
        case (4)
            k = int(ilaw(4))
            ng = int(ilaw(5))
            sz = 1 + 3*n*(ng + 1) + 2*n*k*(ng + 1) + 2*m*k*(ng + 1) + law_rsize(ilaw(6:), n)
        case default
            sz = 0
        end select
    end function law_rsize

    !> The law (see the module notes); `nrl` = number of rlaw entries of a kind-2 law.
    recursive subroutine build_law(ilaw, rlaw, nrl, pylaw, plant, n, law, info, msg)
        integer(c_int64_t), intent(in) :: ilaw(:)
        real(dp), intent(in) :: rlaw(:)
        integer, intent(in) :: nrl, n
        external :: pylaw
        type(mech_plant), intent(in) :: plant
        class(feedback_law), allocatable, intent(out) :: law
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        integer :: m, used, o, k, ng, sz
        m = int(ilaw(2))
        info = CM_SUCCESS
        msg = "success"
        select case (int(ilaw(1)))
        case (0)
            allocate (zero_law :: law)
        case (1)
            block
                type(callback_law) :: cb
                cb%f => pylaw
                cb%n = int(n, c_int)
                allocate (law, source=cb)
            end block
        case (2)
            block
                type(c_law) :: cl
                cl%fp = transfer(int(ilaw(3), c_intptr_t), c_null_funptr)
                cl%p = rlaw(1:nrl)
                allocate (law, source=cl)
            end block
        case (3)
            block
                type(vhc_law) :: vl
                vl%plant = plant
                call build_vhc(ilaw, rlaw, n/2, vl%con, used)
                vl%kp = rlaw(used + 1:used + n/2 - 1)
                vl%kd = rlaw(used + n/2:used + n - 2)
                if (plant%n_inputs /= n/2 - 1) then
                    info = CM_BAD_INPUT
                    msg = "control: a virtual constraint needs n - 1 inputs (one passive "// &
                          "degree of freedom)"
                    return
                end if
                allocate (law, source=vl)
            end block
        case (4)
            block
                type(transverse_lqr_law) :: ll
                class(feedback_law), allocatable :: nom
                ll%n = int(ilaw(3))
                k = int(ilaw(4))
                ng = int(ilaw(5))
                ll%k = k
                ll%ng = ng
                ll%period = rlaw(1)
                o = 1
                ll%xs = reshape(rlaw(o + 1:o + n*(ng + 1)), [n, ng + 1])
                o = o + n*(ng + 1)
                ll%fs = reshape(rlaw(o + 1:o + n*(ng + 1)), [n, ng + 1])
                o = o + n*(ng + 1)
                ll%as = reshape(rlaw(o + 1:o + n*(ng + 1)), [n, ng + 1])
                o = o + n*(ng + 1)
                ll%qs = reshape(rlaw(o + 1:o + n*k*(ng + 1)), [n, k, ng + 1])
                o = o + n*k*(ng + 1)
                ll%qd = reshape(rlaw(o + 1:o + n*k*(ng + 1)), [n, k, ng + 1])
                o = o + n*k*(ng + 1)
                ll%ks = reshape(rlaw(o + 1:o + m*k*(ng + 1)), [m, k, ng + 1])
                o = o + m*k*(ng + 1)
                ll%km = reshape(rlaw(o + 1:o + m*k*(ng + 1)), [m, k, ng + 1])
                o = o + m*k*(ng + 1)
                sz = law_rsize(ilaw(6:), n)
                if (int(ilaw(6)) == 2) sz = size(rlaw) - o
                call build_law(ilaw(6:), rlaw(o + 1:), sz, pylaw, plant, n, nom, info, msg)
                if (info /= CM_SUCCESS) return
                call move_alloc(nom, ll%nominal)
                ll%has_nominal = .true.
                allocate (law, source=ll)
            end block
        case default
            info = CM_BAD_INPUT
            msg = "control: unknown kind of feedback law"
            return
        end select
        law%n_inputs = m
    end subroutine build_law

    !> tau, xi (k, nx), the distance of the states xs (n, nx) under a transverse LQR law;
    !! nfail counts the states whose section equation had no root near the orbit.
    subroutine project_states(law, xs, taus, xis, dists, nfail, info, message)
        class(feedback_law), intent(in) :: law
        real(dp), intent(in) :: xs(:, :)
        real(dp), intent(out) :: taus(:), xis(:, :), dists(:)
        integer(c_int), intent(out) :: nfail, info
        character(len=*), intent(out) :: message
        integer :: i, i2
        nfail = 0
        info = CM_SUCCESS
        message = "success"
        select type (law)
        type is (transverse_lqr_law)
            if (law%k /= size(xis, 1) .or. law%n /= size(xs, 1)) then
                info = CM_BAD_INPUT
                message = "project: sizes do not match the law"
                return
            end if
            do i = 1, size(xs, 2)
                call law%project(xs(:, i), taus(i), xis(:, i), dists(i), i2)
                if (i2 /= CM_SUCCESS) nfail = nfail + 1
            end do
        class default
            info = CM_BAD_INPUT
            message = "project: not a transverse LQR law"
        end select
    end subroutine project_states

    !> The outputs of a periodic Riccati solution res of lq, as both Riccati routines return
    !! them: the Hamiltonian's multipliers (when computed) and, when res succeeded, the
    !! closed loop's multipliers, P's periodicity and smallest eigenvalue, the refinement
    !! passes, and P and the gain K (u = K x) at the times t; what res does not give is
    !! left as the caller set it (zero).
    subroutine pack_riccati(res, lq, t, ps, ks, hmr, hmi, cmr, cmi, periodicity, min_eig, &
                            passes)
        type(riccati_result), intent(in) :: res
        class(periodic_lq), intent(in) :: lq
        real(dp), intent(in) :: t(:)
        real(dp), intent(inout) :: ps(:, :, :), ks(:, :, :), hmr(:), hmi(:), cmr(:), cmi(:)
        real(dp), intent(inout) :: periodicity, min_eig
        integer(c_int), intent(inout) :: passes
        real(dp) :: kg(size(ks, 1), size(ks, 2))
        integer :: i, i2
        if (allocated(res%hmr)) then
            hmr = res%hmr
            hmi = res%hmi
        end if
        if (res%info /= CM_SUCCESS) return
        cmr = res%cmr
        cmi = res%cmi
        periodicity = res%periodicity
        min_eig = res%min_eig
        passes = res%passes
        do i = 1, size(t)
            call riccati_gain(res, lq, t(i), kg, ps(:, :, i), i2)
            ks(:, :, i) = -kg
        end do
    end subroutine pack_riccati

end module conmech_support_control
