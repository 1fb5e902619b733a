"""What joint play does to the paper's Bennett prints: the PLA linkage and its 1 deg and 2 deg misaligned variants
with radial clearances of 0 (ideal revolute joints), 0.05, 0.1, 0.2 and 0.3 mm in the three passive joints
(``docs/formulation.md``, Eqs. (P1)-(P7); the clamp and the driven joint stay ideal), one quasi-static revolution
each at one discretisation.

For each run: the largest coupler deviation from the ideal point at the same drive angle and the largest distance
to the ideal path (mm), the assembled state's largest von Mises stress and strain energy (the misfit the loop is
closed with), the largest |driving torque| (N mm), the pins' largest eccentricity in their bores and deepest
penetration (as a fraction of the play), the DH parameters identified from the tracked links by the paper's method
(:mod:`identification`, the axes of a loose joint wobble with its pin), whether the run verified itself, and the
wall times. The question the paper raises (does play let the misaligned prints assemble with less stress and follow
the ideal path more closely?) is answered by the table as measured.

Usage::

    .venv/bin/python -m bench clearance_variants --json out/clearance_variants.json
    .venv/bin/python -m bench clearance_variants --variants pla2 --clearances 0,0.1 --outputs 73
    .venv/bin/python -m bench clearance_variants --workers 2   # two runs at once (their wall times share the cores)
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

import numpy as np

from bench.bennett_variants import add_discretisation_arguments, finish


def run_row(variant: str, radial_mm: float, h: float, order: int, modes: int, outputs: int) -> dict:
    """Build and run one variant with ``radial_mm`` of radial play (0: ideal joints) quasi-statically; the row."""
    from ffrf.errors import StaticDivergence
    from ffrf.paper.bennett_scene import bennett_options, build_bennett_from_options
    from ffrf.scenes.linkage_run import run_linkage
    from identification.circle_fit import IdentificationError
    from identification.loop import identify_dh

    clock = time.perf_counter()
    options = bennett_options(variant, h=h, order=order, n_modes=modes)
    if radial_mm > 0.0:  # the pin bears along the housing's whole bore
        pin_length_mm = 1e3 * options.design.housing_length
        options = replace(options, joint_play={"radial_mm": radial_mm, "pin_length_mm": pin_length_mm})
    scene = build_bennett_from_options(options, variant)
    built = time.perf_counter()
    try:
        result = run_linkage(scene, mode="quasi_static", n_outputs=outputs)
        stopped = None
    except StaticDivergence as error:  # as measured: the row of the revolution up to where its path stopped
        if error.partial is None:
            raise
        result, stopped = error.partial, result_stop(error.partial)
    ran = time.perf_counter()
    summary = result.summary()
    assembly = result.assembly
    if assembly is None:
        raise RuntimeError(f"the {variant} run reports no assembly stress")
    sensors = result.sensors
    tracked = {k: np.stack([sensors[f"link{k}_node{j}"] for j in range(3)], axis=1) for k in (1, 2, 3)}
    unidentified: str | None = None
    try:
        loop = identify_dh(tracked)
    except IdentificationError as error:  # a path that stopped early turns the links too little to fit their axes
        loop, unidentified = None, str(error)
    loose = [j.name for j in scene.loose_joints]
    eccentricity = max((float(np.max(sensors[f"{name}_eccentricity"])) for name in loose), default=0.0)
    penetration = max((float(np.max(sensors[f"{name}_contacts"][:, 0, :2])) for name in loose), default=0.0)
    verification = result.verification
    return {
        "run": f"{variant}_{radial_mm:g}mm",
        "variant": variant,
        "radial_mm": radial_mm,
        "loose_joints": loose,
        "max_coupler_deviation_mm": 1e3 * summary["max_coupler_deviation_m"],
        "max_distance_to_path_mm": 1e3 * summary["max_coupler_distance_to_path_m"],
        "max_abs_driving_torque_Nmm": 1e3 * summary["max_abs_driving_torque_Nm"],
        "assembly_max_von_mises_MPa": 1e-6 * assembly.as_dict()["max_von_mises_pa"],
        "assembly_strain_energy_mJ": 1e3 * assembly.as_dict()["strain_energy_j"],
        "max_pin_eccentricity_mm": 1e3 * eccentricity,
        "max_penetration_over_play": penetration / (1e-3 * radial_mm) if radial_mm > 0.0 else None,
        "identified_a_mm": None if loop is None else (1e3 * loop.dh.a).tolist(),
        "identified_alpha_deg": None if loop is None else np.degrees(loop.dh.alpha).tolist(),
        "identified_d_mm": None if loop is None else (1e3 * loop.dh.d).tolist(),
        "identified_axis3_twist_deviation_deg": None if loop is None else float(np.degrees(loop.axis3_twist_deviation)),
        "unidentified": unidentified,
        "energy_balance_relative": summary["energy_balance_relative"],
        "verified": None if verification is None else bool(verification.verified),
        "stopped": stopped,
        "n_coordinates": scene.system.n_coordinates,
        "wall_time_s": {"build": built - clock, "run": ran - built, **result.metadata["timings_s"]},
    }


def result_stop(result) -> str:
    """Where and why a run's path stopped, in the drive's degrees."""
    where = result.metadata["stopped"]
    return f"stopped at {np.degrees(result.sensors['drive_angle'][-1]):.1f} deg of drive: {where['message']}"


def table(rows: list[dict]) -> str:
    """The rows as a Markdown table."""
    lines = [
        "| variant | radial play (mm) | max deviation (mm) | max distance to path (mm) | assembly max von Mises (MPa) "
        "| assembly strain energy (mJ) | max abs torque (N mm) | max pin eccentricity (mm) | identified alpha (deg) "
        "| identified d (mm) | verified | run (s) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        alpha = ", ".join(f"{a:.3f}" for a in r["identified_alpha_deg"] or []) or "-"
        d = ", ".join(f"{x:.3f}" for x in r["identified_d_mm"] or []) or "-"
        lines.append(
            f"| {r['variant']} | {r['radial_mm']:g} | {r['max_coupler_deviation_mm']:.4g} "
            f"| {r['max_distance_to_path_mm']:.4g} | {r['assembly_max_von_mises_MPa']:.3g} "
            f"| {r['assembly_strain_energy_mJ']:.3g} | {r['max_abs_driving_torque_Nmm']:.4g} "
            f"| {r['max_pin_eccentricity_mm']:.4g} | {alpha} | {d} | {'stopped' if r['stopped'] else r['verified']} "
            f"| {r['wall_time_s']['run']:.0f} |"
        )
    return "\n".join(lines)


def _printed(r: dict) -> dict:
    """The row, printed in a line."""
    print(
        f"{r['variant']}, {r['radial_mm']:g} mm: deviation {r['max_coupler_deviation_mm']:.4f} mm, assembly "
        f"{r['assembly_max_von_mises_MPa']:.3f} MPa, torque {r['max_abs_driving_torque_Nmm']:.3f} N mm, "
        f"eccentricity {r['max_pin_eccentricity_mm']:.4f} mm, verified {r['verified']}, "
        f"run {r['wall_time_s']['run']:.1f} s",
        flush=True,
    )
    return r


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_discretisation_arguments(parser)
    parser.add_argument("--variants", default="pla,pla1,pla2")
    parser.add_argument("--clearances", default="0,0.05,0.1,0.2,0.3", help="radial clearances (mm), 0: ideal joints")
    parser.add_argument("--json", type=Path)
    parser.add_argument(
        "--workers", type=int, default=1, help="runs at once, each in its own process with one BLAS thread"
    )
    args = parser.parse_args(argv)

    started = time.perf_counter()
    cases = [
        (variant, radial, args.h, args.order, args.modes, args.outputs)
        for variant in args.variants.split(",")
        for radial in (float(c) for c in args.clearances.split(","))
    ]
    if args.workers > 1:
        os.environ["OPENBLAS_NUM_THREADS"] = "1"  # read by the spawned workers' BLAS as it loads
        with ProcessPoolExecutor(args.workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            rows = [_printed(row) for row in pool.map(run_row, *zip(*cases, strict=True))]
    else:
        rows = [_printed(run_row(*case)) for case in cases]
    report = {
        "h": args.h,
        "order": args.order,
        "modes": args.modes,
        "outputs": args.outputs,
        "workers": args.workers,
        "total_wall_time_s": time.perf_counter() - started,
        "rows": rows,
    }
    return finish(args, report, table(rows))


if __name__ == "__main__":
    main()
