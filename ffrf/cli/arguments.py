"""The command line's shared argument types and rules: whole numbers and numbers in a range as the files check them
(:func:`count_at_least`, :func:`number_in`, also used by ``python -m validation``), the output folder, and the
options and run-length check every linkage run (``bennett``, ``linkage``) shares."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from pathlib import Path

from ffrf.errors import FEInputError, SceneError
from ffrf.scenes.limits import MAX_OUTPUTS, MAX_TIME_STEPS, linkage_run_steps, steps_problem
from ffrf.scenes.scene_schema import PARAMETRIC_H_RANGE
from ffrf.system.drives import rpm

__all__ = [
    "count_at_least",
    "number_in",
    "positive_count",
    "element_edge",
    "output_folder",
    "configure_linkage_run",
    "check_run_length",
    "run_options",
]


def count_at_least(smallest: int, largest: int | None = None) -> Callable[[str], int]:
    """An argparse type: a whole number >= ``smallest`` (and <= ``largest``)."""

    def count(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = smallest - 1
        if value < smallest:
            raise argparse.ArgumentTypeError(f"must be a whole number >= {smallest}, got {text!r}")
        if largest is not None and value > largest:
            raise argparse.ArgumentTypeError(f"must be a whole number <= {largest:.3g}, got {text!r}")
        return value

    return count


def number_in(low: float, high: float, closed_low: bool = True, unit: str = "") -> Callable[[str], float]:
    """An argparse type: a finite number in ``[low, high]`` (``(low, high]`` without ``closed_low``), as a file key."""
    if math.isinf(high):
        bounds = f"{'>=' if closed_low else '>'} {low:g}{unit}"
    else:
        bounds = f"in {'[' if closed_low else '('}{low:g}, {high:g}]{unit}"

    def number(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a number {bounds}, got {text!r}") from None
        inside = (low <= value if closed_low else low < value) and value <= high
        if not (math.isfinite(value) and inside):
            raise argparse.ArgumentTypeError(f"must be a finite number {bounds}, got {text!r}")
        return value

    return number


#: A count of workers, threads, steps: a whole number >= 1.
positive_count = count_at_least(1)
#: An element edge (m) in the range the scene files allow for parametric links.
element_edge = number_in(*PARAMETRIC_H_RANGE, unit=" m")


def output_folder(path: Path) -> Path:
    """Create ``--out`` before the work, so that an unwritable folder fails at once, not after a long run."""
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise FEInputError(
            f"cannot write to --out {path} ({error.strerror}); give a folder you can write to"
        ) from error
    return path


def configure_linkage_run(parser: argparse.ArgumentParser) -> None:
    """Options of every linkage run: discretisation, mode, outputs, ParaView series, output folder."""
    # Defaults: the cheapest discretisation with the coupler path within 0.01 mm (docs/speed_vs_error.md).
    parser.add_argument("--h", type=element_edge, default=6e-3, help="maximum element edge in metres (paper: 0.002)")
    parser.add_argument("--order", type=int, choices=(1, 2), default=2, help="tetrahedron order (paper: 1)")
    parser.add_argument(
        "--modes", type=count_at_least(1), default=4, help="fixed-interface modes per link, >= 1 (paper: 32)"
    )
    parser.add_argument(
        "--joint-offsets",
        choices=("body", "marker"),
        default="body",
        help="joint point off the bore centre in the body frame (paper, Exudyn) or the bore's frame",
    )
    parser.add_argument(
        "--dt",
        type=number_in(0.0, math.inf, closed_low=False, unit=" s"),
        default=None,
        help="time step of a dynamic run (s); default: the drive turns 0.06 deg per step, at most 10 ms "
        "(10 ms at 1 rpm, where the coupler path is within 1e-9 m of shorter steps'; docs/speed_vs_error.md)",
    )
    parser.add_argument(
        "--outputs",
        type=count_at_least(2, MAX_OUTPUTS),
        default=961,
        help="output times over the run (961: every 0.375 deg; the energy balance, a Simpson "
        "integral over them, then closes to 2e-7)",
    )
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--quasi-static", dest="mode", action="store_const", const="quasi_static")
    mode.add_argument("--dynamic", dest="mode", action="store_const", const="dynamic")
    parser.set_defaults(mode="auto")
    parser.add_argument(
        "--stability",
        action="store_true",
        help="judge every equilibrium of a quasi-static run (squared frequencies of small vibrations, "
        "docs/formulation.md Eq. (B1)); writes stability.json and stability.png",
    )
    parser.add_argument(
        "--vtk-every",
        type=count_at_least(0),
        default=0,
        help="also write deformed meshes for ParaView (DIR/bennett.pvd) every N outputs (0: none)",
    )
    parser.add_argument(
        "--clearance-margin",
        type=number_in(0.0, math.inf, unit=" mm"),
        default=None,
        metavar="MM",
        help="clearance the links must keep from each other along the rigid motion, in mm (default 1; "
        "docs/formulation.md Eqs. (CL1)-(CL4)); a run whose links do not keep it exits with 3",
    )
    parser.add_argument(
        "--max-steps",
        type=count_at_least(1),
        default=MAX_TIME_STEPS,
        help=f"largest number of time steps (or equilibria) of the run (default {MAX_TIME_STEPS:.0e}, "
        "docs/bad_input.md): a longer run is refused with its estimated time unless this is raised",
    )
    parser.add_argument(
        "--out",
        type=Path,
        required=True,
        help="output directory (results.npz, metadata.json, assembly.vtu, coupler_deviation.png, driving_torque.png)",
    )


def check_run_length(args: argparse.Namespace) -> None:
    """Refuse, before building, a run of ``bennett`` or ``linkage`` longer than ``--max-steps``: both drive at 1 rpm
    after a 1 s ramp for one revolution (:class:`ffrf.scenes.linkage_description.LinkageOptions`)."""
    steps = linkage_run_steps(rpm(1.0), 1.0, 1.0, args.mode, args.dt)
    problem = steps_problem(steps, args.max_steps, "--max-steps N", " over the revolution")
    if problem is not None:
        raise SceneError(problem)


def run_options(args: argparse.Namespace) -> dict:
    """The run settings of :func:`configure_linkage_run`'s options (:func:`ffrf.cli.report.run_and_report`)."""
    return {
        "mode": args.mode,
        "outputs": args.outputs,
        "step": args.dt,
        "vtk_every": args.vtk_every,
        "stability": args.stability,
        "clearance_margin": None if args.clearance_margin is None else 1e-3 * args.clearance_margin,
    }
