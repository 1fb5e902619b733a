"""Memory of the main job and of fine meshes, and allocations in the Newton loop (issue #22).

Three measurements, each in a new process (``--child``) so that one's heap does not inflate the next's:

* **Main job**: ``python -m ffrf bennett --variant pla --out DIR`` (the README's step 2), its peak resident set
  (``ru_maxrss`` of ``wait4``, :func:`memory_probe.run_child`), and the same job once more inside this benchmark's
  child with its stages wrapped (:class:`memory_probe.StagePeaks`: the peak resident set while each stage ran).
* **Fine meshes** (``--meshes order,h ...``): ``build_bennett("pla", h=h, order=order)`` (4 fixed-interface modes per
  link, as the default) and a short quasi-static run (``--short-run`` s of the drive's ramp), with the peak per stage
  (gmsh, FE assembly, the factorisation of ``K_ii``, Lanczos, the Sturm count, modal moments, static assembly, ...)
  and the sizes: nodes, FE degrees of freedom and stored entries of ``K`` (all links), reduced coordinates.
* **Allocations** (``--child allocations``): numba's runtime count of its allocations (every array made inside a
  jitted function, :func:`memory_probe.nrt_counts`) per Newton iteration, step and pose of the default scene: a
  dynamic run (generalized-alpha, :func:`ffrf.solvers.newton_kernels.alpha_iterations` around
  :func:`ffrf.system.system_kernels.system_residual`) and a quasi-static one; per kernel function of the residual at
  one state; and the time of the residual against the time of as many small allocations in a jitted loop.

Counts of kernels called from Python subtract the arrays passed in: numba wraps each argument array in a runtime
record, one counted allocation per array per call (``ARGUMENT_RECORDS``); the counts inside a kernel called from a
kernel have no such term.

Usage::

    OPENBLAS_NUM_THREADS=1 FFRF_CACHE_DIR=off .venv/bin/python -m bench memory --json out/memory.json
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from numba import njit

from bench import ROOT
from bench.memory_probe import SETUP_STAGES as BUILD_STAGES
from bench.memory_probe import StagePeaks, count_allocations, nrt_counts, run_child, status_mb, stop_counting
from bench.report import write_report

MAIN_JOB = ["-m", "ffrf", "bennett", "--variant", "pla"]

#: (module, function, stage): the build and its stages
SETUP_STAGES = (("ffrf.paper.bennett_scene", "build_bennett", "build_bennett"), *BUILD_STAGES)
#: ... and the run's: static assembly, its stresses, the solver, the sensors, the files
RUN_STAGES = (
    ("ffrf.model", "run_linkage", "run_linkage"),
    ("ffrf.scenes.linkage_run", "assemble", "static_assembly"),
    ("ffrf.scenes.linkage_run", "scene_assembly_stress", "assembly_stress"),
    ("ffrf.scenes.linkage_run", "simulate", "simulate"),
    ("ffrf.scenes.linkage_run", "evaluate_sensors", "sensors"),
    ("ffrf.output.result", "write_results", "write_results"),
    ("ffrf.output.result", "write_assembly_vtu", "write_assembly_vtu"),
    ("ffrf.output.linkage_figures", "plot_coupler_deviation", "plot_coupler_deviation"),
    ("ffrf.output.linkage_figures", "plot_driving_torque", "plot_driving_torque"),
)


def _environment() -> dict:
    return dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1", FFRF_CACHE_DIR="off")


def _load() -> list[float]:
    return [float(x) for x in Path("/proc/loadavg").read_text().split()[:3]]


def _available_gib() -> float:
    for line in Path("/proc/meminfo").read_text().splitlines():
        if line.startswith("MemAvailable:"):
            return float(line.split()[1]) / 1024.0**2
    return float("nan")


def _measured_child(kind: str, *arguments: str) -> dict:
    """``--child kind arguments`` in a new process: its JSON report plus its exit code and wall time. Its peak is the
    report's ``peak_rss_mb`` (:class:`memory_probe.StagePeaks`): ``ru_maxrss`` would only hold the peak since the last
    reset of ``VmHWM``, which the kernel also uses for it."""
    with tempfile.TemporaryDirectory(prefix="ffrf-memory-") as folder:
        out = Path(folder) / "child.json"
        command = [sys.executable, "-m", "bench.memory", "--child", kind, str(out), *arguments]
        code, _, wall = run_child(command, env=_environment(), cwd=ROOT, log=Path(folder) / "log.txt")
        if code != 0:
            raise RuntimeError(f"{kind} {arguments} exited with {code}:\n{(Path(folder) / 'log.txt').read_text()}")
        report = json.loads(out.read_text())
    return dict(report, exit_code=code, wall_s=wall)


# --------------------------------------------------------------------------------------------
# Children
# --------------------------------------------------------------------------------------------


def _staged() -> StagePeaks:
    """Import the solver (its resident set is the floor of every stage) and wrap the stages."""
    peaks = StagePeaks()
    for module, name, stage in SETUP_STAGES + RUN_STAGES:
        peaks.wrap(module, name, stage)
    return peaks


def child_main_job(out: Path) -> None:
    """The main job through the CLI's entry point, with its stages measured."""
    started = status_mb("VmRSS")
    peaks = _staged()
    imported = status_mb("VmRSS")
    from ffrf.cli import main

    with tempfile.TemporaryDirectory(prefix="ffrf-memory-job-") as folder:
        code = main(["bennett", "--variant", "pla", "--out", folder])
    out.write_text(json.dumps(dict(peaks.report(), exit_code=code, start_rss_mb=started, imported_rss_mb=imported)))


