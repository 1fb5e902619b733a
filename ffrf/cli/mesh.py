"""``python -m ffrf mesh``: mesh one of the paper's Bennett links and write its ``.vtu`` and a JSON summary."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ffrf.cli.arguments import element_edge, output_folder
from ffrf.fe.fe_model import FEModel
from ffrf.fe.interfaces import interface_from_group
from ffrf.fe.materials import PLA
from ffrf.geometry.link_geometry import LinkDesign, mesh_link
from ffrf.mesh.tet_mesh import quality_summary, write_vtu
from ffrf.paper.axes import bennett_axes, paper_link_axes

__all__ = ["HELP", "configure", "run", "link_summary"]

HELP = "mesh one Bennett link and write .vtu + JSON summary"


def link_summary(model: FEModel, geometry, interfaces) -> dict:
    """JSON-ready summary of a meshed link."""
    return {
        "order": model.order,
        "n_vertices": model.n_vertices,
        "n_nodes": len(model.nodes),
        "n_tetrahedra": len(model.mesh.tets),
        "n_dofs": model.n_dofs,
        "quality": quality_summary(model.mesh).as_dict(),
        "material": {
            "name": model.material.name,
            "E": model.material.E,
            "nu": model.material.nu,
            "rho": model.material.rho,
        },
        "volume_m3": model.mesh.volume,
        "mass_kg": model.total_mass,
        "center_of_mass_m": model.center_of_mass.tolist(),
        "inertia_tensor_kgm2": model.inertia_tensor.tolist(),
        "link_length_m": geometry.length,
        "joint_points_m": geometry.joint_points.tolist(),
        "axes": {
            name: {"point_m": axis.point.tolist(), "direction": axis.direction.tolist()}
            for name, axis in zip(geometry.interface_names, geometry.axes, strict=True)
        },
        "interfaces": {
            i.name: {
                "n_nodes": int(len(i.nodes)),
                "weights_sum": float(i.weights.sum()),
                "area_m2": i.area,
                "axial_offset_m": geometry.interface_offsets.get(i.name),
            }
            for i in interfaces
        },
    }


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--link", type=int, choices=(0, 1, 2, 3), required=True, help="link index, 0 = base")
    parser.add_argument("--alpha3-deg", type=float, default=90.0, help="base-link twist alpha_3 in degrees")
    parser.add_argument("--h", type=element_edge, default=2e-3, help="maximum element edge length in metres")
    parser.add_argument("--order", type=int, choices=(1, 2), default=1, help="tetrahedron order")
    parser.add_argument("--out", type=Path, required=True, help="output directory")


def run(args: argparse.Namespace) -> int:
    first, second, names = paper_link_axes(args.link, bennett_axes(args.alpha3_deg))
    stem = f"link{args.link}"
    mesh, geometry = mesh_link(
        first, second, h=args.h, design=LinkDesign(), names=names, mount=args.link == 0, name=stem
    )
    model = FEModel.from_tet_mesh(mesh, PLA, args.order)
    interfaces = [interface_from_group(model, group) for group in sorted(mesh.groups)]
    output_folder(args.out)
    vtu = write_vtu(args.out / f"{stem}.vtu", mesh)
    summary = link_summary(model, geometry, interfaces)
    summary.update(link=args.link, alpha3_deg=args.alpha3_deg, h_m=args.h, vtu=vtu.name)
    (args.out / f"{stem}.json").write_text(json.dumps(summary, indent=2))
    print(
        f"{stem}: {summary['n_tetrahedra']} tets, {summary['n_nodes']} nodes, mass {summary['mass_kg']:.5f} kg, "
        f"min quality {summary['quality']['min_quality']:.3f} -> {args.out}"
    )
    return 0
