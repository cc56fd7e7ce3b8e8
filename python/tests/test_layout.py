"""The Python package's layers: every folder imports only the folders below it, no module
imports itself back through others, the status codes are conmech_status's, and the public
module paths and an installation without sympy keep working.

The layers, from the ground up: _core, ivp, mechanics, stability, control, symbolic
(sympy: an optional dependency). The import graph is read from the installed package's
sources; imports inside functions (the lazy ones) count in the layer check and in the
second circle check, which names the one lazy path that closes a circle."""
import ast
import re
import subprocess
import sys
from pathlib import Path

import conmech
from conmech._core import status

PACKAGE = Path(conmech.__file__).parent
ROOT = Path(__file__).resolve().parents[2]
LAYERS = ["_core", "ivp", "mechanics", "stability", "control", "symbolic"]


def _modules():
    """{dotted name: path} of every module of the installed package (benchmarks excluded:
    test problems built on the whole package)."""
    out = {}
    for p in PACKAGE.rglob("*.py"):
        rel = p.relative_to(PACKAGE).with_suffix("")
        parts = list(rel.parts)
        if parts[0] in ("benchmarks", "__pycache__"):
            continue
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(["conmech"] + parts)] = p
    return out


def _imports(name, path, top_level_only):
    """The conmech modules that module `name` imports (relative imports resolved; `from
    package import module` counts as the module)."""
    tree = ast.parse(path.read_text())
    is_pkg = path.name == "__init__.py"
    pkg = name.split(".") if is_pkg else name.split(".")[:-1]
    nodes = tree.body if top_level_only else list(ast.walk(tree))
    found = set()
    for node in nodes:
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg[:len(pkg) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("conmech"):
                continue
            found.add(target)
            for alias in node.names:
                found.add(f"{target}.{alias.name}")
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith("conmech"))
    return found


def _layer(module):
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in LAYERS else None


def test_every_layer_imports_only_layers_below_it():
    mods = _modules()
    wrong = []
    for name, path in mods.items():
        own = _layer(name)
        if own is None:
            continue
        for target in _imports(name, path, top_level_only=False):
            other = _layer(target)
            if other is None or other == own:
                continue
            lazy_sympy = other == "symbolic"      # the Taylor glue: sympy only on that path
            if LAYERS.index(other) > LAYERS.index(own) and not lazy_sympy:
                wrong.append(f"{name} -> {target}")
            if lazy_sympy and target in _imports(name, path, top_level_only=True):
                wrong.append(f"{name} -> {target} (at module level)")
    assert not wrong, "imports from a higher layer:\n" + "\n".join(sorted(wrong))


def test_no_import_circle_at_module_level():
    mods = _modules()
    graph = {name: {t for t in _imports(name, path, top_level_only=True) if t in mods
                    and t != name}
             for name, path in mods.items()}
    # a package's __init__ imported by its own modules is the package face: not an edge
    for name in graph:
        graph[name] = {t for t in graph[name] if not name.startswith(t + ".")}
    state, stack, circles = {}, [], []

    def visit(n):
        state[n] = 1
        stack.append(n)
        for m in sorted(graph[n]):
            if state.get(m) == 1:
                circles.append(stack[stack.index(m):] + [m])
            elif m not in state:
                visit(m)
        stack.pop()
        state[n] = 2

    for n in sorted(graph):
        if n not in state:
            visit(n)
    assert not circles, "import circles:\n" + "\n".join(" -> ".join(c) for c in circles)


def _circles(graph):
    state, stack, circles = {}, [], []

    def visit(n):
        state[n] = 1
        stack.append(n)
        for m in sorted(graph[n]):
            if state.get(m) == 1:
                circles.append(stack[stack.index(m):] + [m])
            elif m not in state:
                visit(m)
        stack.pop()
        state[n] = 2

    for n in sorted(graph):
        if n not in state:
            visit(n)
    return circles


# imports inside functions that close a circle, each named: the Taylor glue of the
# integrators asks the optional sympy front end to compile the recurrences of a generated
# system on first need (sympy only on that path; checked by the layer test). Any other
# question a lower layer has for a generated system goes through its model
# (conmech._core.model), not through an import of conmech.symbolic.
_LAZY_EDGES = {("conmech.ivp.taylor", "conmech.symbolic"),
               ("conmech.ivp.taylor_generalized", "conmech.symbolic")}


def test_no_import_circle_through_imports_inside_functions():
    mods = _modules()
    graph = {}
    for name, path in mods.items():
        every = _imports(name, path, top_level_only=False)
        graph[name] = {
            t for t in every if t in mods and t != name and not name.startswith(t + ".")
            and (name, t) not in _LAZY_EDGES}
    circles = _circles(graph)
    assert not circles, "import circles:\n" + "\n".join(" -> ".join(c) for c in circles)


def test_no_file_over_600_lines():
    """One concept per file: no module of the package, and no Fortran source of the library
    or the flat layer, over 600 lines."""
    long = []
    files = list(PACKAGE.rglob("*.py"))
    files += list((ROOT / "src").rglob("*.f90")) + list((ROOT / "python" / "conmech" / "flat")
                                                          .rglob("*.f90"))
    for p in files:
        if "__pycache__" in p.parts:
            continue
        n = len(p.read_text().splitlines())
        rel = p.relative_to(PACKAGE).as_posix() if PACKAGE in p.parents else \
            p.relative_to(ROOT).as_posix()
        rel = rel if rel.startswith(("src/", "python/")) else "conmech/" + rel
        if n > 600:
            long.append(f"{rel}: {n} lines")
    assert not long, "files over the limit:\n" + "\n".join(sorted(long))


def test_status_codes_are_the_fortran_ones():
    src = (ROOT / "src" / "core" / "conmech_status.f90").read_text()
    fortran = {m.group(1): int(m.group(2)) for m in
               re.finditer(r"integer, parameter, public :: CM_(\w+) = (-?\d+)", src)}
    assert len(fortran) == 10
    for key, value in fortran.items():
        assert getattr(status, key) == value, key
    assert status.status_message(status.SINGULAR) == "singular matrix"
    assert isinstance(status.error_for(status.BAD_INPUT, b"y0 must be finite"), ValueError)
    err = status.error_for(status.NO_CONVERGENCE, b"   ")
    assert isinstance(err, RuntimeError) and str(err) == "iteration did not converge"


def test_public_module_paths_name_the_layered_modules():
    import conmech.compiled
    import conmech.constrained
    import conmech.degrees_of_freedom
    import conmech.ensemble
    import conmech.systems
    from conmech.compiled import evaluate
    assert conmech.systems is sys.modules["conmech.mechanics.systems"]
    assert conmech.constrained.__name__ == "conmech.mechanics.constrained"
    assert evaluate is conmech.mechanics.compiled.evaluate
    assert conmech.ensemble.solve is conmech.ivp.ensemble.solve
    assert conmech.degrees_of_freedom.degrees_of_freedom(conmech.systems.pendulum_xy()).dof == 1


def test_import_without_sympy():
    """sympy is optional: without it the package imports and integrates."""
    code = ("import sys; sys.modules['sympy'] = None\n"
            "import conmech, conmech.stability, conmech.control, conmech.hill_families\n"
            "r = conmech.solve_ivp(conmech.systems.kepler(), (0, 1), [1, 0, 0, 1])\n"
            "assert r.success and 'sympy' not in [m.split('.')[0] for m in sys.modules "
            "if sys.modules[m] is not None]\n")
    subprocess.run([sys.executable, "-c", code], check=True, cwd="/")
