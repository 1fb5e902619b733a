"""``python -m ffrf compensate LINKAGE.toml --out DIR``: bore corrections to print so that the loaded print follows
the ideal path (:func:`ffrf.scenes.compensation.compensate`, Eq. (D4)), then the corrected print run and verified.

Writes ``compensation.json`` (the corrections in degrees and the file's unit, the largest deviation before and as
the first order predicts it after), ``compensated.toml`` (the linkage file with the corrections added to its bore
errors: the parts to print) and, in ``check/``, the compensated linkage run as ``python -m ffrf run`` does, its
links remeshed on the corrected bores; the exit status is that run's. With ``--drive``, also the drive's correction
along the motion of the compensated print (:func:`ffrf.scenes.drive_correction.correct_drive`, where the task is a
path): ``drive.json`` (the largest deviation before and after, each corrected angle solved for the print's
equilibrium) and ``drive_angles.csv`` (per pose the nominal and corrected drive angle, deg, and the deviation before
and after, mm).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

from ffrf.cli.arguments import count_at_least, output_folder
from ffrf.cli.report import run_and_report
from ffrf.errors import SceneError
from ffrf.model import load
from ffrf.scenes.compensation import MAX_SHIFT, MAX_TWIST, Compensation, compensate
from ffrf.scenes.drive_correction import correct_drive
from ffrf.scenes.linkage_file import linkage_options
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.linkage_scene import build_linkage
from ffrf.scenes.scene_toml import scene_toml

__all__ = ["HELP", "configure", "run"]

HELP = "bore corrections that bring a loaded print onto its ideal path (a linkage file), checked by a run"


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("linkage", type=Path, help="linkage file (TOML)")
    parser.add_argument("--out", type=Path, required=True, help="output directory")
    parser.add_argument(
        "--outputs", type=count_at_least(3), default=121, help="poses of the path the corrections fit (default 121)"
    )
    parser.add_argument(
        "--max-twist-deg",
        type=float,
        default=math.degrees(MAX_TWIST),
        help=f"largest twist correction of a bore (default {math.degrees(MAX_TWIST):g} deg)",
    )
    parser.add_argument(
        "--max-shift-mm",
        type=float,
        default=1e3 * MAX_SHIFT,
        help=f"largest offset or axial correction of a bore (default {1e3 * MAX_SHIFT:g} mm)",
    )
    parser.add_argument(
        "--drive",
        action="store_true",
        help="also correct the drive's angle along the motion of the compensated print (a path task, not a timing)",
    )


def run(args: argparse.Namespace) -> int:
    if not args.linkage.is_file():
        raise SceneError(f"linkage file {args.linkage} not found")
    for name, value in (("--max-twist-deg", args.max_twist_deg), ("--max-shift-mm", args.max_shift_mm)):
        if not value > 0.0:
            raise SceneError(f"{name} must be > 0, got {value!r}")
    document = tomllib.loads(args.linkage.read_text())
    loop, options, _ = linkage_options(document, str(args.linkage))
    measured = [e for e in document["linkage"].get("bore_errors", []) if "point" in e]
    if measured:
        raise SceneError(
            f"{args.linkage}: a bore given by its line (point, direction) takes no correction; give its twist_deg, "
            "offset and axial instead"
        )
    out = output_folder(args.out)
    print(f"Compensating {options.name} over {args.outputs} poses", file=sys.stderr)
    started = time.perf_counter()
    found = compensate(loop, options, args.outputs, math.radians(args.max_twist_deg), 1e-3 * args.max_shift_mm)
    length = 1e-3 if document["linkage"].get("unit") == "mm" else 1.0
    (out / "compensation.json").write_text(json.dumps(_summary(found, length, args), indent=2) + "\n")
    compensated = out / "compensated.toml"
    compensated.write_text(scene_toml(_compensated(document, found, length)))
    print(
        f"{options.name}: largest deviation {1e3 * found.before_m:.4f} mm, to first order "
        f"{1e3 * found.predicted_m:.4f} mm with {len(found.corrections)} bores corrected "
        f"({time.perf_counter() - started:.1f} s) -> {compensated}",
        file=sys.stderr,
    )
    model = load(compensated)
    status = run_and_report(model, out / "check", model.name, time.perf_counter(), model.settings() | {"vtk_every": 0})
    if args.drive:
        _drive(compensated, out, args.outputs)
    return status


def _drive(compensated: Path, out: Path, outputs: int) -> None:
    """The drive's correction of the compensated print (its links as printed), written to ``out``."""
    loop, options, _ = linkage_options(tomllib.loads(compensated.read_text()), str(compensated))
    scene = build_linkage(loop, options)
    result = run_linkage(scene, mode="quasi_static", n_outputs=outputs, sensors="path")
    assert result.multipliers is not None  # a quasi-static run keeps its equilibria's multipliers
    found = correct_drive(scene, result.time, result.q, result.multipliers)
    before, after = (1e3 * np.linalg.norm(d, axis=1) for d in (found.before, found.after))
    summary = {
        "outputs": outputs,
        "before_mm": float(before.max()),
        "after_mm": float(after.max()),
        "max_distance_to_path_mm": float(1e3 * result.sensors["coupler_distance_to_path"].max()),
        "max_correction_deg": float(np.degrees(np.abs(found.corrected_angle - found.drive_angle)).max()),
        "clipped_poses": found.clipped,
        "seconds": found.seconds,
    }
    (out / "drive.json").write_text(json.dumps(summary, indent=2) + "\n")
    rows = np.column_stack([np.degrees(found.drive_angle), np.degrees(found.corrected_angle), before, after])
    header = "drive_angle_deg,corrected_drive_angle_deg,deviation_before_mm,deviation_after_mm"
    np.savetxt(out / "drive_angles.csv", rows, delimiter=",", header=header, comments="", fmt="%.9g")
    print(
        f"drive corrected along the motion: largest deviation {summary['before_mm']:.4f} -> "
        f"{summary['after_mm']:.4f} mm (corrections up to {summary['max_correction_deg']:.3g} deg) -> "
        f"{out / 'drive_angles.csv'}",
        file=sys.stderr,
    )


