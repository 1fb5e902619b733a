"""Hard cases of issue #9 (``bench/hard_cases.py``), fast subset on coarse meshes.

Every check is an independent truth: the constraints, the ideal kinematics of the rigid
Bennett linkage (motion polynomial), the energy balance, and the difference between inertial
and quasi-static motion, never values stored from an earlier run of our own solver.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from bench import hard_cases
from ffrf.fe.materials import PLA, RIGID, Material
from ffrf.scenes.linkage_run import choose_mode
from ffrf.solvers.static_solver import StaticDivergence
from ffrf.system.drives import rpm

COARSE = dict(h=8e-3, order=1, n_modes=2)


@pytest.fixture
def ctx(tmp_path: Path) -> hard_cases.Context:
    return hard_cases.Context("test", True, False, tmp_path, tmp_path / "rows.jsonl")


@pytest.fixture(scope="module")
def rigid_scene():
    return hard_cases.make_scene(RIGID, omega=rpm(60.0), ramp_time=0.05, **COARSE)


def _all_finite(outcome: hard_cases.Outcome) -> bool:
    return all(np.all(np.isfinite(np.asarray(v, float))) for v in outcome.sensors.values())


@pytest.mark.parametrize("step, t_end", [(1e-2, 0.03), (1e-5, 2e-3)])
def test_near_rigid_links_converge_at_large_and_tiny_steps(ctx, rigid_scene, step, t_end):
    """E = 1e15 Pa: the index-3 iteration at 1e-2 s and 1e-5 s steps converges, keeps the
    constraints, and the coupler follows the ideal rigid linkage (motion polynomial)."""
    n_steps = int(round(t_end / step))
    out = hard_cases.simulate(
        ctx, rigid_scene, f"step {step}", "dynamic", t_end, step=step, n_outputs=min(n_steps, 20) + 1
    )
    assert out.row.converged, out.row.error
    assert out.row.steps == n_steps
    assert _all_finite(out)
    assert out.row.max_constraint_residual < 1e-10
    # near-rigid links: the elastic part of the coupler deviation is ~1e-12 m (gravity / 1e15 Pa)
    assert out.row.extra["max_coupler_deviation_m"] < 1e-8
    # the iteration matrix is finite and not exactly singular at either step
    cond = hard_cases.iteration_matrix_condition(rigid_scene.system, out.assembly.q, out.assembly.multipliers, step)
    assert np.isfinite(cond)


def test_near_rigid_energy_balance_closes_with_small_steps(ctx, rigid_scene):
    """With 1e-4 s steps and an output every step the drive's work equals the change of kinetic
    and potential energy (nothing stored elastically, damping negligible)."""
    out = hard_cases.simulate(ctx, rigid_scene, "energy", "dynamic", 0.02, step=1e-4, n_outputs=201)
    assert out.row.converged, out.row.error
    assert out.row.energy_balance_relative < 5e-3


def test_assembly_failure_names_scene_step_and_remedy(monkeypatch):
    """A failed static assembly says which scene (and its misfit: alpha_3 - 90 deg), which
    continuation step, the solver's own diagnosis, and what to do."""
    from ffrf.scenes import assembly

    scene = hard_cases.make_scene(PLA, 92.0, **COARSE)

    def fail(*args, **kwargs):
        raise StaticDivergence("static Newton did not converge in 25 iterations: last increment 1e-3")

    monkeypatch.setattr(assembly, "static_equilibrium", fail)
    with pytest.raises(StaticDivergence) as info:
        assembly.assemble(scene)
    message = str(info.value)
    assert f"scene {scene.name!r} (2 deg of axis misfit)" in message
    assert "continuation step 0/8" in message
    assert "last increment 1e-3" in message
    assert "check the joints' axes" in message and "more steps" in message


def test_misaligned_assembly_at_95_deg_holds_the_constraints(ctx):
    """The end of the issue's misalignment range still assembles and runs a quarter revolution:
    constraints to 1e-10 and an energy balance that closes (quasi-static: work = stored energy)."""
    scene = hard_cases.make_scene(PLA, 95.0, **COARSE)
    t_end = scene.drive.time_for_angle(float(scene.drive.angle(1.0)) + 0.5 * np.pi)
    out = hard_cases.simulate(ctx, scene, "95 deg", "quasi_static", t_end, n_outputs=41)
    assert out.row.converged, out.row.error
    assert _all_finite(out)
    assert out.row.max_constraint_residual < 1e-10
    assert out.row.energy_balance_relative < 1e-2


