"""``python -m ffrf linkage``: a flexible single-loop linkage of Rational Linkages (4R, 6R), built from the options
as the linkage file they stand for (``DIR/linkage.json``), run and reported as every linkage
(:func:`ffrf.cli.report.run_and_report`); with ``--reach`` the energy barriers to the rigid loop's isolated
assemblies (``reach.json``)."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from ffrf.cli.arguments import (
    check_run_length,
    configure_linkage_run,
    count_at_least,
    number_in,
    output_folder,
    run_options,
)
from ffrf.cli.report import run_and_report
from ffrf.errors import SceneError
from ffrf.fe.materials import PLA_TENSILE_STRENGTH
from ffrf.model import load
from ffrf.output.result import Result
from ffrf.scenes.linkage_description import LINKAGE_VARIANTS
from ffrf.scenes.linkage_file import linkage_options, load_linkage
from ffrf.scenes.linkage_reach import ReachOptions, drive_work, isolated_assemblies, reach_isolated
from ffrf.scenes.linkage_scene import LinkageScene
from kinematics.rational_mechanism import MODELS

__all__ = ["HELP", "configure", "run"]

HELP = "simulate a flexible single-loop linkage of Rational Linkages (4R, 6R) and write its sensors"


def _bore_error(text: str) -> dict:
    """``JOINT:LINK:TWIST_DEG[:OFFSET_MM]`` -> a linkage file's bore error (offset in m)."""
    parts = text.split(":")
    try:
        if len(parts) not in (3, 4):
            raise ValueError
        error = {"joint": int(parts[0]), "link": int(parts[1]), "twist_deg": float(parts[2])}
        return error | ({"offset": float(parts[3]) * 1e-3} if len(parts) == 4 else {})
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"bore error {text!r}: write JOINT:LINK:TWIST_DEG or JOINT:LINK:TWIST_DEG:OFFSET_MM, e.g. 3:0:1.0"
        ) from None


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--model", choices=MODELS, required=True, help="a mechanism of rational_linkages.models")

    parser.add_argument("--variant", choices=tuple(LINKAGE_VARIANTS), default="pla", help="link material")
    parser.add_argument(
        "--scale",
        type=number_in(0.0, math.inf, closed_low=False),
        default=0.1,
        help="length scale of the model (its unit -> metres)",
    )
    parser.add_argument("--driver", type=count_at_least(0), default=0, help="driven joint")
    placement = parser.add_mutually_exclusive_group()
    placement.add_argument(
        "--design-points",
        action="store_true",
        help="attach the links where the model's design attaches them (its collision-free connection points)",
    )
    placement.add_argument(
        "--collision-free",
        action="store_true",
        help="place the housings along the axes so that every two links keep --clearance-margin along a revolution "
        "of the driver (docs/formulation.md, (CF5); a minute or more on a 6R)",
    )
    parser.add_argument(
        "--bore-error",
        type=_bore_error,
        action="append",
        default=[],
        metavar="JOINT:LINK:TWIST_DEG[:OFFSET_MM]",
        help="as built: joint JOINT's bore on link LINK turned about the link's common normal (repeatable)",
    )
    parser.add_argument(
        "--reach",
        action="store_true",
        help="after the run: the energy barrier from the motion to each isolated assembly of the rigid loop, by the "
        "string method (docs/stability.md; minutes per assembly); writes reach.json",
    )
    parser.add_argument(
        "--reach-images",
        type=count_at_least(3),
        default=21,
        help="images of the string between the motion and an assembly, both ends included (default 21)",
    )
    configure_linkage_run(parser)


