"""Hard cases of the flexible Bennett solver (issue #9): each case runs, fails cleanly, or says why.

Cases (``--cases`` picks a subset, comma separated):

* ``near_rigid``: E = 1e15 Pa links, generalized-alpha with steps 1e-2 .. 1e-5 s (conditioning of
  the index-3 iteration matrix; its 2-norm condition number at the assembled state is reported);
* ``misalignment``: base twist alpha_3 = 90 .. 95 deg (static assembly with continuation, then one
  quasi-static revolution: driving torque and assembly stress; a failed assembly is recorded
  with its error message);
* ``speed``: drive at 1, 10, 60, 300 rpm, quasi-static and dynamic over the same window: where
  inertia makes quasi-static wrong, and what :func:`ffrf.scenes.linkage_run.choose_mode` decides;
* ``long_run``: 10 revolutions at 60 rpm, dynamic and quasi-static: drift of the constraints,
  of the energy balance and of the periodic motion;
* ``soft``: E from 1.2e9 down to 3e6 Pa (quasi-static revolution): bore rotations and strains
  against the small-deformation assumption of the floating frame;
* ``modes_mesh``: 100 fixed-interface modes per link (h = 4 mm) and a 1 mm mesh: cost and effect;
* ``singular``: the most singular-looking pose of the paper's linkage (the folded pose, found
  from the joint screws) crossed quasi-statically and dynamically by flexible and near-rigid links.

Every run records: converged or not, steps (time steps or equilibria), Newton iterations,
worst constraint residual, relative energy balance error, wall time, and the difference to
Exudyn where the Exudyn twin runs it (``validation/exudyn_bennett.py``). Each case runs in
its own process with a time budget (no hang: a case past its budget is killed and its rows so
far are kept); each run's sensors are saved as ``DIR/runs/<case>/<run>.npz`` (also partial
ones); a failure is a row with ``converged = False`` and the error message. Non-finite
output is cut off at the first non-finite row and reported, never written.

Usage::

    .venv/bin/python -m bench hard_cases --out out/hard_cases          # all, ~30 min
    .venv/bin/python -m bench hard_cases --quick --out out/hard_quick  # ~3 min
    .venv/bin/python -m bench hard_cases --cases near_rigid,speed --no-exudyn

Timings are wall-clock on a shared 2-core machine: noisy, compare them only within a run.
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import time
import traceback
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from bench import ROOT

if TYPE_CHECKING:  # the solver is imported by each case's own process (spawned), not by this module
    from ffrf.solvers.static_solver import StaticSolution

#: Coarse discretisation for the cases that do not study the discretisation itself.
COARSE = dict(h=6e-3, order=1, n_modes=4)


# --------------------------------------------------------------------------------------------
# Rows and context
# --------------------------------------------------------------------------------------------


@dataclass
class Row:
    """One run of a case: the columns of the issue's table, plus case-specific figures."""

    case: str
    run: str
    mode: str
    converged: bool = False
    steps: int = 0
    newton_iterations: int = 0
    max_constraint_residual: float | None = None
    energy_balance_relative: float | None = None
    wall_s: float = 0.0
    exudyn: str = ""
    error: str = ""
    extra: dict = field(default_factory=dict)


@dataclass
class Context:
    """What a case needs: quick mode, Exudyn on/off, where to write, and where rows go."""

    case: str
    quick: bool
    exudyn: bool
    out: Path
    rows_file: Path

    def add(self, row: Row) -> Row:
        row.extra = _finite_json(row.extra)
        with self.rows_file.open("a") as f:
            f.write(json.dumps({"row": asdict(row)}, default=_json_default) + "\n")
        status = "ok" if row.converged else f"FAILED: {row.error}"
        print(
            f"  [{row.case}] {row.run}: {status}; {row.steps} steps, {row.newton_iterations} Newton it., "
            f"|g| {_fmt(row.max_constraint_residual)}, energy {_fmt(row.energy_balance_relative)}, "
            f"{row.wall_s:.1f} s {row.exudyn}",
            flush=True,
        )
        return row

    def finding(self, text: str) -> None:
        with self.rows_file.open("a") as f:
            f.write(json.dumps({"finding": text}) + "\n")
        print(f"  [{self.case}] finding: {text}", flush=True)


def _json_default(value):
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return str(value)


