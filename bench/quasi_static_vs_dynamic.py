"""Quasi-static against dynamic runs of the paper's 1 rpm PLA Bennett scene over the whole ramp + revolution.

The paper (Sect. "Simulation Setup") integrates its Exudyn model dynamically (generalized-alpha);
our default run is quasi-static because the drive is slow against the links' vibrations
(:func:`ffrf.scenes.linkage_run.choose_mode`). This bench measures what that choice costs: both runs
start from the same static assembly (:func:`ffrf.paper.bennett_scene.assemble`) and share their
output times (the dynamic run writes every ``round(t_end / step / (outputs - 1))``-th step;
the quasi-static run solves at exactly those times), and it reports

* the largest and RMS difference of the coupler point over the revolution (m, and relative to
  the largest elastic deviation of the quasi-static coupler from the motion polynomial),
* the largest difference of the driving torque relative to its largest magnitude,
* the transient at the end of the ramp (t in [ramp, ramp + 5 s]) against the rest,
* the energy balance of both runs (:meth:`ffrf.output.result.Result.summary`),
* wall times.

Usage::

    .venv/bin/python -m bench quasi_static_vs_dynamic --json out/qs_vs_dyn.json --out out/qs_vs_dyn
    .venv/bin/python -m bench quasi_static_vs_dynamic --order 1 --h 4e-3 --modes 8 --step 2e-3
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from bench.report import write_report

#: Window after the end of the ramp in which the start-up transient is measured (s).
TRANSIENT_WINDOW = 5.0


def compare(quasi_static, dynamic, ramp_time: float) -> dict:
    """Differences of two :class:`~ffrf.output.result.Result` with the same output times."""
    if quasi_static.time.shape != dynamic.time.shape or np.abs(quasi_static.time - dynamic.time).max() > 1e-9:
        raise ValueError("the runs must share their output times; use the same t_end and outputs")
    qs, dyn = quasi_static.sensors, dynamic.sensors
    t = dynamic.time
    coupler = np.linalg.norm(dyn["coupler_point"] - qs["coupler_point"], axis=1)
    torque = dyn["driving_torque"] - qs["driving_torque"]
    elastic = float(np.max(np.linalg.norm(qs["coupler_deviation"], axis=1)))
    torque_scale = float(np.max(np.abs(qs["driving_torque"])))
    transient = (t >= ramp_time) & (t <= ramp_time + TRANSIENT_WINDOW)
    later = t > ramp_time + TRANSIENT_WINDOW
    worst = int(np.argmax(coupler))
    return {
        "max_coupler_difference_m": float(coupler.max()),
        "max_coupler_difference_at": {
            "t_s": float(t[worst]),
            "drive_angle_since_start_deg": float(np.degrees(qs["drive_angle"][worst] - qs["drive_angle"][0])),
        },
        "max_torque_difference_at_t_s": float(t[int(np.argmax(np.abs(torque)))]),
        "rms_coupler_difference_m": float(np.sqrt(np.mean(coupler**2))),
        "max_coupler_elastic_deviation_m": elastic,
        "max_coupler_difference_relative_to_elastic_deviation": float(coupler.max()) / elastic,
        "rms_coupler_difference_relative_to_elastic_deviation": float(np.sqrt(np.mean(coupler**2))) / elastic,
        "max_abs_driving_torque_Nm": torque_scale,
        "max_torque_difference_Nm": float(np.abs(torque).max()),
        "max_torque_difference_relative": float(np.abs(torque).max()) / torque_scale,
        "ramp_end_transient": {
            "window_s": [ramp_time, ramp_time + TRANSIENT_WINDOW],
            "max_coupler_difference_m": float(coupler[transient].max()),
            "max_torque_difference_Nm": float(np.abs(torque[transient]).max()),
            "max_coupler_difference_afterwards_m": float(coupler[later].max()) if later.any() else None,
            "max_torque_difference_afterwards_Nm": float(np.abs(torque[later]).max()) if later.any() else None,
            "kinetic_energy_at_ramp_end_J": float(np.interp(ramp_time, t, dyn["energy_kinetic"])),
        },
        "energy_balance_relative": {
            "quasi_static": quasi_static.summary()["energy_balance_relative"],
            "dynamic": dynamic.summary()["energy_balance_relative"],
        },
    }


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variant", default="pla", choices=("rigid", "pla", "pla1", "pla2"))
    parser.add_argument("--order", type=int, choices=(1, 2), default=2, help="tetrahedron order (the scene's default)")
    parser.add_argument("--h", type=float, default=6e-3, help="maximum tetrahedron edge (m)")
    parser.add_argument("--modes", type=int, default=4, help="fixed-interface modes per link")
    parser.add_argument("--step", type=float, default=1e-3, help="generalized-alpha time step (s)")
    parser.add_argument("--rho-inf", type=float, default=0.9, help="generalized-alpha spectral radius at infinity")
    parser.add_argument("--outputs", type=int, default=611, help="output times (611: every 0.1 s of 61 s)")
    parser.add_argument("--t-end", type=float, default=None, help="shorter run (s); default ramp + revolution")
    parser.add_argument("--json", type=Path)
    parser.add_argument(
        "--out",
        type=Path,
        help="also write both runs (DIR/quasi_static, DIR/dynamic) and "
        "DIR/difference.png (coupler and torque differences)",
    )
    args = parser.parse_args(argv)

    from ffrf.paper.bennett_scene import build_bennett
    from ffrf.scenes.linkage_run import run_linkage

    started = time.perf_counter()
    scene = build_bennett(args.variant, h=args.h, order=args.order, n_modes=args.modes)
    built = time.perf_counter()
    t_end = scene.t_end if args.t_end is None else args.t_end
    # Output every `every` steps; the quasi-static run then solves at the same times.
    every = max(1, int(round(t_end / args.step / (args.outputs - 1))))
    outputs = int(round(t_end / args.step)) // every + 1
    t_end = (outputs - 1) * every * args.step
    print(
        f"{args.variant}: P{args.order}, h = {1e3 * args.h:g} mm, {args.modes} modes, t_end = {t_end:g} s, "
        f"{outputs} outputs, scene built in {built - started:.1f} s",
        flush=True,
    )
    clock = time.perf_counter()
    quasi_static = run_linkage(scene, mode="quasi_static", n_outputs=outputs, t_end=t_end)
    qs_wall = time.perf_counter() - clock
    print(f"quasi-static: {qs_wall:.1f} s", flush=True)
    clock = time.perf_counter()
    dynamic = run_linkage(scene, mode="dynamic", n_outputs=outputs, step=args.step, rho_inf=args.rho_inf, t_end=t_end)
    dyn_wall = time.perf_counter() - clock
    print(f"dynamic: {dyn_wall:.1f} s ({int(round(t_end / args.step))} steps)", flush=True)

    report = dict(
        variant=args.variant,
        order=args.order,
        h=args.h,
        modes=args.modes,
        step=args.step,
        rho_inf=args.rho_inf,
        t_end=t_end,
        outputs=outputs,
        n_coordinates=scene.system.n_coordinates,
        wall_time_s={
            "build": built - started,
            "quasi_static": qs_wall,
            "dynamic": dyn_wall,
            "dynamic_per_step_ms": 1e3 * dyn_wall / round(t_end / args.step),
        },
        **compare(quasi_static, dynamic, scene.drive.ramp_time),
    )
    tr = report["ramp_end_transient"]
    print(
        f"coupler: dynamic - quasi-static max {report['max_coupler_difference_m']:.3e} m, "
        f"RMS {report['rms_coupler_difference_m']:.3e} m = "
        f"{report['max_coupler_difference_relative_to_elastic_deviation']:.2e} (max) and "
        f"{report['rms_coupler_difference_relative_to_elastic_deviation']:.2e} (RMS) of the elastic deviation "
        f"{1e3 * report['max_coupler_elastic_deviation_m']:.4f} mm"
    )
    print(
        f"driving torque: max difference {1e3 * report['max_torque_difference_Nm']:.4f} N mm = "
        f"{report['max_torque_difference_relative']:.2e} of max |torque| "
        f"{1e3 * report['max_abs_driving_torque_Nm']:.3f} N mm"
    )
    print(
        f"end of ramp (t in {tr['window_s']} s): coupler {tr['max_coupler_difference_m']:.3e} m, torque "
        f"{1e3 * tr['max_torque_difference_Nm']:.4f} N mm; afterwards {tr['max_coupler_difference_afterwards_m']} m, "
        f"{tr['max_torque_difference_afterwards_Nm']} N m; kinetic energy {tr['kinetic_energy_at_ramp_end_J']:.3e} J"
    )
    print(f"energy balance (relative to the drive work): {report['energy_balance_relative']}")
    print(f"wall times: {report['wall_time_s']}")
    if args.out:
        write_outputs(args.out, quasi_static, dynamic)
    if args.json:
        write_report(report, args.json, echo=False)
    return report


def write_outputs(directory: Path, quasi_static, dynamic) -> None:
    """Both runs' results and the differences over the drive angle (um and N mm)."""
    from ffrf.output.linkage_figures import plot_over_drive_angle

    quasi_static.write_tables(directory / "quasi_static")
    dynamic.write_tables(directory / "dynamic")
    angle = quasi_static.sensors["drive_angle"] - quasi_static.sensors["drive_angle"][0]
    coupler = 1e6 * np.linalg.norm(dynamic.sensors["coupler_point"] - quasi_static.sensors["coupler_point"], axis=1)
    torque = 1e3 * (dynamic.sensors["driving_torque"] - quasi_static.sensors["driving_torque"])
    plot_over_drive_angle(
        {
            "|coupler dynamic - quasi-static| (um)": (angle, coupler),
            "torque dynamic - quasi-static (N mm)": (angle, torque),
        },
        "difference",
        directory / "difference.png",
        "Dynamic against quasi-static",
    )


if __name__ == "__main__":
    main()
