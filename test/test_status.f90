!> The status table: every code has its own message, codes outside the table are
!! "unknown status", and only the non-negative codes count as success.
program test_status
    use conmech_status
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts
    integer, parameter :: codes(10) = [CM_SUCCESS, CM_EVENT_STOP, CM_TOO_MANY_STEPS, &
        CM_STEP_TOO_SMALL, CM_NONFINITE, CM_BAD_INPUT, CM_SINGULAR, CM_NO_CONVERGENCE, &
        CM_LAPACK_ERROR, CM_USER_ERROR]
    character(len=*), parameter :: expected(10) = [character(len=65) :: "success", &
        "a termination event occurred", &
        "too many steps: the maximum number of steps was reached", &
        "step size too small: the step size underflowed", &
        "non-finite value (NaN or Inf) in the state or the right-hand side", &
        "bad input", "singular matrix", "iteration did not converge", &
        "LAPACK reported an illegal argument", "a user callback reported an error"]
    integer :: i, j
    logical :: distinct

    ts%name = "test_status"
    do i = 1, size(codes)
        call ts%check(status_message(codes(i)) == trim(expected(i)), &
                      "message of code "//trim(expected(i)))
        call ts%check(len(status_message(codes(i))) == len_trim(expected(i)), &
                      "message without trailing blanks: "//trim(expected(i)))
        call ts%check(status_is_success(codes(i)) .eqv. (codes(i) >= 0), &
                      "success exactly for the non-negative codes: "//trim(expected(i)))
    end do
    distinct = .true.
    do i = 1, size(codes)
        do j = i + 1, size(codes)
            if (codes(i) == codes(j)) distinct = .false.
            if (status_message(codes(i)) == status_message(codes(j))) distinct = .false.
        end do
    end do
    call ts%check(distinct, "the codes and their messages are pairwise distinct")
    call ts%check(status_message(CM_USER_ERROR - 1) == "unknown status", &
                  "below the lowest code: unknown status")
    call ts%check(status_message(CM_EVENT_STOP + 1) == "unknown status", &
                  "above the highest code: unknown status")
    call ts%finish()
end program test_status
