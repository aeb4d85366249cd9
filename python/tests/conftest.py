"""Shared fixtures of the trac0r module's tests (run by CTest: tests/CMakeLists.txt).

CTest sets PYTHONPATH to the build tree's python/ directory (where the module is built),
TRAC0R_BIN to the trac0r command and TRAC0R_SOURCE_DIR to the source tree."""
import os

import numpy as np
import pytest

import trac0r


@pytest.fixture(scope="session")
def source_dir():
    return os.environ.get("TRAC0R_SOURCE_DIR",
                          os.path.join(os.path.dirname(__file__), "..", ".."))


@pytest.fixture(scope="session")
def trac0r_bin():
    path = os.environ.get("TRAC0R_BIN")
    if not path:
        pytest.skip("TRAC0R_BIN (the trac0r command) is not set")
    return path


@pytest.fixture
def cornell():
    """The built-in Cornell box, small."""
    with trac0r.load("builtin:cornell", width=64, height=48) as scene:
        yield scene


def read_pfm(path):
    """A PFM file as (height, width, 3) float32, top row first, read without the module."""
    with open(path, "rb") as f:
        assert f.readline() == b"PF\n"
        width, height = map(int, f.readline().split())
        assert float(f.readline()) < 0  # little-endian
        data = np.fromfile(f, dtype="<f4")
    return np.flipud(data.reshape(height, width, 3))
