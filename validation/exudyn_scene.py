r"""Cross-validation of a scene file (``python -m ffrf run SCENE.toml``) against its Exudyn twin.

Both solvers get the scene's meshes, M, K, interfaces, joints, drives, gravity, damping and
solver settings (:mod:`validation.exudyn_twin`); Exudyn reduces the bodies itself. Each
solver makes its own static start when the scene asks for one, then runs our run's mode
(dynamic: generalized-alpha with our run's step and spectral radius, each step in as many parts as ours took, by
Exudyn's UpdateCurrentTime user function; quasi-static: one ``SolveStatic`` whose load steps turn the drives).
Each run shows its progress; Exudyn's stops at a time limit, and then the outputs it reached are compared. Our
run uses Exudyn's gravity model (``exact_gravity = false``, Eq. (F10)) so that the two solve the same equations;
the effect of the exact gravity is reported separately.

Compared: per body the fixed-interface frequencies and MAC; per sensor the largest distance
between the two runs, relative to the sensor's travel (its largest distance from its start) and, for a linkage,
to the coupler's elastic deviation from the rigid loop's motion (the Bennett report's target); per driven joint
the driving torque relative to its maximum.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TextIO

import numpy as np
from numpy.typing import NDArray

from ffrf.output.result import Result
from ffrf.output.sensors import joint_point_sensors
from ffrf.scenes.scene_file import sensor_arrays

from .bennett_metrics import SCALE_FLOOR_M, TARGETS
from .modes import compare_modes
from .twin_clock import RunClock, compiled_kernels
from .twin_run import TwinRun, run_metadata, twin_run

__all__ = [
    "SCENE_TARGETS",
    "SceneValidation",
    "scene_bodies",
    "run_exudyn_scene",
    "twin_schedule",
    "compared_sensors",
    "elastic_deviation",
    "validate_scene",
    "write_scene_report",
]

#: Targets for a scene: frequencies and MAC as for the Bennett scene; sensors relative to their
#: travel (a linkage's: relative to the coupler's elastic deviation, the Bennett report's target,
#: :data:`validation.bennett_metrics.TARGETS`); driving torques relative to their maximum.
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


def run_exudyn_scene(
    scene,
    bases,
    times: NDArray,
    mode: str,
    step: float | None,
    tolerance: float = 1e-10,
    clock: RunClock | None = None,
    parts: list[list[int]] | None = None,
) -> TwinRun:
    """Exudyn's run of ``scene`` at our output ``times``, in our run's ``mode`` with its dynamic ``step``
    (:func:`twin_schedule`): ``q`` in our layout and basis, the sensors of :func:`compared_sensors` named as ours
    (positions, ``<joint>_torque`` with our sign), the set-up and solution wall times. A ``clock`` shows the run's
    progress and stops it at its deadline: the rows are then those of ``times`` reached, and the metadata's
    ``stopped`` says where the run stopped and why. ``parts``: how many parts each dynamic step of our run took
    (its metadata's ``step_parts``, Eqs. (G7), (G8)); Exudyn takes the very same steps."""
    import exudyn

    from ffrf.scenes.assembly import quasi_static_step
    from ffrf.solvers.generalized_alpha import part_schedule
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
    t_end = float(times[-1])
    if clock is not None:
        twin.mbs.SetPreStepUserFunction(clock.exudyn_pre_step)
    twin.mbs.Assemble()
    setup = time.perf_counter() - started
    started = time.perf_counter()
    if mode == "dynamic":
        if step is None:
            raise ValueError("a dynamic twin needs our run's step")
        settings = dynamic_settings(t_end, step, float(s.get("rho_inf", 0.9)), tolerance, tolerance)
        steps = max(1, round(t_end / step))
        schedule = None if not parts or all(p == 1 for p, _ in parts) else part_schedule(t_end / steps, parts)
        solve_dynamic(twin.mbs, settings, "the scene", schedule)
    else:  # the same intermediate equilibria as ours (ffrf.scenes.assembly.quasi_static_step)
        solve_static(twin.mbs, sweep_settings(refined_times(times, quasi_static_step(scene))[0], tolerance))
    solve = time.perf_counter() - started
    data = read_twin(twin, scene.system, q0)
    same = 1e-9 * max(1.0, t_end)
    stopped = clock is not None and clock.stopped
    if stopped:  # the outputs the run reached
        times = times[times <= data["time"][-1] + same]
    rows = np.array([int(np.argmin(np.abs(data["time"] - t))) for t in times])
    if np.abs(data["time"][rows] - times).max() > same:
        raise RuntimeError(
            f"Exudyn's output times do not contain ours: its run ended at t = {data['time'][-1]:.6g} s of "
            f"{t_end:.6g} s with {len(data['time'])} rows (a load step it could not solve, near a fold?)"
        )
    out = {name: data[name][rows] for name in scene.sensors}
    out |= joint_point_sensors(scene, times, data["q"][rows])
    sign = 1.0 if mode == "dynamic" else -1.0
    for name, key in _torque_keys(scene).items():
        torque = sign * data[key][rows, 2]
        if mode != "dynamic":
            torque[0] = start_torques[name]  # the sweep's first row is the start state, never solved
        out[f"{name}_torque"] = torque
    metadata = run_metadata("exudyn", f"exudyn {exudyn.__version__}", setup, solve, -1)
    if stopped:
        metadata["stopped"] = {"reached_s": float(data["time"][-1]), "t_end_s": t_end}
    return twin_run(times, data["q"][rows], out, metadata)


def elastic_deviation(scene, time: NDArray, sensors: dict[str, NDArray]) -> float | None:
    """A linkage's elastic deviation (m): the largest distance of the twin's ``coupler_point`` from the rigid nominal
    loop's at the same drive angle, the scale of the Bennett report's trajectory target
    (:mod:`validation.bennett_metrics`); ``None`` for a scene file, which has no ideal motion."""
    if not hasattr(scene, "ideal_coupler_points") or "coupler_point" not in sensors:
        return None
    ideal = scene.ideal_coupler_points([scene.drive_angle(float(t)) for t in time])
    return float(np.linalg.norm(sensors["coupler_point"] - ideal, axis=1).max())


def compared_sensors(run: Result) -> dict[str, NDArray]:
    """The sensors of our ``run`` of a scene that both solvers measure (:func:`ffrf.scenes.scene_file.sensor_arrays`:
    node positions, ``<joint>_torque``) and the joint-point sensors (a linkage's ``coupler_point``,
    :func:`ffrf.output.sensors.joint_point_sensors`), which the twin's run gets from its coordinates."""
    if run.multipliers is None:  # every run of a scene records them; a Result read from files has none
        raise ValueError(f"{run.scene.name}: the run has no multipliers to evaluate the sensors from")
    return sensor_arrays(run.scene, run.q, run.multipliers) | joint_point_sensors(run.scene, run.time, run.q)


def _steps_taken(run: Result, step: float | None) -> int | None:
    """The dynamic steps both solvers took (every part of a fixed step counted); ``None`` quasi-statically."""
    if step is None:
        return None
    parts = run.metadata.get("step_parts")
    return int(sum(p * n for p, n in parts)) if parts else max(1, round(float(run.time[-1]) / step))


def validate_scene(
    path: str | Path, basis: str = "exudyn", max_minutes: float | None = None, stream: TextIO | None = sys.stderr
) -> SceneValidation:
    """Load the scene, run ours (Exudyn's gravity model, and the exact one) and Exudyn's, compare. Each run shows its
    progress on ``stream`` (:class:`validation.twin_clock.RunClock`); Exudyn's stops ``max_minutes`` after the
    start, and then the outputs it reached are compared (the metrics' ``stopped``; never ``passed``)."""
    import exudyn

    from ffrf import load
    from ffrf.scenes.scene_file import load_scene

    from .exudyn_conventions import exudyn_convention_system
    from .twin_bases import twin_bases

    deadline = None if max_minutes is None else time.monotonic() + 60.0 * max_minutes
    kernels_s = compiled_kernels(stream)
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
    run = load(equivalent).run(progress=RunClock("ours", 1.0, stream=stream).progress)
    solve_ours = time.perf_counter() - started
    # Exudyn's marker rotation Jacobian copied into ours (validation.exudyn_conventions): what remains is the
    # solvers' own difference; the production difference above adds Exudyn's approximation.
    convention = replace(equivalent, system=exudyn_convention_system(equivalent.system))
    # the variants take the first run's dynamic steps, as Exudyn does: the comparisons are of equations, not steps
    parts = run.metadata.get("step_parts")
    same_steps = {"step_parts": parts} if parts else {}
    run_convention = load(convention).run(
        progress=RunClock("ours, Exudyn's Jacobian", 1.0, stream=stream).progress, **same_steps
    )
    run_exact = load(exact).run(progress=RunClock("ours, exact gravity", 1.0, stream=stream).progress, **same_steps)
    mode, step = twin_schedule(scene, run)
    clock = RunClock("Exudyn", float(run.time[-1]), deadline, stream)
    twin = run_exudyn_scene(scene, bases, run.time, mode, step, clock=clock, parts=parts)
    theirs, setup_exudyn, solve_exudyn = (
        twin.sensors,
        twin.metadata["timings_s"]["setup"],
        twin.metadata["timings_s"]["solve"],
    )
    compared = len(twin.time)  # all our outputs, or those Exudyn reached before the time limit
    ours, convention_arrays, exact_arrays = (
        {name: values[:compared] for name, values in compared_sensors(r).items()}
        for r in (run, run_convention, run_exact)
    )

    elastic = elastic_deviation(scene, twin.time, theirs)
    metrics: dict = {
        "scene": scene.name,
        "mode": mode,
        "step_s": step,  # both solvers' fixed step; each done in as many parts as ours took (step_parts)
        "steps_taken": _steps_taken(run, step),
        "outputs": len(run.time),
        "outputs_compared": compared,
        "modes": {n: c.metrics() for n, c in modes.items()},
        "sensors": {},
        "torques": {},
        "exact_gravity_effect": {},
        "elastic_deviation_m": elastic,
    }
    if elastic is not None:  # the coupler's deviation from the ideal motion by each solver (ours: its run's summary)
        ours_deviation = run.metadata.get("summary", {}).get("max_coupler_deviation_m")
        metrics["coupler_deviation_from_ideal_m"] = {"inhouse": ours_deviation, "exudyn": elastic}
    for name in [*scene.sensors, *scene.joint_sensors]:
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
        if elastic is not None:
            scale = max(elastic, SCALE_FLOOR_M)
            metrics["sensors"][name]["relative_to_elastic_deviation"] = float(distance.max()) / scale
            metrics["sensors"][name]["with_exudyn_jacobian_relative_to_elastic_deviation"] = same_jacobian / scale
        metrics["exact_gravity_effect"][name] = float(np.linalg.norm(exact_arrays[name] - ours[name], axis=1).max())
    for name in scene.driven:
        key = f"{name}_torque"
        scale = max(float(np.abs(theirs[key]).max()), 1e-300)
        same_jacobian = float(np.abs(convention_arrays[key] - theirs[key]).max())
        metrics["torques"][name] = {
            "max_abs_diff_Nm": float(np.abs(ours[key] - theirs[key]).max()),
            "max_abs_Nm": scale,
            "max_rel_diff": float(np.abs(ours[key] - theirs[key]).max()) / scale,
            "with_exudyn_jacobian_max_rel_diff": same_jacobian / scale,
        }
    metrics["timing_s"] = {
        "inhouse": {"setup": setup_ours, "integration": solve_ours, "total": setup_ours + solve_ours},
        "exudyn": {
            "setup": setup_exudyn + sum(b.setup_s for b in bases),
            "integration": solve_exudyn,
            "total": setup_exudyn + sum(b.setup_s for b in bases) + solve_exudyn,
        },
    }
    metrics["timing_s"]["kernels_before_s"] = kernels_s
    metrics["versions"] = {"exudyn": exudyn.__version__, "numpy": np.__version__}
    metrics["settings"] = {k: v for k, v in scene.settings.items()}
    checks = []
    for body, c in metrics["modes"].items():
        checks.append((f"{body}: frequencies, max relative difference", c["max_rel_freq_diff"], SCENE_TARGETS["freq"]))
        checks.append((f"{body}: 1 - min diagonal MAC", 1.0 - c["min_mac_diag"], SCENE_TARGETS["mac"]))
    for name, v in metrics["sensors"].items() if elastic is None else ():  # a linkage: the Bennett target below
        checks.append(
            (
                f"sensor {name}, Exudyn's marker Jacobian in both: max difference / travel",
                v["with_exudyn_jacobian_relative_to_travel"],
                SCENE_TARGETS["sensor"],
            )
        )
    for name, v in metrics["torques"].items():
        checks.append(
            (
                f"{name}: driving torque, Exudyn's marker Jacobian in both: max difference / max",
                v["with_exudyn_jacobian_max_rel_diff"],
                SCENE_TARGETS["torque"],
            )
        )
    if elastic is not None:  # a linkage: the Bennett report's target (validation.bennett_metrics)
        worst = max(v["with_exudyn_jacobian_relative_to_elastic_deviation"] for v in metrics["sensors"].values())
        checks.append(
            (
                "coupler and tracked nodes, Exudyn's marker Jacobian in both: max difference / coupler's elastic "
                "deviation",
                worst,
                TARGETS["trajectory"],
            )
        )
    metrics["checks"] = [{"name": n, "value": float(v), "target": t, "passed": bool(v <= t)} for n, v, t in checks]
    if "stopped" in twin.metadata:
        metrics["stopped"] = {
            **twin.metadata["stopped"],
            "reason": f"Exudyn's run reached the time limit of {max_minutes:g} min",
        }
    metrics["passed"] = all(c["passed"] for c in metrics["checks"]) and "stopped" not in metrics
    return SceneValidation(scene.name, run, twin, modes, metrics)


def _schedule_text(m: dict) -> str:
    """Both solvers' steps, as the report states them."""
    if m["step_s"] is None:
        return f"Both: quasi-static, {m['outputs']} outputs."
    return (
        f"Both: dynamic, {m['outputs']} outputs, {1e3 * m['step_s']:g} ms steps in {m['steps_taken']} parts "
        "(ours, taken by Exudyn too)."
    )


def write_scene_report(v: SceneValidation, directory: str | Path) -> Path:
    """``report.md`` (verdict first), ``metrics.json``, ``difference.png`` and ``mac.png``."""
    from . import figures
    from .markdown import checks_table, format_length, format_sci, markdown_table

    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    m = v.metrics
    (out / "metrics.json").write_text(json.dumps(m, indent=2, default=float))
    ours = compared_sensors(v.ours)
    compared = len(v.exudyn.time)
    figures.series_difference_figure(
        v.exudyn.time,
        {n: (ours[n][:compared], v.exudyn.sensors[n]) for n in m["sensors"]},
        out / "difference.png",
        f"{v.name}: ours minus Exudyn",
    )
    if v.modes:
        figures.mac_figure(v.modes, out / "mac.png")
    failed = [c for c in m["checks"] if not c["passed"]]
    state = "all targets met" if not failed else f"{len(failed)} of {len(m['checks'])} targets missed"
    if "stopped" in m:
        st = m["stopped"]
        state = (
            f"incomplete: {st['reason']} at t = {st['reached_s']:.4g} of {st['t_end_s']:.4g} s; "
            f"{m['outputs_compared']} of {m['outputs']} outputs compared, on which {state}"
        )
    ti, te = m["timing_s"]["inhouse"], m["timing_s"]["exudyn"]
    elastic = m.get("elastic_deviation_m")
    elastic_text = ""
    if elastic is not None:
        d = m["coupler_deviation_from_ideal_m"]
        elastic_text = (
            " The coupler's elastic deviation from the rigid loop's motion (the scale of the Bennett report's target):"
            f" Exudyn {format_length(d['exudyn'])}, ours {format_length(d['inhouse'])}."
        )
    lines = [
        f"# Cross-validation against Exudyn: scene `{v.name}` ({m['mode']})",
        "",
        f"**Verdict: {state}.** Same meshes, M, K, interfaces, joints, drives, gravity model and solver "
        f"settings; Exudyn {m['versions']['exudyn']} reduces the bodies itself. Time: ours "
        f"{ti['integration']:.2f} s, Exudyn {te['integration']:.2f} s. {_schedule_text(m)}",
        "",
        checks_table(m["checks"]),
        "",
        "## Sensors",
        "",
        "Exudyn's joints use an approximate marker rotation Jacobian (`docs/validation.md`); its effect grows with "
        "the bores' elastic rotation. The targets hold the solvers' own difference, measured with that Jacobian "
        "copied into ours; the production difference is shown beside it." + elastic_text,
        "",
        markdown_table(
            [
                "sensor",
                "max abs diff",
                "travel",
                "relative",
                *(["/ elastic deviation"] if elastic else []),
                "with Exudyn's Jacobian",
                "exact gravity moves it by",
            ],
            [
                [
                    n,
                    format_length(s["max_abs_diff_m"]),
                    format_length(s["travel_m"]),
                    format_sci(s["relative_to_travel"]),
                    *([format_sci(s["relative_to_elastic_deviation"])] if elastic else []),
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
                ["joint", "max abs diff (N m)", "max torque (N m)", "relative", "with Exudyn's Jacobian"],
                [
                    [
                        n,
                        format_sci(t["max_abs_diff_Nm"]),
                        format_sci(t["max_abs_Nm"]),
                        format_sci(t["max_rel_diff"]),
                        format_sci(t["with_exudyn_jacobian_max_rel_diff"]),
                    ]
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
        f"Our solver's kernels were compiled (or loaded from numba's cache) before the runs, in "
        f"{m['timing_s']['kernels_before_s']:.1f} s, which no time above includes.",
        "",
    ]
    path = out / "report.md"
    path.write_text("\n".join(lines))
    return path
