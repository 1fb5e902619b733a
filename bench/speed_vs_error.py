"""Speed against error for the Bennett PLA scene, ours and Exudyn's on the same points (issue 9).

Two sweeps, both solvers on every point (unless a point says ``ours``) in the same run:

* **Quasi-static revolution** (``--qs-points order,h,modes``): both solvers build (ours: mesh,
  M, K, Craig-Bampton; Exudyn: its Craig-Bampton on our matrices) and run the paper's 1 rpm
  ramp + revolution quasi-statically (ours: static assembly + equilibria; Exudyn: its static
  assembly + one ``SolveStatic`` sweep) at ``--outputs`` drive angles. Errors against the
  quasi-static run of the reference discretisation at the same drive angles.
* **Dynamic window** (``--dyn-points order,h,modes,step,rho[,ours]``): generalized-alpha (index 3,
  same step and spectral radius in both) from each solver's own static assembly at rest over
  ``--window`` s (default 1.5 s: the 1 s cosine ramp of the drive, where inertia matters most,
  and 0.5 s at full speed after the ramp's jerk). Errors at every step against the *dynamic
  reference*: the reference discretisation with ``--ref-step`` (converged by halving: the run
  with twice the step is compared and its difference printed and stored). Also recorded per
  dynamic point: the error against the quasi-static reference on the window
  (``coupler_error_qs_m``), and quasi-static runs on the window (``--dyn-qs-points``) are scored
  against the dynamic reference: how wrong the quasi-static model is while the drive ramps.

Recorded per point and solver: ``setup_s`` (ours: mesh, FE matrices, reduction, scene; Exudyn:
its Craig-Bampton on our matrices and building the twin; the mesh and M, K it borrows from us are
not counted, so its totals are lower bounds), ``integration_s`` (static assembly + the
quasi-static sweep or the time integration; ``assembly_s`` separately), ``peak_mem_mb`` (rise of
the process's resident-set high-water mark, ``VmHWM``, over its resident set at the start of that
solver's part of the point, after returning freed heap to the system (``malloc_trim``) and
resetting the mark (``/proc/self/clear_refs``): everything resident, numpy, numba and Exudyn's
C++ included; the scene shared with Exudyn counts for ours only), ``peak_rss_mb`` (the absolute
high-water mark), ``coupler_error_m`` (largest distance of the coupler point from the
reference's at the same time) and ``torque_error_rel`` (largest driving-torque difference
relative to the reference's largest torque).

Reference: the Richardson extrapolation (order ``--richardson-order`` in h, 1.91 as observed from
P2 at 6, 4 and 3 mm) of quadratic tetrahedra at 4 mm (``--reference 2,0.004,32``) and 3 mm
(``--fine-reference 2,0.003,32``), 32 fixed-interface modes per link (64 change the quasi-static
path by 1e-14 m). The 4 mm run's distance from it is stored as the reference's own error
(``reference.json``); ``--fine-reference ''`` uses the 4 mm run alone. The dynamic reference
takes ``--ref-step`` (2.5e-4 s), checked against twice the step. ``docs/speed_vs_error.md``
has the numbers.

Output: ``DIR/results.json`` (a list of points: ``solver``, ``sweep`` (``quasi_static`` or
``dynamic_window``), ``mode``, ``order``, ``h``, ``modes``, ``step``, ``rho_inf``, ``t_end``,
``setup_s``, ``integration_s``, ``assembly_s``, ``peak_mem_mb``, ``peak_rss_mb``,
``coupler_error_m``, ``torque_error_rel`` and for dynamic points ``coupler_error_qs_m``),
``DIR/reference.json`` (the reference's checks), ``DIR/pareto_quasi_static.png``,
``DIR/pareto_dynamic.png`` (error against time, both solvers) and ``DIR/cheapest.md``: for each
sweep the cheapest setting reaching 1 mm, 0.1 mm, 0.01 mm and 1 um of coupler accuracy, our time,
Exudyn's and their ratio.

Usage::

    .venv/bin/python -m bench speed_vs_error --out out/speed_vs_error      # full sweep (about an hour)
    .venv/bin/python -m bench speed_vs_error --quick --out /tmp/sve        # two coarse points, ours only
"""