def scene_sizes(scene) -> dict:
    """Nodes, FE degrees of freedom and stored entries of every link's ``K``, and the reduced system's size."""
    models = [link.mesh_model for link in scene.links]
    return {
        "nodes": [int(m.nodes.shape[0]) for m in models],
        "fe_dofs": [int(m.stiffness.shape[0]) for m in models],
        "nnz_k": [int(m.stiffness.nnz) for m in models],
        "tetrahedra": [int(m.mesh.tets.shape[0]) for m in models],
        "total_nodes": int(sum(m.nodes.shape[0] for m in models)),
        "total_fe_dofs": int(sum(m.stiffness.shape[0] for m in models)),
        "total_nnz_k": int(sum(m.stiffness.nnz for m in models)),
        "reduced_coordinates": int(scene.system.n_coordinates),
        "constraints": int(scene.system.n_constraints),
    }


def child_scene(out: Path, order: int, h: float, short_run: float) -> None:
    """The default scene at ``(order, h)``, a quasi-static run over its first ``short_run`` s, stages measured."""
    peaks = _staged()
    from ffrf.paper import bennett_scene
    from ffrf.scenes import linkage_run

    started = time.perf_counter()
    scene = bennett_scene.build_bennett("pla", h=h, order=order)
    built = time.perf_counter()
    sizes = scene_sizes(scene)
    linkage_run.run_linkage(scene, "quasi_static", n_outputs=5, t_end=short_run)
    report = dict(peaks.report(), order=order, h=h, build_s=built - started, run_s=time.perf_counter() - built)
    out.write_text(json.dumps(dict(report, sizes=sizes)))


# --------------------------------------------------------------------------------------------
# Allocations in the kernels
# --------------------------------------------------------------------------------------------


def argument_records(arguments) -> int:
    """Arrays in ``arguments`` (tuples searched): each is wrapped in one counted runtime record per call from Python."""
    if isinstance(arguments, np.ndarray):
        return 1
    if isinstance(arguments, tuple | list):
        return sum(argument_records(a) for a in arguments)
    return 0


def kernel_allocations(function, *arguments, repeats: int = 20) -> float:
    """Allocations per call of the jitted ``function`` made inside it (argument records subtracted)."""
    return count_allocations(lambda: function(*arguments), repeats) - argument_records(arguments)


class _Calls:
    """Wraps ``owner.name`` (a module or class attribute) to record, per call, the allocations inside it (argument
    records of a jitted function subtracted), its seconds and ``iterations(result)``."""

    def __init__(self, owner, name: str, iterations=None, jitted: bool = False):
        self.records: list[tuple[float, int, float]] = []
        function = getattr(owner, name)

        def counted(*args, **kwargs):
            before = nrt_counts()[0]
            started = time.perf_counter()
            result = function(*args, **kwargs)
            seconds = time.perf_counter() - started
            allocations = nrt_counts()[0] - before - (argument_records(args) if jitted else 0)
            self.records.append((allocations, 0 if iterations is None else iterations(result), seconds))
            return result

        setattr(owner, name, counted)

    def summary(self) -> dict:
        if not self.records:
            return {"calls": 0}
        allocations, iterations, seconds = (np.array(column, dtype=float) for column in zip(*self.records, strict=True))
        out = {
            "calls": len(self.records),
            "allocations_per_call": float(allocations.mean()),
            "allocations_min_max": [float(allocations.min()), float(allocations.max())],
            "seconds_per_call": float(seconds.mean()),
        }
        if iterations.any():
            out["iterations_per_call"] = float(iterations.mean())
            out["allocations_per_iteration"] = float(allocations.sum() / iterations.sum())
            out["seconds_per_iteration"] = float(seconds.sum() / iterations.sum())
            if len(set(iterations)) > 1:  # allocations = fixed + per iteration * iterations, exactly?
                slope, intercept = np.polyfit(iterations, allocations, 1)
                out["fit_per_iteration"] = float(slope)
                out["fit_per_call"] = float(intercept)
                out["fit_largest_miss"] = float(np.abs(allocations - slope * iterations - intercept).max())
        return out


