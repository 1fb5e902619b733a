"""The examples (``>>>``) in the public API's docstrings, run as tests.

Each listed module must hold examples and all must pass; a module of ``ffrf`` or ``kinematics``
with examples that is not listed fails too, so that no example goes unchecked. The listed modules
import neither Exudyn, NGsolve nor gmsh sessions, and their examples compile only tiny numba kernels.
"""

from __future__ import annotations

import doctest
import importlib
import io
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

MODULES = (
    "kinematics.quaternion",
    "kinematics.dual_quaternion",
    "kinematics.pluecker",
    "kinematics.dh",
    "ffrf.numerics.small_linalg",
    "ffrf.numerics.eigen",
    "ffrf.mesh.tet_mesh",
    "ffrf.fe.fe_model",
    "ffrf.fe.materials",
    "ffrf.geometry.link_cad",
    "ffrf.system.drives",
)
OPTIONS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_hold(name: str):
    module = importlib.import_module(name)
    tests = [test for test in doctest.DocTestFinder().find(module) if test.examples]
    assert tests, f"{name} is listed in MODULES but has no docstring example"
    out = io.StringIO()
    runner = doctest.DocTestRunner(optionflags=OPTIONS)
    for test in tests:
        runner.run(test, out=out.write)
    assert runner.failures == 0, out.getvalue()


def test_every_module_with_examples_is_listed():
    with_examples = {
        ".".join(path.relative_to(ROOT).with_suffix("").parts)
        for package in ("ffrf", "kinematics")
        for path in (ROOT / package).rglob("*.py")
        if ">>> " in path.read_text()
    }
    assert with_examples - set(MODULES) == set(), "add these modules to MODULES"
