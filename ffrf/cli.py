"""Command line interface: ``python -m ffrf <subcommand> ...``.

Subcommands register themselves in :data:`SUBCOMMANDS` (name -> (configure, run)),
so others can add theirs without touching the existing ones.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from ffrf.fe.fe_model import FEModel
from ffrf.fe.interfaces import interface_from_group
from ffrf.fe.materials import PLA
from ffrf.geometry.link_geometry import LinkDesign, mesh_link
from ffrf.mesh.tet_mesh import quality_summary, write_vtu
from ffrf.paper.axes import bennett_axes, paper_link_axes
from ffrf.scenes.limits import MAX_OUTPUTS, MAX_TIME_STEPS, linkage_run_steps, steps_problem
from ffrf.scenes.scene_cache import CACHE_DIR_VARIABLE
from ffrf.scenes.scene_schema import PARAMETRIC_H_RANGE

from .errors import FEInputError, Interrupted, NewtonDivergence, SceneError, StaticDivergence

__all__ = ["main", "SUBCOMMANDS", "bennett_axes", "link_summary"]

logger = logging.getLogger(__name__)


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


def _output_folder(path: Path) -> Path:
    """Create ``--out`` before the work, so that an unwritable folder fails at once, not after a long run."""
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise FEInputError(
            f"cannot write to --out {path} ({error.strerror}); give a folder you can write to"
        ) from error
    return path


def _configure_mesh(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--link", type=int, choices=(0, 1, 2, 3), required=True, help="link index, 0 = base")
    parser.add_argument("--alpha3-deg", type=float, default=90.0, help="base-link twist alpha_3 in degrees")
    parser.add_argument("--h", type=_element_edge, default=2e-3, help="maximum element edge length in metres")
    parser.add_argument("--order", type=int, choices=(1, 2), default=1, help="tetrahedron order")
    parser.add_argument("--out", type=Path, required=True, help="output directory")


def _run_mesh(args: argparse.Namespace) -> int:
    first, second, names = paper_link_axes(args.link, bennett_axes(args.alpha3_deg))
    stem = f"link{args.link}"
    mesh, geometry = mesh_link(
        first, second, h=args.h, design=LinkDesign(), names=names, mount=args.link == 0, name=stem
    )
    model = FEModel.from_tet_mesh(mesh, PLA, args.order)
    interfaces = [interface_from_group(model, group) for group in sorted(mesh.groups)]
    _output_folder(args.out)
    vtu = write_vtu(args.out / f"{stem}.vtu", mesh)
    summary = link_summary(model, geometry, interfaces)
    summary.update(link=args.link, alpha3_deg=args.alpha3_deg, h_m=args.h, vtu=vtu.name)
    (args.out / f"{stem}.json").write_text(json.dumps(summary, indent=2))
    print(
        f"{stem}: {summary['n_tetrahedra']} tets, {summary['n_nodes']} nodes, mass {summary['mass_kg']:.5f} kg, "
        f"min quality {summary['quality']['min_quality']:.3f} -> {args.out}"
    )
    return 0


def _configure_bennett(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--variant",
        choices=("rigid", "pla", "pla1", "pla2"),
        default="pla",
        help="paper's variant: rigid, PLA, PLA with alpha_3 = 91 or 92 deg",
    )
    _configure_linkage_run(parser)


def _configure_linkage_run(parser: argparse.ArgumentParser) -> None:
    """Options of every linkage run: discretisation, mode, outputs, ParaView series, output folder."""
    # Defaults: the cheapest discretisation with the coupler path within 0.01 mm (docs/speed_vs_error.md).
    parser.add_argument("--h", type=_element_edge, default=6e-3, help="maximum element edge in metres (paper: 0.002)")
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


class _StopRequest:
    """SIGINT (Ctrl-C) and SIGTERM during a command. Inside :meth:`deferred` (a run, the writing of its results) the
    first one is noted and the run stops at its next step (the progress callback, :meth:`check`, raises
    :class:`Interrupted`, and the solver hands over what it computed: issue #32); elsewhere, or a second time, it raises
    :class:`Interrupted` at once. :func:`main` prints one line and exits with 130 (128 + SIGINT, as shells do)."""

    def __init__(self) -> None:
        self.signal: str | None = None
        self.deferring = False

    def handle(self, number: int, frame: object) -> None:
        name = signal.Signals(number).name
        if self.signal is None and self.deferring:
            self.signal = name
            return
        raise Interrupted(f"interrupted by {name}")

    def check(self, where: str = "") -> None:
        """Raise :class:`Interrupted` if a stop was asked for (``where``: what the message adds)."""
        if self.signal is not None:
            raise Interrupted(f"interrupted by {self.signal}{where}")

    @contextmanager
    def deferred(self) -> Iterator[None]:
        before, self.deferring = self.deferring, True
        try:
            yield
        finally:
            self.deferring = before

    @contextmanager
    def installed(self) -> Iterator[None]:
        """The handlers of SIGINT and SIGTERM for one command (main thread only: Python allows no other)."""
        self.signal, self.deferring = None, False
        if threading.current_thread() is not threading.main_thread():
            yield
            return
        before = {number: signal.signal(number, self.handle) for number in (signal.SIGINT, signal.SIGTERM)}
        try:
            yield
        finally:
            for number, handler in before.items():
                signal.signal(number, handler)


_STOP = _StopRequest()


def _progress_printer():
    last = [-1]

    def show(t: float, t_end: float) -> None:
        try:
            _STOP.check()  # a Ctrl-C noted during the run stops it here, between two steps
        except Interrupted:
            print(file=sys.stderr)  # end the progress bar's line
            raise
        percent = int(100 * t / t_end) if t_end > 0 else 100
        if percent != last[0]:
            last[0] = percent
            bar = "#" * (percent // 4)
            print(f"\r  [{bar:<25}] {percent:3d} %  t = {t:7.2f} s", end="", file=sys.stderr, flush=True)
            if percent >= 100:
                print(file=sys.stderr)

    return show


def _run_and_report(
    scene, out: Path, label: str, started: float, options: dict, paper: str = "", then: Callable | None = None
) -> int:
    """Run a built linkage scene (:mod:`ffrf.scenes.linkage_run`) and write what ``bennett`` and ``linkage`` write.

    ``options``: ``mode`` (``auto``, ``quasi_static``, ``dynamic``), ``outputs``, ``step`` (s), ``vtk_every``;
    ``then(result)``: more to do with a run that did not stop (``linkage --reach``)."""
    import time

    from ffrf.output.assembly_stress import scene_assembly_stress, write_assembly_vtu
    from ffrf.output.linkage_figures import plot_coupler_deviation, plot_driving_torque
    from ffrf.paper.figures import VARIANT_COLORS
    from ffrf.scenes.linkage_run import choose_mode, run_linkage, write_results

    auto = options["mode"] == "auto"
    mode, ratio = choose_mode(scene) if auto else (options["mode"], float("nan"))
    if options.get("stability", False):
        if not auto and mode != "quasi_static":
            raise SceneError("stability is judged at equilibria: run quasi-statically (drop --dynamic / mode)")
        mode = "quasi_static"
    print(
        f"Running {mode.replace('_', '-')} over {scene.t_end:.1f} s of drive"
        + (f" (drive time scale / longest link period = {ratio:.0f})" if auto else ""),
        file=sys.stderr,
    )
    try:
        with _STOP.deferred():
            result = run_linkage(
                scene,
                mode=mode,
                n_outputs=options["outputs"],
                step=options["step"],
                progress=_progress_printer(),
                stability=options.get("stability", False),
            )
        stopped = None
    except (StaticDivergence, NewtonDivergence, Interrupted) as error:  # write what was computed, then say so
        if not isinstance(error, Interrupted):  # (the progress bar ended its line)
            print(file=sys.stderr)  # end the progress bar's line
        if error.partial is None:
            raise
        result, stopped = error.partial, error
    clearance = scene.clearance()
    result.metadata["clearance"] = {
        "summary": clearance.summary(),
        "collisions": [
            {"links": [a, b], "clearance_m": d, "drive_angle_rad": angle} for a, b, d, angle in clearance.collisions
        ],
        "contact_m": clearance.contact,
    }
    with _STOP.deferred():
        write_results(result, out)
    if isinstance(stopped, Interrupted):  # the user asked to stop: the results so far, no figures
        end = result.time[-1]
        raise Interrupted(
            f"{stopped}: the results up to t = {end:.6g} s (drive angle {np.degrees(scene.drive_angle(end)):.4g} deg) "
            f"are in {out} (metadata.json: stopped)"
        )
    _STOP.check(f" after the run: its complete results are in {out}, without figures")
    if options["vtk_every"] > 0:
        from ffrf.output.paraview import write_time_series

        pvd = write_time_series(
            out,
            [(link.mesh_model, link.reduction.basis) for link in scene.links],
            [scene.system.block(k) for k in range(len(scene.links))],
            result.time,
            result.q,
            every=options["vtk_every"],
            name="linkage",
        )
        print(f"ParaView series: {pvd}", file=sys.stderr)
    assembly = result.assembly
    assert assembly is not None  # run_linkage always records the assembled state
    write_assembly_vtu(out / "assembly.vtu", scene, assembly)
    plot_coupler_deviation({label: result}, out / "coupler_deviation.png", colors=VARIANT_COLORS)
    plot_driving_torque({label: result}, out / "driving_torque.png", colors=VARIANT_COLORS)
    if "stability" in result.metadata:
        _write_stability(result, out)
        if result.critical is not None:
            critical = result.critical
            stress = scene_assembly_stress(scene, critical.q, critical.multipliers)
            where = write_assembly_vtu(out / "stability_critical.vtu", scene, stress, {"critical_mode": critical.mode})
            print(
                f"critical pose ({critical.where}, drive angle {np.degrees(scene.drive_angle(critical.t)):.4g} deg, "
                f"squared frequency {critical.squared_frequency:.4g} rad^2/s^2) with its mode: {where}"
            )
    summary = result.summary()
    print(
        f"{label}: max coupler deviation from the ideal path "
        f"{1e3 * summary['max_coupler_deviation_m']:.4f} mm at the same drive angle, "
        f"{1e3 * summary['max_coupler_distance_to_path_m']:.4f} mm to the closest point"
        + (f" (paper: below {paper} mm)" if paper else "")
        + f"; max driving torque {1e3 * summary['max_abs_driving_torque_Nm']:.3f} N mm; "
        f"largest constraint residual {summary['max_constraint_residual']:.1e}; energy balance closed to "
        f"{summary['energy_balance_relative']:.1e} of its energy scale (Eq. (C2)); wall time "
        f"{time.perf_counter() - started:.1f} s -> {out}"
    )
    estimate = result.metadata.get("step_error_estimate")
    if estimate is not None:
        print(
            f"time steps of {1e3 * result.metadata['step']:g} ms"
            + (
                f" ({estimate['steps']} steps, down to {1e3 * estimate['shortest_step_s']:.3g} ms where a joint turns "
                "fast, Eq. (G7))"
                if "steps" in estimate and estimate["shortest_step_s"] < 0.999 * result.metadata["step"]
                else ""
            )
            + "; local error estimate of the bodies' positions per "
            f"step (Eq. (G5)): median {estimate['median_m']:.1e} m, largest {estimate['largest_m']:.1e} m "
            f"at t = {estimate['largest_at_s']:.3g} s"
        )
    for pose in result.metadata.get("near_dead_poses", []):
        print(
            f"near-dead pose at drive angle {pose['drive_angle_deg']:.4g} deg: joint {pose['joint']} turns "
            f"{pose['ratio']:.3g} times faster than the driver; the coupler leaves the rigid motion by "
            f"{1e3 * pose['max_coupler_deviation_near_m']:.3g} mm within 2 deg of it "
            f"({1e3 * pose['max_coupler_deviation_elsewhere_m']:.3g} mm elsewhere): the rigid motion is "
            "ill-conditioned there (docs/hard_cases.md)"
        )
    print(f"clearance of the links along the rigid motion: {clearance.summary()}")
    misfit = scene.misfit_degrees > 0.0
    print("assembled state (gravity" + (", misfit" if misfit else "") + f"; {out / 'assembly.vtu'}):")
    for link in assembly.links:
        print("  " + link.line())
    if stopped is not None:
        end = result.time[-1]
        print(
            f"error: the run stopped: {stopped} (the results up to t = {end:.6g} s, drive angle "
            f"{np.degrees(scene.drive_angle(end)):.4g} deg, are in {out})",
            file=sys.stderr,
        )
        return 1
    if then is not None:
        then(result)
    return _report_verification(result.metadata.get("verification"))


def _report_verification(verification: dict | None) -> int:
    """Print the run's warnings and, as the last line, its verdict (``verification`` of ``metadata.json``,
    :mod:`ffrf.output.verification`); exit status 0 when the run verified itself, 3 when a check failed (the
    results are written all the same, and ``verification.reasons`` names what failed)."""
    if verification is None:
        return 0
    for warning in verification["warnings"]:
        print(f"warning: {warning}")
    print(verification["verdict"])
    return 0 if verification["verified"] else 3


def _write_stability(result, out: Path) -> None:
    """``stability.json`` (per output: time, drive angle, squared frequencies of Eq. (B1)) and ``stability.png``."""
    from ffrf.output.linkage_figures import plot_stability

    values = result.sensors["stability_squared_frequencies"]
    angle = result.sensors["drive_angle"]
    table = {
        "summary": result.metadata["stability"],
        "time_s": result.time.tolist(),
        "drive_angle_rad": angle.tolist(),
        "squared_frequencies_rad2_per_s2": values.tolist(),
    }
    (out / "stability.json").write_text(json.dumps(table, indent=1))
    s = result.metadata["stability"]
    folds = [snap["drive_angle_deg"] for snap in s.get("snaps", [])]
    plot_stability(angle, values, result.sensors["driving_torque"], out / "stability.png", folds)
    print(
        f"stability: smallest squared frequency {s['min_squared_frequency']:.4g} rad^2/s^2 "
        f"({s['min_frequency_hz']:.3g} Hz) at drive angle {s['at_drive_angle_deg']:.4g} deg; "
        f"{s['unstable_poses']} unstable pose(s) -> {out / 'stability.json'}"
    )
    for snap in s.get("snaps", []):
        links = sorted(snap["critical_mode_body_shares"].items(), key=lambda item: -item[1])[:2]
        jump = (
            f"the linkage jumps to another branch, coupler point {1e3 * snap['coupler_jump_m']:.4g} mm away, "
            f"releasing {1e3 * snap['energy_released_J']:.4g} mJ"
            if snap["landed"]
            else "no stable equilibrium to land on was found along the traced path (run it dynamically)"
        )
        print(
            f"snap: the equilibrium path folds at drive angle {snap['drive_angle_deg']:.4g} deg "
            f"(driving torque {1e3 * snap['driving_torque_Nm']:.4g} N mm); {jump}; critical mode mostly in "
            + ", ".join(f"{name} ({100 * share:.0f} %)" for name, share in links)
        )


def _run_bennett(args: argparse.Namespace) -> int:
    import time

    from ffrf.paper.bennett_scene import build_bennett, paper_max_coupler_deviation

    started = time.perf_counter()
    _check_run_length(args)
    _output_folder(args.out)
    print(
        f"Building the {args.variant} Bennett scene: 4 links, h = {1e3 * args.h:g} mm, P{args.order}, "
        f"{args.modes} fixed-interface modes per link ...",
        file=sys.stderr,
    )
    scene = build_bennett(
        args.variant, h=args.h, order=args.order, n_modes=args.modes, joint_offsets=args.joint_offsets
    )
    return _run_and_report(
        scene, args.out, args.variant, started, _options(args), paper_max_coupler_deviation(args.variant)
    )


def _check_run_length(args: argparse.Namespace) -> None:
    """Refuse, before building, a run of ``bennett`` or ``linkage`` longer than ``--max-steps``: both drive at 1 rpm
    after a 1 s ramp for one revolution (:class:`ffrf.scenes.linkage_description.LinkageOptions`)."""
    from ffrf.system.drives import rpm

    steps = linkage_run_steps(rpm(1.0), 1.0, 1.0, args.mode, args.dt)
    problem = steps_problem(steps, args.max_steps, "--max-steps N", " over the revolution")
    if problem is not None:
        raise SceneError(problem)


def _options(args: argparse.Namespace) -> dict:
    return {
        "mode": args.mode,
        "outputs": args.outputs,
        "step": args.dt,
        "vtk_every": args.vtk_every,
        "stability": args.stability,
    }


def _bore_error(text: str) -> dict:
    """``JOINT:LINK:TWIST_DEG[:OFFSET_MM]`` -> a linkage file's bore error (offset in m)."""
    parts = text.split(":")
    try:
        if len(parts) not in (3, 4):
            raise ValueError
        error = {"joint": int(parts[0]), "link": int(parts[1]), "twist_deg": float(parts[2])}
        return error | ({"offset": float(parts[3]) * 1e-3} if len(parts) == 4 else {})
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"bore error {text!r}: write JOINT:LINK:TWIST_DEG or JOINT:LINK:TWIST_DEG:OFFSET_MM, e.g. 3:0:1.0"
        ) from None


