"""Will the printed plane_fold_6r snap? The fold of its quasi-static path, the landing, a dynamic run through it,
mesh refinement of the critical drive angle, and the cost of monitoring stability (issue #20).

For each discretisation (``--meshes``, h in mm / element order / fixed-interface modes per link) the PLA
linkage runs quasi-statically up to ``--t-end`` seconds of drive, once without and once with stability
monitoring (Eq. (B1) at every output, and past a fold Eq. (S6): continuation to the landing equilibrium);
the default PLA Bennett scene's revolution (no fold) likewise, for the monitoring's cost alone.
Recorded: the fold's drive angle and driving torque, the other fold, the coupler's jump and the energy
released, and the wall times of both runs (their ratio is the monitoring's cost; the tracing of the fold is part
of it). On the first discretisation a dynamic run (generalized-alpha, ``--step``) drives through the fold: the
drive angle where its coupler point has covered half of the jump from the fold to the landing is where the
dynamic run snaps, to compare with the fold of the quasi-static path.

Usage::

    .venv/bin/python -m bench snap_plane_fold --json out/snap_plane_fold.json

Timings are wall-clock on a shared 2-core machine: compare them only within a run.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

import numpy as np

from bench.report import write_report
from ffrf.errors import StaticDivergence
from ffrf.output.result import Result
from ffrf.scenes.linkage_description import LinkageOptions
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.linkage_scene import build_linkage
from kinematics.rational_mechanism import load_model, loop_from_mechanism, regular_start


def _scene(h_mm: float, order: int, modes: int):
    model = load_model("plane_fold_6r")
    loop = loop_from_mechanism(model, 0.1)
    origin = regular_start(model, loop)
    options = LinkageOptions(h=h_mm * 1e-3, order=order, n_modes=modes, start_angle=float(origin[0]), origin=origin)
    return build_linkage(loop, options)


def _quasi_static(scene, t_end: float, outputs: int, stability: bool):
    started = time.perf_counter()
    try:
        result = run_linkage(scene, "quasi_static", outputs, t_end=t_end, stability=stability)
        stopped = None
    except StaticDivergence as error:
        result, stopped = error.partial, str(error)
    return result, time.perf_counter() - started, stopped


def _dynamic_snap_angle(result, snap: dict, fold: np.ndarray, landing: np.ndarray) -> float | None:
    """The drive angle (deg) where the dynamic coupler point has covered half the fold-to-landing jump."""
    jump = landing - fold
    covered = (result.sensors["coupler_point"] - fold) @ jump / (jump @ jump)
    angles = np.degrees(result.sensors["drive_angle"])
    beyond = np.flatnonzero((covered >= 0.5) & (angles > snap["drive_angle_deg"] - 5.0))
    return float(angles[beyond[0]]) if beyond.size else None


def _kinetic_around(result, t_fold: float) -> dict:
    """The dynamic run's kinetic energy at the fold and its peak in the 3 s after it (J): the snap turns the
    released potential energy into motion, which damping then takes."""
    time_s = result.time
    kinetic = result.sensors["energy_kinetic"]
    after = (time_s >= t_fold) & (time_s <= t_fold + 3.0)
    at_fold = float(np.interp(t_fold, time_s, kinetic))
    peak = float(kinetic[after].max()) if after.any() else None
    return {"kinetic_at_fold_J": at_fold, "peak_kinetic_after_fold_J": peak}


def _bennett_monitoring_cost(outputs: int) -> dict:
    """The default PLA Bennett scene (no fold): a quasi-static revolution without and with stability monitoring."""
    from ffrf.paper.bennett_scene import build_bennett

    scene = build_bennett("pla")
    run_linkage(scene, "quasi_static", 5, t_end=0.5)  # compile and warm the kernels outside the timings
    times = {}
    for stability in (False, True):
        started = time.perf_counter()
        result = run_linkage(scene, "quasi_static", outputs, stability=stability)
        times[stability] = time.perf_counter() - started
    return {
        "outputs": outputs,
        "plain_run_s": times[False],
        "monitored_run_s": times[True],
        "monitoring_cost_ratio": times[True] / times[False],
        "min_squared_frequency": result.metadata["stability"]["min_squared_frequency"],
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshes", default="6/2/4,4/2/4", help="h_mm/order/modes, comma separated")
    parser.add_argument("--t-end", type=float, default=27.0, help="seconds of drive (1 rpm after a 1 s ramp)")
    parser.add_argument("--outputs", type=int, default=109)
    parser.add_argument("--step", type=float, default=4e-3, help="dynamic time step (s)")
    parser.add_argument("--json", type=Path, required=True)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    rows = []
    dynamic = None
    for k, spec in enumerate(args.meshes.split(",")):
        h_mm, order, modes = float(spec.split("/")[0]), int(spec.split("/")[1]), int(spec.split("/")[2])
        started = time.perf_counter()
        scene = _scene(h_mm, order, modes)
        built = time.perf_counter() - started
        plain, plain_time, plain_stop = _quasi_static(scene, args.t_end, args.outputs, False)
        monitored, monitored_time, monitored_stop = _quasi_static(scene, args.t_end, args.outputs, True)
        snaps = monitored.metadata["stability"]["snaps"]
        row = {
            "h_mm": h_mm,
            "order": order,
            "modes_per_link": modes,
            "n_coordinates": scene.system.n_coordinates,
            "build_s": built,
            "plain_run_s": plain_time,
            "plain_stopped": plain_stop,
            "plain_last_drive_angle_deg": float(np.degrees(plain.sensors["drive_angle"][-1])),
            "monitored_run_s": monitored_time,
            "monitored_stopped": monitored_stop,
            "monitoring_cost_ratio": monitored_time / plain_time,
            "min_squared_frequency_before_fold": monitored.metadata["stability"]["min_squared_frequency"],
            "snaps": snaps,
        }
        rows.append(row)
        print(json.dumps({key: value for key, value in row.items() if key != "snaps"}), flush=True)
        print(json.dumps(snaps, indent=1), flush=True)
        if k == 0 and snaps and snaps[0]["landed"]:
            snap = snaps[0]
            t_fold = snap["time_s"]
            after = np.searchsorted(monitored.time, t_fold)
            fold_point = monitored.sensors["coupler_point"][after - 1]
            landing_point = monitored.sensors["coupler_point"][after]
            started = time.perf_counter()
            run: Result | None
            try:
                run = run_linkage(scene, "dynamic", 2000, step=args.step, t_end=args.t_end)
                stopped = None
            except Exception as error:  # noqa: BLE001 - a stopped dynamic run is a result here
                run, stopped = getattr(error, "partial", None), str(error)
            angle = None if run is None else _dynamic_snap_angle(run, snap, fold_point, landing_point)
            kinetic = {} if run is None else _kinetic_around(run, t_fold)
            dynamic = {
                **kinetic,
                "energy_released_by_continuation_J": snap["energy_released_J"],
                "step_s": args.step,
                "run_s": time.perf_counter() - started,
                "stopped": stopped,
                "snap_drive_angle_deg": angle,
                "fold_drive_angle_deg": snap["drive_angle_deg"],
                "difference_deg": None if angle is None else angle - snap["drive_angle_deg"],
                "criterion": "half of the coupler's jump from the last output before the fold to the first after",
            }
            print(json.dumps(dynamic), flush=True)
    folds = [r["snaps"][0]["drive_angle_deg"] for r in rows if r["snaps"]]
    bennett = _bennett_monitoring_cost(args.outputs)
    print(json.dumps(bennett), flush=True)
    report = {
        "linkage": "plane_fold_6r, PLA, scale 0.1, 1 rpm",
        "bennett_pla_revolution": bennett,
        "meshes": rows,
        "dynamic": dynamic,
        "fold_change_between_meshes_deg": float(np.ptp(folds)) if len(folds) > 1 else None,
    }
    write_report(report, args.json, echo=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
