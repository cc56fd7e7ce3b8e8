"""The README's Python code blocks run as written (each in a fresh interpreter, from a
temporary directory), and what their comments say they print is what they print.

The convention the README follows: the comment that quotes a print call's output is its
trailing comment, or (when it has none) the comment lines right below it; the quote ends at
the first ": " (what follows is commentary). In the quote

- every number must match a number the call printed, to the precision written
  (0.5348 matches 0.5347844; [0, -1] matches [-3.1e-17, -1.0]);
- "< X" bounds every number the call printed in absolute value;
- classification words (unstable, degenerate, centre, branch point, True, ...) must be
  printed.

Claims about values outside print calls are checked one by one below (the pendulum's period
at theta0 = 1, Hénon's Gamma of the loss of stability of family g)."""
import json
import math
import os
import re
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# a number written in a comment: not part of a name, an exponent or a ratio (z^2, T/4)
QUOTED = re.compile(r"(?<![\w.^/*])([-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?)(?![\w.(])")
PRINTED = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")
BOUND = re.compile(r"<\s*([-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?)")
WORDS = ["unstable", "stable", "degenerate", "centre", "center", "saddle", "node", "focus",
         "branch point", "period doubling", "fold", "neimark-sacker", "S=+1", "S=-1",
         "True", "False"]

RUNNER = r"""
import builtins, io, json, sys
out = {}
_print = builtins.print
def hooked(*args, **kw):
    frame = sys._getframe(1)
    if frame.f_code.co_filename == "<readme>":
        buf = io.StringIO()
        _print(*args, **{k: v for k, v in kw.items() if k != "file"}, file=buf)
        out.setdefault(frame.f_lineno, []).append(buf.getvalue())
    _print(*args, **kw)
builtins.print = hooked
code = open(sys.argv[1]).read()
try:
    exec(compile(code, "<readme>", "exec"), {"__name__": "__main__"})
finally:
    with open(sys.argv[2], "w") as fh:
        json.dump(out, fh)
"""


def _readme():
    with open(os.path.join(ROOT, "README.md")) as fh:
        return fh.read()


def _blocks():
    return re.findall(r"```python\n(.*?)```", _readme(), flags=re.S)


def tolerance(text):
    """Half a unit in the last written digit."""
    mant, _, exp = text.lower().lstrip("+-").partition("e")
    decimals = len(mant.split(".")[1]) if "." in mant else 0
    return 0.5 * 10.0 ** (int(exp or 0) - decimals)


def quotes(code):
    """{line number: quote} for the print calls of a block that quote their output."""
    lines = code.split("\n")
    out = {}
    for i, line in enumerate(lines):
        if "print(" not in line.split("#")[0]:
            continue
        quote = line.split("#", 1)[1].strip() if "#" in line else ""
        j = i + 1
        while not quote and j < len(lines) and lines[j].strip().startswith("#"):
            quote += " " + lines[j].strip().lstrip("#").strip()
            j += 1
        if quote:
            out[i + 1] = quote.split(": ")[0]
    return out


