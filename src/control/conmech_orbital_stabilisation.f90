!> Design of the transverse LQR that makes a periodic orbit of a controlled system
!! orbitally asymptotically stable (see conmech_transverse_lqr for the law).
!!
!! `orbital_design(plant, nominal, y0, period, qw, rw, ng, opt, ropt, des)`:
!! 1. the closed loop x' = F(x, u_nom(x) + w) and its transverse linearisation with the
!!    input w (2n - 1 coordinates: no energy, the input changes it): A_perp, B_perp and
!!    the controllability Gramian W = int Phi(T, s) B_perp B_perp^T Phi(T, s)^T ds over
!!    one period;
!! 2. stabilisability: the directions in the kernel of W (eigenvalues below 1e-10 of its
!!    largest) carry the uncontrollable multipliers (eigenvalues of the transverse
!!    monodromy's transpose restricted to that kernel); one on or outside the unit circle
!!    is an error ("uncontrollable transverse linearisation");
!! 3. the stabilising periodic Riccati solution (conmech_periodic_riccati);
!! 4. the law's table on ng + 1 equally spaced phases (K with its periodic cubic spline).
module conmech_orbital_stabilisation
    use conmech_kinds, only: dp
    use conmech_status
    use conmech_outcome, only: outcome
    use conmech_lapack, only: la_sym_eig, la_eig
    use conmech_control_system, only: control_system, feedback_law, closed_loop, control_model
    use conmech_transverse_general, only: transverse_options, transverse_frame, &
                                          transverse_build, transverse_eval, &
                                          transverse_jacobian, ENERGY_NONE
    use conmech_periodic_riccati, only: riccati_options, riccati_result, periodic_riccati, &
                                        riccati_gain
    use conmech_transverse_lqr, only: transverse_lq, transverse_lqr_law, periodic_spline
    implicit none
    private
    public :: orbital_design_result, orbital_design

    !> What the design produced.
    type, extends(outcome) :: orbital_design_result
        type(transverse_lq) :: lq                    !! the transverse linearisation
        type(riccati_result) :: ric                  !! P(t), closed-loop multipliers
        type(transverse_lqr_law) :: law              !! the controller
        real(dp), allocatable :: gramian_eig(:)      !! eigenvalues of the Gramian
        real(dp), allocatable :: ur(:), ui(:)        !! uncontrollable multipliers
    end type orbital_design_result

contains

    subroutine orbital_design(plant, nominal, has_nominal, y0, period, qw, rw, ng, topt, ropt, &
                              des)
        class(control_system), intent(in) :: plant
        class(feedback_law), intent(in) :: nominal
        logical, intent(in) :: has_nominal
        real(dp), intent(in) :: y0(:), period, qw(:, :), rw(:, :)
        integer, intent(in) :: ng
        type(transverse_options), intent(in) :: topt
        type(riccati_options), intent(in) :: ropt
        type(orbital_design_result), intent(out) :: des
        type(closed_loop) :: cl
        type(control_model) :: cm
        type(transverse_options) :: to
        real(dp), allocatable :: w(:, :), ev(:), v(:, :), mt(:, :), nb(:, :), x(:), qp(:, :)
        real(dp), allocatable :: ap(:, :), bp(:, :), dq(:, :), f(:), a(:, :), kg(:, :), p(:, :)
        real(dp) :: tau
        integer :: n, k, m, info, j, nk, i
        character(len=24) :: b1

        n = size(y0)
        m = plant%n_inputs
        if (m < 1 .or. ng < 8) then
            call des%fail(CM_BAD_INPUT, "orbital design: need at least one input and ng >= 8")
            return
        end if
        allocate (cl%plant, source=plant)
        allocate (cl%law, source=nominal)
        if (.not. has_nominal) then
            call des%fail(CM_BAD_INPUT, "orbital design: a nominal law is required (use a zero law)")
            return
        end if
        cl%n_inputs = m
        allocate (cm%sys, source=cl)
        cm%n_inputs = m
        to = topt
        to%energy = ENERGY_NONE
        to%full_monodromy = .true.
        call transverse_build(cl, cm, y0, period, to, des%lq%fr)
        if (des%lq%fr%info /= CM_SUCCESS) then
            des%info = des%lq%fr%info
            des%message = des%lq%fr%message
            return
        end if
        k = des%lq%fr%k
        des%lq%k = k
        des%lq%m = m
        des%lq%period = period

        ! ---- stabilisability from the controllability Gramian
        allocate (w(k, k), ev(k), v(k, k))
        w = 0.5_dp*(des%lq%fr%gramian + transpose(des%lq%fr%gramian))
        call la_sym_eig(w, ev, info, v)
        des%gramian_eig = ev
        nk = count(ev <= 1.0e-10_dp*max(ev(k), tiny(1.0_dp)))
        allocate (des%ur(nk), des%ui(nk))
        if (nk > 0) then
            allocate (nb(k, nk), mt(nk, nk))
            nb = v(:, 1:nk)
            mt = matmul(transpose(nb), matmul(transpose(des%lq%fr%monodromy), nb))
            call la_eig(mt, des%ur, des%ui, info)
            if (any(sqrt(des%ur**2 + des%ui**2) >= 1.0_dp - 1.0e-9_dp)) then
                write (b1, '(es10.3)') maxval(sqrt(des%ur**2 + des%ui**2))
                call des%fail(CM_BAD_INPUT, "orbital design: uncontrollable transverse "// &
                          "linearisation: an uncontrollable multiplier of modulus "// &
                          trim(adjustl(b1))//" is not inside the unit circle (the input "// &
                          "cannot reach it)")
                return
            end if
        end if

        ! ---- the periodic Riccati equation
        call periodic_riccati(des%lq, qw, rw, ropt, des%ric)
        if (des%ric%info /= CM_SUCCESS) then
            des%info = des%ric%info
            des%message = des%ric%message
            return
        end if

        ! ---- the law's table
        des%law%n_inputs = m
        des%law%n = n
        des%law%k = k
        des%law%ng = ng
        des%law%period = period
        allocate (des%law%nominal, source=nominal)
        des%law%has_nominal = .true.
        allocate (des%law%xs(n, ng + 1), des%law%fs(n, ng + 1), des%law%as(n, ng + 1))
        allocate (des%law%qs(n, k, ng + 1), des%law%qd(n, k, ng + 1), des%law%ks(m, k, ng + 1))
        allocate (x(n), qp(n, k), ap(k, k), bp(k, m), dq(n, k), f(n), a(n, n), kg(m, k), &
                  p(k, k))
        do j = 1, ng + 1
            i = j
            if (j == ng + 1) i = 1
            tau = period*real(i - 1, dp)/ng
            call transverse_eval(des%lq%fr, tau, x, qp, ap, bp, info, dq)
            if (info /= CM_SUCCESS) then
                call des%fail(info, "orbital design: the transverse frame could not be evaluated")
                return
            end if
            call transverse_jacobian(cl, tau, x, f, a)
            call riccati_gain(des%ric, des%lq, tau, kg, p, info)
            des%law%xs(:, j) = x
            des%law%fs(:, j) = f
            des%law%as(:, j) = matmul(a, f)
            des%law%qs(:, :, j) = qp
            des%law%qd(:, :, j) = dq
            des%law%ks(:, :, j) = -kg
        end do
        allocate (des%law%km(m, k, ng + 1))
        block
            real(dp) :: kflat(m*k, ng + 1), kmf(m*k, ng + 1)
            kflat = reshape(des%law%ks, [m*k, ng + 1])
            call periodic_spline(kflat, period/ng, kmf, info)
            if (info /= CM_SUCCESS) then
                call des%fail(info, "orbital design: the gain's spline failed")
                return
            end if
            des%law%km = reshape(kmf, [m, k, ng + 1])
        end block
        des%info = CM_SUCCESS
        des%message = des%ric%message

    end subroutine orbital_design

end module conmech_orbital_stabilisation
