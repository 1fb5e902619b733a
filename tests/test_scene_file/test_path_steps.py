"""A scene file's quasi-static path on its own steps (``docs/formulation.md``, Eq. (S10); issue #32).

The path of a generic scene file is followed on steps of its own (:func:`ffrf.scenes.assembly.quasi_static_path_step`:
the time in which the fastest drive turns 3 deg, or t_end / 120 without a drive) and every output is solved from it,
so the equilibria at a given time do not depend on how many outputs the scene asks for. Scene: the paper's parametric
link 1 turned about a horizontal axis through its first bore at 1 rpm (``scene_fixtures.driven_link_scene``).
"""

from __future__ import annotations

import numpy as np
import pytest
from scene_fixtures import driven_link_scene

from ffrf import load
from ffrf.body.euler_parameters import rotation_matrix
from ffrf.scenes.assembly import MAX_DRIVE_STEP, quasi_static_path_step
from ffrf.scenes.scene_file import load_scene, sensor_arrays

#: s: the cosine ramp (1 s) and 4.4 s at 1 rpm, 29 deg; the path steps 0.5 s, the outputs 0.9, 0.45, 0.18 s
T_END = 5.4


def _run(tmp_path, outputs: int):
    path = tmp_path / f"link_{outputs}.toml"
    path.write_text(driven_link_scene("[0.0, 1.0, 0.0]", t_end=T_END, outputs=outputs, modes=3))
    scene = load_scene(path)
    return scene, load(scene).run()


def test_the_path_step_of_a_driven_scene_turns_its_drive_3_deg(tmp_path):
    """1 rpm turns 3 deg in 0.5 s."""
    path = tmp_path / "link.toml"
    path.write_text(driven_link_scene("[0.0, 1.0, 0.0]", t_end=T_END, outputs=7, modes=2))
    scene = load_scene(path)
    assert MAX_DRIVE_STEP == pytest.approx(np.radians(3.0))
    assert quasi_static_path_step(scene, T_END)(2.0) == pytest.approx(0.5, rel=1e-12)


def test_equilibria_at_common_times_do_not_depend_on_the_outputs(tmp_path):
    """7, 13 and 31 outputs over the same run share the times 0, 0.9, ..., 5.4 s (most of them between the path's
    own times, every 0.5 s, so solved from the path's polynomial): there the coordinates agree to Newton's tolerance
    (measured 3.3e-12 and 6.9e-12 of the largest coordinate), and so does the driving torque, which is also the rigid
    link's gravity moment about the drive axis
    (the elastic part is small): the torque the drive applies to the link balances gravity's moment about the axis,
    tau = -a . ((c - p) x m g), c the undeformed centre of mass turned by the drive angle, p the bore's point
    (measured within 1.1e-5 relative)."""
    runs = {n: _run(tmp_path, n) for n in (7, 13, 31)}
    common = np.linspace(0.0, T_END, 7)
    picked = {}
    for n, (scene, run) in runs.items():
        assert run.time.shape == (n,)
        rows = [int(np.argmin(np.abs(run.time - t))) for t in common]
        np.testing.assert_allclose(run.time[rows], common, atol=1e-12)
        torque = sensor_arrays(scene, run.q, run.multipliers)["motor_torque"][rows]
        picked[n] = (run.q[rows], torque)
    scale = np.abs(picked[7][0]).max()
    for n in (13, 31):
        print(n, "largest coordinate difference", np.abs(picked[n][0] - picked[7][0]).max() / scale)
        np.testing.assert_allclose(picked[n][0], picked[7][0], rtol=0, atol=1e-9 * scale)
        np.testing.assert_allclose(picked[n][1], picked[7][1], rtol=1e-7, atol=1e-12)
    scene, run = runs[7]
    motor = next(c for c in scene.system.all_constraints if c.name == "motor")
    body = scene.system.bodies[0]
    block = run.q[0][scene.system.block(0)]
    centre0 = block[:3] + rotation_matrix(block[3:7]) @ body.moments.s0 / body.moments.mass
    bore, axis = np.array([0.0, 0.0, 0.0085]), np.array([0.0, 1.0, 0.0])
    gravity = body.moments.mass * scene.system.gravity
    closed = []
    for t in common:
        turn = motor.angle(t) - motor.angle(0.0)
        c, s = np.cos(turn), np.sin(turn)
        turned = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]) @ (centre0 - bore)
        closed.append(axis @ np.cross(turned, gravity))
    closed = np.array(closed)
    print("torque", picked[7][1], "closed form", closed)
    assert np.abs(closed).max() > 1e-3  # N m: the drive lifts the link
    np.testing.assert_allclose(picked[7][1], -closed, rtol=1e-4)
