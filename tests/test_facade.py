"""The front door (ffrf.model): ffrf.load tells every kind of source apart, every run path returns the one Result,
and Result.save reads back through ffrf.read_results.

Numbers are checked against what does not go through the facade: the solver called directly on the same scene
(the same generalized-alpha run, to the bit), and statics (a quasi-static linkage driven from inside hangs on its
clamp alone, which carries its whole weight m g in every pose).
"""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from scene_fixtures import COARSE_BENNETT_FILE, PENDULUM, write_bar

import ffrf
from ffrf import LinkageOptions, Model, Result, SceneError, load, read_results
from ffrf.paper.bennett_scene import build_bennett
from ffrf.solvers.simulate import simulate
from ffrf.solvers.stability import check_judged_at_equilibria
from kinematics import BennettLinkage, SingleLoop

COARSE = {"h": 0.012, "order": 1, "n_modes": 2}
#: The paper's Bennett linkage as a linkage file (mm), coarse, joint 3 driven from -90 deg, link 2 the coupler.
BENNETT_FILE = COARSE_BENNETT_FILE


@pytest.fixture(scope="module")
def linkage() -> tuple[Model, Result]:
    """The coarse PLA Bennett linkage, 5 equilibria over the ramp and the first second of the revolution."""
    model = load(build_bennett("pla", **COARSE))
    return model, model.run("quasi_static", outputs=5, t_end=2.0)


def test_load_tells_the_kinds_of_source_apart(tmp_path):
    write_bar(tmp_path)
    (tmp_path / "pendulum.toml").write_text(PENDULUM)
    (tmp_path / "bennett.toml").write_text(BENNETT_FILE)
    scene_file = load(tmp_path / "pendulum.toml")
    assert scene_file.kind == "scene" and scene_file.name == "bar pendulum"
    scene_mapping = load(tomllib.loads(PENDULUM), base=tmp_path)
    assert scene_mapping.kind == "scene"
    assert np.array_equal(scene_mapping.scene.q_initial, scene_file.scene.q_initial)
    assert load(scene_file.scene).scene is scene_file.scene

    linkage_file = load(str(tmp_path / "bennett.toml"))
    assert linkage_file.kind == "linkage" and linkage_file.name == "bennett"  # named after the file
    assert load(tomllib.loads(BENNETT_FILE)).kind == "linkage"
    paper = BennettLinkage.paper()
    options = LinkageOptions(driver=3, tool_link=2, start_angle=np.radians(-90.0), **COARSE)
    from_loop = load(SingleLoop.from_dh(paper.a, paper.alpha), options)
    assert from_loop.kind == "linkage"
    # the same linkage, once in mm from a file and once in metres from a loop: the same start
    np.testing.assert_allclose(from_loop.scene.q_initial, linkage_file.scene.q_initial, rtol=0, atol=1e-12)


def test_load_refuses_what_it_cannot_build(tmp_path):
    with pytest.raises(SceneError, match="cannot load a float"):
        load(3.0)
    with pytest.raises(SceneError, match="options build a kinematics SingleLoop"):
        load(tmp_path / "any.toml", LinkageOptions())


def test_a_dynamic_scene_run_is_one_result_with_the_solvers_numbers(tmp_path):
    """The pendulum's run through the facade against generalized-alpha called directly with the file's settings."""
    write_bar(tmp_path)
    (tmp_path / "pendulum.toml").write_text(PENDULUM)
    result = load(tmp_path / "pendulum.toml").run()
    assert type(result) is Result and result.kind == "scene"
    scene = ffrf.load(tmp_path / "pendulum.toml").scene  # built again, run without the facade
    run = simulate(
        scene.system, scene.q_initial.copy(), "dynamic", 0.1, 101, step=1e-3, rho_inf=0.8, qd0=scene.qd_initial
    )
    assert np.array_equal(result.time, run.time) and np.array_equal(result.q, run.q)
    assert np.array_equal(result.qd, run.qd) and np.array_equal(result.multipliers, run.multipliers)
    assert result.metadata["verification"]["verified"]
    shorter = load(tmp_path / "pendulum.toml").run(t_end=0.05, outputs=11)  # settings as keywords
    assert shorter.time[-1] == pytest.approx(0.05) and len(shorter.time) == 11
    np.testing.assert_allclose(shorter.q[-1], result.q[50], rtol=0, atol=1e-12)  # the same steps to t = 0.05 s


