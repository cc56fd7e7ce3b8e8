!> The Radau IIA stepper's init, start and step (RADAU5's loop: Jacobian when due, the two
!! LU factorisations, the simplified Newton iteration, the error test, the step control),
!! one accepted step per call. A submodule of conmech_radau_stepper, so that the Newton and
!! control modules can work on the stepper's type.
submodule(conmech_radau_stepper) conmech_radau_step
    use conmech_status
    use conmech_text, only: rtoa
    use conmech_ode_stepper, only: check_first_step, tolerance_vectors, FORM_POWER, &
        min_step_at, MSG_STEP_TOO_SMALL, MSG_TOO_MANY_STEPS
    use conmech_radau_coefficients, only: NIT, THET
    use conmech_jacobian_structure, only: LU_AUTO, LU_SPARSE
    use conmech_radau_sparse, only: SPARSE_MIN_N, SPARSE_MAX_DENSITY
    use conmech_radau_collocation, only: radau_collocation_update
    use conmech_radau_newton, only: radau_rhs, radau_jacobian, radau_decompose, radau_newton
    use conmech_radau_control, only: radau_initial_step, radau_estimate_error, &
        radau_propose_step, radau_predictive_step, radau_next_step
    implicit none

contains

    module procedure radau_setup
        integer :: n, m
        n = self%n
        call check_first_step(self, opt, info, msg)
        if (info /= CM_SUCCESS) return
        info = CM_BAD_INPUT
        if (allocated(self%mass)) then
            if (size(self%mass, 1) /= n .or. size(self%mass, 2) /= n) then
                msg = "bad input: the mass matrix must be n x n"
                return
            else if (.not. all(abs(self%mass) <= huge(1.0_dp))) then
                msg = "bad input: the mass matrix contains NaN or Inf"
                return
            end if
        end if
        if (allocated(self%index2)) then
            if (size(self%index2) /= n) then
                msg = "bad input: index2 must have n elements"
                return
            end if
        end if
        if (allocated(self%dae_index)) then
            if (size(self%dae_index) /= n) then
                msg = "bad input: dae_index must have n elements"
                return
            else if (any(self%dae_index < 1 .or. self%dae_index > 3)) then
                msg = "bad input: dae_index values must be 1, 2 or 3"
                return
            end if
        else if (allocated(self%mass)) then
            allocate (self%dae_index(n))
            self%dae_index = 1
            if (allocated(self%index2)) then
                where (self%index2) self%dae_index = 2
            end if
        end if
        call tolerance_vectors(opt, n, self%rtolv, self%atolv, info, msg)
        if (info /= CM_SUCCESS) return

        self%nf = 3
        self%form = FORM_POWER
        ! the sparse path: a pattern, no mass matrix, and the caller's choice or the rule
        ! (n >= SPARSE_MIN_N, at most SPARSE_MAX_DENSITY of the entries in the pattern)
        self%sparse = .false.
        if (self%jstruct%grouped() .and. .not. allocated(self%mass)) then
            select case (self%jstruct%lu)
            case (LU_SPARSE)
                self%sparse = .true.
            case (LU_AUTO)
                self%sparse = n >= SPARSE_MIN_N .and. real(size(self%jstruct%row_idx) + n, &
                    dp) <= SPARSE_MAX_DENSITY*real(n, dp)**2
            end select
        end if
        if (allocated(self%jac)) deallocate (self%jac, self%e1, self%e2, self%ip1, self%ip2)
        if (allocated(self%f0)) deallocate (self%f0, self%scal0)
        allocate (self%f0(n), self%scal0(n))
        if (self%sparse) then
            allocate (self%jac(0, 0), self%e1(0, 0), self%e2(0, 0), self%ip1(0), self%ip2(0))
            self%jval = [(0.0_dp, m = 1, size(self%jstruct%row_idx))]
            call self%slu%build(self%jstruct)
        else
            allocate (self%jac(n, n), self%e1(n, n), self%e2(n, n), self%ip1(n), self%ip2(n))
            self%jval = [real(dp) ::]
        end if
        call radau_allocate_work(self)
        self%jac = 0.0_dp
        self%e1 = 0.0_dp
        self%e2 = 0.0_dp
        self%ip1 = 0
        self%ip2 = 0
        self%uround = epsilon(1.0_dp)
        self%hmax = min(abs(opt%max_step), abs(self%tf - self%t))
        self%fnewt = max(10.0_dp*self%uround/minval(self%rtolv), &
                         min(0.03_dp, sqrt(minval(self%rtolv))))
        self%safe = 0.9_dp
        if (opt%safety > 0.0_dp) self%safe = opt%safety
        self%facl = 5.0_dp
        self%facr = 1.0_dp/8.0_dp
        if (opt%fac_min > 0.0_dp) self%facl = 1.0_dp/opt%fac_min
        if (opt%fac_max > 0.0_dp) self%facr = 1.0_dp/opt%fac_max
        self%cfac = self%safe*real(1 + 2*NIT, dp)
        self%first_step = opt%first_step
        self%max_steps = opt%max_steps
        call radau_collocation_basis(self%cvec, self%pmat)
        self%first = .true.
        self%reject = .false.
        self%caljac = .false.
        self%need_jac = .true.
        self%need_lu = .true.
        self%have_cont = .false.
        self%newton_failed = .false.
        self%f_ok = .true.
        self%final_step = .false.
        self%h_capped = .false.
        self%faccon = 1.0_dp
        self%theta = THET
        self%hacc = 0.0_dp
        self%erracc = 1.0_dp
        self%nsteps = 0
        self%nsing = 0
        self%nfail = 0
    end procedure radau_setup

    module procedure radau_start
        info = CM_SUCCESS
        msg = "success"
        call radau_rhs(sys, self%st, self%t, self%y, self%f0)
        if (.not. all(abs(self%f0) <= huge(1.0_dp))) then
            info = CM_NONFINITE
            msg = "the right-hand side is not finite at the initial point"
            return
        end if
        self%scal = self%atolv + self%rtolv*abs(self%y)
        self%scal0 = self%scal
        if (self%first_step > 0.0_dp) then
            self%h = min(self%first_step, self%hmax)*self%posneg
        else if (allocated(self%mass)) then
            self%h = min(1.0e-6_dp, self%hmax)*self%posneg     ! RADAU5's default for DAEs
        else
            self%h = radau_initial_step(self, sys)
        end if
        self%final_step = (self%t + self%h - self%tf)*self%posneg >= 0.0_dp
        if (self%final_step) self%h = self%tf - self%t
        self%hacc = self%h
    end procedure radau_start

    !> Attempt steps until one is accepted (RADAU5's loop; `target` other than tf is not
    !! used: the step control decides, and the last step lands on tf).
    module procedure radau_step
        real(dp) :: quot, hmin
        integer :: lainfo
        logical :: first_try

        info = CM_SUCCESS
        if (self%f_stale) call self%refresh_f(sys)
        first_try = .true.
        do
            ! SciPy's smallest step (below 10 eps |t|: the cheap test first); a proposed
            ! step below it is raised to it once, an attempt below it ends the run
            if (abs(self%h) <= 10.0_dp*self%uround*abs(self%t) .or. &
                abs(self%h) < tiny(1.0_dp)) then
                hmin = min_step_at(self%t, self%posneg)
                if (first_try .and. .not. self%h_capped .and. abs(self%h) < hmin .and. &
                    abs(self%h) >= tiny(1.0_dp)) then
                    ! raised, then cut at tf (a last step may be shorter, as SciPy's)
                    self%h = self%posneg*hmin
                    self%final_step = (self%t + self%h - self%tf)*self%posneg >= 0.0_dp
                    if (self%final_step) self%h = self%tf - self%t
                    self%need_lu = .true.
                else if (abs(self%h) < hmin .or. abs(self%h) < tiny(1.0_dp)) then
                    info = CM_STEP_TOO_SMALL
                    msg = MSG_STEP_TOO_SMALL//rtoa(self%t)
                    if (self%newton_failed) msg = msg//" (the Newton iteration did not "// &
                                                  "converge)"
                    return
                end if
            end if
            first_try = .false.
            if (self%nsteps >= self%max_steps) then
                info = CM_TOO_MANY_STEPS
                msg = MSG_TOO_MANY_STEPS//rtoa(self%t)
                return
            end if
            if (self%need_jac) then
                call radau_jacobian(self, sys)
                if (.not. (all(abs(self%jac) <= huge(1.0_dp)) .and. &
                           all(abs(self%jval) <= huge(1.0_dp)))) then
                    info = CM_NONFINITE
                    msg = "non-finite Jacobian at t ="//rtoa(self%t)
                    return
                end if
                self%caljac = .true.
                self%need_jac = .false.
                self%need_lu = .true.
            end if
            if (self%need_lu) then
                call radau_decompose(self, lainfo)
                if (lainfo /= 0) then
                    self%nsing = self%nsing + 1
                    if (self%nsing >= 5) then
                        info = CM_SINGULAR
                        msg = "singular iteration matrix (gamma/h I - J) five times in a "// &
                              "row at t ="//rtoa(self%t)
                        return
                    end if
                    self%h = 0.5_dp*self%h
                    self%reject = .true.
                    self%final_step = .false.
                    cycle
                end if
                self%need_lu = .false.
                self%nsing = 0
            end if
            self%nsteps = self%nsteps + 1
            self%scal = self%scal0
            if (allocated(self%dae_index)) then
                where (self%dae_index == 2) self%scal = self%scal0/abs(self%h)
                where (self%dae_index == 3) self%scal = self%scal0/self%h**2
            end if

            call radau_newton(self, sys)
            if (.not. self%converged) then
                if (self%newton_failed) self%nfail = self%nfail + 1
                if (self%nfail > 60) then
                    info = CM_STEP_TOO_SMALL
                    msg = "step size too small at t ="//rtoa(self%t)//" (the Newton "// &
                          "iteration did not converge in 60 step reductions)"
                    return
                end if
                self%reject = .true.
                self%final_step = .false.
                self%need_lu = .true.
                if (.not. self%caljac) self%need_jac = .true.
                cycle
            end if
            self%newton_failed = .false.
            self%nfail = 0
            call radau_estimate_error(self, sys)

            quot = radau_propose_step(self)
            if (self%err < 1.0_dp) exit
            ! ------------------------------------------------------------ rejected step
            self%reject = .true.
            self%final_step = .false.
            if (self%first) then
                self%h = 0.1_dp*self%h
            else
                self%h = self%hnew
            end if
            if (self%st%naccept >= 1) self%st%nreject = self%st%nreject + 1
            self%need_lu = .true.
            ! (the Jacobian is kept: SciPy's rule; RADAU5 refreshes an old one here)
        end do

        ! ---------------------------------------------------------------- accepted step
        self%first = .false.
        self%st%naccept = self%st%naccept + 1
        call radau_predictive_step(self, quot, self%st%naccept)
        call radau_collocation_update(self%pmat, self%y, self%z1, self%z2, self%z3, self%fc)
        self%have_cont = .true.
        self%dense_ready = .true.
        self%h_done = self%h
        self%t_old = self%t
        self%y_old = self%y
        self%last = self%final_step
        if (self%last) then
            self%t = self%tf
        else
            self%t = self%t + self%h
        end if
        self%y = self%y + self%z3
        self%caljac = self%jstruct%constant
        if (self%last) return
        call radau_next_step(self)
        ! f(t, y) and the scale of the next step: by refresh_f, after the driver's outputs
        ! (a terminal event ends the run without it, as RADAU5 ends)
        self%f_stale = .true.
    end procedure radau_step

end submodule conmech_radau_step
