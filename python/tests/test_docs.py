"""Every ```python block of docs/python.md runs as a whole program (in a scratch
directory, so the files the examples write land there)."""
import os
import re
import subprocess
import sys

import pytest


SOURCE_DIR = os.environ.get("TRAC0R_SOURCE_DIR",
                            os.path.join(os.path.dirname(__file__), "..", ".."))
with open(os.path.join(SOURCE_DIR, "docs", "python.md")) as f:
    BLOCKS = re.findall(r"```python\n(.*?)```", f.read(), re.S)


def test_docs_have_examples():
    assert len(BLOCKS) >= 10


@pytest.mark.parametrize("code", BLOCKS, ids=[f"example{k}" for k in range(len(BLOCKS))])
def test_docs_example(code, tmp_path):
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                       text=True)
    assert r.returncode == 0, f"{code}\n{r.stderr}"


def test_examples_compile():
    """examples/python/ (run by hand: they render for tens of seconds) at least parse."""
    folder = os.path.join(SOURCE_DIR, "examples", "python")
    scripts = [f for f in os.listdir(folder) if f.endswith(".py")]
    assert len(scripts) >= 2
    for name in scripts:
        with open(os.path.join(folder, name)) as f:
            compile(f.read(), name, "exec")