def test_a_quasi_static_linkage_run_is_one_result_whose_clamp_carries_the_weight(linkage):
    model, result = linkage
    assert type(result) is Result and result.kind == "linkage" and result.metadata["mode"] == "quasi_static"
    weight = 9.81 * sum(link.fe.total_mass for link in model.scene.links)
    clamp = np.linalg.norm(result.sensors["joint_reactions"][:, 0, :3], axis=1)  # row 0: the clamp
    np.testing.assert_allclose(clamp / weight, 1.0, rtol=0, atol=1e-12)
    assert set(result.summary()) >= {"max_coupler_deviation_m", "energy_balance_relative"}


def test_stability_is_judged_at_equilibria_in_one_rule(linkage):
    model, _ = linkage
    for mode in ("auto", "quasi_static"):
        check_judged_at_equilibria(mode, True, "never raised")
    check_judged_at_equilibria("dynamic", False, "never raised")
    with pytest.raises(SceneError, match=r"^scene.toml: stability is judged at equilibria: set mode$"):
        check_judged_at_equilibria("dynamic", True, "set mode", "scene.toml")
    assert model.choose_mode("auto", stability=True)[0] == "quasi_static"
    with pytest.raises(SceneError, match="stability is judged at equilibria"):
        model.run("dynamic", stability=True)  # refused before anything runs


def test_save_writes_what_the_command_line_writes_and_reads_back(tmp_path, linkage):
    _, result = linkage
    folder = result.save(tmp_path / "out")
    arrays, metadata = read_results(folder)
    assert np.array_equal(arrays["time"], result.time) and np.array_equal(arrays["q"], result.q)
    for name, values in result.sensors.items():
        assert np.array_equal(arrays[name], values), name
    assert metadata["verification"] == result.metadata["verification"]
    assert metadata["clearance"]["summary"] == result.metadata["clearance"]["summary"]
    for name in ("assembly.vtu", "coupler_deviation.png", "driving_torque.png"):
        assert (folder / name).is_file(), name


def test_a_scene_result_saves_its_sensors_and_its_stress_free_start(tmp_path):
    write_bar(tmp_path)
    (tmp_path / "pendulum.toml").write_text(PENDULUM)
    result = load(tmp_path / "pendulum.toml").run(t_end=0.01, outputs=3)
    arrays, metadata = read_results(result.save(tmp_path / "out"))
    assert np.array_equal(arrays["tip"], result.sensors["tip"]) and metadata["scene"] == "bar pendulum"
    assert not (tmp_path / "out" / "assembly.vtu").exists()  # the pendulum starts from its poses, unassembled


def test_a_run_uses_one_blas_thread_unless_told_otherwise(tmp_path):
    """Under some OpenBLAS kernels (Haswell) a dense solve's last digits depend on the thread count: a library run
    uses one BLAS thread, as the command line and a study's workers do, so the three agree to the bit; ``None``
    keeps the process's own setting. Read from inside the run by its progress callback."""
    from threadpoolctl import threadpool_info, threadpool_limits

    write_bar(tmp_path)
    (tmp_path / "pendulum.toml").write_text(PENDULUM)
    model = load(tmp_path / "pendulum.toml")

    def blas_threads() -> set[int]:
        return {pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"}

    seen: list[set[int]] = []
    with threadpool_limits(limits=2, user_api="blas"):
        model.run(t_end=0.01, outputs=3, progress=lambda t, t_end: seen.append(blas_threads()))
        assert seen and all(threads == {1} for threads in seen)
        seen.clear()
        model.run(t_end=0.01, outputs=3, progress=lambda t, t_end: seen.append(blas_threads()), blas_threads=None)
        assert seen and all(threads == {2} for threads in seen)
