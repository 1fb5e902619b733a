"""The examples run and give their physical answer."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).parents[1] / "examples"


def _run(name: str) -> float:
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.main()


def test_example_1_configuration_ratio_is_sqrt3():
    assert _run("ex01_bennett_motion") == pytest.approx(np.sqrt(3.0), abs=1e-12)


def test_example_2_hinge_carries_a_quarter_of_the_weight():
    length, thickness = 0.2, 0.01
    expected = 1 - length**2 / (4 * (length**2 / 3 + thickness**2 / 12))
    assert _run("ex02_rigid_pendulum") == pytest.approx(expected, rel=1e-10)


def test_example_3_tumbling_bar_keeps_its_angular_momentum():
    assert _run("ex03_tumbling_flexible_bar") < 1e-11