from __future__ import annotations

import argparse
import itertools
import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from bench.memory_probe import memory_start, memory_stop

QS_POINTS = [f"1,{h},{m}" for h in (0.006, 0.004, 0.003) for m in (2, 8)] + [f"2,0.006,{m}" for m in (4, 8)]
_STEPS = (0.004, 0.002, 0.001, 0.0005)
DYN_POINTS = (  # cheap first, so that an interrupted sweep still covers every axis
    [f"1,0.006,{m},0.004,0.9" for m in (2, 8)]
    + [f"1,0.004,{m},0.004,0.9" for m in (2, 16)]  # discretisation
    + [f"2,0.006,{m},0.004,0.9" for m in (4, 8)]
    + ["2,0.006,8,0.002,0.9,ours"]
    + [f"1,0.004,8,{s},{r},ours" for s in _STEPS for r in (0.5, 0.8, 1.0)]  # spectral radius, ours
    + [f"1,0.004,8,0.004,{r}" for r in (0.5, 1.0)]  # spectral radius, Exudyn too at the cheapest step
    + [f"1,0.004,8,{s},0.9" for s in _STEPS]  # the time step, both solvers
)
DYN_QS_POINTS = ["1,0.004,8", "2,0.006,8"]
THRESHOLDS_M = (1e-3, 1e-4, 1e-5, 1e-6)


# --------------------------------------------------------------------------------------------
# Runs
# --------------------------------------------------------------------------------------------


def _build(order: int, h: float, modes: int):
    from ffrf.paper.bennett_scene import build_bennett

    started = time.perf_counter()
    scene = build_bennett("pla", h=h, order=order, n_modes=modes)
    return scene, time.perf_counter() - started


def _exudyn_setup(scene):
    from validation.exudyn_bennett import bennett_bodies
    from validation.twin_bases import twin_bases

    started = time.perf_counter()
    bases = twin_bases(bennett_bodies(scene))
    return bases, time.perf_counter() - started


def _scene(order: int, h: float, modes: int, cache: dict | None):
    """Build, or take the scene from ``cache`` (key -> (scene, setup_s); used for the reference
    only, whose several runs share one build; the recorded set-up is the build's own time)."""
    key = (order, h, modes)
    if cache is not None and key in cache:
        return cache[key]
    built = _build(order, h, modes)
    if cache is not None:
        cache.clear()  # keep one scene: the reference's is large
        cache[key] = built
    return built


def _exudyn_assembled(scene) -> tuple:
    """Exudyn's reduction and static assembly of ``scene``, timed: ``(memory mark, bases, set-up s,
    assembled start, assembly s, perf_counter at the assembly's start)``."""
    from validation.exudyn_bennett import assemble_exudyn_bennett

    mem = memory_start()
    bases, setup = _exudyn_setup(scene)
    started = time.perf_counter()
    start = assemble_exudyn_bennett(scene, bases)
    return mem, bases, setup, start, time.perf_counter() - started, started


def run_quasi_static(
    order: int, h: float, modes: int, times: np.ndarray, exudyn: bool, scene_cache: dict | None = None
) -> dict:
    """Both solvers' quasi-static runs at ``times`` on one discretisation."""
    from ffrf.scenes.linkage_run import run_linkage

    out = {}
    mem = memory_start()
    scene, setup = _scene(order, h, modes, scene_cache)
    result = run_linkage(scene, mode="quasi_static", n_outputs=len(times), t_end=float(times[-1]))
    timings = result.metadata["timings_s"]
    out["ffrf"] = {
        "setup_s": setup,
        "integration_s": timings["assembly"] + timings["solve"],
        "assembly_s": timings["assembly"],
        **memory_stop(mem),
        "time": result.time,
        "coupler": result.sensors["coupler_point"],
        "torque": result.sensors["driving_torque"],
    }
    if exudyn:
        from validation.exudyn_bennett import quasi_static_exudyn_bennett

        mem, bases, setup, start, assembly, started = _exudyn_assembled(scene)
        trajectory = quasi_static_exudyn_bennett(scene, start, times, bases=bases)
        solve = time.perf_counter() - started
        # the twin's build inside the sweep is set-up, as for the dynamic runs
        twin_setup = trajectory.metadata["timings_s"]["setup"]
        out["exudyn"] = {
            "setup_s": setup + twin_setup,
            "integration_s": solve - twin_setup,
            "assembly_s": assembly,
            **memory_stop(mem),
            "time": trajectory.time,
            "coupler": trajectory.sensors["coupler_point"],
            "torque": trajectory.sensors["driving_torque"],
        }
    return out


