!> Compiled user models loaded at run time from a shared library (dlopen), so that programs
!! such as `sweep` run a user's own system (e.g. built by `python -m conmech.symbolic
!! build MODEL.py`) with no recompilation of conmech.
!!
!! A model library exports, with C linkage:
!!
!!     void conmech_model_info(int info[6]);   /* kind (1 ode, 2 generalized, 3
!!                                               constrained), n, n_hol, n_nh,
!!                                               rheonomic (0/1), number of parameters */
!!     void conmech_model_params(double *p);   /* the default parameter values */
!!     void conmech_model_param_names(char *buf, int len);  /* blank-separated names */
!!
!! and the functions of its kind with the signatures of conmech_c_system /
!! conmech_c_mechanics, named conmech_<entry> after the table of compiled functions
!! (python/conmech/_slot_table.py, conmech_c_entries): conmech_rhs, conmech_jac (ode);
!! conmech_mass, conmech_forces, conmech_forces_jac, conmech_energy (generalized and
!! constrained); conmech_phi, conmech_phi_jac, conmech_phi_t, conmech_phi_gamma,
!! conmech_nh_matrix, conmech_nh_gamma, optionally conmech_constraint_hessian
!! (constrained). Optional fast entries: conmech_jac_prod (ode: J x for a block x,
!! `set_c_jac_prod`, used by `integrate_stm`), conmech_mass_forces (M and Q in one call),
!! conmech_accel (a = M^-1 Q) and conmech_accel_jac (a and d a/d[q, v]) for generalized
!! models. Missing optional functions fall back to finite differences (or to mass +
!! forces). The library stays loaded for the life of the process. Before dlopen the file is checked
!! (`conmech_library_check`: ELF headers, segments and sections within the file, the symbol
!! conmech_model_info defined), so a truncated or foreign file is an error naming it, never
!! a crash.
module conmech_model_library
    use, intrinsic :: iso_c_binding, only: c_ptr, c_funptr, c_char, c_int, c_double, &
                                           c_null_char, c_associated, &
                                           c_f_pointer, c_f_procpointer, c_size_t
    use conmech_kinds, only: dp
    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT
    use conmech_ode_system, only: ode_system
    use conmech_generalized, only: generalized_ode
    use conmech_constrained_system, only: constrained_system
    use conmech_c_system, only: c_ode_system, make_c_ode, set_c_jac_prod
    use conmech_c_mechanics, only: c_generalized_system, c_constrained_system, &
                                   c_mech_pointers, make_c_generalized, make_c_constrained
    use conmech_c_entries, only: N_MECH_ENTRIES, MECH_ENTRY_NAMES, set_mech_entry
    use conmech_library_check, only: check_shared_library
    implicit none
    private

    public :: model_library, load_model, model_system, model_constrained
    public :: MODEL_KIND_ODE, MODEL_KIND_GENERALIZED, MODEL_KIND_CONSTRAINED

    integer, parameter :: MODEL_KIND_ODE = 1, MODEL_KIND_GENERALIZED = 2, MODEL_KIND_CONSTRAINED = 3
    integer(c_int), parameter :: RTLD_NOW = 2

    !> A loaded model: its kind, dimensions, default parameters and function pointers.
    type :: model_library
        character(len=:), allocatable :: path
        integer :: kind = 0, n = 0, n_hol = 0, n_nh = 0
        logical :: rheonomic = .false.
        real(dp), allocatable :: defaults(:)         !! default parameter values
        character(len=:), allocatable :: param_names !! blank-separated names
        type(c_funptr) :: rhs, jac
        type(c_funptr) :: jac_prod      !! optional Jacobian product (ode models)
        type(c_mech_pointers) :: fp
    end type model_library

    interface
        function c_dlopen(filename, flag) result(h) bind(c, name="dlopen")
            import :: c_ptr, c_char, c_int
            character(kind=c_char), intent(in) :: filename(*)
            integer(c_int), value :: flag
            type(c_ptr) :: h
        end function c_dlopen
        function c_dlsym(handle, symbol) result(f) bind(c, name="dlsym")
            import :: c_ptr, c_funptr, c_char
            type(c_ptr), value :: handle
            character(kind=c_char), intent(in) :: symbol(*)
            type(c_funptr) :: f
        end function c_dlsym
        function c_dlerror() result(p) bind(c, name="dlerror")
            import :: c_ptr
            type(c_ptr) :: p
        end function c_dlerror
        function c_strlen(s) result(n) bind(c, name="strlen")
            import :: c_ptr, c_size_t
            type(c_ptr), value :: s
            integer(c_size_t) :: n
        end function c_strlen
        subroutine info_fn(info) bind(c)
            import :: c_int
            integer(c_int), intent(out) :: info(6)
        end subroutine info_fn
        subroutine params_fn(p) bind(c)
            import :: c_double
            real(c_double), intent(out) :: p(*)
        end subroutine params_fn
        subroutine names_fn(buf, len) bind(c)
            import :: c_char, c_int
            character(kind=c_char), intent(out) :: buf(*)
            integer(c_int), value :: len
        end subroutine names_fn
    end interface

contains

    !> The text of dlerror() (empty if none).
    function dl_message() result(s)
        character(len=:), allocatable :: s
        type(c_ptr) :: p
        character(kind=c_char), pointer :: chars(:)
        integer :: i, n
        p = c_dlerror()
        n = 0
        if (c_associated(p)) n = int(c_strlen(p))
        allocate (character(len=n) :: s)
        if (n == 0) return
        call c_f_pointer(p, chars, [n])
        do i = 1, n
            s(i:i) = chars(i)
        end do
    end function dl_message

    !> The path as dlopen must see it to open this very file: a name without a slash
    !! would be searched in the library path instead of the current directory.
    function dl_path(path) result(p)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: p
        if (index(path, "/") == 0) then
            p = "./"//path
        else
            p = path
        end if
    end function dl_path

    type(c_funptr) function symbol(handle, name)
        type(c_ptr), intent(in) :: handle
        character(len=*), intent(in) :: name
        symbol = c_dlsym(handle, trim(name)//c_null_char)
    end function symbol

    !> Open the model library `path` and read its description. info = CM_BAD_INPUT with a
    !! message naming the file and the problem (not found, not a conmech model, bad kind).
    subroutine load_model(path, lib, info, msg)
        character(len=*), intent(in) :: path
        type(model_library), intent(out) :: lib
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        type(c_ptr) :: h
        type(c_funptr) :: f
        procedure(info_fn), pointer :: get_info
        procedure(params_fn), pointer :: get_params
        procedure(names_fn), pointer :: get_names
        integer(c_int) :: desc(6)
        character(kind=c_char) :: buf(4096)
        integer :: i, np
        ! before dlopen: a truncated library would be mapped past its end (SIGBUS at the
        ! first access); a foreign file is named as such
        call check_shared_library(trim(path), ["conmech_model_info"], info, msg)
        if (info /= CM_SUCCESS) then
            msg = "cannot load the model library '"//trim(path)//"': "//msg
            return
        end if
        info = CM_BAD_INPUT
        h = c_dlopen(dl_path(trim(path))//c_null_char, RTLD_NOW)
        if (.not. c_associated(h)) then
            msg = "cannot load the model library '"//trim(path)//"': "//dl_message()
            return
        end if
        f = symbol(h, "conmech_model_info")
        if (.not. c_associated(f)) then
            msg = "'"//trim(path)//"' is not a conmech model (no conmech_model_info)"
            return
        end if
        call c_f_procpointer(f, get_info)
        desc = 0
        call get_info(desc)
        if (desc(1) < MODEL_KIND_ODE .or. desc(1) > MODEL_KIND_CONSTRAINED .or. desc(2) < 1 &
            .or. desc(3) < 0 .or. desc(4) < 0 .or. desc(6) < 0 .or. desc(6) > 4096) then
            msg = "'"//trim(path)//"': invalid description from conmech_model_info"
            return
        end if
        lib%path = trim(path)
        lib%kind = desc(1)
        lib%n = desc(2)
        lib%n_hol = desc(3)
        lib%n_nh = desc(4)
        lib%rheonomic = desc(5) /= 0
        np = desc(6)
        allocate (lib%defaults(np))
        f = symbol(h, "conmech_model_params")
        if (np > 0) then
            if (.not. c_associated(f)) then
                msg = "'"//trim(path)//"' has parameters but no conmech_model_params"
                return
            end if
            call c_f_procpointer(f, get_params)
            call get_params(lib%defaults)
        end if
        lib%param_names = ""
        f = symbol(h, "conmech_model_param_names")
        if (c_associated(f)) then
            call c_f_procpointer(f, get_names)
            buf = c_null_char
            call get_names(buf, int(size(buf), c_int))
            do i = 1, size(buf)
                if (buf(i) == c_null_char) exit
                lib%param_names = lib%param_names//buf(i)
            end do
        end if
        lib%rhs = symbol(h, "conmech_rhs")
        lib%jac = symbol(h, "conmech_jac")
        lib%jac_prod = symbol(h, "conmech_jac_prod")
        do i = 1, N_MECH_ENTRIES
            call set_mech_entry(lib%fp, i, symbol(h, "conmech_"//trim(MECH_ENTRY_NAMES(i))))
        end do
        info = CM_SUCCESS
        msg = "success"
    end subroutine load_model

    !> The first-order system of an ode or generalized model, with parameters `params`
    !! (size = the model's number of parameters).
    subroutine model_system(lib, params, sys, info, msg)
        type(model_library), intent(in) :: lib
        real(dp), intent(in) :: params(:)
        class(ode_system), allocatable, intent(out) :: sys
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        if (.not. check_params(lib, params, info, msg)) return
        select case (lib%kind)
        case (MODEL_KIND_ODE)
            block
                type(c_ode_system) :: s
                call make_c_ode(lib%n, lib%rhs, lib%jac, params, s, info, msg)
                call set_c_jac_prod(s, lib%jac_prod)
                if (info == CM_SUCCESS) allocate (sys, source=s)
            end block
        case (MODEL_KIND_GENERALIZED)
            block
                type(c_generalized_system) :: g
                type(generalized_ode) :: w
                call make_c_generalized(lib%n, lib%fp, params, g, info, msg)
                if (info == CM_SUCCESS) then
                    allocate (w%mech, source=g)
                    allocate (sys, source=w)
                end if
            end block
        case default
            info = CM_BAD_INPUT
            msg = "the model '"//lib%path//"' is a constrained system, not a first-order one"
        end select
    end subroutine model_system

    !> The constrained system of a constrained model, with parameters `params`.
    subroutine model_constrained(lib, params, cs, info, msg)
        type(model_library), intent(in) :: lib
        real(dp), intent(in) :: params(:)
        class(constrained_system), allocatable, intent(out) :: cs
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        if (.not. check_params(lib, params, info, msg)) return
        if (lib%kind /= MODEL_KIND_CONSTRAINED) then
            info = CM_BAD_INPUT
            msg = "the model '"//lib%path//"' is not a constrained system"
            return
        end if
        block
            type(c_constrained_system) :: s
            call make_c_constrained(lib%n, lib%n_hol, lib%n_nh, lib%rheonomic, lib%fp, &
                                    params, s, info, msg)
            if (info == CM_SUCCESS) allocate (cs, source=s)
        end block
    end subroutine model_constrained

    logical function check_params(lib, params, info, msg)
        type(model_library), intent(in) :: lib
        real(dp), intent(in) :: params(:)
        integer, intent(out) :: info
        character(len=:), allocatable, intent(out) :: msg
        character(len=16) :: a, b
        check_params = .false.
        info = CM_BAD_INPUT
        if (lib%kind == 0) then
            msg = "no model loaded"
            return
        end if
        if (size(params) /= size(lib%defaults)) then
            write (a, '(i0)') size(params)
            write (b, '(i0)') size(lib%defaults)
            msg = trim(a)//" parameters given; the model '"//lib%path//"' has "//trim(b) &
                  //" ("//lib%param_names//")"
            return
        end if
        info = CM_SUCCESS
        msg = "success"
        check_params = .true.
    end function check_params

end module conmech_model_library
