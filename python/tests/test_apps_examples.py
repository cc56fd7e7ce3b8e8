"""Every example in example/ runs once (`fpm run --example NAME`) and says what it should.

The examples are what a newcomer reads first; CI runs each of them.
Examples added later are picked up by name and checked to run cleanly; the ones known here
are also checked against a published or closed-form value.
"""
import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted(p.stem for p in (ROOT / "example").glob("*.f90")
                  if re.search(r"^\s*program\s", p.read_text(), re.M | re.I))


def value(text, label):
    m = re.search(re.escape(label) + r"\s*[:=]?\s*([-+0-9.Ee]+)", text)
    assert m, f"'{label}' not in the output"
    return float(m.group(1))


CHECKS = {
    # Hill (1877): c = 1.0715832774160 at m = 0.080848933808312 (REFERENCE.md)
    "hill_perigee": lambda out: abs(value(out, "perigee c") - 1.0715832774160) < 1e-12,
    # Van der Pol, mu = 1: period 6.6632868593 (published limit-cycle period)
    "stability_tour": lambda out: abs(value(out, "Van der Pol (mu = 1) period:")
                                      - 6.6632868593) < 1e-8,
    # the projected pendulum stays on |phi| <= 1e-12 where the unprojected one drifts
    "constrained_quickstart": lambda out: all(
        float(row.split()[6]) < 1e-12 for row in out.splitlines()
        if re.match(r"^\s*[0-9.]+\s+-?[0-9]", row)),
}


@pytest.mark.parametrize("name", EXAMPLES)
def test_example_runs(name):
    if shutil.which("fpm") is None:
        pytest.fail("fpm is not on PATH: run the tests through scripts/test.sh")
    r = subprocess.run(["fpm", "run", "--example", name], cwd=ROOT, capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.strip(), "no output"
    assert not re.search(r"error stop|backtrace|nan\b", r.stdout + r.stderr, re.I)
    if name in CHECKS:
        assert CHECKS[name](r.stdout), r.stdout


def test_examples_found():
    assert {"quickstart", "hill_perigee"} <= set(EXAMPLES)
