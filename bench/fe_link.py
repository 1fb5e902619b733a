"""Benchmark: mesh, assembly and modal-analysis time and peak memory of one link.

Usage (from the repository root)::

    .venv/bin/python -m bench fe_link                 # link 2, P1, h = 4, 2, 1 mm
    .venv/bin/python -m bench fe_link --order 2 --h 0.004 0.002
    .venv/bin/python -m bench fe_link --json results.json

Every case runs in a fresh subprocess so that the peak resident memory
(``ru_maxrss``, which includes gmsh, scikit-fem and SuperLU allocations) is that
case's own. The peak is cumulative over the stages: the number reported after a
stage is the largest resident size up to the end of that stage.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

from bench import ROOT
from bench.report import write_report


def _peak_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: KiB


def run_case(link: int, h: float, order: int, n_modes: int) -> dict:
    """One benchmark case in this process (called in a subprocess by :func:`main`)."""
    from ffrf.fe.fe_model import FEModel
    from ffrf.fe.materials import PLA
    from ffrf.geometry.link_geometry import mesh_link
    from ffrf.mesh.tet_mesh import quality_summary
    from ffrf.paper.axes import paper_link_axes
    from ffrf.reduction.free_free import free_free_basis

    result: dict = {"link": link, "h_m": h, "order": order}
    a, b, names = paper_link_axes(link)
    t0 = time.perf_counter()
    mesh, _ = mesh_link(a, b, h=h, names=names, mount=link == 0)
    result.update(
        mesh_s=time.perf_counter() - t0,
        peak_after_mesh_MiB=_peak_mib(),
        n_tets=len(mesh.tets),
        min_quality=quality_summary(mesh).min_quality,
    )
    t0 = time.perf_counter()
    model = FEModel.from_tet_mesh(mesh, PLA, order)
    result.update(
        assembly_s=time.perf_counter() - t0,
        peak_after_assembly_MiB=_peak_mib(),
        n_dofs=model.n_dofs,
        nnz_stiffness=int(model.stiffness.nnz),
    )
    t0 = time.perf_counter()
    modes = free_free_basis(model, n_modes)
    result.update(
        modal_s=time.perf_counter() - t0,
        peak_after_modal_MiB=_peak_mib(),
        n_rigid=len(modes.rigid_body_eigenvalues),
        first_frequencies_hz=modes.frequencies_hz[:4].tolist(),
    )
    return result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--link", type=int, default=2, choices=(0, 1, 2, 3))
    parser.add_argument("--order", type=int, default=1, choices=(1, 2))
    parser.add_argument("--h", type=float, nargs="+", default=[0.004, 0.002, 0.001])
    parser.add_argument("--modes", type=int, default=10, help="flexible free-free modes")
    parser.add_argument("--json", type=Path, help="also write the results here")
    parser.add_argument("--case", help=argparse.SUPPRESS)  # internal: run one case, print JSON
    args = parser.parse_args(argv)
    if args.case:
        print(json.dumps(run_case(args.link, float(args.case), args.order, args.modes)))
        return 0
    results = []
    header = (
        f"{'h [mm]':>7} {'P':>2} {'tets':>8} {'DOFs':>9} {'mesh s':>8} {'asm s':>8} {'modal s':>8} "
        f"{'peak MiB':>9} {'f1 Hz':>8}"
    )
    print(header)
    for h in args.h:
        out = subprocess.run(
            [
                sys.executable,
                "-m",
                "bench.fe_link",
                "--link",
                str(args.link),
                "--order",
                str(args.order),
                "--modes",
                str(args.modes),
                "--case",
                repr(h),
            ],
            capture_output=True,
            text=True,
            cwd=ROOT,
        )
        if out.returncode != 0:
            print(f"h={h}: failed\n{out.stderr[-2000:]}")
            continue
        r = json.loads(out.stdout.strip().splitlines()[-1])
        results.append(r)
        print(
            f"{h * 1e3:7.1f} {r['order']:2d} {r['n_tets']:8d} {r['n_dofs']:9d} {r['mesh_s']:8.2f} "
            f"{r['assembly_s']:8.2f} {r['modal_s']:8.2f} {r['peak_after_modal_MiB']:9.0f} "
            f"{r['first_frequencies_hz'][0]:8.1f}",
            flush=True,
        )
    if args.json:
        write_report(results, args.json, echo=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
