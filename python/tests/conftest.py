"""Fixtures of the bigstep Python tests.

Environment (set by the CTest test `python`, python/CMakeLists.txt):
  BIGSTEP_SOURCE_DIR  the source tree (default: two folders up)
  BIGSTEP_CLI         the command line `bigstep` of the same build
  BIGSTEP_PREFIX      the prefix the package was built against (include/, lib/)
"""
import os
import shutil

import pytest

SRC = os.environ.get("BIGSTEP_SOURCE_DIR") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def _cli():
    c = os.environ.get("BIGSTEP_CLI")
    if c and os.path.exists(c):
        return c
    for c in (os.path.join(SRC, "build", "app", "bigstep"), shutil.which("bigstep")):
        if c and os.path.exists(c):
            return c
    return None


@pytest.fixture(scope="session")
def src():
    return SRC


@pytest.fixture(scope="session")
def cli():
    c = _cli()
    if not c:
        pytest.skip("no bigstep command line (BIGSTEP_CLI)")
    return c


@pytest.fixture(scope="session")
def prefix():
    p = os.environ.get("BIGSTEP_PREFIX")
    if not p:  # the system's install (setup.sh's)
        p = "/usr/local"
    return p


def material(model="neo_hookean", youngs=1e5):
    return {"model": model, "youngs": youngs, "poisson": 0.3, "density": 1000}


def cube_scene(**kw):
    """A small dynamic scene as a dict: a 3^3-cell cube pulled at xmax, clamped at xmin."""
    d = {
        "time": {"fps": 24, "frames": 6, "steps_per_frame": 2},
        "solver": {"method": "optimization", "linear": "cg", "tolerance": 1e-6},
        "gravity": [0, -9.8, 0],
        "bodies": [{
            "mesh": "box", "box": {"cells": [3, 3, 3], "size": [1, 1, 1]},
            "material": material("fixed_corotated", 1e5),
            "scripted": [{"group": "xmin", "fixed": True},
                         {"group": "xmax", "velocity": [0.5, 0, 0]}],
        }],
        "qoi": [{"name": "tip_y", "quantity": "displacement", "group": "ymax", "component": "y"}],
        "output": {"dir": ""},
    }
    d.update(kw)
    return d
