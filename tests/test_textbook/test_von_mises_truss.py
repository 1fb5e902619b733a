"""A von Mises truss of two flexible bars, run from a scene file, against its closed form (issue #20).

Two steel bars 0.1 x 0.1 m, L0 = sqrt(a^2 + h^2) long (a = 1 m, h = 0.05 m), pinned to the ground at their feet
and to each other at the apex (revolute joints about y on the end faces' centres, which lie on the bars' axes),
carry a dead load growing at the apex. Pinned at both ends and loaded only there, each bar is a two-force member:
its frame (attached to the foot face) turns onto the line of the pins and the bar only stretches, by N L0 / (EA)
exactly (linear elasticity in the frame, the large rotation in the frame). So the FFRF truss has the closed form of
the textbook truss of axial springs k = EA/L0 (``validation.textbook_cases.truss_closed_form``): limit load
P_max = 2 k (L0 - L*) z* / L*, L* = (L0 a^2)^(1/3), z* = sqrt(L*^2 - a^2). The bars' own Euler load
pi^2 EI / L0^2 = 1.7e7 N is 6.6 times their largest compression along the path (flat, 2.6e6 N; 1.8e6 N at the
limit point), so the bars do not buckle first (our linear bodies could not show it: see docs/formulation.md, (B1)).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.optimize import brentq

from ffrf import load
from ffrf.cli import main
from ffrf.errors import StaticDivergence
from ffrf.scenes.assembly import PATH_STEPS_WITHOUT_DRIVE, quasi_static_path_step
from ffrf.scenes.scene_file import load_scene
from validation.textbook_cases import HALF_SPAN, LOAD_RATE, RISE, truss_closed_form, truss_load, write_truss_scene


def test_the_bars_axial_stiffness_is_ea_over_l_and_their_euler_load_is_far(tmp_path):
    """With nu = 0 the uniform axial strain is an exact FE state with rigid end faces (the module docstring of
    ``validation.textbook_cases``), and Craig-Bampton's static modes of the apex face contain it: the condensed
    stiffness along the bar, 1 / (d^T C d) with C the apex face's translational compliance (moment free), is EA/L0
    (measured 1.1e-14 relative). The bars' Euler load exceeds their largest compression 6.6 times."""
    c = truss_closed_form()
    assert c["euler_load"] > 5.0 * max(c["force_flat"], c["force_at_limit"])
    scene = load_scene(write_truss_scene(tmp_path))
    for body, side in zip(scene.bodies, (-1.0, 1.0), strict=True):
        axis = np.array([-side * HALF_SPAN, 0.0, RISE]) / c["length"]
        compliance = np.linalg.inv(body.reduction.reduced_stiffness)[:3, :3]
        print("axial stiffness error", 1.0 / (axis @ compliance @ axis) / c["stiffness"] - 1.0)
        assert 1.0 / (axis @ compliance @ axis) == pytest.approx(c["stiffness"], rel=1e-10)


@pytest.fixture(scope="module")
def truss_run(tmp_path_factory):
    """``python -m ffrf run truss.toml`` (16 outputs, stability): its output folder."""
    folder = tmp_path_factory.mktemp("truss")
    scene = write_truss_scene(folder)
    assert main(["run", str(scene), "--out", str(folder / "out")]) == 0
    return folder / "out"


def test_the_scene_file_run_snaps_at_the_limit_load_onto_the_inverted_branch(truss_run):
    """``python -m ffrf run truss.toml`` with ``stability = true`` loads the truss to 1.5 P_max: the run stops
    at the fold, traces the path through it (Eq. (S6)), lands on the inverted branch and goes on. The snap in
    the metadata is at P_max of the closed form (measured 8.8e-9 relative), Eq. (B1) is near zero there, the
    energy released (the bars' strain energy and the dead load's work in the jump) is the closed form's (7e-8),
    and the apex at the end of the run holds the closed form's equilibrium on the inverted branch: P(z) = P_end
    for z < -z* (brentq on it; measured 1.4e-13 m)."""
    c = truss_closed_form()
    metadata = json.loads((truss_run / "metadata.json").read_text())
    snaps = metadata["stability"]["snaps"]
    assert len(snaps) == 1 and snaps[0]["landed"]
    print("limit load error", snaps[0]["time_s"] * LOAD_RATE / c["limit_load"] - 1.0)
    assert snaps[0]["time_s"] * LOAD_RATE == pytest.approx(c["limit_load"], rel=1e-3)
    results = np.load(truss_run / "results.npz")
    first = results["stability_squared_frequencies"][0, 0]
    assert abs(snaps[0]["squared_frequency_at_fold"]) < 1e-3 * first
    assert np.all(results["stability_squared_frequencies"][:, 0] > 0.0)  # every output is a stable equilibrium
    table = json.loads((truss_run / "stability.json").read_text())
    assert table["summary"]["critical"]["where"] == "fold"
    assert table["summary"]["critical"]["time_s"] == pytest.approx(snaps[0]["time_s"], rel=1e-12)
    assert (truss_run / "stability_critical.vtu").is_file()
    end_load = LOAD_RATE * results["time"][-1]
    rise = brentq(lambda z: truss_load(z) - end_load, -10.0 * c["critical_rise"], -c["critical_rise"])
    print("landing rise error", results["apex_point1"][-1, 2] - rise)
    assert results["apex_point1"][-1, 2] == pytest.approx(rise, abs=1e-9)
    # energy_released counts the strain energy the bars lose in the jump and the dead load's work in it: from the
    # closed form, k [(L - L0)^2 at z* less at the landing z < -z* under P_max] + P_max (z* - z)
    landing = brentq(lambda z: truss_load(z) - c["limit_load"], -10.0 * c["critical_rise"], -c["critical_rise"])
    stretch = [np.hypot(HALF_SPAN, z) - c["length"] for z in (c["critical_rise"], landing)]
    released = c["stiffness"] * (stretch[0] ** 2 - stretch[1] ** 2) + c["limit_load"] * (c["critical_rise"] - landing)
    print("energy released error", snaps[0]["energy_released_J"] / released - 1.0)
    assert snaps[0]["energy_released_J"] == pytest.approx(released, rel=1e-6)


