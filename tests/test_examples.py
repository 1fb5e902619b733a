"""The examples run and give their physical answer."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).parents[1] / "examples"


def _run(name: str) -> float:
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    assert spec is not None and spec.loader is not None, f"examples/{name}.py cannot be loaded"
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.main()


def test_example_1_configuration_ratio_is_sqrt3():
    assert _run("ex01_bennett_motion") == pytest.approx(np.sqrt(3.0), abs=1e-14)  # measured 4.4e-16


def test_example_2_hinge_carries_a_quarter_of_the_weight():
    length, thickness = 0.2, 0.01
    expected = 1 - length**2 / (4 * (length**2 / 3 + thickness**2 / 12))
    assert _run("ex02_rigid_pendulum") == pytest.approx(expected, rel=1e-13)  # measured 0 (exact to rounding)


def test_example_3_tumbling_bar_keeps_its_angular_momentum():
    assert _run("ex03_tumbling_flexible_bar") < 1e-12  # measured 9.8e-15


def test_example_4_clamp_carries_the_weight_and_a_revolution_does_no_net_work():
    """Statics of the quasi-static flexible linkage: the clamp, its only support, carries m g in
    every pose; over one closed revolution gravity returns the drive's work (measured: clamp
    force m g to 4.4e-16, net work 7.7e-12 of the integral of |torque|; 2026-11, AMD EPYC)."""
    out = _run("ex04_flexible_bennett")
    assert out["turned"] == pytest.approx(2 * np.pi, abs=1e-12)
    np.testing.assert_allclose(out["clamp_over_weight"], 1.0, atol=1e-13)
    assert abs(out["net_work_relative"]) < 1e-9


def test_example_5_any_linkage_as_built_keeps_the_statics_of_example_4():
    """A 6R of Rational Linkages with a bore 0.5 deg off, assembled elastically: the clamp carries m g in every
    pose and a closed revolution does no net drive work (measured: m g to 2.2e-16, net work 1.2e-12 of the
    integral of |torque|; 2026-11-24, AMD EPYC)."""
    out = _run("ex05_any_linkage")
    assert out["turned"] == pytest.approx(2 * np.pi, abs=1e-12)
    np.testing.assert_allclose(out["clamp_over_weight"], 1.0, atol=1e-13)
    assert abs(out["net_work_relative"]) < 1e-9