@njit(cache=True)
def _small_allocations(count: int, size: int) -> float:
    """``count`` arrays of ``size`` float64 made and dropped, as the kernels' temporaries are."""
    total = 0.0
    for i in range(count):
        a = np.empty(size)
        a[0] = i
        total += a[0]
    return total


def _seconds_per_call(call, repeats: int, batches: int = 5) -> float:
    """The fastest of ``batches`` mean times of ``call()`` over ``repeats`` (the machine is shared)."""
    call()
    best = np.inf
    for _ in range(batches):
        started = time.perf_counter()
        for _ in range(repeats):
            call()
        best = min(best, (time.perf_counter() - started) / repeats)
    return best


def residual_breakdown(packed, q, qd, qdd, lam, phi) -> dict:
    """Allocations inside each kernel function of :func:`system_residual` at one state, per call."""
    from ffrf.body.flexible_body import body_residual
    from ffrf.system import system_kernels as sk
    from ffrf.system.marker_kernels import marker_frame_transpose, marker_pose

    bodies, joints, gravity = packed.bodies, packed.joints, packed.gravity
    offsets, row_starts = bodies[0], joints[3]
    forces = np.zeros(q.shape[0])
    out: dict = {
        "system_residual": kernel_allocations(sk.system_residual, bodies, joints, q, qd, qdd, lam, gravity, phi),
        "_body_residuals": kernel_allocations(sk._body_residuals, bodies, q, qd, qdd, gravity),
        "_constraint_forces": kernel_allocations(sk._constraint_forces, joints, offsets, q, phi, lam, forces),
        "body_residual": [],
        "body_residual_at_rest": [],
        "joints": [],
    }
    for b in range(offsets.shape[0] - 1):
        s, e = offsets[b], offsets[b + 1]
        moments = sk._moments(bodies[3], bodies[4], b, e - s - 7)
        common = (gravity, bodies[1][b], *moments, bodies[2][b])
        out["body_residual"].append(kernel_allocations(body_residual, q[s:e], qd[s:e], qdd[s:e], *common))
        rest = np.zeros(e - s)
        out["body_residual_at_rest"].append(kernel_allocations(body_residual, q[s:e], rest, rest, *common))
    weight_point, weight_axes = np.ones(3), np.ones((3, 3))
    for j in range(joints[0].shape[0]):
        r0, r1 = row_starts[j], row_starts[j + 1]
        if joints[0][j] == 0:
            out["joints"].append(
                {"joint": j, "kind": "euler", "_euler": kernel_allocations(sk._euler, joints, j, q, offsets)}
            )
            continue
        entry: dict[str, Any] = {
            "joint": j,
            "kind": "marker",
            "bodies": [int(joints[1][j]), int(joints[2][j])],
            "_marker_joint_forces": kernel_allocations(
                sk._marker_joint_forces, joints, j, q, offsets, phi, lam[r0:r1], forces
            ),
            "marker_pose": [],
            "marker_frame_transpose": [],
        }
        for side, body in ((joints[5], joints[1][j]), (joints[6], joints[2][j])):
            if body < 0:
                continue
            q_body = q[offsets[body] : offsets[body + 1]]
            data = sk._side_data(side, j)
            entry["marker_pose"].append(kernel_allocations(marker_pose, q_body, *data))
            entry["marker_frame_transpose"].append(
                kernel_allocations(marker_frame_transpose, q_body, *data, weight_point, weight_axes)
            )
        entry["_marker_joint_forces_own"] = (
            entry["_marker_joint_forces"] - sum(entry["marker_pose"]) - sum(entry["marker_frame_transpose"])
        )
        out["joints"].append(entry)
    markers = [j for j in out["joints"] if j["kind"] == "marker"]
    out["summary"] = {
        "marker_sides": sum(len(j["marker_pose"]) for j in markers),
        "marker_pose_total": sum(sum(j["marker_pose"]) for j in markers),
        "marker_frame_transpose_total": sum(sum(j["marker_frame_transpose"]) for j in markers),
        "marker_joints_own_total": sum(j["_marker_joint_forces_own"] for j in markers),
        "euler_total": sum(j["_euler"] for j in out["joints"] if j["kind"] == "euler"),
        "body_residuals_total": sum(out["body_residual"]),
    }
    return out


