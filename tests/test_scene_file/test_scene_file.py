"""Scenes from TOML files: the same pendulum as built in Python, a driven parametric link,
and clear errors for bad scenes."""

import numpy as np
import pytest
from pendulum_fixtures import pendulum, tip_position
from scene_fixtures import PENDULUM, driven_link_scene, write_bar

from ffrf import load
from ffrf.cli import main
from ffrf.scenes.scene_file import SceneError, load_scene
from ffrf.solvers.generalized_alpha import generalized_alpha


def test_file_pendulum_equals_the_python_pendulum(tmp_path):
    write_bar(tmp_path)
    (tmp_path / "scene.toml").write_text(PENDULUM)
    assert main(["run", str(tmp_path / "scene.toml"), "--out", str(tmp_path / "out")]) == 0
    data = np.load(tmp_path / "out" / "results.npz")
    system, model, psi, _ = pendulum(n_modes=3)
    q0 = system.initial_state()
    reference = generalized_alpha(system, q0, np.zeros_like(q0), 0.1, 1e-3, rho_inf=0.8)
    np.testing.assert_allclose(data["tip"], [tip_position(q, model, psi) for q in reference.q], atol=1e-9)


def test_driven_parametric_link(tmp_path):
    (tmp_path / "link.toml").write_text(driven_link_scene("[0.0, 0.0, 1.0]", t_end=5.0, outputs=6, modes=2))
    load(tmp_path / "link.toml").run().save(tmp_path / "out")
    torque = np.load(tmp_path / "out" / "results.npz")["motor_torque"]
    # Turning about the vertical axis h0 does no work against gravity: the drive torque vanishes.
    assert torque.shape == (6,) and np.abs(torque).max() < 1e-9


def test_bad_scenes_are_named(tmp_path):
    write_bar(tmp_path)
    (tmp_path / "bad.toml").write_text(PENDULUM.replace('body1 = "bar"', 'body1 = "rod"'))
    with pytest.raises(SceneError, match="unknown body 'rod'"):
        load_scene(tmp_path / "bad.toml")
    (tmp_path / "bad2.toml").write_text(PENDULUM.replace('interface1 = "hinge"', 'interface1 = "bore"'))
    with pytest.raises(SceneError, match="no interface 'bore'"):
        load_scene(tmp_path / "bad2.toml")
    (tmp_path / "bad3.toml").write_text(PENDULUM.replace('mesh = "bar.vtu"', 'mesh = "missing.vtu"'))
    with pytest.raises(SceneError, match="missing.vtu not found"):
        load_scene(tmp_path / "bad3.toml")