def run_dynamic(
    order: int,
    h: float,
    modes: int,
    step: float,
    rho: float,
    t_end: float,
    exudyn: bool,
    scene_cache: dict | None = None,
) -> dict:
    """Both solvers' generalized-alpha runs from their own static assembly at rest, one row per step."""
    from ffrf.paper.bennett_scene import assemble
    from validation.bennett_validation import dynamic_solve, run_ours

    out = {}
    times = step * np.arange(int(round(t_end / step)) + 1)
    mem = memory_start()
    scene, setup = _scene(order, h, modes, scene_cache)
    started = time.perf_counter()
    q0 = assemble(scene).q
    assembly = time.perf_counter() - started
    run = run_ours("ffrf", scene, scene.system, times, q0, setup, dynamic_solve(step, rho))
    out["ffrf"] = {
        "setup_s": setup,
        "integration_s": assembly + run.metadata["timings_s"]["solve"],
        "assembly_s": assembly,
        **memory_stop(mem),
        "time": run.time,
        "coupler": run.sensors["coupler_point"],
        "torque": run.sensors["driving_torque"],
    }
    if exudyn:
        from validation.exudyn_bennett import run_exudyn_bennett

        mem, bases, setup, start, assembly, _ = _exudyn_assembled(scene)
        trajectory = run_exudyn_bennett(scene, start[4], t_end, step, rho, bases=bases)
        timings = trajectory.metadata["timings_s"]
        out["exudyn"] = {
            "setup_s": setup + timings["setup"],
            "integration_s": assembly + timings["solve"],
            "assembly_s": assembly,
            **memory_stop(mem),
            "time": trajectory.time,
            "coupler": trajectory.sensors["coupler_point"],
            "torque": trajectory.sensors["driving_torque"],
        }
    return out


def _errors(run: dict, reference: dict) -> tuple[float, float]:
    """Coupler (m) and relative torque errors at the run's rows that are rows of the reference."""
    ref_time = reference["time"]
    index = np.searchsorted(ref_time, run["time"] - 1e-9)
    index = np.minimum(index, len(ref_time) - 1)
    common = np.abs(ref_time[index] - run["time"]) < 1e-9
    if not common.any():
        raise ValueError("the run and the reference share no output time")
    rows, ref_rows = np.flatnonzero(common), index[common]
    coupler = float(np.linalg.norm(run["coupler"][rows] - reference["coupler"][ref_rows], axis=1).max())
    torque = float(
        np.abs(run["torque"][rows] - reference["torque"][ref_rows]).max() / np.abs(reference["torque"]).max()
    )
    return coupler, torque


# --------------------------------------------------------------------------------------------
# Reports
# --------------------------------------------------------------------------------------------


def _richardson(h_coarse: float, h_fine: float, order: float) -> Callable[[dict, dict], dict]:
    """``(coarse, fine) -> extrapolated`` run (coupler and torque at the same rows)."""
    wc, wf = h_coarse**order, h_fine**order

    def extrapolate(coarse: dict, fine: dict) -> dict:
        if coarse["time"].shape != fine["time"].shape:
            raise ValueError("the two references have different rows")
        return {
            "time": coarse["time"],
            **{k: (wc * fine[k] - wf * coarse[k]) / (wc - wf) for k in ("coupler", "torque")},
        }

    return extrapolate