def child_allocations(out: Path, dynamic_end: float, static_end: float) -> None:
    """Allocations per iteration, step and pose of the default scene, per kernel function, and their time."""
    from ffrf.paper.bennett_scene import build_bennett
    from ffrf.scenes.assembly import assemble, dynamic_step, quasi_static_step
    from ffrf.solvers import generalized_alpha, static_solver
    from ffrf.solvers.newton_kernels import alpha_iterations
    from ffrf.solvers.simulate import simulate
    from ffrf.system.packed_system import PackedSystem, pack_system
    from ffrf.system.system_kernels import system_residual

    scene = build_bennett("pla")
    assembly = assemble(scene)
    packed = pack_system(scene.system)
    if packed is None:
        raise RuntimeError("the default scene has no packed form: the fast path measured here is not taken")
    # Timed without counting: counting adds an atomic increment to every allocation.
    sizes = {"3": 3, "9": 9, "27": 27, "3n": 3 * packed.n_coordinates}
    ns_per_allocation = {
        k: 1e9 * _seconds_per_call(lambda s=s: _small_allocations(10_000, s), 20) / 1e4 for k, s in sizes.items()
    }
    nrt_counts()
    start = nrt_counts()
    steps = _Calls(generalized_alpha, "_step", iterations=lambda r: r[1])
    calls = _Calls(generalized_alpha, "alpha_iterations", iterations=lambda r: int(r[1]), jitted=True)
    factors = _Calls(generalized_alpha, "_factor_iteration_matrix")
    captured: list = []
    kernel = generalized_alpha.alpha_iterations

    def capture(*args):
        captured[:] = [a.copy() if isinstance(a, np.ndarray) else a for a in args]
        return kernel(*args)

    name = "alpha_iterations"  # the jitted function (already counted), wrapped once more
    setattr(generalized_alpha, name, capture)
    step = dynamic_step(scene)
    started = time.perf_counter()
    run = simulate(scene.system, assembly.q, "dynamic", dynamic_end, 11, step=step)
    dynamic_s = time.perf_counter() - started
    del run
    poses = _Calls(static_solver, "_advance", iterations=lambda r: r[0])
    tangents = _Calls(static_solver, "_factor_tangent")
    residuals = _Calls(PackedSystem, "residual")
    started = time.perf_counter()
    run = simulate(scene.system, assembly.q, "quasi_static", static_end, 33, max_static_step=quasi_static_step(scene))
    static_s = time.perf_counter() - started
    del run
    gc.collect()
    end = nrt_counts()
    # One state of the dynamic run (the last iteration's arguments): the residual's allocations by function.
    (_, _, gravity, phi, lu, piv, q_base, qd_base, accel_base, to_accel, h2_beta, h_gamma) = captured[:12]
    qdd, lam = captured[14], captured[15]
    accel = accel_base + to_accel * qdd
    q, qd = q_base + h2_beta * accel, qd_base + h_gamma * accel
    breakdown = residual_breakdown(packed, q, qd, qdd, lam, phi)
    arguments = (packed.bodies, packed.joints, q, qd, qdd, lam, gravity, phi)
    stop_counting()
    residual_s = _seconds_per_call(lambda: system_residual(*arguments), 500)

    def one_iteration():  # tolerance 0 and ``done`` far below the refactoring rule's fifth: exactly one iteration
        return alpha_iterations(*captured[:14], qdd.copy(), lam.copy(), 0.0, 1, np.inf, -100)

    iteration_s = _seconds_per_call(one_iteration, 500)
    report = {
        "scene": 'build_bennett("pla"): P2, h = 6 mm, 4 fixed-interface modes per link',
        "coordinates": packed.n_coordinates,
        "constraints": packed.n_constraints,
        "dynamic": {
            "t_end_s": dynamic_end,
            "step_s": step,
            "run_s": dynamic_s,
            "per_step": steps.summary(),
            "alpha_iterations": calls.summary(),
            "factorisations": factors.summary(),
        },
        "quasi_static": {
            "t_end_s": static_end,
            "run_s": static_s,
            "per_pose": poses.summary(),
            "tangents": tangents.summary(),
            "residual_calls": residuals.summary(),
        },
        "residual_by_function": breakdown,
        "allocated_minus_freed_over_both_runs": (end[0] - start[0]) - (end[1] - start[1]),
        "time": {
            "system_residual_us": 1e6 * residual_s,
            "alpha_iteration_us": 1e6 * iteration_s,
            "ns_per_small_allocation": ns_per_allocation,
            "allocations_of_residual_us": breakdown["system_residual"] * ns_per_allocation["9"] * 1e-3,
            "note": "fastest of 5 batches; calls from Python (argument records included)",
        },
    }
    out.write_text(json.dumps(report))


