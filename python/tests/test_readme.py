"""The README's Python code blocks run as written (each in a fresh interpreter, from a
temporary directory), so the front page never shows code that does not work."""
import os
import re
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _blocks():
    with open(os.path.join(ROOT, "README.md")) as fh:
        text = fh.read()
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_readme_has_python_blocks():
    assert len(_blocks()) >= 3


@pytest.mark.parametrize("index", range(len(_blocks())))
def test_readme_python_block_runs(index, tmp_path):
    code = _blocks()[index]
    env = dict(os.environ, MPLBACKEND="Agg", CONMECH_CACHE=str(tmp_path / "cache"))
    p = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, f"README block {index} failed:\n{code}\n{p.stderr[-3000:]}"