def _setting(p: dict) -> str:
    text = f"P{p['order']}, {1e3 * p['h']:g} mm, {p['modes']} modes"
    if p["sweep"] == "dynamic_window":
        text += (
            ", quasi-static" if p["mode"] == "quasi_static" else f", dt {1e3 * p['step']:g} ms, rho {p['rho_inf']:g}"
        )
    return text


def _total(p: dict) -> float:
    return p["setup_s"] + p["integration_s"]


def cheapest_table(points: list[dict], sweep: str) -> str:
    """Markdown: for each accuracy threshold the cheapest point of each solver (set-up + run) that reaches it."""
    lines = [
        "| coupler accuracy | ours: setting, time (s) | Exudyn: setting, time (s) | Exudyn / ours |",
        "|---|---|---|---|",
    ]
    for threshold in THRESHOLDS_M:
        cells, times = [], {}
        for solver in ("ffrf", "exudyn"):
            ok = [
                p for p in points if p["sweep"] == sweep and p["solver"] == solver and p["coupler_error_m"] <= threshold
            ]
            if not ok:
                cells.append("not reached")
                continue
            best = min(ok, key=_total)
            times[solver] = _total(best)
            cells.append(f"{_setting(best)}: {times[solver]:.2f}")
        ratio = f"{times['exudyn'] / times['ffrf']:.1f}" if len(times) == 2 else ""
        lines.append(f"| {1e3 * threshold:g} mm | {cells[0]} | {cells[1]} | {ratio} |")
    return "\n".join(lines)


def same_point_table(points: list[dict], sweep: str) -> str:
    """Markdown: every point both solvers ran, side by side (integration only and total)."""
    lines = [
        "| setting | coupler error ours / Exudyn (m) | run ours / Exudyn (s) | ratio "
        "| total ours / Exudyn (s) | ratio |",
        "|---|---|---|---|---|---|",
    ]
    # a pair is ours and Exudyn's run of one point, back to back in the list (same load)
    for p, e in itertools.pairwise(points):
        if (
            p["sweep"] != sweep
            or p["solver"] != "ffrf"
            or e["solver"] != "exudyn"
            or not all(e[k] == p[k] for k in ("sweep", "mode", "order", "h", "modes", "step", "rho_inf"))
        ):
            continue
        row = (
            f"| {_setting(p)} | {p['coupler_error_m']:.2e} / {e['coupler_error_m']:.2e} | "
            f"{p['integration_s']:.2f} / {e['integration_s']:.2f} | {e['integration_s'] / p['integration_s']:.1f} | "
            f"{_total(p):.2f} / {_total(e):.2f} | {_total(e) / _total(p):.1f} |"
        )
        if p["mode"] == "dynamic":
            ours, theirs = _ms_per_step(p), _ms_per_step(e)
            row += f" {ours:.2f} / {theirs:.1f} | {theirs / ours:.1f} |"
        lines.append(row)
    if sweep == "dynamic_window":
        lines[0] += " ms/step ours / Exudyn | ratio |"
        lines[1] += "---|---|"
    return "\n".join(lines)


def _ms_per_step(p: dict) -> float:
    """Time integration alone (without the static assembly) per step, ms."""
    return 1e3 * (p["integration_s"] - p["assembly_s"]) / round(p["t_end"] / p["step"])


