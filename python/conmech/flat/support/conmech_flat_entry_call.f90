!> A call of one compiled model function given by its address (an entry of a model
!! library: `void f(double t, const double *a1, ..., double *out, ..., const double *p)`, or
!! `double f(...)` for a returned value), for the flat routine that lets Python call a
!! model's entries with f2py's argument handling instead of ctypes' (which builds a Python
!! object for every pointer). The entries take 3 to 6 pointers after t (conmech's slot
!! table, conmech.compiled); the pointers come in the order of the C signature.
module conmech_flat_entry_call
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t, c_ptr, c_funptr, &
        c_f_procpointer
    implicit none
    private
    public :: call_entry

    abstract interface
        subroutine entry3(t, a, b, c) bind(C)
            import :: c_double, c_ptr
            real(c_double), value :: t
            type(c_ptr), value :: a, b, c
        end subroutine entry3
        subroutine entry4(t, a, b, c, d) bind(C)
            import :: c_double, c_ptr
            real(c_double), value :: t
            type(c_ptr), value :: a, b, c, d
        end subroutine entry4
        subroutine entry5(t, a, b, c, d, e) bind(C)
            import :: c_double, c_ptr
            real(c_double), value :: t
            type(c_ptr), value :: a, b, c, d, e
        end subroutine entry5
        subroutine entry6(t, a, b, c, d, e, f) bind(C)
            import :: c_double, c_ptr
            real(c_double), value :: t
            type(c_ptr), value :: a, b, c, d, e, f
        end subroutine entry6
        function value3(t, a, b, c) result(v) bind(C)
            import :: c_double, c_ptr
            real(c_double), value :: t
            type(c_ptr), value :: a, b, c
            real(c_double) :: v
        end function value3
    end interface

contains

    !> Call the function at `address` with t and the pointers p(1:np) (np in 3..6; a
    !! returned value: np = 3 and returns = 1, the value in `value`). info = 1 for a
    !! combination no entry has (nothing is called), else 0.
    subroutine call_entry(address, returns, t, np, p, value, info)
        integer(c_int64_t), intent(in) :: address
        integer(c_int), intent(in) :: returns, np
        real(c_double), intent(in) :: t
        type(c_ptr), intent(in) :: p(:)
        real(c_double), intent(out) :: value
        integer(c_int), intent(out) :: info
        type(c_funptr) :: fp
        procedure(entry3), pointer :: f3
        procedure(entry4), pointer :: f4
        procedure(entry5), pointer :: f5
        procedure(entry6), pointer :: f6
        procedure(value3), pointer :: v3

        value = 0.0_c_double
        info = 0
        fp = transfer(address, fp)
        if (returns /= 0) then
            if (np /= 3) then
                info = 1
                return
            end if
            call c_f_procpointer(fp, v3)
            value = v3(t, p(1), p(2), p(3))
            return
        end if
        select case (np)
        case (3)
            call c_f_procpointer(fp, f3)
            call f3(t, p(1), p(2), p(3))
        case (4)
            call c_f_procpointer(fp, f4)
            call f4(t, p(1), p(2), p(3), p(4))
        case (5)
            call c_f_procpointer(fp, f5)
            call f5(t, p(1), p(2), p(3), p(4), p(5))
        case (6)
            call c_f_procpointer(fp, f6)
            call f6(t, p(1), p(2), p(3), p(4), p(5), p(6))
        case default
            info = 1
        end select
    end subroutine call_entry

end module conmech_flat_entry_call
