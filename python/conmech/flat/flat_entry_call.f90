!> A compiled model's entry called from Python through f2py (conmech.symbolic's
!! CompiledModel.call): the entry's address, t, its input arrays and its parameters in,
!! its outputs (fresh arrays, flattened in Fortran order) out. f2py converts a float64
!! array argument for a fraction of what ctypes spends on a pointer argument, and the
!! outputs it allocates are the arrays handed to the user. Sizes are at least 1 (f2py
!! cannot pass empty arrays): an empty input or output is a one-element placeholder.

!> out1(1:m1) = f(t, x1(1:n1); p): an entry with one input and one output (rhs, jac, mass,
!! phi, phi_jac, phi_t). info = 0, or CM_BAD_INPUT for a null address.
subroutine flat_entry_call_1(address, t, n1, x1, m1, np, p, out1, info)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t, c_ptr, c_loc
    use conmech_status, only: CM_BAD_INPUT
    use conmech_flat_entry_call, only: call_entry
    implicit none
    integer(c_int64_t), intent(in) :: address
    real(c_double), intent(in) :: t
    integer(c_int), intent(in) :: n1, m1, np
    real(c_double), intent(in), target :: x1(n1), p(np)
    real(c_double), intent(out), target :: out1(m1)
    integer(c_int), intent(out) :: info
    type(c_ptr) :: ptrs(3)
    real(c_double) :: value

    out1 = 0.0_c_double
    info = CM_BAD_INPUT
    if (address == 0_c_int64_t) return
    ptrs = [c_loc(x1), c_loc(out1), c_loc(p)]
    call call_entry(address, 0_c_int, t, 3_c_int, ptrs, value, info)
    if (info /= 0) info = CM_BAD_INPUT
end subroutine flat_entry_call_1

!> Any entry: nin (1..3) inputs x1, x2, x3 (the unused ones placeholders), nout (0..2)
!! outputs out1, out2 (m1, m2 numbers each), parameters p, in the order of the C
!! signature (inputs, outputs, p); returns = 1 for an entry that returns a double (in
!! `value`, no output array). info = 0, or CM_BAD_INPUT (a null address, or counts that
!! no entry has: nothing is called).
subroutine flat_entry_call(address, returns, t, nin, n1, x1, n2, x2, n3, x3, nout, m1, m2, &
                           np, p, out1, out2, value, info)
    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int64_t, c_ptr, c_loc
    use conmech_status, only: CM_BAD_INPUT
    use conmech_flat_entry_call, only: call_entry
    implicit none
    integer(c_int64_t), intent(in) :: address
    integer(c_int), intent(in) :: returns, nin, n1, n2, n3, nout, m1, m2, np
    real(c_double), intent(in) :: t
    real(c_double), intent(in), target :: x1(n1), x2(n2), x3(n3), p(np)
    real(c_double), intent(out), target :: out1(m1), out2(m2)
    real(c_double), intent(out) :: value
    integer(c_int), intent(out) :: info
    type(c_ptr) :: ptrs(6)
    integer(c_int) :: k

    out1 = 0.0_c_double
    out2 = 0.0_c_double
    value = 0.0_c_double
    info = CM_BAD_INPUT
    if (address == 0_c_int64_t .or. nin < 1 .or. nin > 3 .or. nout < 0 .or. nout > 2) return
    if (returns /= 0 .and. nout /= 0) return
    ptrs(1) = c_loc(x1)
    if (nin >= 2) ptrs(2) = c_loc(x2)
    if (nin >= 3) ptrs(3) = c_loc(x3)
    k = nin
    if (nout >= 1) then
        k = k + 1
        ptrs(k) = c_loc(out1)
    end if
    if (nout >= 2) then
        k = k + 1
        ptrs(k) = c_loc(out2)
    end if
    k = k + 1
    ptrs(k) = c_loc(p)
    call call_entry(address, returns, t, k, ptrs(1:k), value, info)
    if (info /= 0) info = CM_BAD_INPUT
end subroutine flat_entry_call