def pareto_figure(points: list[dict], sweep: str, path: Path, xlabel: str) -> None:
    """Error against set-up + run time, one marker per point, both solvers."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for solver, color, name in (("ffrf", "tab:blue", "ours"), ("exudyn", "tab:red", "Exudyn")):
        for mode, marker in (("dynamic", "o"), ("quasi_static", "s")):
            chosen = [p for p in points if p["sweep"] == sweep and p["solver"] == solver and p["mode"] == mode]
            if chosen:
                label = name + (" (quasi-static)" if sweep == "dynamic_window" and mode == "quasi_static" else "")
                ax.loglog(
                    [_total(p) for p in chosen],
                    [max(p["coupler_error_m"], 1e-12) for p in chosen],
                    ls="none",
                    marker=marker,
                    color=color,
                    mfc="none" if mode == "quasi_static" else color,
                    label=label,
                )
    for threshold in THRESHOLDS_M:
        ax.axhline(threshold, color="0.7", lw=0.8, ls=":")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("coupler error against the reference (m)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _point(solver: str, sweep: str, mode: str, spec: tuple, run: dict, errors: tuple, extra: dict) -> dict:
    order, h, modes = spec[:3]
    return {
        "solver": solver,
        "sweep": sweep,
        "mode": mode,
        "order": order,
        "h": h,
        "modes": modes,
        "step": extra.pop("step", None),
        "rho_inf": extra.pop("rho_inf", None),
        "t_end": extra.pop("t_end"),
        "setup_s": run["setup_s"],
        "integration_s": run["integration_s"],
        "assembly_s": run["assembly_s"],
        "peak_mem_mb": run["peak_mem_mb"],
        "peak_rss_mb": run["peak_rss_mb"],
        "coupler_error_m": errors[0],
        "torque_error_rel": errors[1],
        **extra,
    }


def _log(p: dict) -> None:
    extra = f", vs quasi-static ref {p['coupler_error_qs_m']:.2e} m" if "coupler_error_qs_m" in p else ""
    print(
        f"{p['solver']:7s} {_setting(p)}: set-up {p['setup_s']:6.2f} s, run {p['integration_s']:7.2f} s, "
        f"+{p['peak_mem_mb']:6.0f} MiB, coupler {p['coupler_error_m']:.3e} m, "
        f"torque {p['torque_error_rel']:.2e}{extra}",
        flush=True,
    )


def _warm_up() -> None:
    """Load (or compile) the numba kernels once, so that no point's time includes it."""
    from ffrf.paper.bennett_scene import assemble
    from ffrf.scenes.linkage_run import run_linkage
    from validation.bennett_validation import dynamic_solve

    scene, _ = _build(1, 0.008, 2)
    run_linkage(scene, mode="quasi_static", n_outputs=3, t_end=0.1)
    q0 = assemble(scene).q
    dynamic_solve(0.004, 0.9)(scene.system, q0, np.array([0.0, 0.008]))


def _parse(spec: str) -> tuple[Any, bool]:
    """``order,h,modes[,step,rho][,ours]`` -> (the numbers, 3 or 5 of them, as a tuple; whether ours only)."""
    parts = spec.split(",")
    values = [int(parts[0]), float(parts[1]), int(parts[2])] + [float(v) for v in parts[3:5]]
    return tuple(values), (len(parts) > 5 and parts[5] == "ours")


def _mesh(spec: str) -> tuple[int, float, int]:
    """``order,h,modes`` of a reference's mesh."""
    order, h, modes = _parse(spec)[0][:3]
    return order, h, modes


