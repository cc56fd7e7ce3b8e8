!> Model libraries loaded at run time (conmech_model_library): the optional fast entries
!! are looked up and used when the library exports them, the plain path otherwise.
!! The libraries are built from python/tests/data/*.c with the C compiler (`cc`, which
!! gfortran brings) into build/: a Kepler ode model with and without conmech_jac_prod, and
!! a pendulum generalized model with and without conmech_mass_forces / conmech_accel.
program test_model_library
    use, intrinsic :: iso_c_binding, only: c_associated
    use conmech
    use conmech_testing, only: test_suite
    implicit none
    type(test_suite) :: ts

    ts%name = "test_model_library"
    call run()    ! locals of a procedure are freed on return (LeakSanitizer)
    call ts%finish()

contains

    !> Compile the C sources `srcs` (with `flags`) into build/NAME.so; true on success.
    logical function build_lib(name, srcs, flags) result(ok)
        character(len=*), intent(in) :: name, srcs, flags
        integer :: stat, cstat
        character(len=:), allocatable :: cmd
        ! built under a temporary name and renamed: concurrent runs never load a partial file
        cmd = "mkdir -p build && cc -O2 -shared -fPIC "//flags//" -o build/"//name// &
              ".so.tmp$$ "//srcs//" -lm && mv -f build/"//name//".so.tmp$$ build/"//name//".so"
        call execute_command_line(cmd, exitstat=stat, cmdstat=cstat)
        ok = stat == 0 .and. cstat == 0
        call ts%check(ok, "cc builds build/"//name//".so")
    end function build_lib

    subroutine run()
        character(len=*), parameter :: d = "python/tests/data/"
        type(model_library) :: lib_jp, lib_plain, g_fast, g_plain
        class(ode_system), allocatable :: s_jp, s_plain, ref, gs_fast, gs_plain
        type(ode_options) :: opt
        real(dp) :: y(4), p1(4, 4), p2(4, 4), p3(4, 4), y1(4), y2(4), y3(4), x(4, 2), &
                    jx(4, 2), jref(4, 2), f1(2), f2(2), fy(4), fy2(4)
        real(dp), parameter :: pi = acos(-1.0_dp)
        integer :: info, i
        character(len=:), allocatable :: msg
        if (.not. build_lib("cm_test_kepler_jp", d//"c_model_kepler.c "//d//"c_jac_prod.c", &
                            "")) return
        if (.not. build_lib("cm_test_kepler", d//"c_model_kepler.c", "")) return
        if (.not. build_lib("cm_test_spy_fast", d//"c_model_spy.c", "-DFAST")) return
        if (.not. build_lib("cm_test_spy", d//"c_model_spy.c", "")) return

        ! ode model: conmech_jac_prod found and set (has_jacobian_product), J x exact
        call load_model("build/cm_test_kepler_jp.so", lib_jp, info, msg)
        call ts%check(info == CM_SUCCESS .and. c_associated(lib_jp%jac_prod), &
                      "load_model finds conmech_jac_prod")
        call load_model("build/cm_test_kepler.so", lib_plain, info, msg)
        call ts%check(info == CM_SUCCESS .and. .not. c_associated(lib_plain%jac_prod), &
                      "a library without conmech_jac_prod: none")
        call model_system(lib_jp, [1.0_dp], s_jp, info, msg)
        call model_system(lib_plain, [1.0_dp], s_plain, info, msg)
        call make_system("kepler", [1.0_dp], ref, info, msg)
        call ts%check(s_jp%has_jacobian_product() .and. .not. s_plain%has_jacobian_product(), &
                      "model_system: the product only where the library has it")
        y = [0.7_dp, 0.2_dp, -0.3_dp, 1.1_dp]
        x = reshape([(cos(0.7_dp*i), i=1, 8)], [4, 2])
        call s_jp%jacobian_product(0.0_dp, 4, 2, y, x, jx)
        call ref%jacobian_product(0.0_dp, 4, 2, y, x, jref)
        call ts%check_less(maxval(abs(jx - jref))/maxval(abs(jref)), 1.0e-14_dp, &
                           "conmech_jac_prod = the built-in kepler's J x")
        ! f and J x in one call (c_ode_system's rhs_jacobian_product): the same values as
        ! rhs and jacobian_product apart; without the C product, the default (J, then J x)
        call s_jp%rhs(0.0_dp, y, fy)
        call s_jp%rhs_jacobian_product(0.0_dp, 4, 2, y, fy2, x, jx)
        call ts%check(all(fy2 == fy) .and. maxval(abs(jx - jref)) <= 1.0e-14_dp* &
                      maxval(abs(jref)), "rhs_jacobian_product through the C entries")
        call s_plain%rhs_jacobian_product(0.0_dp, 4, 2, y, fy2, x, jx)
        call ts%check(all(fy2 == fy) .and. maxval(abs(jx - jref)) <= 1.0e-6_dp* &
                      maxval(abs(jref)), "rhs_jacobian_product without jac_prod: the default")
        ! the STM of the circular orbit (period 2 pi) through the library's product equals
        ! the built-in's (analytic J) at the tolerance; the plain library's (finite
        ! differences) is close too (1.4e-10 measured)
        opt%method = METHOD_DOP853
        opt%rtol = 1.0e-11_dp
        opt%atol = 1.0e-11_dp
        y1 = [1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp]
        y2 = y1
        y3 = y1
        p1 = 0.0_dp
        do i = 1, 4
            p1(i, i) = 1.0_dp
        end do
        p2 = p1
        p3 = p1
        call integrate_stm(s_jp, 0.0_dp, 2*pi, y1, p1, opt, info)
        call ts%check(info == CM_SUCCESS, "integrate_stm through the library's product")
        call integrate_stm(ref, 0.0_dp, 2*pi, y2, p2, opt, info)
        call integrate_stm(s_plain, 0.0_dp, 2*pi, y3, p3, opt, info)
        call ts%check_less(maxval(abs(p1 - p2))/maxval(abs(p2)), 1.0e-9_dp, &
                           "library product STM = built-in STM")
        call ts%check_less(maxval(abs(p3 - p2))/maxval(abs(p2)), 1.0e-6_dp, &
                           "plain library STM (finite differences) near it")

        ! generalized model: conmech_mass_forces and conmech_accel looked up when present
        call load_model("build/cm_test_spy_fast.so", g_fast, info, msg)
        call ts%check(info == CM_SUCCESS .and. c_associated(g_fast%fp%mass_forces) .and. &
                      c_associated(g_fast%fp%accel), "load_model finds mass_forces and accel")
        call load_model("build/cm_test_spy.so", g_plain, info, msg)
        call ts%check(info == CM_SUCCESS .and. .not. c_associated(g_plain%fp%mass_forces) &
                      .and. .not. c_associated(g_plain%fp%accel), "plain library: neither")
        call model_system(g_fast, [1.0_dp, 0.8_dp, 9.81_dp], gs_fast, info, msg)
        call model_system(g_plain, [1.0_dp, 0.8_dp, 9.81_dp], gs_plain, info, msg)
        call gs_fast%rhs(0.0_dp, [0.6_dp, 0.2_dp], f1)
        call gs_plain%rhs(0.0_dp, [0.6_dp, 0.2_dp], f2)
        ! (accel's a = -g sin(q)/l and the solve of M a = Q may differ in the last bits)
        call ts%check_less(maxval(abs(f1 - f2)), 1.0e-14_dp*maxval(abs(f2)), &
                           "fast and plain entries agree")
        call ts%check_close(f2(2), -9.81_dp*sin(0.6_dp)/0.8_dp, 1.0e-14_dp, &
                            "pendulum acceleration -g sin(q)/l")
    end subroutine run

end program test_model_library
