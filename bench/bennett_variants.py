"""The paper's four Bennett variants (rigid, PLA, PLA with alpha_3 = 91 and 92 deg) run quasi-statically
at one discretisation, side by side with the paper's maximum coupler deviations (Sect. "Results").

For each variant: the largest coupler deviation from the ideal point at the same drive angle and
the largest distance to the ideal path (mm), the largest |driving torque| (N mm), the largest
von Mises stress of the assembled state (MPa, :mod:`ffrf.output.assembly_stress`) and the wall times
(build = gmsh + scikit-fem + Craig-Bampton of the four links; run = assembly + quasi-static
solve + sensors). ``--out DIR`` also writes each run (``DIR/<variant>/``) and the paper-style
overlays ``DIR/coupler_deviation.png`` and ``DIR/driving_torque.png``.

Usage::

    .venv/bin/python -m bench bennett_variants --json out/variants_default.json
    .venv/bin/python -m bench bennett_variants --order 1 --h 0.002 --modes 32 \
        --json out/variants_paper.json
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from bench.report import write_report


def run_variant(
    variant: str, h: float, order: int, modes: int, outputs: int, out: Path | None, collision_free: bool = True
) -> dict:
    """Build and run one variant quasi-statically; the row of the table (SI and display units). ``collision_free``:
    the default links (housings stacked along the axes), or, when False, housings centred on the joint points."""
    from ffrf.paper.bennett_scene import PAPER_MAX_COUPLER_DEVIATION_MM, build_bennett
    from ffrf.scenes.linkage_run import run_linkage

    clock = time.perf_counter()
    scene = build_bennett(variant, h=h, order=order, n_modes=modes, collision_free=collision_free)
    built = time.perf_counter()
    result = run_linkage(scene, mode="quasi_static", n_outputs=outputs)
    ran = time.perf_counter()
    if out is not None:
        result.write_tables(out / variant)
    summary = result.summary()
    assembly = result.assembly
    if assembly is None:
        raise RuntimeError(f"the {variant} run reports no assembly stress")
    return {
        "variant": variant,
        "result": result,
        "max_coupler_deviation_mm": 1e3 * summary["max_coupler_deviation_m"],
        "max_distance_to_path_mm": 1e3 * summary["max_coupler_distance_to_path_m"],
        "paper_max_deviation_mm": PAPER_MAX_COUPLER_DEVIATION_MM[variant],
        "max_abs_driving_torque_Nmm": 1e3 * summary["max_abs_driving_torque_Nm"],
        "assembly_max_von_mises_MPa": 1e-6 * assembly.as_dict()["max_von_mises_pa"],
        "assembly_von_mises_per_link_MPa": [1e-6 * link.max_von_mises_pa for link in assembly.links],
        "assembly_strain_energy_mJ": 1e3 * assembly.as_dict()["strain_energy_j"],
        "max_constraint_residual": summary["max_constraint_residual"],
        "energy_balance_relative": summary["energy_balance_relative"],
        "n_coordinates": scene.system.n_coordinates,
        "nodes_per_link": [len(link.fe.nodes) for link in scene.links],
        "wall_time_s": {"build": built - clock, "run": ran - built, **result.metadata["timings_s"]},
    }


def table(rows: list[dict]) -> str:
    """The rows as a Markdown table."""
    lines = [
        "| variant | max deviation (mm) | max distance to path (mm) | paper (mm) | max abs torque (N mm) "
        "| assembly max von Mises (MPa) | build (s) | run (s) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    from ffrf.paper.bennett_scene import paper_max_coupler_deviation

    for r in rows:
        lines.append(
            f"| {r['variant']} | {r['max_coupler_deviation_mm']:.4g} | {r['max_distance_to_path_mm']:.4g} "
            f"| {paper_max_coupler_deviation(r['variant'])} | {r['max_abs_driving_torque_Nmm']:.4g} "
            f"| {r['assembly_max_von_mises_MPa']:.3g} "
            f"| {r['wall_time_s']['build']:.1f} | {r['wall_time_s']['run']:.1f} |"
        )
    return "\n".join(lines)


def add_discretisation_arguments(parser: argparse.ArgumentParser) -> None:
    """``--h``, ``--order``, ``--modes`` and ``--outputs`` of a run of the paper's linkage (defaults: the default
    discretisation, 241 quasi-static outputs)."""
    parser.add_argument("--h", type=float, default=6e-3, help="maximum tetrahedron edge (m); paper 0.002")
    parser.add_argument("--order", type=int, choices=(1, 2), default=2, help="tetrahedron order; paper 1")
    parser.add_argument("--modes", type=int, default=4, help="fixed-interface modes per link; paper 32")
    parser.add_argument("--outputs", type=int, default=241, help="quasi-static output times over ramp + revolution")


def finish(args: argparse.Namespace, report: dict, table: str) -> dict:
    """Print the discretisation, ``table`` and the total wall time, write ``report`` to ``--json``; the report."""
    print(f"\nP{args.order}, h = {1e3 * args.h:g} mm, {args.modes} modes, {args.outputs} quasi-static outputs:\n")
    print(table)
    print(f"\ntotal wall time {report['total_wall_time_s']:.1f} s")
    if args.json:
        write_report(report, args.json, echo=False)
    return report


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_discretisation_arguments(parser)
    parser.add_argument("--variants", default="rigid,pla,pla1,pla2")
    parser.add_argument(
        "--links-at-joint-points",
        dest="collision_free",
        action="store_false",
        help="housings centred on the joint points (links that pass through each other) instead of the default "
        "collision-free links",
    )
    parser.add_argument("--out", type=Path, help="also write each run and the overlaid figures here")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)

    started = time.perf_counter()
    rows = []
    for variant in args.variants.split(","):
        rows.append(run_variant(variant, args.h, args.order, args.modes, args.outputs, args.out, args.collision_free))
        r = rows[-1]
        print(
            f"{variant}: {r['max_coupler_deviation_mm']:.4f} mm (paper {r['paper_max_deviation_mm']}), "
            f"{r['max_abs_driving_torque_Nmm']:.3f} N mm, {r['assembly_max_von_mises_MPa']:.3f} MPa, "
            f"{r['n_coordinates']} coordinates, nodes per link {r['nodes_per_link']}, "
            f"build {r['wall_time_s']['build']:.1f} s, run {r['wall_time_s']['run']:.1f} s",
            flush=True,
        )
    if args.out is not None:
        from ffrf.output.linkage_figures import plot_coupler_deviation, plot_driving_torque

        runs = {r["variant"]: r["result"] for r in rows}
        plot_coupler_deviation(runs, args.out / "coupler_deviation.png")
        plot_driving_torque(runs, args.out / "driving_torque.png")
    report = {
        "h": args.h,
        "order": args.order,
        "modes": args.modes,
        "outputs": args.outputs,
        "collision_free": args.collision_free,
        "total_wall_time_s": time.perf_counter() - started,
        "rows": [{k: v for k, v in r.items() if k != "result"} for r in rows],
    }
    return finish(args, report, table(rows))


if __name__ == "__main__":
    main()
