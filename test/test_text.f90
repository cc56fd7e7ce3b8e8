!> Numbers as text for messages: integers without blanks, times in es14.6.
program test_text
    use, intrinsic :: iso_fortran_env, only: int64
    use conmech_kinds, only: dp
    use conmech_text, only: itoa, rtoa
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts

    ts%name = "test_text"
    call ts%check(itoa(0) == "0" .and. itoa(-12) == "-12" .and. itoa(4096) == "4096", &
                  "default integers: no blanks")
    call ts%check(itoa(huge(1)) == "2147483647", "the largest default integer")
    call ts%check(itoa(-huge(1_int64) - 1_int64) == "-9223372036854775808", &
                  "the smallest int64")
    call ts%check(rtoa(1.25_dp) == "  1.250000E+00", "1.25 right-justified in 14 characters")
    call ts%check(rtoa(-1.25e-7_dp) == " -1.250000E-07", "negative value, negative exponent")
    call ts%check(len(rtoa(3.0e200_dp)) == 14 .and. index(rtoa(3.0e200_dp), "3.000000") > 0, &
                  "three-digit exponent keeps the width")
    call ts%finish()
end program test_text
