"""A joint with play in a scene file (``clearance = {...}`` on a revolute joint, or in ``[scene]`` for all): the
flexible bar pendulum hangs from a loose hinge pin, its run verifies itself (the pin's penetration against the play)
and the pin rests where the closed form puts it; bad clearance tables are refused in one line."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from scene_fixtures import LOOSE_BENNETT_FILE, PENDULUM, write_bar

from ffrf.errors import SceneError
from ffrf.scenes.builder import build_scene
from ffrf.scenes.scene_file import run_scene
from ffrf.system.clearance_joint import line_contact_stiffness

HANGING = "pose = {euler_parameters = [0.7071067811865476, 0.0, 0.7071067811865476, 0.0]}"  # turned down about y
PLAY = "{radial_mm = 0.1, pin_length_mm = 10.0}"
MASS = 450.0 * 0.2 * 0.02 * 0.01


def _hanging_pendulum(joint_clearance: str | None, scene_clearance: str | None = None) -> dict:
    text = PENDULUM.replace('mode = "dynamic"', 'mode = "quasi_static"')
    text = text.replace('nodes_file = "hinge.txt"}]', 'nodes_file = "hinge.txt"}]\n' + HANGING)
    if joint_clearance is not None:
        text = text.replace("axis = [0.0, 1.0, 0.0]\n", f"axis = [0.0, 1.0, 0.0]\nclearance = {joint_clearance}\n", 1)
    if scene_clearance is not None:
        text = text.replace('mode = "quasi_static"', f'mode = "quasi_static"\nclearance = {scene_clearance}')
    return tomllib.loads(text)


@pytest.mark.parametrize("where", ["joint", "scene"])
def test_a_pendulum_on_a_loose_pin_rests_at_the_clearance_plus_its_weight_over_the_contact_stiffness(tmp_path, where):
    """The flexible bar hangs from a pin of 0.1 mm radial clearance and 10 mm contact length (its centre of mass
    axially between the rims): the pin's centre sits at c + m g / (2 k) below the bore's axis, k = E* L / 2 of the
    bar's material (Eq. (P5)), as the rigid closed form has it (the bar's bending shifts the rims' shares by 1e-6,
    the centre not); the run verifies itself with the pin's penetration, 3.2 % of the play, judged."""
    write_bar(tmp_path)
    description = _hanging_pendulum(PLAY, None) if where == "joint" else _hanging_pendulum(None, PLAY)
    scene = build_scene(description, base=tmp_path)
    assert [j.name for j in scene.loose_joints] == ["hinge"] and scene.system.constraints == ()
    result = run_scene(scene)
    stiffness = line_contact_stiffness(1e8, 0.3, 1e8, 0.3, 0.01)
    expected = 1e-4 + MASS * 9.81 / (2.0 * stiffness)
    np.testing.assert_allclose(result.sensors["hinge_eccentricity"], expected, rtol=0.0, atol=1e-12)
    penetration, force = result.sensors["hinge_contacts"][0]
    np.testing.assert_allclose(force[:2].sum(), MASS * 9.81, rtol=1e-9)
    verification = result.metadata["verification"]
    assert verification["verified"], verification["reasons"]
    judged = {c["name"]: c for c in verification["checks"]}
    assert judged["pin_penetration"]["value"] == pytest.approx(penetration[:2].max() / 1e-4)
    assert "loop_closure" not in judged  # a loose pin opens the joint by its play, which is not a failure


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d["joints"][0].update(type="fixed"), "only a passive revolute joint can have clearance"),
        (lambda d: d["joints"][0]["clearance"].update(radial_mm=-0.1), "radial_mm"),
        (lambda d: d["joints"][0]["clearance"].pop("pin_length_mm"), "pin_length_mm"),
        (lambda d: d["joints"][0]["clearance"].update(spring=1.0), "spring"),
    ],
)
def test_a_bad_clearance_table_is_refused_in_one_line(tmp_path, change, message):
    write_bar(tmp_path)
    description = _hanging_pendulum(PLAY)
    change(description)
    with pytest.raises(SceneError, match=message) as error:
        build_scene(description, base=tmp_path)
    assert "\n" not in str(error.value)


