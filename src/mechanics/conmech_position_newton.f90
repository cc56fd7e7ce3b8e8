!> The Newton iteration of the position projections of conmech_constrained_system (see
!! there), shared by the dense and the banded paths: each computes its own correction dq
!! (a Schur-complement solve) and hands it to `position_newton_step`.
submodule(conmech_constrained_system) conmech_position_newton
    implicit none

contains

    module procedure position_newton_step
        qk = qk - dq
        call sys%phi(t, qk, ph)
        rnorm = maxval(abs(ph))
        state = NEWTON_RUNNING
        if (.not. (rnorm < huge(1.0_dp))) then
            state = NEWTON_DIVERGED
        else if (rnorm <= tol) then
            q = qk
            state = NEWTON_CONVERGED
        end if
    end procedure position_newton_step

    module procedure position_not_converged
        character(len=32) :: buf
        iters = min(iters, max_iter)
        info = CM_NO_CONVERGENCE
        write (buf, '(es10.3)') rnorm
        msg = "position projection did not converge: |phi| ="//trim(buf)// &
              " (inconsistent constraints, or too far from the manifold)"
    end procedure position_not_converged

end submodule conmech_position_newton
