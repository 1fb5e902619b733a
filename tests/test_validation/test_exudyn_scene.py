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

from scene_fixtures import PENDULUM, write_bar  # noqa: E402

from validation.__main__ import main  # noqa: E402

DRIVEN = """
[scene]
name = "lifted link"
mode = "quasi_static"
t_end = 20.0
outputs = 11
beta = 0.005
[[bodies]]
name = "link1"
parametric = {link = 1, h = 0.008}
material = {E = 1.2e9, nu = 0.33, rho = 450.0}
modes = 3
interfaces = [{name = "a", group = "joint0"}, {name = "b", group = "joint1"}]
[[joints]]
name = "motor"
type = "driven_revolute"
body0 = "ground"
body1 = "link1"
interface1 = "a"
axis = [0.0, 1.0, 0.0]
point = [0.0, 0.0, 0.0085]
drive = {rpm = 1.0, ramp_time = 1.0}
[[sensors]]
name = "far_bore"
body = "link1"
point = [0.11, 0.0, 0.0]
"""


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