def _configure_linkage(parser: argparse.ArgumentParser) -> None:
    from kinematics.rational_mechanism import MODELS

    parser.add_argument("--model", choices=MODELS, required=True, help="a mechanism of rational_linkages.models")
    from ffrf.scenes.linkage_description import LINKAGE_VARIANTS

    parser.add_argument("--variant", choices=tuple(LINKAGE_VARIANTS), default="pla", help="link material")
    parser.add_argument(
        "--scale",
        type=number_in(0.0, math.inf, closed_low=False),
        default=0.1,
        help="length scale of the model (its unit -> metres)",
    )
    parser.add_argument("--driver", type=count_at_least(0), default=0, help="driven joint")
    parser.add_argument(
        "--design-points",
        action="store_true",
        help="attach the links where the model's design attaches them (its collision-free connection points)",
    )
    parser.add_argument(
        "--bore-error",
        type=_bore_error,
        action="append",
        default=[],
        metavar="JOINT:LINK:TWIST_DEG[:OFFSET_MM]",
        help="as built: joint JOINT's bore on link LINK turned about the link's common normal (repeatable)",
    )
    parser.add_argument(
        "--reach",
        action="store_true",
        help="after the run: the energy barrier from the motion to each isolated assembly of the rigid loop, by the "
        "string method (docs/stability.md; minutes per assembly); writes reach.json",
    )
    parser.add_argument(
        "--reach-images",
        type=count_at_least(3),
        default=21,
        help="images of the string between the motion and an assembly, both ends included (default 21)",
    )
    _configure_linkage_run(parser)


