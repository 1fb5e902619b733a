"""``python -m ffrf export [LINKAGE] --out DIR``: a linkage's links as parts to print (STEP and STL in mm, an assembly
STEP, a print sheet) and a scene file that runs the printed parts (:func:`ffrf.scenes.linkage_export.export_linkage`).

LINKAGE: ``bennett`` (the paper's PLA Bennett, the default), a model of Rational Linkages (as ``python -m ffrf
linkage --model``, at ``--scale``) or a linkage file (TOML with a ``[linkage]`` table)."""

from __future__ import annotations

import argparse
import math
import tomllib
from pathlib import Path

from ffrf.cli.arguments import number_in
from ffrf.errors import SceneError
from ffrf.geometry.link_cad import MM
from ffrf.paper.bennett_scene import bennett_description
from ffrf.scenes.linkage_description import linkage_description
from ffrf.scenes.linkage_export import PRINTED_SCENE, export_linkage
from ffrf.scenes.linkage_file import linkage_options
from kinematics.rational_mechanism import MODELS

__all__ = ["HELP", "configure", "run"]

HELP = "write a linkage's links as STEP and STL (mm) with an assembly, a print sheet and a scene of the printed parts"


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "linkage",
        nargs="?",
        default="bennett",
        help=f"'bennett' (the paper's PLA Bennett, default), a Rational Linkages model ({', '.join(MODELS)}) or a "
        "linkage file (TOML with [linkage])",
    )
    parser.add_argument(
        "--scale",
        type=number_in(0.0, math.inf, closed_low=False),
        default=0.1,
        help="length scale of a Rational Linkages model (its unit -> metres)",
    )
    parser.add_argument(
        "--pin-diameter",
        type=number_in(0.0, math.inf, closed_low=False, unit=" mm"),
        metavar="MM",
        help="diameter of the pins the bores are made for (mm; with --radial-clearance); default: the design's bore",
    )
    parser.add_argument(
        "--radial-clearance",
        type=float,
        metavar="MM",
        help="radial clearance between pin and bore (mm): bore radius = pin / 2 + clearance",
    )
    parser.add_argument(
        "--stl-tolerance",
        type=number_in(0.0, math.inf, closed_low=False, unit=" mm"),
        default=0.05,
        metavar="MM",
        help="largest distance of an STL facet from the exact surface (mm, default 0.05: for the printer); the solver "
        "meshes the printed parts as finely as their facets, 0.6 to simulate them",
    )
    parser.add_argument("--out", type=Path, required=True, help="output directory (STEP, STL, print sheet, scene)")


def _description(linkage: str, scale: float) -> dict:
    """The scene description of LINKAGE (module docstring)."""
    if linkage == "bennett":
        return bennett_description("pla")
    if linkage in MODELS:
        document = {"linkage": {"model": linkage, "scale": scale}}
        where = f"python -m ffrf export {linkage}"
    else:
        path = Path(linkage)
        try:
            document = tomllib.loads(path.read_text(encoding="utf-8-sig"))
        except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
            raise SceneError(
                f"{linkage}: neither 'bennett', a model ({', '.join(MODELS)}) nor a readable linkage file ({error})"
            ) from error
        if "linkage" not in document:
            raise SceneError(f"{linkage}: not a linkage file (no [linkage] table); give a linkage file or a model")
        where = path.name
    loop, options, _ = linkage_options(document, where)
    return linkage_description(loop, options)


def run(args: argparse.Namespace) -> int:
    if (args.pin_diameter is None) != (args.radial_clearance is None):
        raise SceneError("give --pin-diameter and --radial-clearance together (bore radius = pin / 2 + clearance)")
    description = _description(args.linkage, args.scale)
    sheet = export_linkage(  # checks the bores and the tolerance before it creates --out
        description,
        args.out,
        pin_diameter=None if args.pin_diameter is None else args.pin_diameter * MM,
        radial_clearance=None if args.radial_clearance is None else args.radial_clearance * MM,
        tolerance=args.stl_tolerance * MM,
    )
    print(sheet.markdown(), end="")
    print(f"-> {args.out}: link*.step, link*.stl, assembly.step, print_sheet.json, print_sheet.md, {PRINTED_SCENE}")
    return 0