def _finite_json(value):
    """Replace non-finite floats by None (JSON has no NaN, and the table must not show one)."""
    if isinstance(value, dict):
        return {k: _finite_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_finite_json(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


def _fmt(value: float | None, digits: int = 2) -> str:
    return "-" if value is None else f"{value:.{digits}e}"


# --------------------------------------------------------------------------------------------
# Scenes and runs
# --------------------------------------------------------------------------------------------


def make_scene(material=None, alpha3_deg: float = 90.0, **kwargs):
    """:func:`ffrf.paper.bennett_scene.build_bennett` with any material and base twist.

    ``build_bennett`` takes both from its ``VARIANTS`` table only, so the pair is registered
    under a temporary name for the call (the scene keeps it in ``settings['variant']``)."""
    from ffrf.fe.materials import PLA
    from ffrf.paper import bennett_scene

    material = PLA if material is None else material
    name = f"hard:E={material.E:g}:alpha3={alpha3_deg:g}"
    bennett_scene.VARIANTS[name] = (material, float(alpha3_deg))
    try:
        return bennett_scene.build_bennett(name, **kwargs)
    finally:
        bennett_scene.VARIANTS.pop(name, None)


class BudgetExceeded(RuntimeError):
    """Raised from the integrator's progress callback when a run exceeds its time budget."""


@dataclass
class Outcome:
    """A finished, failed or interrupted run: row plus the sensors up to the last good output."""

    row: Row
    time: np.ndarray
    q: np.ndarray
    sensors: dict
    iterations: np.ndarray
    assembly: StaticSolution | None = None


def _finite_prefix(time_: np.ndarray, sensors: dict) -> int:
    """Number of leading output rows whose sensors are all finite."""
    good = np.ones(len(time_), bool)
    for value in sensors.values():
        value = np.asarray(value, float).reshape(len(time_), -1)
        good &= np.all(np.isfinite(value), axis=1)
    return len(time_) if good.all() else int(np.argmin(good))


def simulate(
    ctx: Context,
    scene,
    run: str,
    mode: str,
    t_end: float,
    *,
    step: float = 1e-3,
    n_outputs: int = 61,
    rho_inf: float = 0.9,
    budget_s: float = 600.0,
    chunks: int = 10,
    add: bool = True,
) -> Outcome:
    """Assemble and run ``scene`` (``quasi_static`` or ``dynamic``) to ``t_end`` (s); never raises.

    Quasi-static runs go in ``chunks`` so that a failure keeps the equilibria before it;
    dynamic runs keep the partial result of :class:`ffrf.solvers.generalized_alpha.NewtonDivergence`."""
    from ffrf.errors import NewtonDivergence, StaticDivergence
    from ffrf.paper.bennett_scene import assemble
    from ffrf.scenes.linkage_run import evaluate_sensors
    from ffrf.solvers.generalized_alpha import generalized_alpha
    from ffrf.solvers.static_solver import quasi_static

    row = Row(ctx.case, run, mode)
    started = time.perf_counter()
    system = scene.system
    empty = Outcome(row, np.zeros(0), np.zeros((0, system.n_coordinates)), {}, np.zeros(0, int))
    try:
        assembly = assemble(scene)
    except Exception as error:  # noqa: BLE001 - every failure becomes a row
        row.error = f"assembly failed: {type(error).__name__}: {error}"
        row.wall_s = time.perf_counter() - started
        if add:
            ctx.add(row)
        return empty
    assembled = time.perf_counter()
    row.extra["assembly_s"] = assembled - started
    # the run's outputs, arrays once it produced any
    q: Any = None
    qd: Any = None
    lam: Any = None
    times: Any = None
    iterations: list[int] = []
    try:
        if mode == "quasi_static":
            grid = np.linspace(0.0, t_end, n_outputs)
            qs: list[np.ndarray] = []
            lams: list[np.ndarray] = []
            done: list[float] = []
            start_q = assembly.q
            for part in np.array_split(np.arange(n_outputs), min(chunks, n_outputs)):
                if time.perf_counter() - started > budget_s:
                    raise BudgetExceeded(f"time budget {budget_s:g} s exceeded at t = {grid[part[0]]:.4g} s")
                # each chunk restarts at the last equilibrium (its first time repeats the previous one)
                first = part[0] - 1 if part[0] > 0 else 0
                sub = grid[first : part[-1] + 1]
                try:
                    solution = quasi_static(system, start_q, sub)
                except StaticDivergence as error:
                    # its step numbers count within this chunk: say where the chunk starts
                    raise StaticDivergence(
                        f"{error} [chunk from output {first} at t = {grid[first]:.6g} s; {len(done)} equilibria done]"
                    ) from error
                skip = 1 if part[0] > 0 else 0
                qs.extend(solution.q[skip:])
                lams.extend(solution.multipliers[skip:])
                iterations.extend(solution.iterations[skip:])
                done.extend(sub[skip:])
                start_q = solution.q[-1]
                times, q, lam = np.array(done), np.array(qs), np.array(lams)
        else:
            # outputs on the quasi-static grid: the step is shortened to divide each output interval
            every = max(1, int(math.ceil(t_end / step / (n_outputs - 1) - 1e-9)))
            step = t_end / (every * (n_outputs - 1))
            row.extra["step_s"] = step

            def progress(t: float, _end: float) -> None:
                if time.perf_counter() - started > budget_s:
                    raise BudgetExceeded(
                        f"time budget {budget_s:g} s exceeded at t = {t:.4g} s (generalized_alpha "
                        "returns no partial states when interrupted)"
                    )

            try:
                result = generalized_alpha(
                    system,
                    assembly.q,
                    np.zeros_like(assembly.q),
                    t_end,
                    step,
                    rho_inf=rho_inf,
                    output_every=every,
                    progress=progress,
                )
            except NewtonDivergence as error:
                result = error.partial
                row.error = f"NewtonDivergence: {error}"
            times, q, qd, lam = result.time, result.q, result.qd, result.multipliers
            iterations = list(result.newton_iterations)
    except (StaticDivergence, BudgetExceeded, np.linalg.LinAlgError, FloatingPointError) as error:
        row.error = f"{type(error).__name__}: {error}"
    except Exception as error:  # noqa: BLE001 - unexpected, but still a row with its traceback tail
        row.error = f"unexpected {type(error).__name__}: {error} ({traceback.format_exc(limit=2).splitlines()[-3]})"
    row.extra["solve_s"] = time.perf_counter() - assembled
    row.steps = len(iterations)
    row.newton_iterations = int(np.sum(iterations)) if iterations else 0
    row.extra["max_newton_per_step"] = int(np.max(iterations)) if iterations else None
    sensors: dict = {}
    if times is not None and len(times) >= 2:
        sensors = evaluate_sensors(scene, times, q, qd, lam)
        n = _finite_prefix(times, sensors)
        if n < len(times):
            row.error = (
                row.error + "; " if row.error else ""
            ) + f"non-finite output from t = {times[n]:.4g} s on (cut off)"
            times, q = times[:n], q[:n]
            sensors = {k: np.asarray(v)[:n] for k, v in sensors.items()}
    if len(sensors) and len(times) >= 2:
        g = np.asarray(sensors["constraint_residual"])
        work = np.abs(sensors["energy_drive_work"]).max()
        row.max_constraint_residual = float(g.max())
        row.energy_balance_relative = float(np.abs(sensors["energy_balance_residual"]).max() / max(work, 1e-300))
        row.extra["t_reached_s"] = float(times[-1])
        row.extra["max_abs_driving_torque_Nm"] = float(np.abs(sensors["driving_torque"]).max())
        row.extra["max_coupler_deviation_m"] = float(np.linalg.norm(sensors["coupler_deviation"], axis=1).max())
        _save(ctx, run, times, sensors)
    row.converged = not row.error and times is not None and abs(float(times[-1]) - t_end) <= 1e-9 * max(1.0, t_end)
    if not row.converged and not row.error:
        row.error = "run ended early without an error"
    row.wall_s = time.perf_counter() - started
    out = Outcome(
        row,
        np.asarray(times if times is not None else []),
        np.asarray(q if q is not None else []),
        sensors,
        np.asarray(iterations, int),
        assembly,
    )
    if add:
        ctx.add(row)
    return out


def _save(ctx: Context, run: str, times: np.ndarray, sensors: dict) -> None:
    keep = (
        "drive_angle",
        "driving_torque",
        "coupler_point",
        "coupler_deviation",
        "constraint_residual",
        "energy_kinetic",
        "energy_strain",
        "energy_potential",
        "energy_drive_work",
        "energy_dissipated",
        "energy_balance_residual",
    )
    directory = ctx.out / "runs" / ctx.case
    directory.mkdir(parents=True, exist_ok=True)
    safe = "".join(c if c.isalnum() or c in "-_.=" else "_" for c in run)
    arrays: dict[str, Any] = {"time": times, **{k: np.asarray(sensors[k]) for k in keep if k in sensors}}
    np.savez(directory / f"{safe}.npz", **arrays)


def exudyn_dynamic(scene, t_end: float, step: float, rho_inf: float = 0.9) -> str:
    """Our generalized-alpha against the Exudyn twin from the same assembled state (Exudyn's
    simplified gravity in both): largest coupler difference and driving-torque difference."""
    from ffrf.paper.bennett_scene import assemble
    from validation.bennett_trajectory import compare, run_ffrf_bennett
    from validation.exudyn_bennett import run_exudyn_bennett

    twin_scene = scene.with_exact_gravity(False)
    q0 = assemble(twin_scene).q
    try:
        theirs = run_exudyn_bennett(twin_scene, q0, t_end, step, rho_inf)
    except Exception as error:  # noqa: BLE001 - a failure of the reference is reported, not raised
        return f"Exudyn failed: {type(error).__name__}: {str(error)[:160]}"
    ours = run_ffrf_bennett(twin_scene, twin_scene.system, q0, t_end, step, rho_inf, tolerance=1e-10)
    d = compare(ours, theirs)
    return (
        f"coupler {d['coupler_m']:.1e} m, torque {d['torque_relative']:.1e} rel. "
        f"(Exudyn {theirs.metadata['timings_s']['solve']:.1f} s, ours {ours.metadata['timings_s']['solve']:.1f} s)"
    )


def iteration_matrix_condition(system, q: np.ndarray, lam: np.ndarray, step: float, rho_inf: float = 0.9) -> float:
    """2-norm condition number of the generalized-alpha iteration matrix (Eq. (G3), constraint
    rows scaled by 1/beta' as the integrator does) at ``q`` at rest."""
    from ffrf.solvers.generalized_alpha import AlphaParameters
    from ffrf.system.packed_system import newton_model

    par = AlphaParameters(rho_inf)
    beta_p = step * step * par.beta * (1.0 - par.alpha_f) / (1.0 - par.alpha_m)
    gamma_p = step * par.gamma * (1.0 - par.alpha_f) / (1.0 - par.alpha_m)
    zeros = np.zeros_like(q)
    matrix = newton_model(system, True).iteration_matrix(q, zeros, zeros, lam, 0.0, 1.0, beta_p, gamma_p)
    return float(np.linalg.cond(matrix))


# --------------------------------------------------------------------------------------------
# Cases
# --------------------------------------------------------------------------------------------

#: Small-deformation limits of the floating frame's linear elasticity: the neglected second-order
#: displacement of an arm whose end turns by theta is about theta^2 L / 2 against the linear theta L / 2,
#: a relative error of the order of theta; 0.05 rad keeps it near 5 %. Strains below 1 % (small strain).
ROTATION_LIMIT_RAD = 0.05
STRAIN_LIMIT = 0.01


def deformation(scene, out: Outcome) -> dict:
    """Largest elastic rotation of any bore marker relative to its body frame (rad, over all
    outputs) and the largest equivalent strain (von Mises stress / E) at the output of largest
    strain energy, with the verdict against the small-deformation limits."""
    from ffrf.output.assembly_stress import scene_assembly_stress

    if not len(out.time):
        return {}
    system = scene.system
    theta = max(
        float(np.linalg.norm(m.rotation_vector(q[system.block(link.index)])))
        for q in out.q
        for link in scene.links
        for m in link.markers.values()
    )
    worst = int(np.argmax(np.asarray(out.sensors["energy_strain"])))
    stress = scene_assembly_stress(scene, out.q[worst])
    strain = max(
        link_stress.max_von_mises_pa / link.fe.material.E
        for link_stress, link in zip(stress.links, scene.links, strict=True)
    )
    return {
        "max_bore_rotation_rad": theta,
        "max_equivalent_strain": strain,
        "max_von_mises_MPa": 1e-6 * stress.as_dict()["max_von_mises_pa"],
        "small_deformation_valid": bool(theta < ROTATION_LIMIT_RAD and strain < STRAIN_LIMIT),
    }


def case_near_rigid(ctx: Context) -> None:
    from ffrf.fe.materials import RIGID
    from ffrf.system.drives import rpm

    scene = make_scene(RIGID, omega=rpm(60.0), ramp_time=0.05, **COARSE)
    t_end = 0.02 if ctx.quick else 0.1
    steps = (1e-2, 1e-3, 1e-4, 1e-5)
    results, outcomes = [], []
    for step in steps:
        n_steps = int(round(t_end / step))
        out = simulate(
            ctx,
            scene,
            f"E=1e15, step {step:g} s",
            "dynamic",
            t_end,
            step=step,
            n_outputs=min(n_steps, 10 if ctx.quick else 50) + 1,
            add=False,
        )
        if out.assembly is not None:
            out.row.extra["iteration_matrix_cond"] = iteration_matrix_condition(
                scene.system, out.assembly.q, out.assembly.multipliers, step
            )
        if ctx.exudyn and not ctx.quick and step >= 1e-4:
            out.row.exudyn = exudyn_dynamic(scene, t_end if step >= 1e-3 else 0.02, step)
        outcomes.append(out)
    # step convergence of the driving torque (a Lagrange multiplier) against the finest step
    finest = outcomes[-1]
    if finest.row.converged:
        for out in outcomes[:-1]:
            if len(out.time) > 1:
                reference = np.interp(out.time, finest.time, finest.sensors["driving_torque"])
                scale = np.abs(finest.sensors["driving_torque"]).max()
                out.row.extra["torque_error_vs_finest_rel"] = float(
                    np.abs(out.sensors["driving_torque"] - reference).max() / scale
                )
                out.row.extra["kinetic_energy_end_J"] = float(out.sensors["energy_kinetic"][-1])
        finest.row.extra["kinetic_energy_end_J"] = float(finest.sensors["energy_kinetic"][-1])
    for out in outcomes:
        results.append(ctx.add(out.row))
    ok = [r for r in results if r.converged]
    errors = ", ".join(
        f"{r.extra['torque_error_vs_finest_rel']:.1e}" for r in results if "torque_error_vs_finest_rel" in r.extra
    )
    conds = ", ".join(f"{r.extra.get('iteration_matrix_cond', float('nan')):.1e}" for r in results)
    ctx.finding(
        f"{len(ok)}/{len(results)} step sizes 1e-2..1e-5 s converge with E = 1e15 Pa; worst constraint "
        f"residual {max((r.max_constraint_residual or 0) for r in ok) if ok else float('nan'):.1e}; "
        f"Newton iterations per step at most {max((r.extra['max_newton_per_step'] or 0) for r in ok) if ok else 0}; "
        f"iteration-matrix condition numbers {conds} at the assembled state; driving torque error against the "
        f"1e-5 s run {errors} (relative to its peak) for steps 1e-2, 1e-3, 1e-4 s: first order in the step, "
        f"while positions and kinetic energy agree"
    )


def case_misalignment(ctx: Context) -> None:
    from ffrf.output.assembly_stress import scene_assembly_stress
    from kinematics import PAPER_A, PAPER_ALPHA
    from kinematics.mobility import rigid_mobility

    # the range, then beyond it until something breaks
    angles = (92.0, 95.0) if ctx.quick else (90.0, 91.0, 92.0, 93.0, 94.0, 95.0, 100.0, 105.0, 110.0, 120.0)
    rows = []
    for alpha3 in angles:
        try:
            scene = make_scene(None, alpha3, **COARSE)
        except Exception as error:  # noqa: BLE001 - the geometry itself may not exist
            rows.append(
                ctx.add(
                    Row(
                        ctx.case,
                        f"alpha3 = {alpha3:g} deg",
                        "build",
                        error=f"scene build failed: {type(error).__name__}: {error}",
                    )
                )
            )
            continue
        alpha = np.array(PAPER_ALPHA, float)
        alpha[3] = np.radians(alpha3)
        try:
            misfit = rigid_mobility(PAPER_A, alpha, n_angles=72).max_translation_residual
        except Exception:  # noqa: BLE001 - context only
            misfit = float("nan")
        n_out = 37 if ctx.quick else 73
        out = simulate(ctx, scene, f"alpha3 = {alpha3:g} deg", "quasi_static", scene.t_end, n_outputs=n_out, add=False)
        out.row.extra["rigid_closure_misfit_m"] = misfit
        if out.assembly is not None:
            stress = scene_assembly_stress(scene, out.assembly.q, out.assembly.multipliers)
            out.row.extra["assembly_max_von_mises_MPa"] = 1e-6 * stress.as_dict()["max_von_mises_pa"]
            out.row.extra["assembly_torque_Nm"] = float(out.assembly.multipliers[-1])
        if len(out.time):
            out.row.extra.update(deformation(scene, out))
        if ctx.exudyn and not ctx.quick and alpha3 in (92.0, 95.0):
            out.row.exudyn = exudyn_assembly(scene, out.assembly)
        rows.append(ctx.add(out.row))
    ok = [r for r in rows if r.converged]
    failed = [r for r in rows if not r.converged]
    text = (
        f"assembled and ran {len(ok)}/{len(rows)} twists; largest |torque|, equivalent strain, bore rotation: "
        + ", ".join(
            f"{r.run.split('= ')[1]}: {1e3 * r.extra.get('max_abs_driving_torque_Nm', float('nan')):.3g} N mm, "
            f"{100 * r.extra.get('max_equivalent_strain', float('nan')):.2g} %, "
            f"{r.extra.get('max_bore_rotation_rad', float('nan')):.2g} rad"
            f"{'' if r.extra.get('small_deformation_valid', True) else ' (outside small deformation)'}"
            for r in ok
        )
    )
    if failed:
        text += f"; first failure at {failed[0].run}: {failed[0].error[:300]}"
    ctx.finding(text)


def exudyn_assembly(scene, ours) -> str:
    """Exudyn's own static assembly with continuation against ours (simplified gravity in both)."""
    from ffrf.paper.bennett_scene import assemble
    from validation.bennett_trajectory import system_points
    from validation.exudyn_bennett import assemble_exudyn_bennett

    twin_scene = scene.with_exact_gravity(False)
    try:
        q_e, torque_e, coupler_e, _, _ = assemble_exudyn_bennett(twin_scene)
    except Exception as error:  # noqa: BLE001 - a failure of the reference is reported, not raised
        return f"Exudyn assembly failed too: {type(error).__name__}: {str(error)[:160]}"
    try:
        mine = assemble(twin_scene)
    except Exception as error:  # noqa: BLE001 - our failure where Exudyn succeeded is the finding
        return f"Exudyn assembled (torque {torque_e:.4g} N m) where we failed: {type(error).__name__}"
    coupler = system_points(twin_scene, twin_scene.system, mine.q[None])[0][0]
    return (
        f"assembly: coupler {np.linalg.norm(coupler - coupler_e):.1e} m, torque "
        f"{abs(mine.multipliers[-1] - torque_e) / max(abs(torque_e), 1e-300):.1e} rel."
    )


def case_speed(ctx: Context) -> None:
    from ffrf.scenes.linkage_run import choose_mode, inertia_number
    from ffrf.system.drives import rpm

    speeds = (10.0, 300.0) if ctx.quick else (1.0, 10.0, 60.0, 300.0)
    steps = {1.0: 2e-3, 10.0: 1e-3, 60.0: 5e-4, 300.0: 2.5e-4}
    summary = []
    for speed in speeds:
        scene = make_scene(None, omega=rpm(speed), ramp_time=1.0, **COARSE)
        chosen, ratio = choose_mode(scene)
        # the paper's 1 s ramp, then a quarter revolution at full speed
        t_end = scene.drive.time_for_angle(float(scene.drive.angle(1.0)) + 0.5 * np.pi)
        if ctx.quick:
            t_end = 0.3 if speed >= 300 else 1.0
        n_out = 81
        qs = simulate(ctx, scene, f"{speed:g} rpm quasi-static", "quasi_static", t_end, n_outputs=n_out, add=False)
        dyn = simulate(
            ctx, scene, f"{speed:g} rpm dynamic", "dynamic", t_end, step=steps[speed], n_outputs=n_out, add=False
        )
        for out in (qs, dyn):
            out.row.extra.update(auto_choice=chosen, quasi_static_ratio=ratio, inertia_number=inertia_number(scene))
        if len(qs.time) == len(dyn.time) and len(qs.time) > 1 and np.allclose(qs.time, dyn.time):
            torque_scale = np.abs(qs.sensors["driving_torque"]).max()
            d_torque = np.abs(dyn.sensors["driving_torque"] - qs.sensors["driving_torque"]).max() / torque_scale
            dev_scale = np.linalg.norm(qs.sensors["coupler_deviation"], axis=1).max()
            d_coupler = np.linalg.norm(dyn.sensors["coupler_point"] - qs.sensors["coupler_point"], axis=1).max()
            after = qs.time >= scene.drive.ramp_time
            d_after = (
                np.abs(dyn.sensors["driving_torque"] - qs.sensors["driving_torque"])[after].max() / torque_scale
                if after.any()
                else float("nan")
            )
            dyn.row.extra.update(
                torque_diff_to_quasi_static_rel=d_torque,
                coupler_diff_to_quasi_static_m=d_coupler,
                coupler_diff_rel_to_deviation=d_coupler / dev_scale,
                torque_diff_after_ramp_rel=d_after,
            )
            summary.append(
                f"{speed:g} rpm: auto -> {chosen} (vibration ratio {ratio:.3g}, inertia number "
                f"{inertia_number(scene):.2g}), dynamic vs quasi-static torque "
                f"{100 * d_torque:.2g} % of its peak (after the ramp {100 * d_after:.2g} %), coupler "
                f"{1e6 * d_coupler:.3g} um ({100 * d_coupler / dev_scale:.2g} % of the elastic deviation)"
            )
        if ctx.exudyn and not ctx.quick and speed == 300.0:
            dyn.row.exudyn = exudyn_dynamic(scene, 0.2, steps[speed])
        ctx.add(qs.row)
        ctx.add(dyn.row)
    ctx.finding("; ".join(summary))


def case_long_run(ctx: Context) -> None:
    from ffrf.system.drives import rpm

    revolutions = 2 if ctx.quick else 10
    scene = make_scene(None, omega=rpm(60.0), ramp_time=1.0, revolutions=revolutions, **COARSE)
    t_end = scene.t_end  # 1 s ramp (half a revolution) + revolutions at 1 rev/s
    # outputs per second (= per revolution at 60 rpm): every 2nd step of the dynamic run, so that the
    # energy integrals resolve the torque's vibrations; 50 equilibria per revolution quasi-statically
    dense, sparse = (100, 50) if ctx.quick else (500, 50)
    dyn = simulate(
        ctx,
        scene,
        f"{revolutions} rev dynamic 1e-3 s",
        "dynamic",
        t_end,
        step=1e-3,
        n_outputs=int(round(t_end * dense)) + 1,
        budget_s=1500.0,
        add=False,
    )
    qs = simulate(
        ctx,
        scene,
        f"{revolutions} rev quasi-static",
        "quasi_static",
        t_end,
        n_outputs=int(round(t_end * sparse)) + 1,
        budget_s=900.0,
        add=False,
    )
    text = []
    for out, per_rev in ((dyn, dense), (qs, sparse)):
        s = out.sensors
        if not s or abs(out.time[-1] - t_end) > 1e-9:
            continue
        idx = np.nonzero(out.time >= 1.0 - 1e-9)[0]  # after the ramp, rows per_rev apart are a revolution apart
        g = np.asarray(s["constraint_residual"])
        balance = np.asarray(s["energy_balance_residual"])
        work = np.asarray(s["energy_drive_work"])
        revs = [(idx[0] + k * per_rev, idx[0] + (k + 1) * per_rev) for k in range(revolutions)]
        out.row.extra["constraint_residual_per_rev"] = [float(g[a : b + 1].max()) for a, b in revs]
        # energy balance error gained in each revolution, relative to the energy the drive exchanges in it
        # (peak-to-peak work: lifting and lowering the links; the net work per revolution is only the damping)
        out.row.extra["energy_balance_per_rev_rel"] = [
            float((balance[b] - balance[a]) / np.ptp(work[a : b + 1])) for a, b in revs
        ]
        out.row.extra["drive_work_per_rev_J"] = [float(work[b] - work[a]) for a, b in revs]
        out.row.extra["drive_work_peak_to_peak_per_rev_J"] = [float(np.ptp(work[a : b + 1])) for a, b in revs]
        coupler = np.asarray(s["coupler_point"])
        torque = np.asarray(s["driving_torque"])
        period = [
            float(np.linalg.norm(coupler[a + per_rev : b + per_rev] - coupler[a:b], axis=1).max()) for a, b in revs[:-1]
        ]
        out.row.extra["coupler_change_per_rev_m"] = period
        out.row.extra["torque_change_per_rev_Nm"] = [
            float(np.abs(torque[a + per_rev : b + per_rev] - torque[a:b]).max()) for a, b in revs[:-1]
        ]
        e = out.row.extra["energy_balance_per_rev_rel"]
        text.append(
            f"{out.row.run}: |g| first/last revolution {out.row.extra['constraint_residual_per_rev'][0]:.1e}/"
            f"{out.row.extra['constraint_residual_per_rev'][-1]:.1e}, energy balance error per revolution "
            f"{e[0]:.1e}/{e[-1]:.1e} of the work exchanged in it "
            f"({out.row.extra['drive_work_peak_to_peak_per_rev_J'][-1]:.3g} J "
            f"peak to peak; net {out.row.extra['drive_work_per_rev_J'][-1]:.2g} J), "
            f"coupler repeats to {max(period[-3:]) if period else float('nan'):.1e} m and torque to "
            f"{max(out.row.extra['torque_change_per_rev_Nm'][-3:]) if period else float('nan'):.1e} N m "
            f"from one revolution to the next"
        )
    ctx.add(dyn.row)
    ctx.add(qs.row)
    ctx.finding("; ".join(text))


def case_soft(ctx: Context) -> None:
    from ffrf.fe.materials import PLA, Material

    moduli = (1.2e9, 1e7) if ctx.quick else (1.2e9, 1e8, 3e7, 1e7, 3e6)
    reference = None
    verdicts, limits = [], []
    for E in moduli:
        material = Material(E, PLA.nu, PLA.rho, f"PLA-like E={E:g}")
        scene = make_scene(material, h=6e-3, order=1, n_modes=8)
        out = simulate(
            ctx, scene, f"E = {E:g} Pa", "quasi_static", scene.t_end, n_outputs=37 if ctx.quick else 73, add=False
        )
        if len(out.time):
            d = deformation(scene, out)
            deviation = out.row.extra["max_coupler_deviation_m"]
            if reference is None:
                reference = (E, deviation)
                # rotations scale with 1/E while the response is linear: where they reach the limit
                limits.append(E * d["max_bore_rotation_rad"] / ROTATION_LIMIT_RAD)
            # a linear response scales with 1/E: 1 means "as linear as the reference material"
            scaling = deviation * E / (reference[0] * reference[1])
            out.row.extra.update(d, deviation_times_E_rel=scaling)
            verdicts.append(
                f"E = {E:g}: bore rotation {d['max_bore_rotation_rad']:.2g} rad, strain "
                f"{100 * d['max_equivalent_strain']:.2g} %, deviation {1e3 * deviation:.3g} mm (x E: "
                f"{scaling:.3g}) -> {'valid' if d['small_deformation_valid'] else 'OUTSIDE small deformation'}"
            )
        elif out.row.error:
            verdicts.append(f"E = {E:g}: failed ({out.row.error[:120]})")
        ctx.add(out.row)
    if limits:
        verdicts.append(
            f"bore rotations reach {ROTATION_LIMIT_RAD} rad at E = {limits[0]:.2g} Pa (1/E scaling from "
            f"the stiffest run): below that the linear floating-frame model is outside its assumptions "
            f"although it still converges and its answers stay proportional to 1/E"
        )
    ctx.finding("; ".join(verdicts))


def case_modes_mesh(ctx: Context) -> None:
    runs = ((6e-3, 4), (6e-3, 30)) if ctx.quick else ((4e-3, 8), (4e-3, 100), (1e-3, 8))
    text = []
    for h, modes in runs:
        started = time.perf_counter()
        label = f"h = {1e3 * h:g} mm, {modes} modes"
        try:
            scene = make_scene(None, h=h, order=1, n_modes=modes)
        except Exception as error:  # noqa: BLE001 - a mesh that fails becomes a row
            ctx.add(
                Row(
                    ctx.case,
                    label,
                    "build",
                    error=f"build failed: {type(error).__name__}: {error}",
                    wall_s=time.perf_counter() - started,
                )
            )
            continue
        build = time.perf_counter() - started
        qs = simulate(ctx, scene, label + " quasi-static", "quasi_static", scene.t_end, n_outputs=73, add=False)
        dyn = simulate(ctx, scene, label + " dynamic 0.05 s", "dynamic", 0.05, step=1e-3, n_outputs=11, add=False)
        freq = min(float(link.reduction.fixed_interface_frequencies_hz[-1]) for link in scene.links)
        for out in (qs, dyn):
            out.row.extra.update(
                build_s=build,
                nodes_per_link=[int(link.fe.nodes.shape[0]) for link in scene.links],
                n_coordinates=scene.system.n_coordinates,
                highest_mode_hz_min_over_links=freq,
            )
        ms = 1e3 * dyn.row.wall_s / max(dyn.row.steps, 1)
        text.append(
            f"{label}: build {build:.0f} s, {scene.system.n_coordinates} coordinates, quasi-static revolution "
            f"{qs.row.wall_s:.1f} s, dynamic {ms:.1f} ms/step (incl. assembly), max coupler deviation "
            f"{1e3 * qs.row.extra.get('max_coupler_deviation_m', float('nan')):.4g} mm"
        )
        ctx.add(qs.row)
        ctx.add(dyn.row)
    ctx.finding("; ".join(text))


def locked_screw_conditioning(n: int = 721) -> tuple[np.ndarray, np.ndarray]:
    """Smallest singular value of the 6 x 3 matrix of the undriven joints' screws (Pluecker
    coordinates, moments in m) of the ideal paper linkage along one revolution of the drive;
    zero would be a singular pose (the drive no longer determines the motion)."""
    from kinematics import BennettLinkage

    linkage = BennettLinkage.paper()
    drive = np.linspace(0.0, 2.0 * np.pi, n)
    out = np.empty(n)
    for k, angle in enumerate(drive):
        poses = linkage.link_poses(linkage.parameter_from_joint(linkage.home_theta[3] - angle, joint=3))
        movers = (poses[0], poses[1], poses[3])  # h0 on the base, h1 moves with link 1, h2 with link 3
        columns = []
        for pose, axis in zip(movers, linkage.axes[:3], strict=True):
            direction = pose.rotation_matrix() @ axis.direction
            columns.append(np.concatenate([direction, np.cross(pose.act(axis.point), direction)]))
        out[k] = np.linalg.svd(np.array(columns).T, compute_uv=False)[-1]
    return drive, out


def case_singular(ctx: Context) -> None:
    from ffrf.fe.materials import RIGID
    from ffrf.system.drives import rpm

    drive, sigma = locked_screw_conditioning()
    worst = float(np.degrees(drive[np.argmin(sigma)]))
    text = (
        f"smallest singular value of the undriven joints' screws {sigma.min():.3f} (at drive angle {worst:.0f} deg, "
        f"the folded pose) against {sigma.max():.3f} at best: no singular pose exists for the paper's linkage"
    )
    span = np.radians(60.0)
    runs = [("PLA", None, "quasi_static", 1.0), ("E=1e15", RIGID, "quasi_static", 1.0)]
    if not ctx.quick:
        runs += [("PLA", None, "dynamic", 60.0), ("E=1e15", RIGID, "dynamic", 60.0)]
    for name, material, mode, speed in runs:
        # start 30 deg before the folded pose (drive angle 360 = 0 deg) and cross it by 30 deg
        scene = make_scene(material, start_angle=np.radians(330.0), omega=rpm(speed), ramp_time=0.1, **COARSE)
        t_end = scene.drive.time_for_angle(span)
        out = simulate(
            ctx,
            scene,
            f"{name} {mode} through the folded pose at {speed:g} rpm",
            mode,
            t_end,
            step=5e-4,
            n_outputs=31 if ctx.quick else 121,
            add=False,
        )
        if len(out.iterations) and len(out.time) > 2:
            angle = np.degrees(np.asarray(out.sensors["drive_angle"]))
            out.row.extra["drive_angle_range_deg"] = [float(angle[0]), float(angle[-1])]
        ctx.add(out.row)
    ctx.finding(text)


CASES: dict[str, Callable[[Context], None]] = {
    "near_rigid": case_near_rigid,
    "misalignment": case_misalignment,
    "speed": case_speed,
    "long_run": case_long_run,
    "soft": case_soft,
    "modes_mesh": case_modes_mesh,
    "singular": case_singular,
}

#: Wall-time budget of each case's process (s), full and quick.
BUDGET = {
    "near_rigid": (900, 240),
    "misalignment": (900, 240),
    "speed": (1800, 300),
    "long_run": (2400, 300),
    "soft": (900, 240),
    "modes_mesh": (3600, 300),
    "singular": (900, 240),
}


# --------------------------------------------------------------------------------------------
# Driver: one process per case, a time budget, partial results kept
# --------------------------------------------------------------------------------------------


def _child(name: str, quick: bool, exudyn: bool, out: str, rows_file: str) -> None:
    import logging

    logging.basicConfig(level=logging.WARNING)
    ctx = Context(name, quick, exudyn, Path(out), Path(rows_file))
    try:
        CASES[name](ctx)
    except Exception as error:  # noqa: BLE001 - the case itself broke: record it, keep the rows so far
        ctx.add(
            Row(
                name,
                "(case)",
                "-",
                error=f"case raised {type(error).__name__}: {error}; "
                + " | ".join(traceback.format_exc(limit=4).splitlines()[-4:]),
            )
        )


def run_case(name: str, quick: bool, exudyn: bool, out: Path) -> dict:
    """Run one case in its own process within its budget; its rows and finding."""
    rows_file = out / "runs" / f"{name}.jsonl"
    rows_file.parent.mkdir(parents=True, exist_ok=True)
    rows_file.write_text("")
    budget = BUDGET[name][1 if quick else 0]
    started = time.perf_counter()
    process = multiprocessing.get_context("spawn").Process(
        target=_child, args=(name, quick, exudyn, str(out), str(rows_file))
    )
    process.start()
    process.join(budget)
    problem = ""
    if process.is_alive():
        process.terminate()
        process.join(10)
        if process.is_alive():
            process.kill()
        problem = f"case exceeded its time budget of {budget} s and was stopped; the rows before are kept"
    elif process.exitcode != 0:
        problem = f"case process died with exit code {process.exitcode} (crash or out of memory); rows before kept"
    rows, findings = [], []
    for line in rows_file.read_text().splitlines():
        record = json.loads(line)
        if "row" in record:
            rows.append(record["row"])
        else:
            findings.append(record["finding"])
    if problem:
        rows.append(asdict(Row(name, "(case)", "-", error=problem, wall_s=time.perf_counter() - started)))
        print(f"  [{name}] {problem}", flush=True)
    return {"case": name, "rows": rows, "findings": findings, "wall_s": time.perf_counter() - started}


def markdown(results: list[dict], quick: bool) -> str:
    """The issue's table and one paragraph per case."""
    lines = [
        f"# Hard cases{' (quick)' if quick else ''}",
        "",
        "Columns: converged; steps (time steps, or equilibria for quasi-static runs); Newton iterations "
        "(total); worst constraint residual |g| (m or rad); energy balance error (largest |W - dE - D| over "
        "the run / largest drive work); wall time (s, shared 2-core machine: noisy); difference to Exudyn.",
        "",
        "| case | run | mode | converged | steps | Newton it. | worst abs(g) | energy balance | time (s) "
        "| vs Exudyn | note |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for result in results:
        for r in result["rows"]:
            note = r["error"][:200].replace("|", "/") if r["error"] else ""
            lines.append(
                f"| {r['case']} | {r['run']} | {r['mode']} | {'yes' if r['converged'] else '**no**'} "
                f"| {r['steps']} | {r['newton_iterations']} | {_fmt(r['max_constraint_residual'], 1)} "
                f"| {_fmt(r['energy_balance_relative'], 1)} | {r['wall_s']:.1f} "
                f"| {r['exudyn'] or '-'} | {note} |"
            )
    lines.append("")
    for result in results:
        lines.append(
            f"**{result['case']}** ({result['wall_s']:.0f} s): " + " ".join(result["findings"] or ["(no finding)"])
        )
        lines.append("")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> list[dict]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", default=",".join(CASES), help=f"comma-separated subset of {','.join(CASES)}")
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "hard_cases")
    parser.add_argument("--quick", action="store_true", help="short windows and fewer points (a few minutes)")
    parser.add_argument("--no-exudyn", action="store_true", help="skip the Exudyn comparisons")
    args = parser.parse_args(argv)
    names = [n.strip() for n in args.cases.split(",") if n.strip()]
    unknown = sorted(set(names) - set(CASES))
    if unknown:
        parser.error(f"unknown case(s) {unknown}; choose from {list(CASES)}")
    args.out.mkdir(parents=True, exist_ok=True)
    # cases not rerun now are kept from an earlier run into the same directory (same --quick)
    kept: dict[str, dict] = {}
    previous = args.out / "hard_cases.json"
    if previous.exists():
        try:
            old = json.loads(previous.read_text())
            if old.get("quick") == args.quick:
                kept = {c["case"]: c for c in old.get("cases", [])}
        except (json.JSONDecodeError, KeyError, TypeError):
            kept = {}
    fresh: dict[str, dict] = {}
    results: list[dict] = []
    for name in names:
        print(f"case {name} ...", flush=True)
        fresh[name] = run_case(name, args.quick, not args.no_exudyn, args.out)
        results = [fresh[n] if n in fresh else kept[n] for n in CASES if n in fresh or n in kept]
        # rewrite after each case: an interrupted suite keeps what it has
        (args.out / "hard_cases.json").write_text(
            json.dumps({"quick": args.quick, "cases": results}, indent=1, default=_json_default)
        )
        (args.out / "hard_cases.md").write_text(markdown(results, args.quick))
    print(f"wrote {args.out / 'hard_cases.json'} and {args.out / 'hard_cases.md'}")
    return results


if __name__ == "__main__":
    main()
