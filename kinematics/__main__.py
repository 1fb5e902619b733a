"""Command line: ``python -m kinematics bennett [--alpha3-deg A] [--out DIR]`` and ``nearby --model M``.

``bennett`` prints the DH table, the joint axes as in the paper, the configuration curve and the
motion polynomial of the Bennett linkage, and writes the ideal coupler path (CSV, PNG and
JSON) to ``DIR``. With a misaligned base twist it reports that the rigid loop cannot move.
``nearby`` prints the isolated (rigid) assemblies of a Rational Linkages model near its motion
(:func:`kinematics.assemblies.nearby_assemblies`), and writes them as JSON with ``--json FILE``.
Bad input (a non-finite twist, too few points, an unwritable ``DIR``) is one line ``error: ...``
on stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from .assemblies import NearbyAssemblies, nearby_assemblies
from .bennett import PAPER_A, PAPER_ALPHA, BennettConditionError, BennettLinkage
from .mobility import rigid_mobility
from .rational_mechanism import MODELS, load_model, loop_from_mechanism, regular_start
from .single_loop import trace_motion


def _quaternion_text(q: np.ndarray) -> str:
    terms = []
    for value, unit in zip(q, ("", "i", "j", "k"), strict=True):
        if abs(value) > 1e-12:
            terms.append(f"{value:+.6g}{unit}")
    return " ".join(terms) if terms else "0"


def _dual_quaternion_text(coeffs: np.ndarray) -> str:
    return f"{_quaternion_text(coeffs[:4])} + eps({_quaternion_text(coeffs[4:])})"


def _print_bennett(linkage: BennettLinkage, out: Path, n: int) -> None:
    print("Joint axes in the home configuration (paper's embedding h = l - eps m, metres):")
    for i, line in enumerate(linkage.axes):
        point = ", ".join(f"{1e3 * c:.3f}" for c in line.point)
        print(f"  h{i} = {_dual_quaternion_text(line.to_dual_quaternion().coeffs)}   (through [{point}] mm)")
    k = linkage.coefficients
    print("Configuration curve: (t0, t1, t2, t3) = (" + ", ".join(f"{c:.6g} t" for c in k) + ")")
    print("Motion polynomial of the coupler (link 2) relative to the base, C(t) = (t - h0)(k1 t - h1):")
    for power, c in zip((2, 1, 0), linkage.motion_polynomial().coefficients, strict=True):
        print(f"  t^{power}: {_dual_quaternion_text(c)}")
    path = linkage.coupler_path(n=n)
    residual = linkage.closure_residual(linkage.parameter_from_joint(np.linspace(0, 2 * np.pi, n), joint=3))
    print(f"Loop closure along the motion: max {residual.translation.max():.2e} m, {residual.rotation.max():.2e} rad")
    out.mkdir(parents=True, exist_ok=True)
    np.savetxt(out / "coupler_path.csv", path, delimiter=",", header="x_m,y_m,z_m", comments="")
    from .plotting import plot_coupler_path

    fig, _ = plot_coupler_path(linkage, path)
    fig.savefig(out / "coupler_path.png", dpi=150, bbox_inches="tight")
    summary = {
        "a_m": list(linkage.a),
        "alpha_rad": list(linkage.alpha),
        "axes": [{"direction": line.direction.tolist(), "moment": line.moment.tolist()} for line in linkage.axes],
        "configuration_ratios": k.tolist(),
        "motion_polynomial": linkage.motion_polynomial().coefficients.tolist(),
        "coupler_point_m": linkage.coupler_point().tolist(),
    }
    (out / "kinematics.json").write_text(json.dumps(summary, indent=2))
    print(f"Wrote {out / 'coupler_path.png'}, {out / 'coupler_path.csv'} and {out / 'kinematics.json'}")


def _argument_problem(alpha3_deg: float, points: int) -> str | None:
    """What is wrong with the command line's numbers (None if nothing); argparse takes "nan" as a float."""
    if not np.isfinite(alpha3_deg):
        return f"--alpha3-deg {alpha3_deg} is not a finite angle; give the base twist in degrees, e.g. 90"
    if points < 4:  # the mobility scan of a misaligned loop samples points // 4 driver angles
        return f"--points {points}: sample the coupler path at 4 points or more (default 720)"
    return None


def _print_nearby(model: str, scale: float, result: NearbyAssemblies, seconds: float) -> None:
    print(
        f"{model} (scale {scale:g}): {result.starts} starts (seed {result.seed}, spread {result.spread:g} rad), "
        f"{result.converged} closed the loop, {result.on_motion} on the motion; {len(result.assemblies)} "
        f"assemblies off it ({len(result.isolated)} isolated) in {seconds:.1f} s"
    )
    if not result.assemblies:
        return
    print("  kind      rank  s_min/s_max  drive [deg]  max dphi [deg]  rms dphi [deg]  gap [mm]  gap [deg]  hits")
    for a in result.assemblies:
        print(
            f"  {a.kind:8s}  {a.rank:4d}  {a.smallest_singular:11.2e}  {np.degrees(a.driver_angle):11.2f}  "
            f"{np.degrees(a.distance_max):14.2f}  {np.degrees(a.distance_rms):14.2f}  {1e3 * a.gap_translation:8.3f}  "
            f"{np.degrees(a.gap_rotation):9.3f}  {a.hits:4d}"
        )
    print("  (drive: joint 0 at the nearest pose of the motion; gap: largest closure misfit on the straight path)")