def test_a_linkage_files_clearance_loosens_every_passive_joint_and_keeps_the_drive_and_the_clamp():
    """``[scene] clearance`` of a linkage file: joints 0, 1 and 2 become pins in bores with the PLA contact stiffness
    (Eq. (P5): 12 mm pins, E* = E / (2 (1 - nu^2))), the driven joint 3 and the clamp stay constraints."""
    from ffrf.fe.materials import PLA
    from ffrf.scenes.linkage_file import load_linkage

    scene = load_linkage(tomllib.loads(LOOSE_BENNETT_FILE))
    assert [j.name for j in scene.loose_joints] == ["joint0", "joint1", "joint2"]
    assert [c.name for c in scene.system.constraints] == ["clamp", "joint3 (drive)"]
    expected = line_contact_stiffness(PLA.E, PLA.nu, PLA.E, PLA.nu, 0.012)
    assert all(j.stiffness == pytest.approx(expected, rel=1e-15) and j.radial == 1e-4 for j in scene.loose_joints)


def test_a_loose_bennett_from_a_linkage_file_runs_and_verifies_itself(tmp_path, capsys):
    """The coarse Bennett of 110 / 220 mm links with 0.1 mm play in its passive joints, 18 deg of drive from the
    command line: assembled ideal, settled into the bores, followed quasi-statically; the run verifies itself (the
    energy balance closes with the contacts' energy counted; the pins' penetration is 4 % of the play). Measured
    18 s on the 2-core machine."""
    from ffrf.cli import main

    path = tmp_path / "loose.toml"
    path.write_text(LOOSE_BENNETT_FILE)
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 0
    assert "verified: true" in capsys.readouterr().out


@pytest.mark.slow
def test_a_loose_bennett_turns_a_whole_revolution_and_verifies_itself(tmp_path, capsys):
    """The same linkage over a whole revolution (73 outputs): its pins cross their bores where the loads through them
    reverse (about 177 deg of drive, where the path stopped before jumps settled at the shortest step tried); the
    run verifies itself, its energy books closed with the contacts' stored energy (measured 8.6e-5 of their scale).
    Measured 77 s on the 2-core machine."""
    from ffrf.cli import main

    path = tmp_path / "loose.toml"
    path.write_text(
        LOOSE_BENNETT_FILE.replace("revolutions = 0.05", "revolutions = 1.0").replace("outputs = 5", "outputs = 73")
    )
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 0
    assert "verified: true" in capsys.readouterr().out


def test_what_does_not_model_play_yet_refuses_a_loose_linkage_in_one_line():
    """Path sensitivities (Eq. (D1) needs a smooth path) and the Exudyn twin (Exudyn has no pin-in-bore joint) refuse
    a linkage with play instead of answering for the linkage without it."""
    from ffrf.errors import SensitivityError
    from ffrf.scenes.linkage_file import load_linkage
    from ffrf.scenes.path_sensitivity import material_sensitivity
    from validation.exudyn_twin import build_twin

    scene = load_linkage(tomllib.loads(LOOSE_BENNETT_FILE))
    q = scene.q_initial[None]
    with pytest.raises(SensitivityError, match="joints with play") as error:
        material_sensitivity(scene, np.zeros(1), q, np.zeros((1, scene.system.n_constraints)))
    assert "\n" not in str(error.value)
    with pytest.raises(TypeError, match="joints with play .* have no Exudyn twin"):
        build_twin([], scene.system, scene.q_initial, 0.0)


@pytest.mark.slow
def test_a_loose_bennett_runs_dynamically_and_its_energy_books_close_with_the_contacts(tmp_path, capsys):
    """The same linkage driven dynamically over 36 deg (generalized-alpha, its pins' contacts in the packed system's
    Newton): the run verifies itself, its energy balance closed with the contacts' stored energy (measured 8.7e-7 of
    its scale) and its step error estimated. Measured 30 s on the 2-core machine."""
    from ffrf.cli import main

    path = tmp_path / "loose.toml"
    dynamic = LOOSE_BENNETT_FILE.replace('mode = "quasi_static"', 'mode = "dynamic"')
    path.write_text(dynamic.replace("revolutions = 0.05", "revolutions = 0.1").replace("outputs = 5", "outputs = 41"))
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 0
    assert "verified: true" in capsys.readouterr().out


def test_a_loose_linkages_play_and_its_links_clearance_are_kept_apart_in_the_metadata():
    """The ``[scene] clearance`` (the pins' play) is the run's ``joint_play``; ``clearance`` is the links' clearance
    along the rigid motion (a loose linkage that checks it crashed on the name before)."""
    from ffrf.scenes.linkage_file import load_linkage
    from ffrf.scenes.linkage_run import run_linkage

    scene = load_linkage(tomllib.loads(LOOSE_BENNETT_FILE.replace("check_clearance = false\n", "")))
    result = run_linkage(scene, mode="quasi_static", n_outputs=3, t_end=0.5)
    assert result.metadata["joint_play"] == {"radial_mm": 0.1, "pin_length_mm": 12.0}
    clearance = result.add_clearance()
    assert clearance is not None and "summary" in clearance and len(clearance["pairs"]) == 6
