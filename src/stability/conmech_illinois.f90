!> Illinois' regula falsi on a bracket [a, b] of a sign change of f: the trial point is the
!! secant root (the midpoint when the secant root is not strictly inside, e.g. fa == fb),
!! and when the same end survives two updates running its value is halved, which keeps the
!! convergence superlinear where plain regula falsi would stall on one end. The bracket
!! holds the numbers only; a locator moves whatever it keeps with each end (points,
!! tangents, guesses) as `illinois_update` says.
module conmech_illinois
    use conmech_kinds, only: dp
    implicit none
    private

    public :: illinois_bracket

    !> The two ends and their values; b is the latest trial.
    type :: illinois_bracket
        real(dp) :: a = 0.0_dp, b = 0.0_dp
        real(dp) :: fa = 0.0_dp, fb = 0.0_dp
        integer :: side = 0            !! 1 when b replaced the previous b (a kept) last time
    contains
        procedure :: trial => illinois_trial
        procedure :: update => illinois_update
    end type illinois_bracket

contains

    !> The next trial point: the secant root of (a, fa), (b, fb), or the midpoint.
    pure real(dp) function illinois_trial(br) result(c)
        class(illinois_bracket), intent(in) :: br
        c = (br%a*br%fb - br%b*br%fa)/(br%fb - br%fa)
        if (.not. (c > min(br%a, br%b) .and. c < max(br%a, br%b))) c = 0.5_dp*(br%a + br%b)
    end function illinois_trial

    !> Take the trial (c, fc) as the new end b. moved is true when the sign change lies
    !! between b and c, so the old b became the end a (the caller moves its a data to b's
    !! before storing c's as b); otherwise a stays and fa is halved on its second stay.
    pure subroutine illinois_update(br, c, fc, moved)
        class(illinois_bracket), intent(inout) :: br
        real(dp), intent(in) :: c, fc
        logical, intent(out) :: moved
        moved = fc*br%fb < 0.0_dp
        if (moved) then
            br%a = br%b
            br%fa = br%fb
            br%side = 0
        else
            if (br%side == 1) br%fa = 0.5_dp*br%fa
            br%side = 1
        end if
        br%b = c
        br%fb = fc
    end subroutine illinois_update

end module conmech_illinois
