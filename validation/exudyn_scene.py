r"""Cross-validation of a scene file (``python -m ffrf run SCENE.toml``) against its Exudyn twin.

Both solvers get the scene's meshes, M, K, interfaces, joints, drives, gravity, damping and
solver settings (:mod:`validation.exudyn_twin`); Exudyn reduces the bodies itself. Each
solver makes its own static start when the scene asks for one, then runs the scene's mode
(dynamic: generalized-alpha with the scene's step and spectral radius; quasi-static: one
``SolveStatic`` whose load steps turn the drives). Our run uses Exudyn's gravity model
(``exact_gravity = false``, Eq. (F10)) so that the two solve the same equations; the effect
of the exact gravity is reported separately.

Compared: per body the fixed-interface frequencies and MAC; per sensor the largest distance
between the two runs, relative to the sensor's travel (its largest distance from its start);
per driven joint the driving torque relative to its maximum.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ffrf.output.result import Result
from ffrf.scenes.scene_file import sensor_arrays

from .modes import compare_modes
from .twin_run import TwinRun, run_metadata, twin_run

__all__ = [
    "SCENE_TARGETS",
    "SceneValidation",
    "scene_bodies",
    "run_exudyn_scene",
    "twin_schedule",
    "compared_sensors",
    "validate_scene",
    "write_scene_report",
]

#: Targets for a scene: frequencies and MAC as for the Bennett scene; sensors relative to their
#: travel; driving torques relative to their maximum.
SCENE_TARGETS = {"freq": 1e-8, "mac": 1e-6, "sensor": 1e-6, "torque": 1e-4}


@dataclass
class SceneValidation:
    """Both runs, ours (Exudyn's gravity model) and the twin's, the mode comparisons and the metrics."""

    name: str
    ours: Result
    exudyn: TwinRun
    modes: dict
    metrics: dict


def scene_bodies(scene) -> list:
    """The scene's bodies as :class:`validation.twin_bases.TwinBody` s (markers on every interface)."""
    from ffrf.system.markers import rigid_interface_marker

    from .twin_bases import TwinBody

    out = []
    for k, body in enumerate(scene.bodies):
        markers = {
            name: rigid_interface_marker(
                k, body.fe.nodes, body.reduction.basis, itf.nodes, itf.weights, name=f"{body.name}:{name}"
            )
            for name, itf in body.interfaces.items()
        }
        out.append(TwinBody(body.name, body.fe, body.interfaces, markers, body.reduction))
    return out


def _torque_keys(scene) -> dict[str, str]:
    from .exudyn_twin import joint_key

    return {name: f"torque:{joint_key(name)}" for name in scene.driven}


def twin_schedule(scene, run: Result) -> tuple[str, float | None]:
    """The mode and the dynamic step (s; ``None`` quasi-statically) of our ``run`` of ``scene``, which its twin takes:
    a linkage's run chooses both (the mode by its quasi-static ratio, the step by its drive,
    :func:`ffrf.scenes.assembly.dynamic_step`) and records them; a scene file's run takes its settings'."""
    mode = str(run.metadata.get("mode") or scene.settings.get("mode", "dynamic"))
    if mode != "dynamic":
        return mode, None
    step = run.metadata.get("step")
    return mode, float(scene.settings.get("step", 1e-3) if step is None else step)


def run_exudyn_scene(scene, bases, times: NDArray, mode: str, step: float | None, tolerance: float = 1e-10) -> TwinRun:
    """Exudyn's run of ``scene`` at our output ``times``, in our run's ``mode`` with its dynamic ``step``
    (:func:`twin_schedule`): ``q`` in our layout and basis, the sensors of :func:`compared_sensors` named as ours
    (positions, ``<joint>_torque`` with our sign), the set-up and solution wall times."""
    import exudyn

    from ffrf.scenes.assembly import quasi_static_step
    from ffrf.solvers.static_solver import refined_times

    from .exudyn_solvers import dynamic_settings, solve_dynamic, solve_static, static_settings, sweep_settings
    from .exudyn_twin import add_node_sensor, build_twin, read_twin
    from .twin_bases import to_twin_layout

    s = scene.settings
    beta = float(s.get("beta", 0.0))
    bodies = scene_bodies(scene)
    started = time.perf_counter()
    q0 = to_twin_layout(scene.system, scene.q_initial, bases)  # the bodies' start poses, as our runs
    start_torques = {name: 0.0 for name in scene.driven}
    if s.get("static_start", mode != "dynamic"):
        twin = build_twin(bodies, scene.system, q0, beta, symbolic=False, frozen_drive_time=0.0, bases=bases)
        twin.mbs.Assemble()
        solve_static(twin.mbs, static_settings(2, tolerance))
        data = read_twin(twin, scene.system, q0)
        q0 = data["twin_q"][-1]
        # Exudyn's static multipliers have the opposite sign of its dynamic ones (and ours).
        start_torques = {name: -float(data[key][-1, 2]) for name, key in _torque_keys(scene).items()}
    twin = build_twin(bodies, scene.system, q0, beta, symbolic=True, bases=bases)
    for name, (body, node) in scene.sensors.items():
        add_node_sensor(twin, name, body, node)
    twin.mbs.Assemble()
    setup = time.perf_counter() - started
    started = time.perf_counter()
    t_end = float(times[-1])
    if mode == "dynamic":
        if step is None:
            raise ValueError("a dynamic twin needs our run's step")
        settings = dynamic_settings(t_end, step, float(s.get("rho_inf", 0.9)), tolerance, tolerance)
        solve_dynamic(twin.mbs, settings, "the scene")
    else:  # the same intermediate equilibria as ours (ffrf.scenes.assembly.quasi_static_step)
        solve_static(twin.mbs, sweep_settings(refined_times(times, quasi_static_step(scene))[0], tolerance))
    solve = time.perf_counter() - started
    data = read_twin(twin, scene.system, q0)
    rows = np.array([int(np.argmin(np.abs(data["time"] - t))) for t in times])
    if np.abs(data["time"][rows] - times).max() > 1e-9 * max(1.0, t_end):
        raise RuntimeError("Exudyn's output times do not contain ours")
    out = {name: data[name][rows] for name in scene.sensors}
    sign = 1.0 if mode == "dynamic" else -1.0
    for name, key in _torque_keys(scene).items():
        torque = sign * data[key][rows, 2]
        if mode != "dynamic":
            torque[0] = start_torques[name]  # the sweep's first row is the start state, never solved
        out[f"{name}_torque"] = torque
    metadata = run_metadata("exudyn", f"exudyn {exudyn.__version__}", setup, solve, -1)
    return twin_run(times, data["q"][rows], out, metadata)


def compared_sensors(run: Result) -> dict[str, NDArray]:
    """The sensors of our ``run`` of a scene that both solvers measure (:func:`ffrf.scenes.scene_file.sensor_arrays`:
    node positions, ``<joint>_torque``)."""
    if run.multipliers is None:  # every run of a scene records them; a Result read from files has none
        raise ValueError(f"{run.scene.name}: the run has no multipliers to evaluate the sensors from")
    return sensor_arrays(run.scene, run.q, run.multipliers)


def validate_scene(path: str | Path, basis: str = "exudyn") -> SceneValidation:
    """Load the scene, run ours (Exudyn's gravity model, and the exact one) and Exudyn's, compare."""
    import exudyn

    from ffrf import load
    from ffrf.scenes.scene_file import load_scene

    from .exudyn_conventions import exudyn_convention_system
    from .twin_bases import twin_bases

    started = time.perf_counter()
    scene = load_scene(path)
    setup_ours = time.perf_counter() - started
    equivalent, exact = scene.with_exact_gravity(False), scene.with_exact_gravity(True)
    bases = twin_bases(scene_bodies(scene), basis)
    modes = {
        b.name: compare_modes(b.fe, b.reduction, tb.matrix, tb.fixed_interface_frequencies_hz, tb.setup_s)
        for b, tb in zip(scene.bodies, bases, strict=True)
        if tb.source == "exudyn"
    }
    started = time.perf_counter()
    run = load(equivalent).run()
    times = run.time
    solve_ours = time.perf_counter() - started
    ours = compared_sensors(run)
    # Exudyn's marker rotation Jacobian copied into ours (validation.exudyn_conventions): what remains is the
    # solvers' own difference; the production difference above adds Exudyn's approximation.
    convention = replace(equivalent, system=exudyn_convention_system(equivalent.system))
    run_convention = load(convention).run()
    convention_arrays = compared_sensors(run_convention)
    run_exact = load(exact).run()
    exact_arrays = compared_sensors(run_exact)
    mode, step = twin_schedule(scene, run)
    twin = run_exudyn_scene(scene, bases, times, mode, step)
    theirs, setup_exudyn, solve_exudyn = (
        twin.sensors,
        twin.metadata["timings_s"]["setup"],
        twin.metadata["timings_s"]["solve"],
    )

    metrics: dict = {
        "scene": scene.name,
        "mode": mode,
        "step_s": step,  # both solvers' (Exudyn's fixed; ours the base step, its parts where the drive turns fast)
        "modes": {n: c.metrics() for n, c in modes.items()},
        "sensors": {},
        "torques": {},
        "exact_gravity_effect": {},
    }
    for name in scene.sensors:
        distance = np.linalg.norm(ours[name] - theirs[name], axis=1)
        travel = max(float(np.linalg.norm(theirs[name] - theirs[name][0], axis=1).max()), 1e-300)
        same_jacobian = float(np.linalg.norm(convention_arrays[name] - theirs[name], axis=1).max())
        metrics["sensors"][name] = {
            "max_abs_diff_m": float(distance.max()),
            "travel_m": travel,
            "relative_to_travel": float(distance.max()) / travel,
            "with_exudyn_jacobian_max_abs_diff_m": same_jacobian,
            "with_exudyn_jacobian_relative_to_travel": same_jacobian / travel,
        }
        metrics["exact_gravity_effect"][name] = float(np.linalg.norm(exact_arrays[name] - ours[name], axis=1).max())
    for name in scene.driven:
        key = f"{name}_torque"
        scale = max(float(np.abs(theirs[key]).max()), 1e-300)
        metrics["torques"][name] = {
            "max_abs_diff_Nm": float(np.abs(ours[key] - theirs[key]).max()),
            "max_abs_Nm": scale,
            "max_rel_diff": float(np.abs(ours[key] - theirs[key]).max()) / scale,
        }
    metrics["timing_s"] = {
        "inhouse": {"setup": setup_ours, "integration": solve_ours, "total": setup_ours + solve_ours},
        "exudyn": {
            "setup": setup_exudyn + sum(b.setup_s for b in bases),
            "integration": solve_exudyn,
            "total": setup_exudyn + sum(b.setup_s for b in bases) + solve_exudyn,
        },
    }
    metrics["versions"] = {"exudyn": exudyn.__version__, "numpy": np.__version__}
    metrics["settings"] = {k: v for k, v in scene.settings.items()}
    checks = []
    for body, c in metrics["modes"].items():
        checks.append((f"{body}: frequencies, max relative difference", c["max_rel_freq_diff"], SCENE_TARGETS["freq"]))
        checks.append((f"{body}: 1 - min diagonal MAC", 1.0 - c["min_mac_diag"], SCENE_TARGETS["mac"]))
    for name, v in metrics["sensors"].items():
        checks.append(
            (
                f"sensor {name}, Exudyn's marker Jacobian in both: max difference / travel",
                v["with_exudyn_jacobian_relative_to_travel"],
                SCENE_TARGETS["sensor"],
            )
        )
    for name, v in metrics["torques"].items():
        checks.append((f"{name}: driving torque, max difference / max", v["max_rel_diff"], SCENE_TARGETS["torque"]))
    metrics["checks"] = [{"name": n, "value": float(v), "target": t, "passed": bool(v <= t)} for n, v, t in checks]
    metrics["passed"] = all(c["passed"] for c in metrics["checks"])
    return SceneValidation(scene.name, run, twin, modes, metrics)


def write_scene_report(v: SceneValidation, directory: str | Path) -> Path:
    """``report.md`` (verdict first), ``metrics.json``, ``difference.png`` and ``mac.png``."""
    from . import figures
    from .markdown import checks_table, format_length, format_sci, markdown_table

    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    m = v.metrics
    (out / "metrics.json").write_text(json.dumps(m, indent=2, default=float))
    ours = compared_sensors(v.ours)
    figures.series_difference_figure(
        v.ours.time,
        {n: (ours[n], v.exudyn.sensors[n]) for n in m["sensors"]},
        out / "difference.png",
        f"{v.name}: ours minus Exudyn",
    )
    if v.modes:
        figures.mac_figure(v.modes, out / "mac.png")
    failed = [c for c in m["checks"] if not c["passed"]]
    state = "all targets met" if not failed else f"{len(failed)} of {len(m['checks'])} targets missed"
    ti, te = m["timing_s"]["inhouse"], m["timing_s"]["exudyn"]
    lines = [
        f"# Cross-validation against Exudyn: scene `{v.name}` ({m['mode']})",
        "",
        f"**Verdict: {state}.** Same meshes, M, K, interfaces, joints, drives, gravity model and solver "
        f"settings; Exudyn {m['versions']['exudyn']} reduces the bodies itself. Time: ours "
        f"{ti['integration']:.2f} s, Exudyn {te['integration']:.2f} s.",
        "",
        checks_table(m["checks"]),
        "",
        "## Sensors",
        "",
        "Exudyn's joints use an approximate marker rotation Jacobian (`docs/validation.md`); its effect grows with "
        "the bores' elastic rotation. The targets hold the solvers' own difference, measured with that Jacobian "
        "copied into ours; the production difference is shown beside it.",
        "",
        markdown_table(
            ["sensor", "max abs diff", "travel", "relative", "with Exudyn's Jacobian", "exact gravity moves it by"],
            [
                [
                    n,
                    format_length(s["max_abs_diff_m"]),
                    format_length(s["travel_m"]),
                    format_sci(s["relative_to_travel"]),
                    format_length(s["with_exudyn_jacobian_max_abs_diff_m"]),
                    format_length(m["exact_gravity_effect"][n]),
                ]
                for n, s in m["sensors"].items()
            ],
        ),
        "",
        "![difference](difference.png)",
    ]
    if m["torques"]:
        lines += [
            "",
            "## Driving torques",
            "",
            markdown_table(
                ["joint", "max abs diff (N m)", "max torque (N m)", "relative"],
                [
                    [n, format_sci(t["max_abs_diff_Nm"]), format_sci(t["max_abs_Nm"]), format_sci(t["max_rel_diff"])]
                    for n, t in m["torques"].items()
                ],
            ),
        ]
    if v.modes:
        lines += [
            "",
            "## Modes",
            "",
            markdown_table(
                ["body", "max rel. frequency diff", "min diagonal MAC"],
                [[n, format_sci(c.max_rel_freq_diff), f"{c.min_mac_diag:.12f}"] for n, c in v.modes.items()],
            ),
            "",
            "![MAC](mac.png)",
        ]
    lines += [
        "",
        "## Wall time (s)",
        "",
        markdown_table(
            ["", "set-up", "run", "total"],
            [
                ["ours", f"{ti['setup']:.2f}", f"{ti['integration']:.2f}", f"{ti['total']:.2f}"],
                ["Exudyn", f"{te['setup']:.2f}", f"{te['integration']:.2f}", f"{te['total']:.2f}"],
            ],
        ),
        "",
    ]
    path = out / "report.md"
    path.write_text("\n".join(lines))
    return path