def main(argv: list[str] | None = None) -> list[dict]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--qs-points", nargs="*", default=QS_POINTS, help="order,h,modes")
    parser.add_argument("--dyn-points", nargs="*", default=DYN_POINTS, help="order,h,modes,step,rho[,ours]")
    parser.add_argument(
        "--dyn-qs-points", nargs="*", default=DYN_QS_POINTS, help="order,h,modes: quasi-static on the window"
    )
    parser.add_argument("--reference", default="2,0.004,32")
    parser.add_argument(
        "--fine-reference",
        default="2,0.003,32",
        help="a finer mesh of the reference: the references become the Richardson extrapolation "
        "of the two ('' for the reference alone)",
    )
    parser.add_argument(
        "--richardson-order",
        type=float,
        default=1.91,
        help="order of the mesh error in h (1.91: observed from P2 at 6, 4 and 3 mm)",
    )
    parser.add_argument(
        "--ref-step", type=float, default=2.5e-4, help="dynamic reference step (s); checked against twice it"
    )
    parser.add_argument("--ref-rho", type=float, default=0.9)
    parser.add_argument("--outputs", type=int, default=121, help="quasi-static drive angles over ramp + revolution")
    parser.add_argument("--window", type=float, default=1.5, help="dynamic window (s) from the start of the ramp")
    parser.add_argument("--qs-window-every", type=float, default=0.02, help="quasi-static rows on the window (s)")
    parser.add_argument("--no-exudyn", action="store_true")
    parser.add_argument("--quick", action="store_true", help="two coarse points per sweep, coarse reference, ours only")
    parser.add_argument("--report-only", action="store_true", help="rewrite the report from DIR/results.json")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    if args.report_only:
        recorded: list[dict] = json.loads((args.out / "results.json").read_text())
        write_report(recorded, args.out, args.window)
        return recorded
    if args.quick:  # a smoke test of the whole pipeline, for the test suite
        args.qs_points, args.dyn_qs_points = ["1,0.01,2", "1,0.008,2"], []
        args.dyn_points = ["1,0.01,2,0.004,0.9,ours", "1,0.008,2,0.004,0.9,ours"]
        args.reference, args.ref_step, args.window, args.outputs, args.no_exudyn = "1,0.006,2", 0.002, 0.1, 7, True
        args.fine_reference = ""
    args.out.mkdir(parents=True, exist_ok=True)
    exudyn = not args.no_exudyn
    ref_spec = _mesh(args.reference)
    points: list[dict] = []
    checks: dict = {
        "reference": dict(zip(("order", "h", "modes"), ref_spec, strict=True)),
        "ref_step": args.ref_step,
        "ref_rho": args.ref_rho,
        "window_s": args.window,
    }

    def save() -> None:  # partial results survive an interrupted sweep
        (args.out / "results.json").write_text(json.dumps(points, indent=2))
        (args.out / "reference.json").write_text(json.dumps(checks, indent=2))

    _warm_up()
    # The reference's runs share one build -------------------------------------------------
    cache: dict = {}
    reference_scene, _ = _scene(*ref_spec, cache)
    t_end = reference_scene.t_end
    if args.qs_points:
        qs_times = np.linspace(0.0, t_end, args.outputs)
        print(f"quasi-static reference: {args.reference}", flush=True)
        reference = run_quasi_static(*ref_spec, qs_times, False, cache)["ffrf"]
        checks["quasi_static_reference_s"] = {"setup": reference["setup_s"], "run": reference["integration_s"]}
    if args.dyn_points or args.dyn_qs_points:
        print(
            f"dynamic reference: {args.reference}, step {args.ref_step} s, rho {args.ref_rho}, window {args.window} s",
            flush=True,
        )
        dyn_ref = run_dynamic(*ref_spec, args.ref_step, args.ref_rho, args.window, False, cache)["ffrf"]
        half = run_dynamic(*ref_spec, 2 * args.ref_step, args.ref_rho, args.window, False, cache)["ffrf"]
        qs_window = np.arange(0.0, args.window + 1e-9, args.qs_window_every)
        qs_ref = run_quasi_static(*ref_spec, qs_window, False, cache)["ffrf"]
        step_check = _errors(half, dyn_ref)
        dynamic_effect = _errors(qs_ref, dyn_ref)
        checks["dynamic_reference"] = {
            "setup_s": dyn_ref["setup_s"],
            "run_s": dyn_ref["integration_s"],
            "twice_the_step_coupler_m": step_check[0],
            "twice_the_step_torque_rel": step_check[1],
            "quasi_static_vs_dynamic_coupler_m": dynamic_effect[0],
            "quasi_static_vs_dynamic_torque_rel": dynamic_effect[1],
        }
        print(
            f"dynamic reference: step {2 * args.ref_step} vs {args.ref_step} s differ by {step_check[0]:.3e} m "
            f"(torque {step_check[1]:.2e}); quasi-static vs dynamic reference {dynamic_effect[0]:.3e} m "
            f"(torque {dynamic_effect[1]:.2e})",
            flush=True,
        )
    del reference_scene
    cache.clear()
    if args.fine_reference:
        # Richardson: f(h) = f* + C h^p on the two meshes gives f*; the reference's own error is |f(h) - f*|
        fine_spec = _mesh(args.fine_reference)
        print(
            f"finer reference {args.fine_reference}: Richardson extrapolation, order {args.richardson_order}",
            flush=True,
        )
        extrapolate = _richardson(ref_spec[1], fine_spec[1], args.richardson_order)
        checks["fine_reference"] = dict(zip(("order", "h", "modes"), fine_spec, strict=True))
        checks["richardson_order"] = args.richardson_order
        if args.qs_points:
            fine = run_quasi_static(*fine_spec, qs_times, False, cache)["ffrf"]
            coarse, reference = reference, extrapolate(reference, fine)
            checks["reference_error_quasi_static"] = dict(
                zip(("coarse_coupler_m", "coarse_torque_rel"), _errors(coarse, reference), strict=True)
            )
        if args.dyn_points or args.dyn_qs_points:
            fine = run_dynamic(*fine_spec, args.ref_step, args.ref_rho, args.window, False, cache)["ffrf"]
            coarse, dyn_ref = dyn_ref, extrapolate(dyn_ref, fine)
            checks["reference_error_dynamic"] = dict(
                zip(("coarse_coupler_m", "coarse_torque_rel"), _errors(coarse, dyn_ref), strict=True)
            )
            fine = run_quasi_static(*fine_spec, qs_window, False, cache)["ffrf"]
            qs_ref = extrapolate(qs_ref, fine)
        cache.clear()
        print(
            "reference's own error: "
            + json.dumps({k: v for k, v in checks.items() if k.startswith("reference_error")}),
            flush=True,
        )
    save()

    # Quasi-static sweep ---------------------------------------------------------------------
    for spec in args.qs_points:
        parsed, ours_only = _parse(spec)
        order, h, modes = parsed[:3]
        for solver, run in run_quasi_static(order, h, modes, qs_times, exudyn and not ours_only).items():
            p = _point(solver, "quasi_static", "quasi_static", parsed, run, _errors(run, reference), {"t_end": t_end})
            points.append(p)
            _log(p)
        save()

    # Dynamic window -------------------------------------------------------------------------
    for spec in args.dyn_points:
        parsed, ours_only = _parse(spec)
        order, h, modes, step, rho = parsed
        runs = run_dynamic(order, h, modes, step, rho, args.window, exudyn and not ours_only)
        for solver, run in runs.items():
            extra = {
                "t_end": args.window,
                "step": parsed[3],
                "rho_inf": parsed[4],
                "coupler_error_qs_m": _errors(run, qs_ref)[0],
            }
            p = _point(solver, "dynamic_window", "dynamic", parsed, run, _errors(run, dyn_ref), extra)
            points.append(p)
            _log(p)
        save()
    for spec in args.dyn_qs_points:
        parsed, ours_only = _parse(spec)
        order, h, modes = parsed[:3]
        for solver, run in run_quasi_static(order, h, modes, qs_window, exudyn and not ours_only).items():
            p = _point(
                solver,
                "dynamic_window",
                "quasi_static",
                parsed,
                run,
                _errors(run, dyn_ref),
                {"t_end": args.window, "coupler_error_qs_m": _errors(run, qs_ref)[0]},
            )
            points.append(p)
            _log(p)
        save()

    save()
    write_report(points, args.out, args.window)
    return points


def write_report(points: list[dict], out: Path, window: float) -> None:
    """``pareto_*.png`` and ``cheapest.md`` (cheapest settings and same-point tables per sweep)."""
    report = []
    for sweep, title, xlabel in (
        ("quasi_static", "Quasi-static ramp + revolution", "set-up + quasi-static revolution (s)"),
        ("dynamic_window", f"Dynamic window ({window:g} s)", f"set-up + {window:g} s window (s)"),
    ):
        if any(p["sweep"] == sweep for p in points):
            pareto_figure(points, sweep, out / f"pareto_{sweep}.png", "wall time: " + xlabel)
            report += [
                f"## {title}",
                "",
                "Cheapest setting per accuracy (time: set-up + run):",
                "",
                cheapest_table(points, sweep),
                "",
                "Both solvers on the same points:",
                "",
                same_point_table(points, sweep),
                "",
            ]
    (out / "cheapest.md").write_text("\n".join(report))
    print("\n".join(report))


if __name__ == "__main__":
    main()
