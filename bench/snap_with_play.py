"""Does joint play change where a 6R snaps? ``plane_fold_6r`` (PLA, scale 0.1) run quasi-statically with stability
monitoring, once with ideal joints and once with radial play in its five passive joints (``docs/formulation.md``,
"Joints with play"): the folds of its path (drive angle, released energy, coupler jump), the pins' largest
eccentricity, whether each run verified itself, and the wall times.

Usage::

    .venv/bin/python -m bench snap_with_play --json out/snap_with_play.json
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from bench.report import write_report


def _scene(play_mm: float, h_mm: float, order: int, modes: int):
    """The scene of ``bench/snap_plane_fold.py`` with ``play_mm`` of radial play (pins as long as the housings)."""
    from ffrf.scenes.linkage_description import LinkageOptions
    from ffrf.scenes.linkage_scene import build_linkage
    from kinematics.rational_mechanism import load_model, loop_from_mechanism, regular_start

    model = load_model("plane_fold_6r")
    loop = loop_from_mechanism(model, 0.1)
    origin = regular_start(model, loop)
    options = LinkageOptions(h=h_mm * 1e-3, order=order, n_modes=modes, start_angle=float(origin[0]), origin=origin)
    if play_mm > 0.0:
        play = {"radial_mm": play_mm, "pin_length_mm": 1e3 * options.design.housing_length}
        options = replace(options, joint_play=play)
    return build_linkage(loop, options)


def run(play_mm: float, h_mm: float, order: int, modes: int, t_end: float, outputs: int) -> dict:
    """One quasi-static run with stability monitoring; ``play_mm`` 0: ideal joints."""
    from ffrf.errors import StaticDivergence
    from ffrf.scenes.linkage_run import run_linkage

    scene = _scene(play_mm, h_mm, order, modes)
    started = time.perf_counter()
    try:
        result, stopped = run_linkage(scene, "quasi_static", outputs, t_end=t_end, stability=True), None
    except StaticDivergence as error:
        if error.partial is None:
            raise
        result, stopped = error.partial, str(error)
    wall = time.perf_counter() - started
    snaps = result.metadata.get("stability", {}).get("snaps", [])
    loose = [j.name for j in scene.loose_joints]
    eccentricity = max((float(np.max(result.sensors[f"{name}_eccentricity"])) for name in loose), default=0.0)
    return {
        "radial_play_mm": play_mm,
        "snaps": [
            {
                "drive_angle_deg": snap["drive_angle_deg"],
                "time_s": snap["time_s"],
                "energy_released_mJ": 1e3 * snap["energy_released_J"],
                "coupler_jump_mm": 1e3 * snap["coupler_jump_m"],
            }
            for snap in snaps
        ],
        "max_pin_eccentricity_mm": 1e3 * eccentricity,
        "last_drive_angle_deg": float(np.degrees(result.sensors["drive_angle"][-1])),
        "verified": None if result.verification is None else bool(result.verification.verified),
        "stopped": stopped,
        "run_s": wall,
    }


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--play", type=float, default=0.1, help="radial play of the passive joints (mm)")
    parser.add_argument("--h", type=float, default=6.0, help="tetrahedron edge (mm)")
    parser.add_argument("--order", type=int, default=2)
    parser.add_argument("--modes", type=int, default=4)
    parser.add_argument("--t-end", type=float, default=30.0, help="seconds of drive (the ramp is 1 s, then 1 rpm)")
    parser.add_argument("--outputs", type=int, default=61)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)
    rows = {}
    for name, play in (("ideal", 0.0), ("play", args.play)):
        rows[name] = run(play, args.h, args.order, args.modes, args.t_end, args.outputs)
        r = rows[name]
        folds = ", ".join(f"{s['drive_angle_deg']:.2f} deg ({s['energy_released_mJ']:.3g} mJ)" for s in r["snaps"])
        print(f"{name}: folds at {folds or 'none'}; verified {r['verified']}; {r['run_s']:.0f} s", flush=True)
    report = {"h_mm": args.h, "order": args.order, "modes": args.modes, "t_end_s": args.t_end, **rows}
    if args.json:
        write_report(report, args.json, echo=False)
    return report


if __name__ == "__main__":
    main()