def _compensated(document: dict, found: Compensation, length: float) -> dict:
    """The linkage file with the corrections added to its bore errors, bore by bore, in its unit."""
    entries = {(e["joint"], e["link"]): dict(e) for e in document["linkage"].get("bore_errors", [])}
    for c in found.corrections:
        entry = entries.setdefault((c.joint, c.link), {"joint": c.joint, "link": c.link})
        entry["twist_deg"] = entry.get("twist_deg", 0.0) + math.degrees(c.twist)
        entry["offset"] = entry.get("offset", 0.0) + c.offset / length
        entry["axial"] = entry.get("axial", 0.0) + c.axial / length
    linkage = dict(document["linkage"], bore_errors=list(entries.values()))
    if "name" in linkage:
        linkage["name"] = f"{linkage['name']}, compensated"
    return dict(document, linkage=linkage)


def _summary(found: Compensation, length: float, args: argparse.Namespace) -> dict:
    unit = "mm" if length == 1e-3 else "m"
    return {
        "outputs": args.outputs,
        "max_twist_deg": args.max_twist_deg,
        "max_shift_mm": args.max_shift_mm,
        "before_mm": 1e3 * found.before_m,
        "predicted_mm": 1e3 * found.predicted_m,
        "unit": unit,
        "corrections": [
            {
                "joint": c.joint,
                "link": c.link,
                "twist_deg": math.degrees(c.twist),
                f"offset_{unit}": c.offset / length,
                f"axial_{unit}": c.axial / length,
            }
            for c in found.corrections
        ],
        "seconds": found.seconds,
    }