def check_quote(quote, printed):
    """Problems with a quote of the printed text (empty list: it is true)."""
    problems = []
    numbers = [float(x) for x in PRINTED.findall(printed)]
    bounds = BOUND.findall(quote)
    for b in bounds:
        if not numbers or max(abs(x) for x in numbers) >= float(b):
            problems.append(f"'< {b}' but printed {numbers}")
    rest = BOUND.sub(" ", quote)
    for text in QUOTED.findall(rest):
        x, tol = float(text), tolerance(text)
        if not any(abs(y - x) <= tol * (1 + 1e-9) for y in numbers):
            problems.append(f"{text} (+-{tol:g}) is not among the printed numbers {numbers}")
    low_q, low_p = quote.lower(), printed.lower()
    for w in WORDS:
        pattern = r"(?<![\w-])" + re.escape(w.lower()) + r"(?![\w-])"
        if re.search(pattern, low_q) and not re.search(pattern, low_p):
            problems.append(f"says '{w}', which is not printed")
    return problems


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    """Run every block once (in its own interpreter): [(returncode, stderr, {line: [printed
    text]})]."""
    res = []
    for k, code in enumerate(_blocks()):
        d = tmp_path_factory.mktemp(f"readme{k}")
        (d / "block.py").write_text(code)
        (d / "runner.py").write_text(RUNNER)
        env = dict(os.environ, MPLBACKEND="Agg", CONMECH_CACHE=str(d / "cache"))
        p = subprocess.run([sys.executable, str(d / "runner.py"), str(d / "block.py"),
                            str(d / "out.json")], cwd=d, env=env, capture_output=True,
                           text=True, timeout=900)
        printed = {}
        if (d / "out.json").exists():
            printed = {int(k): v for k, v in json.loads((d / "out.json").read_text()).items()}
        res.append((p.returncode, p.stderr, printed))
    return res


def test_readme_has_python_blocks():
    assert len(_blocks()) >= 3


@pytest.mark.parametrize("index", range(len(_blocks())))
def test_readme_python_block_runs(index, outputs):
    rc, err, _ = outputs[index]
    assert rc == 0, f"README block {index} failed:\n{_blocks()[index]}\n{err[-3000:]}"


@pytest.mark.parametrize("index", range(len(_blocks())))
def test_readme_comments_quote_what_is_printed(index, outputs):
    code = _blocks()[index]
    _, _, printed = outputs[index]
    bad = []
    for line, quote in quotes(code).items():
        text = "".join(printed.get(line, []))
        if not text:
            bad.append(f"line {line}: quoted '{quote}' but nothing was printed")
            continue
        bad += [f"line {line} ({code.splitlines()[line - 1].strip()[:50]}): {p}"
                for p in check_quote(quote, text)]
    assert not bad, "\n".join(bad)


def test_quote_checker_catches_the_old_mistakes():
    """The comments the README used to carry fail the check against what the code prints."""
    assert check_quote("T/4, [[0, -1]]", "[0.5347844] [[-3.1e-17 -1.0]]") == []
    assert check_quote("c = 1.07158327741604", "1.0715832774159906 0.90") != []
    assert check_quote("saddle", "theta = 0.0000: unstable, eigenvalues [0 0 4.095 -4.095]")
    assert check_quote("S = +1 at period 1.22587457 (Gamma 4.49998584)",
                       "[('branch point', 1.2258745663196369)]") != []
    assert check_quote("< 1e-9", "3.7e-11") == [] and check_quote("< 1e-12", "3.7e-11")


def _literal(pattern):
    m = re.search(pattern, _readme())
    assert m, pattern
    return m.group(1)


def test_readme_pendulum_period_is_the_period_at_theta0_1():
    """`T = ...  # one period at theta0 = 1`: 4 K(sin^2(1/2)) sqrt(l/g), g = 9.81, l = 1."""
    from scipy.special import ellipk
    text = _literal(r"\nT = ([0-9.]+) +# one period at theta0 = 1")
    exact = 4 * ellipk(math.sin(0.5) ** 2) / math.sqrt(9.81)
    assert abs(float(text) - exact) <= tolerance(text)


def test_readme_henon_gamma_of_the_loss_of_stability():
    """Gamma of family g's loss of stability as the README's comment gives it: Hill's
    variation orbit at the m where S = +1, in Hénon's units (conmech.hill)."""
    from conmech import hill
    from conmech import hill_families as hf
    m = float(_literal(r"at m = ([0-9.]+): the same orbit"))
    text = _literal(r"the same orbit, Gamma = ([0-9.]+)\)")
    orb = hill.variation_orbit(m)
    assert abs(orb.stability_index - 1) < 1e-9
    assert abs(hf.gamma(hill.to_henon(m, orb.y0)) - float(text)) <= tolerance(text)
