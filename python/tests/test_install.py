"""`cmake --install` puts the module where it says, and it imports from there."""
import os
import re
import subprocess
import sys

import pytest


def test_install_prints_and_imports(tmp_path):
    cmake = os.environ.get("CMAKE_COMMAND")
    build = os.environ.get("TRAC0R_BUILD_DIR")
    if not cmake or not build:
        pytest.skip("CMAKE_COMMAND and TRAC0R_BUILD_DIR are not set")
    prefix = tmp_path / "prefix"
    out = subprocess.run([cmake, "--install", build, "--prefix", str(prefix)], check=True,
                         capture_output=True, text=True).stdout
    m = re.search(r"Python module trac0r: (\S+)", out)
    assert m, out
    site = m.group(1)
    assert site.startswith(str(prefix))
    assert [f for f in os.listdir(site) if f.startswith("trac0r.") and f.endswith(".so")]
    env = dict(os.environ, PYTHONPATH=site)
    code = ("import trac0r; s = trac0r.load('builtin:cornell', width=8, height=8); "
            "print(trac0r.__file__, trac0r.render(s, spp=1).image.shape)")
    r = subprocess.run([sys.executable, "-c", code], env=env, cwd=tmp_path, check=True,
                       capture_output=True, text=True)
    assert r.stdout.startswith(site) and "(8, 8, 3)" in r.stdout