def _run_linkage(args: argparse.Namespace) -> int:
    import time

    from ffrf.scenes.linkage_description import LINKAGE_VARIANTS
    from ffrf.scenes.linkage_file import linkage_options, load_linkage

    started = time.perf_counter()
    if args.reach and args.bore_error:
        raise SceneError(
            "--reach measures the nominal linkage (the isolated assemblies are the nominal loop's): drop --bore-error"
        )
    if args.reach and args.variant == "rigid":
        raise SceneError("--reach measures strain energy, which rigid links do not store: use --variant pla")
    _check_run_length(args)
    material = LINKAGE_VARIANTS[args.variant]
    document = {  # the linkage file these options stand for (ffrf.scenes.linkage_file)
        "linkage": {
            "name": f"{args.model} {args.variant}",
            "model": args.model,
            "scale": args.scale,
            "driver": args.driver,
            "material": {"E": material.E, "nu": material.nu, "rho": material.rho, "name": material.name}
            | ({} if material.strength is None else {"strength": material.strength}),
            "h": args.h,
            "order": args.order,
            "modes": args.modes,
            "bore_errors": args.bore_error,
            "design_points": args.design_points,
        },
        "scene": {"joint_offsets": args.joint_offsets},
    }
    linkage_options(document, where="python -m ffrf linkage")  # the file's checks (bore errors ...) before --out
    _output_folder(args.out)
    print(
        f"Building {args.model} ({args.variant}, scale {args.scale:g}): h = {1e3 * args.h:g} mm, P{args.order}, "
        f"{args.modes} fixed-interface modes per link ...",
        file=sys.stderr,
    )
    scene = load_linkage(document, where="python -m ffrf linkage")
    (args.out / "linkage.json").write_text(json.dumps(document, indent=2))
    then = (lambda result: _write_reach(scene, result, args.out, args.reach_images)) if args.reach else None
    return _run_and_report(scene, args.out, f"{args.model} {args.variant}", started, _options(args), then=then)


