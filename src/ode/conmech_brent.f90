!> Brent's root finder on a step, by reverse communication (no closures needed): the caller
!! evaluates its function where the solver asks. Used to locate event zeros on the dense
!! output of a step, x in [0, 1] mapping to t + x h, to near machine precision in t.
!!
!!     call brent_init(s, g0, g1, t, h)        ! g(0) and g(1) of opposite signs
!!     do it = 1, 200
!!         call brent_step(s, done)
!!         if (done) exit
!!         call brent_take(s, g(s%b))            ! the function at the new abscissa s%b
!!     end do
!!     root = t + s%b*h
module conmech_brent
    use conmech_kinds, only: dp
    implicit none
    private
    public :: brent_state, brent_init, brent_step, brent_take

    !> The bracket and the interpolation memory of Brent's method.
    type :: brent_state
        real(dp) :: a = 0.0_dp, b = 1.0_dp, c = 0.0_dp   !! abscissae; b is the best
        real(dp) :: fa = 0.0_dp, fb = 0.0_dp, fc = 0.0_dp
        real(dp) :: d = 1.0_dp, e = 1.0_dp                 !! last and second-last steps
        real(dp) :: t = 0.0_dp, h = 1.0_dp                 !! the step: x -> t + x h
    end type brent_state

contains

    !> Start on [0, 1] with g(0) = ga, g(1) = gb (of opposite signs or one of them zero).
    pure subroutine brent_init(s, ga, gb, t, h)
        type(brent_state), intent(out) :: s
        real(dp), intent(in) :: ga, gb, t, h
        s%a = 0.0_dp
        s%b = 1.0_dp
        s%fa = ga
        s%fb = gb
        s%c = s%a
        s%fc = s%fa
        s%d = s%b - s%a
        s%e = s%d
        s%t = t
        s%h = h
    end subroutine brent_init

    !> One step: done when the bracket is below the tolerance in t (relative machine
    !! precision of t + x h) or a zero was hit; otherwise s%b is the next abscissa.
    pure subroutine brent_step(s, done)
        type(brent_state), intent(inout) :: s
        logical, intent(out) :: done
        real(dp) :: tol, m, p, q, r, sr
        if (abs(s%fc) < abs(s%fb)) then
            s%a = s%b; s%b = s%c; s%c = s%a
            s%fa = s%fb; s%fb = s%fc; s%fc = s%fa
        end if
        tol = 2.0_dp*epsilon(1.0_dp)*abs(s%t + s%b*s%h)/abs(s%h) + 0.5_dp*tiny(1.0_dp)
        tol = max(tol, 2.0_dp*epsilon(1.0_dp))
        m = 0.5_dp*(s%c - s%b)
        done = abs(m) <= tol .or. s%fb == 0.0_dp
        if (done) return
        if (abs(s%e) < tol .or. abs(s%fa) <= abs(s%fb)) then
            s%d = m; s%e = m
        else
            sr = s%fb/s%fa
            if (s%a == s%c) then
                p = 2.0_dp*m*sr
                q = 1.0_dp - sr
            else
                q = s%fa/s%fc
                r = s%fb/s%fc
                p = sr*(2.0_dp*m*q*(q - r) - (s%b - s%a)*(r - 1.0_dp))
                q = (q - 1.0_dp)*(r - 1.0_dp)*(sr - 1.0_dp)
            end if
            if (p > 0.0_dp) then
                q = -q
            else
                p = -p
            end if
            if (2.0_dp*p < min(3.0_dp*m*q - abs(tol*q), abs(s%e*q))) then
                s%e = s%d
                s%d = p/q
            else
                s%d = m; s%e = m
            end if
        end if
        s%a = s%b
        s%fa = s%fb
        if (abs(s%d) > tol) then
            s%b = s%b + s%d
        else
            s%b = s%b + sign(tol, m)
        end if
    end subroutine brent_step

    !> The function's value at the abscissa s%b proposed by brent_step.
    pure subroutine brent_take(s, fb)
        type(brent_state), intent(inout) :: s
        real(dp), intent(in) :: fb
        s%fb = fb
        if ((fb > 0.0_dp .and. s%fc > 0.0_dp) .or. (fb < 0.0_dp .and. s%fc < 0.0_dp)) then
            s%c = s%a
            s%fc = s%fa
            s%d = s%b - s%a
            s%e = s%d
        end if
    end subroutine brent_take

end module conmech_brent