def test_run_with_stability_on_a_dynamic_scene_is_refused(tmp_path, capsys):
    """``python -m ffrf run --stability`` judges equilibria: a scene that runs dynamically is refused in one line."""
    scene = write_truss_scene(tmp_path)
    text = scene.read_text().replace('mode = "quasi_static"', 'mode = "dynamic"').replace("stability = true", "")
    scene.write_text(text)
    assert main(["run", str(scene), "--stability", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and 'set mode = "quasi_static"' in err
    assert not (tmp_path / "out").exists()


@pytest.mark.slow  # a second run of the truss (55 s); the default suite's run above folds at the closed form's load
def test_the_fold_and_the_landing_do_not_depend_on_the_outputs(tmp_path, truss_run):
    """The truss has no drive: its path steps t_end / PATH_STEPS_WITHOUT_DRIVE (Eq. (S10)), and the trace through the
    fold starts from where that path stops with the path's step, so 5 and 16 outputs fold at the same load
    (measured identical to the last digit, 2.2e-9 from the closed form's P_max; before, with the path and the trace
    on the outputs' spacing, 7 and 16 outputs folded 1.8e-6 and 8.8e-9 from it) and land on the same equilibrium
    (the apex at the end)."""
    c = truss_closed_form()
    scene = load_scene(write_truss_scene(tmp_path, outputs=5))
    assert quasi_static_path_step(scene, 1.5)(0.3) == pytest.approx(1.5 / PATH_STEPS_WITHOUT_DRIVE, rel=1e-12)
    run = load(scene).run()
    snaps = run.metadata["stability"]["snaps"]
    assert run.time.shape == (5,) and len(snaps) == 1
    sixteen = json.loads((truss_run / "metadata.json").read_text())["stability"]["snaps"][0]["time_s"]
    print("fold loads", [t * LOAD_RATE / c["limit_load"] - 1.0 for t in (snaps[0]["time_s"], sixteen)])
    assert snaps[0]["time_s"] * LOAD_RATE == pytest.approx(c["limit_load"], rel=1e-6)
    assert sixteen == pytest.approx(snaps[0]["time_s"], rel=1e-12)
    apex = np.load(truss_run / "results.npz")["apex_point1"][-1]
    np.testing.assert_allclose(run.sensors["apex_point1"][-1], apex, rtol=0, atol=1e-9 * np.abs(apex).max())


@pytest.mark.slow  # the halvings at the fold: 4 min on the loaded 2-core machine
def test_without_monitoring_the_run_stops_at_the_fold_whatever_the_outputs(tmp_path):
    """Without ``stability`` the truss's path cannot pass the fold: it stops there (Eq. (S4), the step halved 8
    times), and the partial run ends with the path's last equilibrium. On its own steps that stop is the same for
    5 and 9 outputs and lies within 1/256 of a path step (1.5e-4 s) below the closed form's limit time P_max / rate
    (measured 1.0078223 s for both, 2.1e-5 s below; before, the run ended at the last output before the fold:
    0.75 s with 5 outputs, 0.9375 s with 9, by construction, not measured)."""
    c = truss_closed_form()
    stops = []
    for outputs in (5, 9):
        (tmp_path / str(outputs)).mkdir()
        path = write_truss_scene(tmp_path / str(outputs), outputs=outputs)
        path.write_text(path.read_text().replace("stability = true", ""))
        with pytest.raises(StaticDivergence) as stopped:
            load(load_scene(path)).run()
        stops.append(float(stopped.value.partial.time[-1]))
    limit_time = c["limit_load"] / LOAD_RATE
    print("stops", stops, "limit time", limit_time)
    assert stops[1] == stops[0]
    assert limit_time - 1.5 / PATH_STEPS_WITHOUT_DRIVE / 256 <= stops[0] <= limit_time
