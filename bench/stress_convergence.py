"""Is a link's peak von Mises stress a design quantity? Its value against the mesh (issue #35, Eqs. (D9), (D10)).

    .venv/bin/python -m bench record stress_convergence                   # docs/results/stress_convergence.json
    .venv/bin/python -m bench stress_convergence --json out/stress.json    # the same, written elsewhere

The PLA Bennett of ``examples/design_bennett_section.toml`` (its default 16 x 12 mm arm) under its weight, at 13
poses of a revolution, meshed at several element sizes: each link's peak von Mises stress over the poses and its
corners, where it lies (the distance of that element from the nearest housing's centre: 16 mm is the housing's outer
radius, where the arm meets it), and the norm of Eq. (D10). A peak that grows as the elements shrink sits on a
singular stress (the re-entrant edge where the arm meets the housing, or the mount): no mesh gives its value, and a
bound on it is a bound on the mesh. Beside it, the largest stress averaged over balls of material of
:data:`RADII_MM` around each vertex (Eq. (D14)), what a design bounds instead: finite, and converging.
"""

from __future__ import annotations

import argparse
import time
import tomllib
from pathlib import Path

import numpy as np

from bench.report import write_report
from ffrf.fe.fe_model import FEModel
from ffrf.output.peak_stress import peak_stress, strain_modes, stress_norm
from ffrf.output.stress_average import ball_average
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.linkage_scene import build_linkage
from ffrf.scenes.section_design import load_design

EXAMPLE = Path(__file__).parents[1] / "examples" / "design_bennett_section.toml"
#: Element sizes (mm) of the links, coarsest first.
SIZES_MM = (8.0, 6.0, 4.5, 3.5, 2.5)
#: Radii (mm) of the balls the stress is averaged over (Eq. (D14)).
RADII_MM = (2.0, 4.0)
POSES = 13


def _row(size_mm: float) -> dict:
    text = EXAMPLE.read_text().replace("start_angle_deg = -90.0\n", f"start_angle_deg = -90.0\nh = {size_mm / 1e3}\n")
    loop, options, _ = load_design(tomllib.loads(text))
    started = time.perf_counter()
    scene = build_linkage(loop, options)
    result = run_linkage(scene, mode="quasi_static", n_outputs=POSES, sensors="path")
    links = []
    for k, body in enumerate(scene.bodies):
        assert isinstance(body.fe, FEModel) and body.geometry is not None  # parametric links, meshed by us
        modes = strain_modes(body.fe, body.reduction.basis)
        block = scene.system.block(k)
        material = body.fe.material
        peaks = [peak_stress(modes, result.q[r, block][7:], material.E, material.nu) for r in range(POSES)]
        norms = [stress_norm(modes, result.q[r, block][7:], material.E, material.nu).value for r in range(POSES)]
        pose = int(np.argmax([p.value for p in peaks]))
        centroid = body.fe.mesh.points[body.fe.mesh.tets[peaks[pose].element]].mean(axis=0)
        housing = min(float(np.linalg.norm(centroid - c)) for c in body.geometry.housing_centers)
        averaged = []
        for radius_mm in RADII_MM:
            average = ball_average(body.fe, radius_mm / 1e3)
            smooth = strain_modes(body.fe, body.reduction.basis, average)
            at = [peak_stress(smooth, result.q[r, block][7:], material.E, material.nu) for r in range(POSES)]
            best = at[int(np.argmax([p.value for p in at]))]
            centre = body.fe.mesh.points[average.vertices[best.element]]
            averaged.append(
                {
                    "radius_m": radius_mm / 1e3,
                    "peak_pa": best.value,
                    "from_housing_centre_m": min(
                        float(np.linalg.norm(centre - c)) for c in body.geometry.housing_centers
                    ),
                }
            )
        links.append(
            {
                "link": k,
                "peak_pa": peaks[pose].value,
                "norm_pa": max(norms),
                "pose": pose,
                "from_housing_centre_m": housing,
                "elements": int(len(body.fe.mesh.tets)),
                "averaged": averaged,
            }
        )
    return {"size_m": size_mm / 1e3, "links": links, "seconds": time.perf_counter() - started}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, required=True)
    args = parser.parse_args()
    rows = []
    for size in SIZES_MM:
        rows.append(_row(size))
        write_report({"example": EXAMPLE.name, "poses": POSES, "meshes": rows}, args.json, echo=False)
    peaks = np.array([[link["peak_pa"] for link in row["links"]] for row in rows])
    summary: dict = {"peak_growth_finest_over_coarsest": (peaks[-1] / peaks[0]).tolist()}
    for index, radius_mm in enumerate(RADII_MM):
        averaged = np.array([[link["averaged"][index]["peak_pa"] for link in row["links"]] for row in rows])
        summary[f"averaged_over_{radius_mm:g}_mm_balls"] = {
            "finest_over_coarsest": (averaged[-1] / averaged[0]).tolist(),
            "spread_over_meshes": (averaged.max(axis=0) / averaged.min(axis=0) - 1.0).tolist(),
            "last_change": (averaged[-1] / averaged[-2] - 1.0).tolist(),
        }
    write_report({"example": EXAMPLE.name, "poses": POSES, "meshes": rows, "summary": summary}, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
