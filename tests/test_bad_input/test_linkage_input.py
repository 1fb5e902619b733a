"""Bad linkage files (ffrf.scenes.linkage_file) are refused with one line naming the key and the fix."""

from __future__ import annotations

import pytest

from ffrf.errors import SceneError
from ffrf.scenes.scene_file import load_scene

GOOD = """[linkage]
dh = {a = [110, 220, 110, 220], alpha_deg = [150, 90, 150, 90]}
unit = "mm"
driver = 3
tool_link = 2
"""

#: Four lines in general position: they close at home, but no joint can turn.
RIGID_AXES = (
    "axes = [{point = [0, 0, 0], direction = [0, 0, 1]}, {point = [100, 0, 0], direction = [0, 1, 0]}, "
    "{point = [100, 80, 30], direction = [1, 0, 1]}, {point = [-20, 90, 40], direction = [1, 1, 0]}]"
)
#: A planar crank-rocker (parallel axes, mm) whose joint 3, the rocker's pivot, swings only about 40 deg.
CRANK_ROCKER = (
    "axes = [{point = [0, 0, 0], direction = [0, 0, 1]}, {point = [50, 86.6, 0], direction = [0, 0, 1]}, "
    "{point = [250, 250, 0], direction = [0, 0, 1]}, {point = [400, 0, 0], direction = [0, 0, 1]}]"
)
#: case -> (text replaced, replacement, words the one-line error must contain)
LINKAGE_CASES = {
    "two sources": (
        'unit = "mm"',
        'unit = "mm"\naxes = [{point = [0, 0, 0], direction = [0, 0, 1]}]',
        ["exactly one source", "['dh', 'axes']"],
    ),
    "no source": (
        "dh = {a = [110, 220, 110, 220], alpha_deg = [150, 90, 150, 90]}",
        "",
        ["exactly one source", "none"],
    ),
    "unknown model": (
        'dh = {a = [110, 220, 110, 220], alpha_deg = [150, 90, 150, 90]}\nunit = "mm"',
        'model = "bennet"',
        ["'model' must be one of", "bennett_ark24"],
    ),
    "misspelt linkage key": ("driver = 3", "drver = 3", ["unknown key 'drver'", "did you mean 'driver'"]),
    "bodies beside a linkage": ("tool_link = 2", 'tool_link = 2\n[[bodies]]\nname = "x"', ["unknown key 'bodies'"]),
    "DH lists of different lengths": (
        "alpha_deg = [150, 90, 150, 90]",
        "alpha_deg = [150, 90, 150]",
        ["'alpha_deg' has 3 entries but a has 4"],
    ),
    "DH table that does not close": (
        "alpha_deg = [150, 90, 150, 90]",
        "alpha_deg = [150, 90, 150, 91]",
        ["does not close", "give joint angles that close the loop"],
    ),
    "rigid loop": (
        "dh = {a = [110, 220, 110, 220], alpha_deg = [150, 90, 150, 90]}",
        RIGID_AXES,
        ["NOT mobile, rigid", "closure gap"],
    ),
    "driver out of range": ("driver = 3", "driver = 4", ["driver 4 does not exist", "joints 0 to 3"]),
    "tool link out of range": ("tool_link = 2", "tool_link = 4", ["tool_link 4 does not exist"]),
    "bore error on a joint the link does not carry": (
        "tool_link = 2",
        "tool_link = 2\nbore_errors = [{joint = 2, link = 0, twist_deg = 1.0}]",
        ["link 0 does not carry joint 2", "link k carries joints k-1 and k"],
    ),
    "bore axis without direction": (
        "tool_link = 2",
        "tool_link = 2\nbore_errors = [{joint = 3, link = 0, point = [0, 0, 0]}]",
        ["give both point and direction of the bore's axis"],
    ),
    "bore axis and twist together": (
        "tool_link = 2",
        "tool_link = 2\nbore_errors = [{joint = 3, link = 0, twist_deg = 1.0, point = [0, 0, 0], "
        "direction = [0, 0, 1]}]",
        ["give either twist_deg/offset/tilt_deg/shift or the bore's axis"],
    ),
    "design points for a DH table": (
        "driver = 3",
        "driver = 3\ndesign_points = true",
        ["'design_points' takes a model"],
    ),
    "scale for a DH table": ("driver = 3", "driver = 3\nscale = 0.1", ["'scale' scales a model"]),
    "drive past a dead point": (
        "dh = {a = [110, 220, 110, 220], alpha_deg = [150, 90, 150, 90]}",
        CRANK_ROCKER,
        ["the run turns joint 3 by 363 deg", "cannot turn further", "drive another joint"],
    ),
    "negative link design": ("driver = 3", "driver = 3\nlink_design = {arm_width = -16}", ["'arm_width'", "> 0"]),
    "bore wider than its housing": (
        "driver = 3",
        "driver = 3\nlink_design = {bore_radius = 20}",
        ["link_design: LinkDesign: bore radius 0.02 m must be smaller than the housing outer radius 0.016 m"],
    ),
    "nan in a DH table": ("a = [110, 220, 110, 220]", "a = [110, nan, 110, 220]", ["'a' must be finite"]),
    # issue #32: size guards and numbers that used to end in a traceback or a run of months
    "a million revolutions": (
        "tool_link = 2",
        "tool_link = 2\nrevolutions = 1e6",  # 1e6 turns at 3 deg per equilibrium: 1.2e8 equilibria
        ["1.2e+08 time steps over the run", "more than 1e+07", "max_steps = N in [scene]"],
    ),
    "dynamic step of a nanosecond": (
        "tool_link = 2",
        'tool_link = 2\n[scene]\nmode = "dynamic"\nstep = 1e-9',  # 1 s ramp + 60 s at 1 rpm: 6.1e10 steps
        ["6.1e+10 time steps over the run", "max_steps = N in [scene]"],
    ),
    "step longer than the linkage run": (
        "tool_link = 2",
        'tool_link = 2\n[scene]\nmode = "dynamic"\nstep = 100.0',
        ["step = 100.0 s is longer than the run (61 s"],
    ),
    "bore twist of 1e300 deg": (
        "tool_link = 2",
        "tool_link = 2\nbore_errors = [{joint = 3, link = 0, twist_deg = 1e300}]",
        ["'twist_deg' must lie in [-180, 180]"],
    ),
    "bore offset of a kilometre": (
        "tool_link = 2",
        "tool_link = 2\nbore_errors = [{joint = 3, link = 0, offset = 1e6}]",
        ["'offset' = 1000000.0 is 1e+03 m, more than 10 m"],
    ),
    "start angle of 1e300 deg": ("driver = 3", "driver = 3\nstart_angle_deg = 1e300", ["'start_angle_deg' must lie"]),
    "no modes": ("driver = 3", "driver = 3\nmodes = 0", ["'modes' must be >= 1, got 0"]),
    "bore axis of length 1e-300": (
        "tool_link = 2",
        "tool_link = 2\nbore_errors = [{joint = 3, link = 0, point = [0, 0, 0], direction = [0, 0, 1e-300]}]",
        ["'direction' has length 1e-300, too short to give a direction"],
    ),
}


@pytest.mark.parametrize("case", LINKAGE_CASES)
def test_bad_linkage_file_is_refused_with_a_clear_message(tmp_path, case):
    old, new, words = LINKAGE_CASES[case]
    assert old in GOOD, case
    (tmp_path / "linkage.toml").write_text(GOOD.replace(old, new, 1))
    with pytest.raises(SceneError) as raised:
        load_scene(tmp_path / "linkage.toml")
    message = str(raised.value)
    assert "\n" not in message and "linkage.toml" in message
    for word in words:
        assert word in message, (case, message)
