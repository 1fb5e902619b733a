"""The drive's correction along the motion (Eq. (D8), issue #35): where the task is a path, a drive that runs ahead
or behind removes the deviation's component along the path, leaving the print's distance to the ideal curve."""

import numpy as np
import pytest

from ffrf.fe.materials import PLA
from ffrf.scenes.drive_correction import TANGENT_TOLERANCE, correct_drive
from ffrf.scenes.linkage_run import run_linkage


@pytest.fixture(scope="module")
def sagging_bennett():
    from bench import hard_cases

    scene = hard_cases.make_scene(PLA, h=8e-3, order=1, n_modes=2)
    return scene, run_linkage(scene, mode="quasi_static", n_outputs=25, sensors="path")


def test_the_corrected_drive_leaves_the_distance_to_the_ideal_curve(sagging_bennett):
    """The coarse PLA Bennett sagging under its weight, 25 poses over the ramp and a revolution: at each corrected
    angle (the print's equilibrium solved there) the coupler's deviation from the ideal point equals the print's
    distance to the exact ideal curve, found by another algorithm (the closest point of Eq. (C1) from the nominal
    pose), to 1e-7 m (measured 8e-11 m to 8e-8 m: the second order, the deviation squared over the path's curvature
    radius), across the path; the deviation falls from 0.078 mm to 0.050 mm (measured). The last pose, at the end
    of the motion, cannot run on and is held there."""
    scene, result = sagging_bennett
    found = correct_drive(scene, result.time, result.q, result.multipliers)
    distance = result.sensors["coupler_distance_to_path"]
    after = np.linalg.norm(found.after, axis=1)
    held = found.corrected_angle >= scene.drive_angle(scene.t_end)
    assert found.clipped == 1 and held[-1] and held.sum() == 1
    np.testing.assert_allclose(after[~held], distance[~held], rtol=0, atol=1e-10 + 1e-7)
    assert np.all(after <= np.linalg.norm(found.before, axis=1) + 1e-12)
    assert found.after_m < 0.7 * found.before_m
    sides = scene.ideal_coupler_points(np.concatenate([found.drive_angle + 1e-6, found.drive_angle - 1e-6]))
    tangents = sides[:25] - sides[25:]
    along = np.abs(np.einsum("pc,pc->p", tangents, found.after)) / np.linalg.norm(tangents, axis=1)
    assert np.all(along[~held] <= TANGENT_TOLERANCE * after[~held] + 1e-15)
    assert np.degrees(np.abs(found.corrected_angle - found.drive_angle)).max() < 0.1  # small corrections


def test_a_print_without_load_keeps_its_drive(sagging_bennett):
    """Without gravity the print rests on its ideal path (nothing bends it): nothing to correct, every angle kept,
    no equilibrium solved."""
    from dataclasses import replace

    scene, _ = sagging_bennett
    weightless = replace(scene, system=replace(scene.system, gravity=np.zeros(3)))
    result = run_linkage(weightless, mode="quasi_static", n_outputs=7, sensors="path")
    assert np.abs(result.sensors["coupler_deviation"]).max() < 1e-12
    found = correct_drive(weightless, result.time, result.q, result.multipliers)
    np.testing.assert_array_equal(found.corrected_angle, found.drive_angle)
    assert found.steps.sum() == 0 and found.after_m == found.before_m
