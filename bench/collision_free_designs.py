"""Collision-free links of a mechanism of Rational Linkages: our stacking design against its own design (issue #34).

Rational Linkages (``CollisionFreeOptimization``, after Li et al. 2020) designs a mechanism collision-free on its
line model: every link a segment between two connection points on its joint axes, every joint a segment between its
two links' points, no two segments crossing along the motion (``RationalMechanism.collision_check``, exact, by the
roots of polynomials in the motion's parameter). The models it ships carry such a design (``collisions_free_6r``
was made so). The printed parts have thickness; ours are the parametric links of
``ffrf.geometry.link_geometry.build_link`` (default ``LinkDesign``: 16 mm housings, 16 x 12 mm arms). For each case
(a model and the scale its unit lengths are multiplied by) three sets of those links, the same section each:

* ``joint_points``: both housings of a joint about its joint point (no design);
* ``rational_linkages``: housings centred on the model's own connection points (``design_points = true``);
* ``ours``: the stacking of ``ffrf.scenes.collision_free.design_stacking``, margin 1 mm, as ``collision_free = true``
  designs it (links with the axial gap of ``designed_axial_gap``, 1.5 mm; the model's own design one more start),
  or its refusal (the closest pair, drive angle and clearance reached).

Per set: the signed clearance of the meshed link solids along one revolution of the driver, bounded between the
poses (``LinkageScene.clearance``, Eqs. (CL1)-(CL4) of ``docs/formulation.md``): per pair the smallest (negative: the
depth by which they overlap), and whether every pair keeps the margin; the links' mass (PLA) and the length of
their centre lines (housing centre to housing centre, summed over the links: the length Rational Linkages' smallest
polyline minimises); the design's time. With ``--design MODEL...`` ours runs on those models only. With
``--rl-check`` also the time of Rational Linkages' own check of its shipped design; with ``--rl-search MODEL...``
its own design from scratch (``CollisionFreeOptimization.optimize("combinatorial_search")`` from the smallest
polyline, default step, 10 shift sizes, each joint segment as long as our two housings at a joint, centre to
centre): its time, the candidates it checked, and our links on the points it found.

Usage::

    .venv/bin/python -m bench collision_free_designs --json out/collision_free.json [--cases collisions_free_6r:0.25]
        [--rl-check] [--rl-search bennett_ark24] [--design bennett_ark24]

Timings are wall-clock on a shared 2-core machine: compare them only within a run.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from bench.report import write_report
from ffrf.errors import GeometryError, SceneError
from ffrf.geometry.link_geometry import LinkDesign
from ffrf.scenes.collision_free import Stacking, design_stacking, designed_axial_gap
from ffrf.scenes.linkage_description import start_pose
from ffrf.scenes.linkage_file import linkage_options
from ffrf.scenes.linkage_scene import LinkageScene, build_linkage
from kinematics.rational_mechanism import attach_points, load_model

#: (model, scale) compared by default: the models that ship a design (``plane_fold_6r`` and ``interp_4poses_6r`` put
#: both points of a joint at one place); the Bennett at about the paper's size (links 121 and 209 mm against 110 and
#: 220 mm), the 6R where its design's two points at a joint lie a housing apart (18 mm) and at twice that size.
CASES = ("bennett_ark24:0.5", "collisions_free_6r:0.25", "collisions_free_6r:0.5")
MARGIN = 1e-3


def _centre_line_length(attach: np.ndarray) -> float:
    """Sum over the links of the distance between their two housing centres (link k: joint k-1's second point,
    joint k's first; ``attach`` ``(n, 2, 3)`` as ``LinkageOptions.attach_points``)."""
    n = len(attach)
    return float(sum(np.linalg.norm(attach[k, 0] - attach[k - 1, 1]) for k in range(n)))


def _clearance_row(scene: LinkageScene, poses: int) -> dict:
    """The set of links' signed clearance along a revolution, its mass and its centre lines."""
    started = time.perf_counter()
    clearance = scene.clearance(poses, MARGIN)
    pairs: list[dict] = [
        {
            "pair": [int(a), int(b)],
            "smallest_m": float(gap),
            "drive_angle_deg": float(np.degrees(angle)),
            "bound_m": float(bound),
        }
        for (a, b), gap, angle, bound in zip(
            clearance.pairs, clearance.distance, clearance.drive_angle, clearance.bound, strict=True
        )
    ]
    closest = pairs[int(np.argmin(clearance.distance))]
    return {
        "margin_met": clearance.margin_met,
        "smallest_m": closest["smallest_m"],
        "closest_pair": closest["pair"],
        "closest_at_deg": closest["drive_angle_deg"],
        "pairs_missing_margin": int(np.sum(clearance.distance < MARGIN)),
        "pairs": pairs,
        "mass_g": 1e3 * float(sum(body.mesh_model.total_mass for body in scene.bodies)),
        "clearance_s": time.perf_counter() - started,
        "summary": clearance.summary(),
    }


def _linkage(model: str, scale: float, h: float, extra: dict, attach: np.ndarray | None = None) -> LinkageScene:
    """The linkage of a linkage file's ``[linkage]`` table (``extra`` added), its links attached at ``attach`` if
    given (``LinkageOptions.attach_points``)."""
    document = {"linkage": {"model": model, "scale": scale, "h": h, "order": 2, "modes": 1, **extra}}
    loop, options, _ = linkage_options(document)
    if attach is not None:
        options = replace(options, attach_points=attach)
    return build_linkage(loop, options)


def _rl_search(model: str, scale: float, h: float, poses: int, design: LinkDesign) -> dict:
    """Rational Linkages' combinatorial search from its smallest polyline, its joint segments as long as our two
    housings at a joint (centre to centre, ``2 s``), and the links built on the points it finds."""
    from rational_linkages import CollisionFreeOptimization

    mechanism = load_model(model)
    printed = io.StringIO()
    started = time.perf_counter()
    with contextlib.redirect_stdout(printed):  # it prints every candidate
        found = CollisionFreeOptimization(mechanism).optimize(
            "combinatorial_search",
            step_length=10.0,
            min_joint_segment_length=2.0 * design.housing_offset / scale,
            max_iters=10,
        )
    row: dict = {"seconds": time.perf_counter() - started, "candidates": printed.getvalue().count("--- ")}
    if found is None:
        return dict(row, found=False)
    points = attach_points(mechanism, scale)
    try:
        built = _linkage(model, scale, h, {}, points)
    except (SceneError, GeometryError) as error:
        return dict(row, found=True, not_built=str(error), centre_lines_m=_centre_line_length(points))
    return dict(row, found=True, **_clearance_row(built, poses), centre_lines_m=_centre_line_length(points))


def compare_case(
    model: str, scale: float, h: float, poses: int, rl_check: bool, rl_search: bool, run_ours: bool
) -> dict:
    """The three sets of links of one case (module docstring)."""
    row: dict = {"model": model, "scale": scale}
    base = {"linkage": {"model": model, "scale": scale}}
    loop, options, _ = linkage_options(base)
    design = LinkDesign()
    started = time.perf_counter()
    row["joint_points"] = _clearance_row(_linkage(model, scale, h, {}), poses)
    row["joint_points"]["centre_lines_m"] = _centre_line_length(Stacking.nominal(loop.n).attach_points(loop, design))
    row["joint_points"]["build_s"] = time.perf_counter() - started
    try:
        row["rational_linkages"] = _clearance_row(_linkage(model, scale, h, {"design_points": True}), poses)
    except (SceneError, GeometryError) as error:  # e.g. points closer than two housings: no links to build
        row["rational_linkages"] = {"not_built": str(error)}
    row["rational_linkages"]["centre_lines_m"] = _centre_line_length(attach_points(load_model(model), scale))
    if rl_check:
        started = time.perf_counter()
        collisions = load_model(model).collision_check(only_links=False, pretty_print=False)
        row["rational_linkages"]["own_check"] = {
            "collision_free": collisions is None,
            "seconds": time.perf_counter() - started,
        }
    if rl_search:
        row["rational_linkages_search"] = _rl_search(model, scale, h, poses, design)
    if not run_ours:
        return row
    phi = start_pose(loop, options.driver, options.start_angle, options.origin)
    # as a linkage file's collision_free = true designs: the widened gap, the model's own design one more start
    design = LinkDesign(axial_gap=designed_axial_gap(MARGIN))
    starts = Stacking.starts_from_design(loop, attach_points(load_model(model), scale), design)
    started = time.perf_counter()
    try:
        designed = design_stacking(loop, options.driver, phi, design, MARGIN, starts=starts)
    except GeometryError as error:
        row["ours"] = {"refused": str(error), "design_s": time.perf_counter() - started}
        return row
    design_s = time.perf_counter() - started
    stacking = designed.stacking
    table = {"offsets": list(stacking.offsets), "spacers": list(stacking.spacers)}
    if stacking.orders is not None:
        table["orders"] = list(stacking.orders)
    ours = _linkage(model, scale, h, {"stacking": table, "link_design": {"axial_gap": design.axial_gap}})
    row["ours"] = _clearance_row(ours, poses)
    row["ours"].update(
        design_s=design_s,
        proxy_smallest_m=float(designed.clearance.smallest[0]),
        spacers_m=float(sum(stacking.spacers)),
        largest_offset_m=float(max(abs(v) for v in stacking.offsets)),
        centre_lines_m=_centre_line_length(stacking.attach_points(loop, design)),
    )
    return row


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", default=list(CASES), help="MODEL:SCALE, a model of rational_linkages")
    parser.add_argument("--h", type=float, default=6e-3, help="tetrahedron edge of the link solids (m)")
    parser.add_argument("--poses", type=int, default=72, help="poses per revolution before bisection (Eq. (CL4))")
    parser.add_argument("--rl-check", action="store_true", help="also time Rational Linkages' own check")
    parser.add_argument(
        "--rl-search", nargs="*", default=[], metavar="MODEL", help="also run Rational Linkages' design on these models"
    )
    parser.add_argument(
        "--design", nargs="*", metavar="MODEL", help="run our design on these models only (default: every case)"
    )
    parser.add_argument("--json", type=Path, required=True)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    rows = []
    for case in args.cases:
        model, scale = case.split(":")
        print(f"== {model} at scale {scale}", flush=True)
        search = model in args.rl_search
        run_ours = args.design is None or model in args.design
        rows.append(compare_case(model, float(scale), args.h, args.poses, args.rl_check, search, run_ours))
    report = {
        "margin_m": MARGIN,
        "h_m": args.h,
        "order": 2,
        "poses": args.poses,
        "cases": rows,
    }
    write_report(report, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