def _write_reach(scene, result, out: Path, images: int) -> None:
    """``reach.json``: per isolated assembly of the nominal loop, the energy barrier from the motion
    (:func:`ffrf.scenes.linkage_reach.reach_isolated`) against the drive's work of ``result`` and PLA's strength."""
    import time

    from ffrf.fe.materials import PLA_TENSILE_STRENGTH
    from ffrf.scenes.linkage_reach import ReachOptions, drive_work, isolated_assemblies, reach_isolated

    started = time.perf_counter()
    work = drive_work(result.sensors["driving_torque"], result.sensors["drive_angle"])
    nearby = isolated_assemblies(scene)
    print(
        f"reach: {len(nearby.isolated)} isolated assemblies of the rigid loop near its motion; the string method "
        f"({images} images) to each ...",
        file=sys.stderr,
    )

    def show(iteration: int, residual: float) -> None:
        if iteration % 100 == 0:
            print(f"\r  iteration {iteration}, residual {residual:.2e} N m", end="", file=sys.stderr, flush=True)

    reaches = reach_isolated(
        scene,
        result.assembly.q,
        nearby.isolated,
        work["work_J"],
        PLA_TENSILE_STRENGTH,
        ReachOptions(images=images),
        show,
    )
    print(file=sys.stderr)
    table = {
        "model": scene.name,
        "drive": {**work, "compared_with": "work_J: the drive's work over the run's last revolution where it drives"},
        "strength_pa": PLA_TENSILE_STRENGTH,
        "strength_source": "PLA at break, NatureWorks Ingeo 4043D data sheet (ffrf.fe.materials.PLA_TENSILE_STRENGTH)",
        "nearby": {
            "starts": nearby.starts,
            "converged": nearby.converged,
            "on_motion": nearby.on_motion,
            "isolated": len(nearby.isolated),
        },
        "assemblies": [r.as_dict() for r in reaches],
        "seconds": time.perf_counter() - started,
    }
    (out / "reach.json").write_text(json.dumps(table, indent=1))
    for k, r in enumerate(reaches):
        print(
            f"reach of isolated assembly {k} ({np.degrees(r.assembly.distance_rms):.3g} deg RMS from the motion): "
            f"barrier {1e3 * r.barrier:.4g} mJ (straight path {1e3 * r.straight_barrier:.4g} mJ), "
            f"{r.work_ratio:.3g} of the drive's work over a revolution, {1e3 * work['work_J']:.4g} mJ: {r.verdict}; "
            f"largest von Mises stress on the way {1e-6 * r.peak_stress:.3g} MPa, {r.stress_ratio:.3g} of PLA's "
            f"strength" + ("" if r.path.converged else f" (string not converged: residual {r.path.residual:.2e} N m)")
        )
    print(f"-> {out / 'reach.json'}")


