"""The description procedures of a model library (conmech_model_library's convention):
conmech_model_info (kind and dimensions), conmech_model_params (the default parameter values)
and conmech_model_param_names, which `sweep --model` and `conmech.compiled.load_model` read."""
from .printer import FortranPrinter
from .source_text import string_constant


def _model_info(d, values):
    """The description procedures of a model library (conmech_model_library's convention):
    kind, dimensions, default parameter values `values` and parameter names."""
    kind = {"ode": 1, "generalized": 2, "constrained": 3}[d.kind]
    n_hol = getattr(d, "n_hol", 0) or 0
    n_nh = getattr(d, "n_nh", 0) or 0
    rheo = int(bool(getattr(d, "rheonomic", False)))
    npar = len(d.params)
    names = string_constant(" ".join(d.param_names), "            ")
    vals = ", ".join(FortranPrinter({})._real(float(v)) for v in values) or "0.0_dp"
    ind = "        "
    return [
        '    subroutine conmech_model_info(info) bind(C, name="conmech_model_info")',
        f"{ind}integer(c_int), intent(out) :: info(6)",
        f"{ind}info = [{kind}, {d.n}, {n_hol}, {n_nh}, {rheo}, {npar}]",
        "    end subroutine conmech_model_info",
        "",
        '    subroutine conmech_model_params(p) bind(C, name="conmech_model_params")',
        f"{ind}real(dp), intent(out) :: p({max(npar, 1)})",
        f"{ind}p = [{vals}]" if npar else f"{ind}p = 0.0_dp",
        "    end subroutine conmech_model_params",
        "",
        '    subroutine conmech_model_param_names(buf, n) bind(C, '
        'name="conmech_model_param_names")',
        f"{ind}integer(c_int), value, intent(in) :: n",
        f"{ind}character(kind=c_char), intent(out) :: buf(n)",
        f"{ind}character(len=*), parameter :: names = &",
        *names,
        f"{ind}integer :: i",
        f"{ind}buf = c_null_char",
        f"{ind}do i = 1, min(n - 1, len(names))",
        f"{ind}    buf(i) = names(i:i)",
        f"{ind}end do",
        "    end subroutine conmech_model_param_names",
        "",
    ]