def test_auto_mode_notices_inertia_at_300_rpm(ctx):
    """At 300 rpm the automatic choice is dynamic, and rightly so: the dynamic driving torque
    differs from the quasi-static one by far more than 10 %; at 1 rpm the choice is quasi-static,
    at 60 rpm dynamic (inertia, not vibration, decides there)."""
    slow = hard_cases.make_scene(PLA, omega=rpm(1.0), **COARSE)
    assert choose_mode(slow)[0] == "quasi_static"
    # 60 rpm: vibrations are slow enough (ratio ~100) but inertia is not (bench: 28 % torque difference)
    assert choose_mode(hard_cases.make_scene(PLA, omega=rpm(60.0), **COARSE))[0] == "dynamic"
    fast = hard_cases.make_scene(PLA, omega=rpm(300.0), ramp_time=0.1, **COARSE)
    assert choose_mode(fast)[0] == "dynamic"
    qs = hard_cases.simulate(ctx, fast, "qs", "quasi_static", 0.15, n_outputs=31)
    dyn = hard_cases.simulate(ctx, fast, "dyn", "dynamic", 0.15, step=5e-4, n_outputs=31)
    assert qs.row.converged and dyn.row.converged
    assert np.allclose(qs.time, dyn.time)
    scale = np.abs(qs.sensors["driving_torque"]).max()
    assert np.abs(dyn.sensors["driving_torque"] - qs.sensors["driving_torque"]).max() > 0.1 * scale


def test_very_soft_links_stay_finite_and_are_flagged(ctx):
    """E = 1e7 Pa converges without NaN, and the small-deformation check flags it (bore rotations
    scale with 1/E: about 100 times those of PLA)."""
    soft = hard_cases.make_scene(Material(1e7, PLA.nu, PLA.rho, "soft"), **COARSE)
    t_end = soft.drive.time_for_angle(float(soft.drive.angle(1.0)) + 0.5 * np.pi)
    out = hard_cases.simulate(ctx, soft, "soft", "quasi_static", t_end, n_outputs=21)
    assert out.row.converged, out.row.error
    assert _all_finite(out)
    measures = hard_cases.deformation(soft, out)
    assert np.isfinite(measures["max_bore_rotation_rad"]) and np.isfinite(measures["max_equivalent_strain"])
    assert measures["max_bore_rotation_rad"] > hard_cases.ROTATION_LIMIT_RAD
    assert not measures["small_deformation_valid"]


def test_budget_stops_a_run_with_a_diagnostic(ctx, rigid_scene):
    """No hang: a run over its time budget ends with converged = False and says why."""
    out = hard_cases.simulate(ctx, rigid_scene, "budget", "dynamic", 1.0, step=1e-5, n_outputs=11, budget_s=0.5)
    assert not out.row.converged
    assert "time budget" in out.row.error
    record = json.loads((ctx.rows_file).read_text().splitlines()[-1])["row"]
    assert record["converged"] is False and "time budget" in record["error"]


def test_non_finite_output_is_cut_off():
    """The guard against NaN in the table: rows from the first non-finite one on are dropped."""
    t = np.arange(5.0)
    sensors = {"a": np.array([1.0, 2.0, np.nan, 4.0, 5.0]), "b": np.ones((5, 3))}
    assert hard_cases._finite_prefix(t, sensors) == 2
    assert hard_cases._finite_json({"x": [1.0, float("nan")], "y": float("inf")}) == {"x": [1.0, None], "y": None}


def test_paper_linkage_has_no_singular_pose():
    """The undriven joints' screws never lose rank over a revolution; the least regular pose is
    the folded one (drive angle 0), where the arms overlap."""
    drive, sigma = hard_cases.locked_screw_conditioning(361)
    assert sigma.min() > 0.05
    worst = np.degrees(drive[np.argmin(sigma)]) % 360.0
    assert min(worst, 360.0 - worst) < 2.0


@pytest.mark.slow
def test_quick_suite_writes_table_without_nan(tmp_path):
    """The whole quick suite: every case finishes, the JSON has no NaN, the table has a row per run."""
    results = hard_cases.main(["--quick", "--no-exudyn", "--out", str(tmp_path)])
    text = (tmp_path / "hard_cases.json").read_text()
    assert "NaN" not in text and "Infinity" not in text
    assert {r["case"] for r in results} == set(hard_cases.CASES)
    table = (tmp_path / "hard_cases.md").read_text()
    assert table.count("\n| ") >= sum(len(r["rows"]) for r in results)