def _nearby(args: argparse.Namespace) -> int:
    if not (np.isfinite(args.scale) and args.scale > 0.0 and np.isfinite(args.spread) and args.spread > 0.0):
        print(f"error: --scale {args.scale} and --spread {args.spread} must be positive numbers", file=sys.stderr)
        return 2
    if args.starts < 1 or args.poses < 8:
        print(f"error: --starts {args.starts} must be >= 1 and --poses {args.poses} >= 8", file=sys.stderr)
        return 2
    mechanism = load_model(args.model)
    loop = loop_from_mechanism(mechanism, scale=args.scale)
    clock = time.perf_counter()
    motion = trace_motion(loop, driver=0, n_poses=args.poses, start=regular_start(mechanism, loop))
    result = nearby_assemblies(motion, starts=args.starts, spread=args.spread, seed=args.seed)
    seconds = time.perf_counter() - clock
    _print_nearby(args.model, args.scale, result, seconds)
    if args.json is not None:
        summary = {
            "model": args.model,
            "scale": args.scale,
            "driver": 0,
            "poses": args.poses,
            "starts": result.starts,
            "seed": result.seed,
            "spread_rad": result.spread,
            "converged": result.converged,
            "on_motion": result.on_motion,
            "seconds": seconds,
            "assemblies": [a.as_dict() for a in result.assemblies],
        }
        try:
            args.json.write_text(json.dumps(summary, indent=2))
        except OSError as error:
            problem = f"cannot write --json {args.json} ({error.strerror}); give a file you can write"
            print(f"error: {problem}", file=sys.stderr)
            return 2
        print(f"Wrote {args.json}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m kinematics", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    bennett = sub.add_parser("bennett", help="the paper's Bennett linkage (or a misaligned variant)")
    bennett.add_argument("--alpha3-deg", type=float, default=90.0, help="twist of the base link (paper: 90, 91, 92)")
    bennett.add_argument("--out", type=Path, default=Path("out"), help="output folder")
    bennett.add_argument("--points", type=int, default=720, help="samples of the coupler path")
    nearby = sub.add_parser("nearby", help="isolated (rigid) assemblies of a Rational Linkages model near its motion")
    nearby.add_argument("--model", choices=MODELS, required=True, help="Rational Linkages model")
    nearby.add_argument("--scale", type=float, default=0.1, help="length scale of the model (its unit -> metres)")
    nearby.add_argument("--starts", type=int, default=200, help="perturbed starts")
    nearby.add_argument("--spread", type=float, default=1.0, help="perturbation size (rad, standard deviation)")
    nearby.add_argument("--seed", type=int, default=0, help="seed of the perturbations")
    nearby.add_argument("--poses", type=int, default=360, help="poses of the traced motion (one revolution of joint 0)")
    nearby.add_argument("--json", type=Path, default=None, help="write the assemblies to this JSON file")
    args = parser.parse_args(argv)
    if args.command == "nearby":
        return _nearby(args)
    problem = _argument_problem(args.alpha3_deg, args.points)
    if problem is not None:
        print(f"error: {problem}", file=sys.stderr)
        return 2

    a = np.array(PAPER_A)
    alpha = np.array(PAPER_ALPHA)
    alpha[3] = np.radians(args.alpha3_deg)
    print("DH parameters (paper's Table 'DH parameters of the 4R mechanism'):")
    print("  i   a_i [mm]   alpha_i [deg]   d_i [mm]")
    for i in range(4):
        print(f"  {i}   {1e3 * a[i]:8.3f}   {np.degrees(alpha[i]):13.3f}   {0.0:8.3f}")
    try:
        linkage = BennettLinkage(tuple(a), tuple(alpha))
    except BennettConditionError as error:
        print(f"Not a Bennett linkage: {error}")
        report = rigid_mobility(a, alpha, n_angles=args.points // 4)
        print(report.summary())
        return 0
    print(
        "Bennett conditions hold: a0 = a2, a1 = a3, alpha0 = alpha2, alpha1 = alpha3, a0/sin(alpha0) = a1/sin(alpha1)"
    )
    try:
        _print_bennett(linkage, args.out, args.points)
    except OSError as error:  # --out names a file, or a folder we may not write to
        print(
            f"error: cannot write to --out {args.out} ({error.strerror}); give a folder you can write to",
            file=sys.stderr,
        )
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
