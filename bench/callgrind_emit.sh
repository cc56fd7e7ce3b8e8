#!/usr/bin/env bash
# Callgrind instructions per Arenstorf period of integrate_stm (DOP853, rtol = atol = 1e-10)
# on the type that `python -m conmech.symbolic emit` writes (example/arenstorf_model.f90):
# with its Jacobian product (rhs_jacobian_product: f and J Phi under one elimination), the
# same type with has_jacobian_product switched off (dense J, then the product kernels),
# and the built-in arenstorf (hand-written product). The driver is written below.
# Usage (from the repository root, fpm and valgrind on PATH): bash bench/callgrind_emit.sh
set -euo pipefail
cd "$(dirname "$0")/.."
FF="${FFLAGS:--O3 -funroll-loops}"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fpm install --prefix "$tmp/cm" --profile release --flag "$FF" >"$tmp/build.log" 2>&1 \
    || { tail -5 "$tmp/build.log"; exit 1; }
libdir=$(ls -d "$tmp"/cm/lib* | head -1)
cat >"$tmp/emit_stm.f90" <<'F90'
!> integrate_stm per Arenstorf period (DOP853, tol 1e-10): the emitted arenstorf_sym with
!! its product, the same type without it (has_jacobian_product false: dense J path), the
!! built-in arenstorf.  usage: emit_stm emitted|dense|builtin REPS
module emit_nodense
    use conmech
    use arenstorf_model, only: arenstorf_sym
    implicit none
    type, extends(arenstorf_sym) :: sym_dense
    contains
        procedure :: has_jacobian_product => no_prod
    end type
contains
    logical function no_prod(self)
        class(sym_dense), intent(in) :: self
        no_prod = .false.
    end function
end module
program emit_stm
    use conmech
    use arenstorf_model, only: arenstorf_sym, new_arenstorf_sym
    use emit_nodense
    implicit none
    character(len=16) :: arg, a2
    type(arenstorf_sym) :: s1
    type(sym_dense) :: s2
    type(arenstorf) :: s3
    type(ode_options) :: opt
    type(ode_stats) :: st
    real(dp) :: y(4), phi(4, 4)
    real(dp), parameter :: T = 17.0652165601579625588917206249_dp
    integer :: reps, r, i, info
    call get_command_argument(1, arg)
    call get_command_argument(2, a2)
    read (a2, *) reps
    s1 = new_arenstorf_sym()
    s2%arenstorf_sym = new_arenstorf_sym()
    opt%method = METHOD_DOP853; opt%rtol = 1.0e-10_dp; opt%atol = 1.0e-10_dp
    do r = 1, reps
        y = [0.994_dp, 0.0_dp, 0.0_dp, -2.00158510637908252240537862224_dp]
        phi = 0.0_dp
        do i = 1, 4
            phi(i, i) = 1.0_dp
        end do
        select case (trim(arg))
        case ("emitted")
            call integrate_stm(s1, 0.0_dp, T, y, phi, opt, info, stats=st)
        case ("dense")
            call integrate_stm(s2, 0.0_dp, T, y, phi, opt, info, stats=st)
        case default
            call integrate_stm(s3, 0.0_dp, T, y, phi, opt, info, stats=st)
        end select
    end do
    print *, trim(arg), info, st%nfev, phi(1, 1) + phi(2, 2) + phi(3, 3) + phi(4, 4)
end program
F90
gfortran $FF -I"$tmp/cm/include" -J "$tmp" example/arenstorf_model.f90 "$tmp/emit_stm.f90" \
    -L"$libdir" -lconmech -llapack -lblas -o "$tmp/emit_stm"
ir() { valgrind --tool=callgrind --callgrind-out-file="$tmp/o.$1.$2" "$tmp/emit_stm" "$1" "$2" \
           >/dev/null 2>&1
       grep -E '^(summary|totals):' "$tmp/o.$1.$2" | head -1 | awk '{print $2}'; }
per() { echo $(( ($(ir "$1" 11) - $(ir "$1" 1))/10 )); }
pe=$(per emitted); pd=$(per dense); pb=$(per builtin)
echo "flags: $FF; nfev: $("$tmp/emit_stm" emitted 1 | awk '{print $3}')"
printf "%-44s %12s\n" "integrate_stm, emitted type with its product" "$pe" \
    "integrate_stm, emitted type, dense J" "$pd" "integrate_stm, built-in arenstorf" "$pb"
awk -v e="$pe" -v d="$pd" -v b="$pb" \
    'BEGIN{printf "ratios to the built-in: %.3f with the product, %.3f dense\n", e/b, d/b}'