def test_only_the_base_is_misaligned_and_continuation_starts_closed():
    """Link 3 is the nominal part: at the start of the continuation (fraction 0) the ideal start
    pose closes every joint; at the end the only gap is the base's bore turned by the misfit, so
    the joint-3 perpendicularity equations read sin(alpha_3 - 90 deg)."""
    scene = hard_cases.make_scene(PLA, 95.0, **COARSE)
    start = scene.q_start
    assert np.abs(scene.with_misalignment(0.0).constraint_values(start, 0.0)).max() < 1e-12
    gap = np.abs(scene.with_misalignment(1.0).constraint_values(start, 0.0)).max()
    assert gap == pytest.approx(np.sin(np.radians(5.0)), rel=1e-9)


def test_long_quasi_static_steps_reach_the_same_equilibria_as_short_ones():
    """Seven equilibria over a whole revolution (60 deg of drive apart) must be the ones a fine
    sequence passes through: a predictor or tangent update must not jump to another equilibrium."""
    from ffrf.paper.bennett_scene import assemble, build_bennett
    from ffrf.solvers.static_solver import quasi_static

    scene = build_bennett("pla", h=0.006, order=1, n_modes=2)  # where Broyden updates once jumped (secant=True)
    start = assemble(scene).q
    fine = quasi_static(scene.system, start, np.linspace(0.0, 61.0, 241))
    coarse = quasi_static(scene.system, start, np.linspace(0.0, 61.0, 7))
    np.testing.assert_allclose(coarse.q, fine.q[::40], atol=1e-8)


def test_a_quick_turn_behind_the_path_steps_does_not_end_a_mild_misfit_run():
    """A variant of the 20-variant study (bore twist 0.143 deg on link 0 joint 3, offset -0.171 mm on link 2 joint 1,
    12 mm P1 links) whose path turns quickly near t = 45.6 s, between two of its own steps (0.5 s): the polynomial
    (S2) through them then misses the path after the turn by 0.79 of any shorter step, so halving alone never met
    Eq. (S4) and the run stopped at t = 46.5 s. Finished along the path's tangent, the run completes, checks itself
    (its energy balance closes on 121 outputs, which sample the turn's torque) and its outputs are the equilibria of
    the same path on steps a fifth as long (where Eq. (S4) never fires)."""
    from dataclasses import replace

    from ffrf import load
    from ffrf.paper.bennett_scene import assemble, bennett_options, build_bennett_from_options
    from ffrf.scenes.linkage_description import BoreError
    from ffrf.solvers.static_solver import quasi_static

    errors = (BoreError(joint=3, link=0, twist=np.radians(0.14297214456910937)), BoreError(1, 2, offset=-1.70667e-4))
    options = bennett_options("pla", h=0.012, order=1, n_modes=2)
    scene = build_bennett_from_options(replace(options, bore_errors=errors, bore_error_model="misfit"))
    run = load(scene).run(mode="quasi_static", outputs=121)
    assert run.time[-1] == pytest.approx(scene.t_end) and run.verification.verified, run.verification.reasons
    finer = quasi_static(scene.system, assemble(scene).q, run.time, path_step=lambda t: 0.1)
    np.testing.assert_allclose(run.q, finer.q, rtol=0, atol=1e-8)


def test_a_loop_that_sags_far_under_its_weight_is_assembled_in_smaller_gravity_steps(monkeypatch):
    """Rational Linkages' collisions_free_6r at five times its default size in PLA (links 125-824 mm, 16 x 12 mm
    arms) sags about 0.1 m under its weight: Newton from the undeformed pose, gravity in two steps, ends on a
    singular tangent. Halving the failed gravity step reaches it; the equilibrium is the one 64 equal steps reach
    (the same branch: a conservative load's equilibrium does not depend on the path to it)."""
    from ffrf.scenes.linkage_file import load_linkage
    from ffrf.solvers import static_solver

    scene = load_linkage({"linkage": {"model": "collisions_free_6r", "scale": 0.5}})
    system = scene.with_misfit(0.0)
    monkeypatch.setattr(static_solver, "MAX_LOAD_HALVINGS", 0)
    with pytest.raises(StaticDivergence, match="singular"):
        static_solver.static_equilibrium(system, scene.q_initial, load_steps=2)
    monkeypatch.undo()
    halved = static_solver.static_equilibrium(system, scene.q_initial, load_steps=2)
    assert len(halved.iterations) > 2  # it did halve
    even = static_solver.static_equilibrium(system, scene.q_initial, load_steps=64)
    np.testing.assert_allclose(halved.q, even.q, rtol=0.0, atol=1e-9 * np.abs(even.q).max())
    sag = np.abs(halved.q - scene.q_initial).max()
    assert sag > 0.05  # far from the start, as the docstring says: not a case Newton reaches anyway
