"""Steps from the fastest joint (issue #32; docs/formulation.md, Eqs. (L9), (G7), (S10)): the figures of
``docs/speed_vs_error.md`` ("Steps from the fastest joint"), ``docs/hard_cases.md`` ("A near-dead pose of the
driver") and (L9), (S10) of ``docs/formulation.md``, each measured with today's library calls:

- ``interp_4poses_6r``: Rational Linkages' 6R with near-rigid links (E = 1e15 Pa, ``--variant rigid``), its default
  dynamic run (961 outputs, steps of (G7)) and the same with the drive's rule alone (no (G7) limit): steps, the
  shortest, the coupler's deviation from the rigid motion (largest, and where), the largest driving torque, the
  energy balance, the (G5) error estimate, the solve time and the near-dead pose the run passed (Eq. (L9));
- the same links without gravity, quasi-static to ``t_end`` = 9 s through the pose at 31 and 241 outputs, on the
  path's own steps (S10) and solved at the outputs (``path_step=None``): the deviation from the rigid motion, or
  where the path stopped;
- ``plane_fold_6r`` in PLA (default links), quasi-static at 61, 241 and 961 outputs, on its own steps and solved at
  the outputs: where the path stops near the flat-folded home pose, the coupler's deviation there;
- ``plane_fold_6r`` with near-rigid links, the default (quasi-static) run at 961 outputs: how far it gets, the
  largest deviation;
- the paper's default Bennett (PLA), quasi-static at 961 outputs on its own steps against solved at the outputs:
  the largest coupler and torque differences, and the solve times (warm kernels, rate profile already traced).

Wall times are of the shared 2-core machine. Keys are stable: ``docs/*.md`` link to them.

Usage::

    .venv/bin/python -m bench step_rules --json out/step_rules.json
"""

from __future__ import annotations

import argparse
import contextlib
import time
import warnings
from pathlib import Path

import numpy as np

import ffrf.scenes.linkage_run as linkage_run  # noqa: E402
from bench.report import write_report
from ffrf.errors import NewtonDivergence, StaticDivergence
from ffrf.fe.materials import PLA, RIGID
from ffrf.paper.bennett_scene import build_bennett
from ffrf.scenes.linkage_description import drive_sign
from ffrf.scenes.linkage_file import load_linkage
from ffrf.scenes.linkage_steps import joint_rate_profile
from kinematics import joint_rates
from kinematics.single_loop import follow_driver

PARTS = ("interp_dynamic", "interp_unloaded", "plane_fold_pla", "plane_fold_rigid", "bennett")


def _material(material) -> dict:
    strength = {} if material.strength is None else {"strength": material.strength}
    return {"E": material.E, "nu": material.nu, "rho": material.rho, "name": material.name} | strength


def linkage(model: str, material, gravity: bool = True):
    """``model`` of Rational Linkages with the CLI's default links (6 mm P2, 4 modes) of ``material``."""
    document: dict = {"linkage": {"name": f"{model} {material.name}", "model": model, "material": _material(material)}}
    if not gravity:
        document["scene"] = {"gravity": [0.0, 0.0, 0.0]}
    return load_linkage(document)


@contextlib.contextmanager
def drive_rule_only():
    """Runs without the joint-rate rules: dynamic steps of the drive's rule alone (no (G7) limit) and the quasi-static
    path solved at the outputs (no (S10) path step), as before issue #32."""
    kept = linkage_run.dynamic_step_limit, linkage_run.quasi_static_path_step
    # None is what the runs take for "no rule" (linkage_run passes it on), not what the rules' functions return
    linkage_run.dynamic_step_limit = lambda scene: None  # type: ignore[return-value]
    linkage_run.quasi_static_path_step = lambda scene: None  # type: ignore[return-value]
    try:
        yield
    finally:
        linkage_run.dynamic_step_limit, linkage_run.quasi_static_path_step = kept


def run(scene, **options) -> dict:
    """One :func:`ffrf.scenes.linkage_run.run_linkage` summed up; a stopped run: its partial result and where."""
    stopped = None
    try:
        result = linkage_run.run_linkage(scene, **options)
    except (StaticDivergence, NewtonDivergence) as error:
        if error.partial is None:
            return {"stopped": {"message": str(error)}, "completed": False}
        result, stopped = error.partial, error.partial.metadata["stopped"]
    deviation = np.linalg.norm(result.sensors["coupler_deviation"], axis=1)
    angles = np.degrees(result.sensors["drive_angle"])
    worst = int(np.argmax(deviation))
    meta = result.metadata
    out = {
        "completed": stopped is None,
        "mode": meta["mode"],
        "outputs": int(len(result.time)),
        "last_drive_angle_deg": float(angles[-1]),
        "max_coupler_deviation_m": float(deviation[worst]),
        "max_coupler_deviation_at_deg": float(angles[worst]),
        "summary": meta["summary"],
        "solve_s": meta["timings_s"]["solve"],
        "step_error_estimate": meta["step_error_estimate"],
        "near_dead_poses": meta["near_dead_poses"],
        "sensors": {
            "coupler_point": result.sensors["coupler_point"],
            "driving_torque": result.sensors["driving_torque"],
        },
    }
    if stopped is not None:
        out["stopped"] = {k: stopped[k] for k in ("time_s", "drive_angle_deg", "reason")}
        out["stopped"]["coupler_deviation_m"] = float(deviation[-1])
    return out


