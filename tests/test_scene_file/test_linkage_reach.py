"""The energy of a linkage with every joint prescribed (ffrf.solvers.forced_joints, docs/formulation.md Eqs. (S7),
(S8)) and the reach of isolated assemblies (ffrf.scenes.linkage_reach, Eq. (S9)), on coarse flexible linkages
(12 mm P1 links, 2 fixed-interface modes)."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pytest
from scipy.optimize import root

from ffrf.paper.bennett_scene import build_bennett
from ffrf.scenes.assembly import assemble
from ffrf.scenes.linkage_description import LinkageOptions, drive_sign
from ffrf.scenes.linkage_reach import drive_work, linkage_energy
from ffrf.scenes.linkage_scene import build_linkage
from ffrf.solvers.forced_joints import ForcedEnergy, joint_angles
from ffrf.solvers.static_solver import quasi_static
from ffrf.system.reactions import driving_torques
from kinematics import trace_motion
from kinematics.rational_mechanism import load_model, loop_from_mechanism, regular_start

COARSE: dict[str, Any] = dict(h=12e-3, order=1, n_modes=2)


def _six_r(gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)):
    mechanism = load_model("collisions_free_6r")
    loop = loop_from_mechanism(mechanism, 0.1)
    origin = regular_start(mechanism, loop)
    options = LinkageOptions(**COARSE, start_angle=float(origin[0]), origin=origin, gravity=gravity)
    return build_linkage(loop, options)


@pytest.mark.parametrize("name", ["collisions_free_6r", "bennett"])
def test_poses_of_the_rigid_motion_hold_no_strain_with_every_joint_prescribed(name):
    """Without gravity, every joint prescribed to a pose of the rigid motion (joint i at drive_sign(i, n) phi_i of
    Eq. (L1)) the links are not strained: V below 1e-12 J and every torque below 1e-9 N m at five poses over half a
    turn of the driver (the Bennett's driver is its closing joint, sign -1). With the closing joint's sign turned
    the links are forced out of the motion: V of at least 1e-4 J at the same poses."""
    if name == "bennett":
        scene = build_bennett("pla", **COARSE, gravity=(0.0, 0.0, 0.0))
    else:
        scene = _six_r(gravity=(0.0, 0.0, 0.0))
    n, q0 = scene.loop.n, assemble(scene).q
    energy = linkage_energy(scene, q0)
    motion = trace_motion(scene.loop, scene.driver, n_poses=5, revolution=np.pi, start=scene.start_phi)
    for phi in motion.phi:
        value, gradient = energy(phi)
        assert value < 1e-12 and np.max(np.abs(gradient)) < 1e-9
    flipped = np.array([drive_sign(i, n) for i in range(n)])
    flipped[-1] = -flipped[-1]
    names = energy.names
    wrong = ForcedEnergy(scene.system, names, flipped, joint_angles(scene.system, names, flipped, q0, np.zeros(n)), q0)
    for phi in motion.phi[1:]:
        assert wrong(phi)[0] > 1e-4


def test_the_gradient_of_v_is_the_driving_torques_and_matches_central_differences():
    """With gravity, at a pose 3 deg (random, seeded) off the assembled one: dV/dphi of Eq. (S8) equals central
    differences of V (step 1e-5 rad; measured 1.2e-10 of the largest component). At the assembled pose itself the
    joints that turn freely carry no torque and the driver's is the assembled linkage's driving torque (its own
    multiplier)."""
    scene = _six_r()
    assembled = assemble(scene)
    energy = linkage_energy(scene, assembled.q)
    start = joint_angles(scene.system, energy.names, energy.signs, assembled.q, scene.start_phi)
    _, gradient = energy(start)
    torque = driving_torques(scene.system, assembled.multipliers)[energy.names[scene.driver]]
    free = np.delete(gradient, scene.driver)
    assert np.max(np.abs(free)) < 1e-10 * abs(torque)
    assert gradient[scene.driver] * drive_sign(scene.driver, scene.loop.n) == pytest.approx(torque, rel=1e-8)
    phi = start + np.radians(3.0) * np.random.default_rng(2).standard_normal(scene.loop.n)
    _, gradient = energy(phi)
    step = 1e-5
    differences = [(energy(phi + step * e)[0] - energy(phi - step * e)[0]) / (2 * step) for e in np.eye(phi.size)]
    print("gradient error", np.max(np.abs(gradient - differences)) / np.max(np.abs(gradient)))
    assert np.allclose(gradient, differences, rtol=0.0, atol=1e-6 * np.max(np.abs(gradient)))


def test_relaxing_with_the_driver_held_is_the_driven_linkages_own_equilibrium():
    """ForcedEnergy.relax at the rigid pose 20 deg of drive on, the driver held: the joint angles equal those of the
    scene's own quasi-static run (its drive at that angle, the other joints free) to 1e-9 rad."""
    scene = _six_r()
    assembled = assemble(scene)
    energy = linkage_energy(scene, assembled.q)
    turn = np.radians(20.0)
    pose = trace_motion(scene.loop, scene.driver, 2, revolution=turn, start=scene.start_phi, endpoint=True).phi[-1]
    relaxed = energy.relax(pose, (energy.names[scene.driver],))
    t = scene.drive.time_for_angle(turn)
    run = quasi_static(scene.system, assembled.q, np.linspace(0.0, t, 9))
    own = joint_angles(scene.system, energy.names, energy.signs, run.q[-1], pose)
    assert np.max(np.abs(relaxed - own)) < 1e-9


def test_the_drive_work_of_a_torque_that_drives_and_brakes():
    """tau = sin(theta) over a ramp of 0.3 rad and one turn: over the last turn the largest |tau| times 2 pi is 2 pi,
    and the drive does work 2 over the half turn where it drives (it brakes over the other)."""
    angle = np.concatenate([np.linspace(-0.3, 0.0, 50, endpoint=False), np.linspace(0.0, 2.0 * np.pi, 2001)])
    work = drive_work(np.sin(angle), angle)
    assert work["turn_rad"] == pytest.approx(2.0 * np.pi)
    assert work["max_torque_work_J"] == pytest.approx(2.0 * np.pi, rel=1e-6)
    assert work["work_J"] == pytest.approx(2.0, rel=1e-6)


#: Bad input of ``python -m ffrf linkage --reach``: the arguments and the words of the one-line error.
REACH_CASES = {
    "reach of an as-built linkage": (["--bore-error", "5:0:1.0"], "--reach measures the nominal linkage"),
    "reach of rigid links": (["--variant", "rigid"], "--reach measures strain energy, which rigid links do not store"),
}


@pytest.mark.parametrize("case", REACH_CASES)
def test_linkage_reach_refuses_bad_input_before_building(tmp_path, capsys, case):
    """Exit 2 with one line naming the fix, before the output folder is made (nothing is built)."""
    from ffrf.cli import main

    arguments, words = REACH_CASES[case]
    out = tmp_path / "out"
    assert main(["linkage", "--model", "collisions_free_6r", "--reach", *arguments, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and words in err
    assert not out.exists()


def test_a_string_of_fewer_than_three_images_is_refused(tmp_path, capsys):
    from ffrf.cli import main

    with pytest.raises(SystemExit) as exit_:
        main(["linkage", "--model", "collisions_free_6r", "--reach", "--reach-images", "2", "--out", str(tmp_path)])
    assert exit_.value.code == 2
    assert "argument --reach-images: must be a whole number >= 3" in capsys.readouterr().err


@pytest.mark.slow
def test_linkage_reach_writes_barriers_that_climb_to_a_saddle_of_v(tmp_path):
    """``python -m ffrf linkage --model collisions_free_6r --reach`` (coarse links, 7 images) writes reach.json
    with both isolated assemblies. For each: the string converged, its barrier lies below the straight path's, and
    the highest point is a saddle of V found independently: scipy's root of the gradient (S8) from the highest
    image, where the Hessian (central differences) has one negative eigenvalue; V there less V at the motion end is
    the barrier to 1 % (measured 0.11 % and 0.035 %, the string's discretisation). The verdict follows the work
    ratio."""
    from ffrf.cli import main

    out = tmp_path / "out"
    args = ["linkage", "--model", "collisions_free_6r", "--h", "0.012", "--order", "1", "--modes", "2"]
    assert main([*args, "--outputs", "61", "--reach", "--reach-images", "7", "--out", str(out)]) == 0
    table = json.loads((out / "reach.json").read_text())
    assert len(table["assemblies"]) == 2
    scene = _six_r()
    energy = linkage_energy(scene, assemble(scene).q)
    for entry in table["assemblies"]:
        assert entry["converged"] and entry["barrier_J"] < entry["straight_path_barrier_J"]
        assert entry["verdict"] == ("within reach" if entry["work_ratio"] <= 1.0 else "out of reach")
        images = np.array(entry["images_phi_rad"])
        for phi in images[: entry["peak_image"] + 1]:  # follow the path from the motion end to the peak
            energy(phi)
        saddle = root(lambda phi: energy(phi)[1], images[entry["peak_image"]], tol=1e-12).x
        step = 1e-4
        columns = [(energy(saddle + step * e)[1] - energy(saddle - step * e)[1]) / (2 * step) for e in np.eye(6)]
        curvatures = np.linalg.eigvalsh(0.5 * (np.column_stack(columns) + np.column_stack(columns).T))
        assert curvatures[0] < 0.0 < curvatures[1]
        barrier = energy(saddle)[0] - entry["motion_end_energy_J"]
        print("barrier error", entry["barrier_J"] / barrier - 1.0)
        assert entry["barrier_J"] == pytest.approx(barrier, rel=0.01)
