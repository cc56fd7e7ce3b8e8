!> The structural check of a shared library before dlopen (conmech_library_check), and the
!! parameter counts of the built-in registries (conmech_systems_params).
!!
!! A model library is built from python/tests/data/c_model_kepler.c with the C compiler into
!! build/; copies of it truncated at every kind of place (inside the ELF header, the program
!! headers, a loaded segment, the section headers), emptied, or replaced by text must be
!! refused with a message saying why, and load_model must refuse them before dlopen (a
!! truncated library would otherwise be mapped past its end: SIGBUS).
program test_library_check
    use, intrinsic :: iso_fortran_env, only: int8, int64
    use conmech
    use conmech_library_check, only: check_shared_library
    use conmech_systems_params, only: builtin_param_count, builtin_param_names
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts

    ts%name = "test_library_check"
    call run()    ! locals of a procedure are freed on return (LeakSanitizer)
    call ts%finish()

contains

    subroutine run()
        integer(int8), allocatable :: good(:)
        integer :: info, k
        integer(int64) :: sz, cuts(6)
        character(len=:), allocatable :: msg
        type(model_library) :: lib
        class(ode_system), allocatable :: sys
        class(constrained_system), allocatable :: cs
        integer :: stat, cstat
        character(len=*), parameter :: so = "build/cm_test_check.so"
        call execute_command_line("mkdir -p build && cc -O2 -shared -fPIC -o "//so// &
            ".tmp$$ python/tests/data/c_model_kepler.c -lm && mv -f "//so//".tmp$$ "//so, &
            exitstat=stat, cmdstat=cstat)
        call ts%check(stat == 0 .and. cstat == 0, "cc builds "//so)
        if (stat /= 0 .or. cstat /= 0) return

        call check_shared_library(so, ["conmech_model_info", "conmech_rhs       "], info, msg)
        call ts%check(info == CM_SUCCESS, "a good model library passes: "//msg)
        call check_shared_library(so, ["conmech_no_such"], info, msg)
        call ts%check(info == CM_BAD_INPUT .and. index(msg, "does not define "// &
                      "conmech_no_such") > 0, "a missing symbol is named: "//msg)

        good = bytes(so)
        sz = size(good, kind=int64)
        ! inside the ELF header, the program headers, the middle, near the end (the section
        ! headers), one byte short
        cuts = [20_int64, 64_int64 + 30_int64, sz/3, sz/2, sz - 200_int64, sz - 1_int64]
        do k = 1, size(cuts)
            call write_bytes("build/cm_test_cut.so", good(:cuts(k)))
            call check_shared_library("build/cm_test_cut.so", ["conmech_model_info"], info, &
                                      msg)
            call ts%check(info == CM_BAD_INPUT .and. (index(msg, "truncated") > 0 .or. &
                          index(msg, "not an ELF") > 0), "a copy cut at a byte is refused: "// &
                          msg)
            call load_model("build/cm_test_cut.so", lib, info, msg)
            call ts%check(info == CM_BAD_INPUT .and. index(msg, "cannot load the model "// &
                          "library 'build/cm_test_cut.so'") == 1, "load_model refuses it: "// &
                          msg)
        end do
        call write_bytes("build/cm_test_cut.so", [integer(int8) ::])
        call check_shared_library("build/cm_test_cut.so", ["x"], info, msg)
        call ts%check(info == CM_BAD_INPUT .and. msg == "empty (0 bytes)", "empty: "//msg)
        call write_bytes("build/cm_test_cut.so", transfer("not a library at all", good(1:20)))
        call check_shared_library("build/cm_test_cut.so", ["x"], info, msg)
        call ts%check(info == CM_BAD_INPUT .and. index(msg, "not an ELF file") == 1, &
                      "text: "//msg)
        call check_shared_library("build/no_such_file.so", ["x"], info, msg)
        call ts%check(info == CM_BAD_INPUT .and. index(msg, "No such file") > 0, &
                      "missing: "//msg)
        ! a segment's file image moved past the end: refused although nothing is cut
        call write_bytes("build/cm_test_cut.so", with_u64(good, 64 + 8, sz + 4096_int64))
        call check_shared_library("build/cm_test_cut.so", ["conmech_model_info"], info, msg)
        call ts%check(info == CM_BAD_INPUT .and. index(msg, "segment 0 ends at byte") > 0, &
                      "a segment past the end: "//msg)
        call load_model(so, lib, info, msg)
        call ts%check(info == CM_SUCCESS .and. lib%kind == MODEL_KIND_ODE, "the good one loads")

        ! parameter counts: more than a built-in has is refused by every registry
        call make_system("pendulum", [9.81_dp, 1.0_dp, 3.0_dp], sys, info, msg)
        call ts%check(info == CM_BAD_INPUT .and. index(msg, "3 parameters given for the "// &
                      "system 'pendulum', which has 2 (g, l)") > 0, "make_system: "//msg)
        call make_system("pendulum", [9.81_dp], sys, info, msg)
        call ts%check(info == CM_SUCCESS, "fewer parameters keep the defaults")
        call make_constrained("pendulum_xy", [1.0_dp, 2.0_dp, 3.0_dp, 4.0_dp, 5.0_dp], cs, &
                              info, msg)
        call ts%check(info == CM_BAD_INPUT .and. index(msg, "which has 3 (m, g, l)") > 0, &
                      "make_constrained: "//msg)
        call make_system("cart_pendulum", [1.0_dp, 1.0_dp, 1.0_dp, 9.81_dp, 0.0_dp], sys, &
                         info, msg)
        call ts%check(info == CM_BAD_INPUT .and. index(msg, "cart_pendulum") > 0, &
                      "a generalized built-in through make_system: "//msg)
        call ts%check(builtin_param_count("rolling_ball") == 5 .and. &
                      builtin_param_names("pendulum_chain_xy") == "N, m, l, g" .and. &
                      builtin_param_count("no_such_system") == -1, "the table")
    end subroutine run

    function bytes(path) result(b)
        character(len=*), intent(in) :: path
        integer(int8), allocatable :: b(:)
        integer :: u
        integer(int64) :: n
        open (newunit=u, file=path, access="stream", form="unformatted", status="old", &
              action="read")
        inquire (unit=u, size=n)
        allocate (b(n))
        read (u) b
        close (u)
    end function bytes

    subroutine write_bytes(path, b)
        character(len=*), intent(in) :: path
        integer(int8), intent(in) :: b(:)
        integer :: u
        open (newunit=u, file=path, access="stream", form="unformatted", status="replace", &
              action="write")
        write (u) b
        close (u)
    end subroutine write_bytes

    !> A copy of `b` with the little-endian 8-byte value `v` at byte offset `off`.
    function with_u64(b, off, v) result(c)
        integer(int8), intent(in) :: b(:)
        integer, intent(in) :: off
        integer(int64), intent(in) :: v
        integer(int8), allocatable :: c(:)
        integer :: k
        c = b
        do k = 0, 7
            c(off + k + 1) = int(ibits(v, 8*k, 8), int8)
        end do
    end function with_u64

end program test_library_check
