"""``python -m validation report --scene``: scene files against their Exudyn twin (issue 7).

Two scenes of ``tests/test_scene_file``: the flexible bar pendulum (dynamic, from the meshes'
configuration) and a parametric PLA link driven about a horizontal axis through its first bore
(quasi-static, static start: the drive about a horizontal axis lifts the link against gravity). Measured when
written: sensors 1e-15 of their travel, torque 1e-12 relative, frequencies 1e-14.
"""

import json

import numpy as np
import pytest

pytest.importorskip("exudyn", reason="Exudyn is the reference implementation for these cross-checks")

from scene_fixtures import PENDULUM, driven_link_scene, write_bar  # noqa: E402

from validation.__main__ import main  # noqa: E402

DRIVEN = driven_link_scene("[0.0, 1.0, 0.0]", t_end=20.0, outputs=11, modes=3, sensor=True)


def report(tmp_path, text: str) -> dict:
    (tmp_path / "scene.toml").write_text(text)
    assert main(["report", "--scene", str(tmp_path / "scene.toml"), "--out", str(tmp_path / "report")]) == 0
    assert (tmp_path / "report" / "report.md").read_text().startswith("# Cross-validation against Exudyn: scene")
    return json.loads((tmp_path / "report" / "metrics.json").read_text())


def test_dynamic_bar_pendulum_scene(tmp_path):
    write_bar(tmp_path)
    m = report(tmp_path, PENDULUM)
    assert m["passed"], [c for c in m["checks"] if not c["passed"]]
    tip = m["sensors"]["tip"]
    assert tip["travel_m"] > 1e-3  # the bar swings
    assert tip["max_abs_diff_m"] < 1e-6 * tip["travel_m"]


def test_quasi_static_driven_link_scene(tmp_path):
    m = report(tmp_path, DRIVEN)
    assert m["passed"], [c for c in m["checks"] if not c["passed"]]
    torque = m["torques"]["motor"]
    assert torque["max_abs_Nm"] > 1e-3  # lifting the link against gravity
    assert m["sensors"]["far_bore"]["travel_m"] > 0.01
    assert np.isfinite(m["exact_gravity_effect"]["far_bore"])
