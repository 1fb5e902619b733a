"""Command line interface: ``python -m ffrf <subcommand> ...``.

Subcommands register themselves in :data:`SUBCOMMANDS` (name -> (configure, run)),
so others can add theirs without touching the existing ones.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import sys
from collections.abc import Callable, Sequence
from pathlib import Path


from .errors import FEInputError
from .fe_model import FEModel
from .interfaces import interface_from_group
from .link_geometry import PAPER_AXES, Axis, LinkDesign, mesh_link, paper_link_axes
from .materials import PLA
from .mesh import quality_summary, write_vtu

__all__ = ["main", "SUBCOMMANDS", "bennett_axes", "link_summary"]

logger = logging.getLogger(__name__)

#: The paper's Denavit-Hartenberg lengths (m) and twists (deg) of the Bennett linkage.
PAPER_A = (0.11, 0.22, 0.11, 0.22)
PAPER_ALPHA_DEG = (150.0, 90.0, 150.0, 90.0)


def bennett_axes(alpha3_deg: float = 90.0) -> tuple:
    """Joint axes h0..h3 of the paper's linkage with base-link twist ``alpha3_deg``.

    The base link (link 0) carries (h3, h0). With alpha_3 != 90 deg the loop
    does not close, so its h3 is the axis where the *base link* wants it:
    ``kinematics.open_loop_axes`` returns h0..h3 chained through links 0..2
    (nominal) and that closing axis, which replaces h3 here. Without the
    kinematics package only the nominal linkage (alpha_3 = 90 deg) is known.
    """
    try:
        from kinematics.dh import open_loop_axes  # written in parallel by the kinematics package
    except ImportError:
        open_loop_axes = None
    if open_loop_axes is not None:
        alpha = [math.radians(a) for a in PAPER_ALPHA_DEG[:3]] + [math.radians(alpha3_deg)]
        axes, closing_axis = open_loop_axes(list(PAPER_A), alpha)
        return tuple(Axis.of(a) for a in axes[:3]) + (Axis.of(closing_axis),)
    if not math.isclose(alpha3_deg, 90.0):
        raise FEInputError(f"--alpha3-deg {alpha3_deg}: misaligned axes need kinematics.dh.open_loop_axes, which "
                           "is not importable; run from the project root with the kinematics package, "
                           "or use the nominal 90 deg")
    return PAPER_AXES


def link_summary(model: FEModel, geometry, interfaces) -> dict:
    """JSON-ready summary of a meshed link."""
    return {
        "order": model.order,
        "n_vertices": model.n_vertices,
        "n_nodes": len(model.nodes),
        "n_tetrahedra": len(model.mesh.tets),
        "n_dofs": model.n_dofs,
        "quality": quality_summary(model.mesh).as_dict(),
        "material": {"name": model.material.name, "E": model.material.E, "nu": model.material.nu,
                     "rho": model.material.rho},
        "volume_m3": model.mesh.volume,
        "mass_kg": model.total_mass,
        "center_of_mass_m": model.center_of_mass.tolist(),
        "inertia_tensor_kgm2": model.inertia_tensor.tolist(),
        "link_length_m": geometry.length,
        "joint_points_m": geometry.joint_points.tolist(),
        "axes": {name: {"point_m": axis.point.tolist(), "direction": axis.direction.tolist()}
                 for name, axis in zip(geometry.interface_names, geometry.axes)},
        "interfaces": {
            i.name: {"n_nodes": int(len(i.nodes)), "weights_sum": float(i.weights.sum()), "area_m2": i.area,
                     "axial_offset_m": geometry.interface_offsets.get(i.name)}
            for i in interfaces
        },
    }


def _configure_mesh(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--link", type=int, choices=(0, 1, 2, 3), required=True, help="link index, 0 = base")
    parser.add_argument("--alpha3-deg", type=float, default=90.0, help="base-link twist alpha_3 in degrees")
    parser.add_argument("--h", type=float, default=2e-3, help="maximum element edge length in metres")
    parser.add_argument("--order", type=int, choices=(1, 2), default=1, help="tetrahedron order")
    parser.add_argument("--out", type=Path, required=True, help="output directory")


def _run_mesh(args: argparse.Namespace) -> int:
    first, second, names = paper_link_axes(args.link, bennett_axes(args.alpha3_deg))
    stem = f"link{args.link}"
    mesh, geometry = mesh_link(first, second, h=args.h, design=LinkDesign(), names=names,
                               mount=args.link == 0, name=stem)
    model = FEModel.from_tet_mesh(mesh, PLA, args.order)
    interfaces = [interface_from_group(model, group) for group in sorted(mesh.groups)]
    args.out.mkdir(parents=True, exist_ok=True)
    vtu = write_vtu(args.out / f"{stem}.vtu", mesh)
    summary = link_summary(model, geometry, interfaces)
    summary.update(link=args.link, alpha3_deg=args.alpha3_deg, h_m=args.h, vtu=vtu.name)
    (args.out / f"{stem}.json").write_text(json.dumps(summary, indent=2))
    print(f"{stem}: {summary['n_tetrahedra']} tets, {summary['n_nodes']} nodes, mass {summary['mass_kg']:.5f} kg, "
          f"min quality {summary['quality']['min_quality']:.3f} -> {args.out}")
    return 0


SUBCOMMANDS: dict[str, tuple[str, Callable[[argparse.ArgumentParser], None], Callable[[argparse.Namespace], int]]] = {
    "mesh": ("mesh one Bennett link and write .vtu + JSON summary", _configure_mesh, _run_mesh),
}


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m ffrf", description="Flexible link FE models")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress")
    sub = parser.add_subparsers(dest="command", required=True)
    for name, (help_text, configure, run) in SUBCOMMANDS.items():
        configure(sub.add_parser(name, help=help_text))
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING)
    try:
        return SUBCOMMANDS[args.command][2](args)
    except FEInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