# --------------------------------------------------------------------------------------------
# The benchmark
# --------------------------------------------------------------------------------------------


def _peak_stage(stages: dict, within: tuple) -> str:
    """The innermost stage holding the peak among ``within`` (nested stages share their children's peaks)."""
    names = [name for *_, name in within if name in stages]
    peak = max(stages[name]["peak_rss_mb"] for name in names)
    return [name for name in names if stages[name]["peak_rss_mb"] == peak][-1]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, required=True)
    parser.add_argument(
        "--meshes",
        nargs="*",
        default=["1,0.002", "1,0.0015", "1,0.001", "2,0.003", "2,0.002"],
        help="order,h (m) of the scenes whose set-up is measured (default: P1 to 1 mm, P2 to 2 mm)",
    )
    parser.add_argument("--short-run", type=float, default=0.2, help="quasi-static run after each build (s of drive)")
    parser.add_argument("--dynamic-end", type=float, default=1.0, help="dynamic run of the allocation count (s)")
    parser.add_argument("--static-end", type=float, default=2.0, help="quasi-static run of the allocation count (s)")
    parser.add_argument("--skip-job", action="store_true", help="no main job")
    args = parser.parse_args()
    report: dict = {"load_average_start": _load(), "memory_available_gib": _available_gib()}
    if not args.skip_job:
        with tempfile.TemporaryDirectory(prefix="ffrf-memory-out-") as folder:
            command = [sys.executable, *MAIN_JOB, "--out", folder]
            code, peak, wall = run_child(command, env=_environment(), cwd=ROOT, log=Path(folder) / "log.txt")
        staged = _measured_child("job")
        report["main_job"] = {
            "command": "python " + " ".join(MAIN_JOB) + " --out DIR",
            "exit_code": code,
            "peak_rss_mb": peak,
            "wall_s": wall,
            "staged_peak_rss_mb": staged["peak_rss_mb"],
            "imported_rss_mb": staged["imported_rss_mb"],
            "setup_peak_rss_mb": staged["stages"]["build_bennett"]["peak_rss_mb"],
            "run_peak_rss_mb": staged["stages"]["run_linkage"]["peak_rss_mb"],
            "peak_stage_setup": _peak_stage(staged["stages"], SETUP_STAGES),
            "peak_stage_run": _peak_stage(staged["stages"], RUN_STAGES[1:]),
            "stages": staged["stages"],
        }
    report["allocations"] = _measured_child("allocations", str(args.dynamic_end), str(args.static_end))
    write_report(report, args.json, echo=False)
    report["meshes"] = []
    for spec in args.meshes:
        order, h = spec.split(",")
        measured = _measured_child("scene", order, h, str(args.short_run))
        measured["peak_stage"] = _peak_stage(measured["stages"], SETUP_STAGES + RUN_STAGES[1:])
        report["meshes"].append(measured)
        write_report(report, args.json, echo=False)  # an interrupted sweep keeps the meshes measured so far
        print(f"P{order} h = {h}: peak {measured['peak_rss_mb']:.0f} MiB ({measured['peak_stage']})", flush=True)
    report["load_average_end"] = _load()
    write_report(report, args.json)
    return 0


if __name__ == "__main__":
    if sys.argv[1:2] == ["--child"]:
        kind, target = sys.argv[2], Path(sys.argv[3])
        if kind == "job":
            child_main_job(target)
        elif kind == "scene":
            child_scene(target, int(sys.argv[4]), float(sys.argv[5]), float(sys.argv[6]))
        elif kind == "allocations":
            child_allocations(target, float(sys.argv[4]), float(sys.argv[5]))
        raise SystemExit(0)
    raise SystemExit(main())