def without_sensors(row: dict) -> dict:
    """``row`` for the report: the sensors (kept for comparisons) left out."""
    return {k: v for k, v in row.items() if k != "sensors"}


def rate_peak(scene) -> dict:
    """The rigid loop's fastest joint against the driver (Eq. (L9)) at its peak: the scene's profile's sample,
    refined on poses 0.005 deg of drive apart within 1 deg of it, with the closure Jacobian's fifth singular value
    over its largest there (its smallest over those poses, and where)."""
    sign = drive_sign(scene.driver, scene.loop.n)
    profile = joint_rate_profile(scene)
    peak = int(np.argmax(profile.ratios))
    fine = profile.driver_angles[peak] + np.radians(np.linspace(-1.0, 1.0, 401))
    motion = follow_driver(scene.loop, scene.driver, fine, start=scene.start_phi)
    rates = np.array([np.abs(joint_rates(scene.loop, phi, scene.driver)) for phi in motion.phi])
    best = int(np.argmax(rates.max(axis=1)))
    singular = motion.singular_values[:, 4] / motion.singular_values[:, 0]
    lowest = int(np.argmin(singular))
    return {
        "ratio": float(rates[best].max()),
        "joint": int(np.argmax(rates[best])),
        "drive_angle_deg": float(np.degrees(sign * fine[best])),
        "profile_ratio": float(profile.ratios[peak]),
        "fifth_singular_value_rel": float(singular[lowest]),
        "fifth_singular_value_at_deg": float(np.degrees(sign * fine[lowest])),
    }


def interp_dynamic() -> dict:
    """The near-rigid interp_4poses_6r's default dynamic run, with (G7) and with the drive's rule alone."""
    scene = linkage("interp_4poses_6r", RIGID)
    out = {
        "rate_peak": rate_peak(scene),
        "g7": without_sensors(run(scene, mode="dynamic", n_outputs=961, sensors="all")),
    }
    with drive_rule_only():
        out["drive_rule"] = without_sensors(run(scene, mode="dynamic", n_outputs=961, sensors="all"))
    return out


def interp_unloaded() -> dict:
    """The near-rigid interp_4poses_6r without gravity, quasi-static through its near-dead pose (t_end = 9 s)."""
    scene = linkage("interp_4poses_6r", RIGID, gravity=False)
    out: dict = {"s10": {}, "output_solved": {}}
    for outputs in (31, 241):
        options = dict(mode="quasi_static", n_outputs=outputs, t_end=9.0, sensors="path")
        out["s10"][str(outputs)] = without_sensors(run(scene, **options))
        with drive_rule_only():
            out["output_solved"][str(outputs)] = without_sensors(run(scene, **options))
    return out


def plane_fold_pla() -> dict:
    """The PLA plane_fold_6r's quasi-static stop near its flat-folded home pose at 61, 241 and 961 outputs."""
    scene = linkage("plane_fold_6r", PLA)
    out: dict = {"s10": {}, "output_solved": {}}
    for outputs in (61, 241, 961):
        options = dict(mode="quasi_static", n_outputs=outputs, sensors="path")
        out["s10"][str(outputs)] = without_sensors(run(scene, **options))
        with drive_rule_only():
            out["output_solved"][str(outputs)] = without_sensors(run(scene, **options))
    return out


def plane_fold_rigid() -> dict:
    """The near-rigid plane_fold_6r's default run (mode chosen by the scene) at 961 outputs."""
    return without_sensors(run(linkage("plane_fold_6r", RIGID), n_outputs=961, sensors="path"))


def bennett() -> dict:
    """The paper's default PLA Bennett, quasi-static at 961 outputs: on its own steps against solved at the outputs."""
    scene = build_bennett("pla")
    options = dict(mode="quasi_static", n_outputs=961, sensors="path")
    run(scene, **options)  # trace the rate profile and warm everything once: the timed runs below are warm
    path = run(scene, **options)
    with drive_rule_only():
        solved = run(scene, **options)
    a, b = path["sensors"], solved["sensors"]
    return {
        "rate_peak": float(np.max(joint_rate_profile(scene).ratios)),
        "s10": without_sensors(path),
        "output_solved": without_sensors(solved),
        "coupler_difference_m": float(np.linalg.norm(a["coupler_point"] - b["coupler_point"], axis=1).max()),
        "torque_difference_Nm": float(np.abs(a["driving_torque"] - b["driving_torque"]).max()),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", nargs="+", choices=PARTS, default=list(PARTS), help="what to measure (default all)")
    parser.add_argument("--json", type=Path, required=True)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    report: dict = {"scenes": "CLI default links (6 mm P2, 4 modes per link); rigid: E = 1e15 Pa"}
    wall: dict = {}
    for part in args.parts:
        started = time.perf_counter()
        report[part] = globals()[part]()
        wall[part] = time.perf_counter() - started
        print(f"{part}: {wall[part]:.1f} s", flush=True)
    report["wall_time_s"] = wall
    write_report(report, args.json, echo=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
