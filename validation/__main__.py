"""Command line: ``python -m validation report (--variant NAME | --scene SCENE.toml) --out DIR``,
``python -m validation summary --variants rigid pla pla1 pla2 --out DIR`` and
``python -m validation testmodels [--models NAME ...] [--no-exudyn] [--json OUT.json]``.

``report`` cross-validates one built-in Bennett variant, or a scene file of ``python -m ffrf
run``, against its Exudyn twin and writes ``DIR/report.md``, ``DIR/metrics.json`` and the
figures (for a scene file, its own mode and settings are used); ``summary`` does so for several
variants (``DIR/<variant>/``) and writes ``DIR/summary.md`` in the layout of the paper's
results; ``testmodels`` runs our twins of Exudyn's TestModels with modal flexible bodies
(:mod:`validation.testmodels`) next to Exudyn's own runs and the values Exudyn stores. Exit status
(scripts and CI rely on it): 0 when every target is met, 1 when a target is
missed (the reports are written and say which), 2 when a run fails (the reason is printed, the
reports written so far stay). A scene's report shows each run's progress on stderr; with ``--max-minutes``
Exudyn's run stops at that time and the outputs it reached are compared (exit status 1, the report says
"incomplete" and why).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from ffrf.cli.arguments import count_at_least, number_in
from ffrf.scenes.limits import MAX_OUTPUTS
from ffrf.scenes.scene_schema import PARAMETRIC_H_RANGE

from .bennett_validation import ValidationSettings, validate_bennett
from .report import write_report, write_summary

VARIANTS = ("rigid", "pla", "pla1", "pla2")


def _settings_arguments(parser: argparse.ArgumentParser) -> None:
    defaults = ValidationSettings()
    parser.add_argument(
        "--h",
        type=number_in(*PARAMETRIC_H_RANGE, unit=" m"),
        default=defaults.h,
        help="maximum tetrahedron edge (m); paper 0.002",
    )
    parser.add_argument("--order", type=int, choices=(1, 2), default=defaults.order, help="element order")
    parser.add_argument(
        "--modes", type=count_at_least(1), default=defaults.n_modes, help="fixed-interface modes per link (paper 32)"
    )
    parser.add_argument(
        "--outputs",
        type=count_at_least(2, MAX_OUTPUTS),
        default=defaults.outputs,
        help="quasi-static rows over the revolution",
    )
    parser.add_argument(
        "--dynamic-window",
        type=number_in(0.0, 3600.0, unit=" s"),
        default=defaults.dynamic_t_end,
        help="seconds of dynamic simulation compared from t = 0 (0: skip)",
    )
    parser.add_argument(
        "--step",
        type=number_in(0.0, 1.0, closed_low=False, unit=" s"),
        default=defaults.step,
        help="time step of the dynamic window (s)",
    )
    parser.add_argument(
        "--rho-inf", type=number_in(0.0, 1.0), default=defaults.rho_inf, help="generalized-alpha spectral radius"
    )
    parser.add_argument(
        "--basis",
        choices=("exudyn", "ffrf"),
        default=defaults.basis,
        help="mode basis of Exudyn's bodies: its own Craig-Bampton (default) or ours",
    )
    parser.add_argument("--out", type=Path, required=True, help="output folder")


def _settings(args, variant: str) -> ValidationSettings:
    return ValidationSettings(
        variant=variant,
        h=args.h,
        order=args.order,
        n_modes=args.modes,
        outputs=args.outputs,
        dynamic_t_end=args.dynamic_window,
        step=args.step,
        rho_inf=args.rho_inf,
        basis=args.basis,
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m validation", description=__doc__.splitlines()[0])
    commands = parser.add_subparsers(dest="command", required=True)
    report = commands.add_parser("report", help="one variant: report.md, metrics.json, figures")
    which = report.add_mutually_exclusive_group()
    which.add_argument("--variant", choices=VARIANTS, default="pla")
    which.add_argument("--scene", type=Path, help="a TOML scene file (see ffrf/scenes/scene_file.py)")
    report.add_argument(
        "--max-minutes",
        type=number_in(0.0, math.inf, closed_low=False, unit=" min"),
        help="with --scene: stop Exudyn's run this long after the start and compare the outputs it reached",
    )
    _settings_arguments(report)
    summary = commands.add_parser("summary", help="several variants and a summary in the paper's layout")
    summary.add_argument("--variants", nargs="+", choices=VARIANTS, default=list(VARIANTS))
    _settings_arguments(summary)
    testmodels = commands.add_parser("testmodels", help="Exudyn's TestModels: stored value, Exudyn's run and ours")
    testmodels.add_argument("--models", nargs="+", metavar="NAME", help="these models only (default: all)")
    testmodels.add_argument("--no-exudyn", action="store_true", help="ours against the stored values only")
    testmodels.add_argument("--json", type=Path, help="write every number to this JSON file")
    args = parser.parse_args(argv)

    if args.command == "testmodels":
        from .testmodels.report import main as testmodels_main

        return testmodels_main(args.models, not args.no_exudyn, args.json)

    if args.command == "report" and args.scene is not None:
        return _scene_report(args.scene, args.basis, args.out, args.max_minutes)
    variants = [args.variant] if args.command == "report" else args.variants
    validations = []
    try:
        for variant in variants:
            folder = args.out if args.command == "report" else args.out / variant
            validation = validate_bennett(_settings(args, variant))
            path = write_report(validation, folder)
            validations.append(validation)
            m = validation.metrics
            print(
                f"[{variant}] {'all targets met' if m['passed'] else 'targets missed (explained in the report)'}; "
                f"coupler diff {m['trajectories']['coupler_point']['max_abs_diff_m']:.3e} m, torque diff "
                f"{m['torque']['max_rel_diff']:.2e}; report: {path}",
                flush=True,
            )
    # A command-line boundary: every failure ends with its reason and exit code 2, and the reports
    # written so far stay (the summary of the variants done is still written).
    except Exception as error:  # noqa: BLE001 - reported, see above
        print(f"validation failed: {type(error).__name__}: {error}", file=sys.stderr)
        if len(validations) > 1 and args.command == "summary":
            write_summary(validations, args.out)
        return 2
    if args.command == "summary":
        print(f"summary: {write_summary(validations, args.out)}")
    return 0 if all(v.metrics["passed"] for v in validations) else 1


def _scene_report(scene: Path, basis: str, out: Path, max_minutes: float | None) -> int:
    from .exudyn_scene import validate_scene, write_scene_report

    try:
        validation = validate_scene(scene, basis, max_minutes)
    except Exception as error:  # noqa: BLE001 - command-line boundary: any failure is reported, exit code 2
        print(f"validation failed: {type(error).__name__}: {error}", file=sys.stderr)
        return 2
    path = write_scene_report(validation, out)
    m = validation.metrics
    state = "all targets met" if m["passed"] else "targets missed"
    if "stopped" in m:
        state = f"incomplete ({m['stopped']['reason']}; {m['outputs_compared']} of {m['outputs']} outputs compared)"
    print(f"[{validation.name}] {state}; report: {path}")
    return 0 if m["passed"] else 1


if __name__ == "__main__":
    sys.exit(main())