def _configure_run(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", type=Path, help="scene file (TOML), see ffrf.scenes.scene_file")
    parser.add_argument("--out", type=Path, required=True, help="output directory (results.npz, metadata.json)")
    parser.add_argument(
        "--stability",
        action="store_true",
        help="as stability = true in the scene: judge every equilibrium of a quasi-static run (Eq. (B1)) and go on "
        "past folds (Eq. (S6)); writes stability.json and stability_critical.vtu",
    )


def _run_scene_file(args: argparse.Namespace) -> int:
    import time

    from ffrf.scenes.linkage_scene import LinkageScene
    from ffrf.scenes.scene_file import load_scene, run_scene

    started = time.perf_counter()
    scene = load_scene(args.scene)
    if args.stability:
        if scene.settings.get("mode", "auto" if isinstance(scene, LinkageScene) else "dynamic") == "dynamic":
            raise SceneError('--stability judges equilibria: set mode = "quasi_static" in the scene file')
        scene = replace(scene, settings={**scene.settings, "stability": True})
    out = _output_folder(args.out)  # after the scene's checks: a refused scene leaves no folder behind
    if isinstance(scene, LinkageScene):  # a linkage file: reported as the built-in linkages are
        s = scene.settings
        options = {
            "mode": s.get("mode", "auto"),
            "outputs": s.get("outputs", 241),
            "step": s.get("step"),
            "vtk_every": 0,
            "stability": s.get("stability", False),
        }
        return _run_and_report(scene, out, scene.name, started, options)
    print(
        f"Scene {scene.name!r}: {len(scene.bodies)} bodies, {len(scene.system.constraints)} joints, "
        f"{scene.system.n_coordinates} coordinates",
        file=sys.stderr,
    )
    with _STOP.deferred():
        metadata = run_scene(scene, out, progress=_progress_printer())
    _STOP.check(f" after the run: its complete results are in {out}")
    for snap in metadata.get("stability", {}).get("snaps", []):
        released = snap["energy_released_J"]
        print(
            f"snap: the equilibrium path folds at t = {snap['time_s']:.6g} s; "
            + (f"it lands on another branch, releasing {released:.4g} J" if snap["landed"] else "no landing found")
        )
    print(f"{scene.name}: wall time {metadata['wall_time_s']:.1f} s -> {args.out}")
    return _report_verification(metadata.get("verification"))


def _configure_study(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("study", type=Path, help="study file (TOML), see ffrf.studies.spec and docs/studies.md")
    parser.add_argument("--out", type=Path, required=True, help="output folder (rows/*.parquet, report.md)")
    parser.add_argument(
        "--scheduler", help="address of a Dask scheduler, e.g. tcp://host:8786 (default: a local cluster)"
    )
    parser.add_argument(
        "--workers", type=_positive_count, help="worker processes of the local cluster (default: cores)"
    )
    parser.add_argument("--no-report", action="store_true", help="do not write report.md after the run")


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


_positive_count = count_at_least(1)
_element_edge = number_in(*PARAMETRIC_H_RANGE, unit=" m")


def _run_study(args: argparse.Namespace) -> int:
    from ffrf.paper.bennett_scene import STUDY_BASES
    from ffrf.studies.spec import load_study

    study = load_study(args.study, STUDY_BASES)  # checked before any worker starts
    if args.scheduler is not None and args.workers is not None:
        raise SceneError("--workers sizes the local cluster; a scheduler (--scheduler) has its own workers")
    out = _output_folder(args.out)
    from ffrf.studies.report import write_report
    from ffrf.studies.runner import run_study

    try:
        run = run_study(study, out, scheduler=args.scheduler, workers=args.workers)
    except Interrupted as error:  # the rows of the finished variants are written (run_study's finally)
        message = f"{error}: the finished variants' rows are in {out}; the same command runs the rest"
        raise Interrupted(message) from None
    print(
        f"{study.name}: {run.design} variants, {run.skipped} finished before, {run.ok} ok and {run.failed} failed "
        f"now, {run.lost} lost (a rerun runs them); {run.wall_time_s:.1f} s -> {out}"
    )
    if not args.no_report:
        print(f"report: {write_report(out)}")
    return 1 if run.lost else 0


def _configure_study_report(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("folder", type=Path, help="a study's output folder (python -m ffrf study ... --out FOLDER)")


def _run_study_report(args: argparse.Namespace) -> int:
    from ffrf.studies.report import write_report

    if not (args.folder / "study.json").is_file():
        raise SceneError(f"{args.folder} holds no study (no study.json); give the --out folder of python -m ffrf study")
    try:
        path = write_report(args.folder)
    except FileNotFoundError as error:
        raise SceneError(str(error)) from error
    print(f"report: {path}")
    return 0


def _configure_warmup(parser: argparse.ArgumentParser) -> None:
    """No options: what it compiles is what a default run uses."""


def _run_warmup(args: argparse.Namespace) -> int:
    """Compile the numba kernels the main job uses, once after install (numba caches them on disk, next to the
    sources): a coarse Bennett scene through a few quasi-static equilibria. Kernels do not depend on the mesh or the
    number of modes, so the default scene's runs then load them. The dynamic solver's kernels (``--dynamic``, the
    validation's dynamic window) are left to their first use: the main job never calls them (issue #22)."""
    import time

    from ffrf.paper.bennett_scene import build_bennett
    from ffrf.scenes.linkage_run import run_linkage

    print(
        "Compiling the solver's kernels (once after install; later runs load them from numba's cache)", file=sys.stderr
    )
    started = time.perf_counter()
    scene = build_bennett("pla", h=0.012, order=1, n_modes=2)
    steps = (
        (
            "quasi-static and stability kernels",
            lambda: run_linkage(scene, "quasi_static", 3, t_end=0.2, stability=True),
        ),
    )
    for k, (name, step) in enumerate(steps, start=1):
        began = time.perf_counter()
        print(f"  [{k}/{len(steps)}] {name} ...", end="", file=sys.stderr, flush=True)
        step()
        print(f" {time.perf_counter() - began:.1f} s", file=sys.stderr)
    print(f"kernels ready in {time.perf_counter() - started:.1f} s", file=sys.stderr)
    return 0


SUBCOMMANDS: dict[str, tuple[str, Callable[[argparse.ArgumentParser], None], Callable[[argparse.Namespace], int]]] = {
    "warmup": (
        "compile the solver's kernels once after install (the main job's first step)",
        _configure_warmup,
        _run_warmup,
    ),
    "mesh": ("mesh one Bennett link and write .vtu + JSON summary", _configure_mesh, _run_mesh),
    "run": ("run a scene file (TOML) built from your own meshes", _configure_run, _run_scene_file),
    "bennett": (
        "simulate the paper's flexible Bennett linkage and write its sensors",
        _configure_bennett,
        _run_bennett,
    ),
    "linkage": (
        "simulate a flexible single-loop linkage of Rational Linkages (4R, 6R) and write its sensors",
        _configure_linkage,
        _run_linkage,
    ),
    "study": (
        "run a tolerance or design study of many linkage variants on Dask (docs/studies.md)",
        _configure_study,
        _run_study,
    ),
    "study-report": (
        "write report.md of a study's rows (percentiles, sensitivities)",
        _configure_study_report,
        _run_study_report,
    ),
}


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m ffrf", description="In-house flexible multibody solver (FFRF)")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress")
    parser.add_argument(
        "--blas-threads",
        type=_positive_count,
        default=1,
        help="threads of the BLAS library (default 1: our dense matrices are small; bench/blas_threads.py)",
    )
    parser.add_argument(
        "--no-cache",
        action="store_true",
        help=f"build meshes, FE models and reductions afresh, not from the disk cache (as {CACHE_DIR_VARIABLE}=off)",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    for name, (help_text, configure, _run) in SUBCOMMANDS.items():
        configure(sub.add_parser(name, help=help_text))
    args = parser.parse_args(argv)
    if args.no_cache:  # in the environment: every scene cache reads it, also those of the workers a study starts
        os.environ[CACHE_DIR_VARIABLE] = "off"
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING)
    try:
        if getattr(args, "stability", False) and getattr(args, "mode", None) == "dynamic":
            raise SceneError("stability is judged at equilibria: run quasi-statically (drop --dynamic)")
        with threadpool_limits(limits=args.blas_threads, user_api="blas"), _STOP.installed():
            return SUBCOMMANDS[args.command][2](args)
    except Interrupted as exc:  # SIGINT or SIGTERM: one line, what was computed is written (_StopRequest)
        print(exc, file=sys.stderr)
        return 130
    except FEInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except (StaticDivergence, NewtonDivergence) as exc:  # not bad input: the model's path ends (a fold, a snap)
        print(f"error: the run stopped: {exc}", file=sys.stderr)
        return 1