def run(args: argparse.Namespace) -> int:
    started = time.perf_counter()
    if args.reach and args.bore_error:
        raise SceneError(
            "--reach measures the nominal linkage (the isolated assemblies are the nominal loop's): drop --bore-error"
        )
    if args.reach and args.variant == "rigid":
        raise SceneError("--reach measures strain energy, which rigid links do not store: use --variant pla")
    check_run_length(args)
    material = LINKAGE_VARIANTS[args.variant]
    document = {  # the linkage file these options stand for (ffrf.scenes.linkage_file)
        "linkage": {
            "name": f"{args.model} {args.variant}",
            "model": args.model,
            "scale": args.scale,
            "driver": args.driver,
            "material": {"E": material.E, "nu": material.nu, "rho": material.rho, "name": material.name}
            | ({} if material.strength is None else {"strength": material.strength}),
            "h": args.h,
            "order": args.order,
            "modes": args.modes,
            "bore_errors": args.bore_error,
            "design_points": args.design_points,
        }
        | ({"collision_free": True} if args.collision_free else {})
        | ({} if args.clearance_margin is None else {"clearance_margin": 1e-3 * args.clearance_margin}),
        "scene": {"joint_offsets": args.joint_offsets},
    }
    linkage_options(document, where="python -m ffrf linkage")  # the file's checks (bore errors ...) before --out
    output_folder(args.out)
    print(
        f"Building {args.model} ({args.variant}, scale {args.scale:g}): h = {1e3 * args.h:g} mm, P{args.order}, "
        f"{args.modes} fixed-interface modes per link ...",
        file=sys.stderr,
    )
    scene = load_linkage(document, where="python -m ffrf linkage")
    (args.out / "linkage.json").write_text(json.dumps(document, indent=2))
    then = (lambda result: _write_reach(scene, result, args.out, args.reach_images)) if args.reach else None
    return run_and_report(load(scene), args.out, f"{args.model} {args.variant}", started, run_options(args), then=then)


def _write_reach(scene: LinkageScene, result: Result, out: Path, images: int) -> None:
    """``reach.json``: per isolated assembly of the nominal loop, the energy barrier from the motion
    (:func:`ffrf.scenes.linkage_reach.reach_isolated`) against the drive's work of ``result`` and PLA's strength."""
    started = time.perf_counter()
    assert result.assembly is not None  # a linkage's run always records the assembled state
    work = drive_work(result.sensors["driving_torque"], result.sensors["drive_angle"])
    nearby = isolated_assemblies(scene)
    print(
        f"reach: {len(nearby.isolated)} isolated assemblies of the rigid loop near its motion; the string method "
        f"({images} images) to each ...",
        file=sys.stderr,
    )

    def show(iteration: int, residual: float) -> None:
        if iteration % 100 == 0:
            print(f"\r  iteration {iteration}, residual {residual:.2e} N m", end="", file=sys.stderr, flush=True)

    reaches = reach_isolated(
        scene,
        result.assembly.q,
        nearby.isolated,
        work["work_J"],
        PLA_TENSILE_STRENGTH,
        ReachOptions(images=images),
        show,
    )
    print(file=sys.stderr)
    table = {
        "model": scene.name,
        "drive": {**work, "compared_with": "work_J: the drive's work over the run's last revolution where it drives"},
        "strength_pa": PLA_TENSILE_STRENGTH,
        "strength_source": "PLA at break, NatureWorks Ingeo 4043D data sheet (ffrf.fe.materials.PLA_TENSILE_STRENGTH)",
        "nearby": {
            "starts": nearby.starts,
            "converged": nearby.converged,
            "on_motion": nearby.on_motion,
            "isolated": len(nearby.isolated),
        },
        "assemblies": [r.as_dict() for r in reaches],
        "seconds": time.perf_counter() - started,
    }
    (out / "reach.json").write_text(json.dumps(table, indent=1))
    for k, r in enumerate(reaches):
        print(
            f"reach of isolated assembly {k} ({np.degrees(r.assembly.distance_rms):.3g} deg RMS from the motion): "
            f"barrier {1e3 * r.barrier:.4g} mJ (straight path {1e3 * r.straight_barrier:.4g} mJ), "
            f"{r.work_ratio:.3g} of the drive's work over a revolution, {1e3 * work['work_J']:.4g} mJ: {r.verdict}; "
            f"largest von Mises stress on the way {1e-6 * r.peak_stress:.3g} MPa, {r.stress_ratio:.3g} of PLA's "
            f"strength" + ("" if r.path.converged else f" (string not converged: residual {r.path.residual:.2e} N m)")
        )
    print(f"-> {out / 'reach.json'}")
