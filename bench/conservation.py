"""Momentum and energy of a free, spinning, elastically excited flexible bar over 10^4 steps:
generalized-alpha (rho_inf = 1 and 0.8) against the variational midpoint integrator (issue 5).

The scene is the validation's free body (``validation.single_body_scenes.free_body_scene``: 0.2 m bar,
omega_bar = (1, 2, 30) rad/s, v = (0.1, 0, 0) m/s, elastic excitation from a 10 mN tip load), no
damping, no gravity. Momenta are summed node by node with the full FE mass matrix (independent
of the modal moments the solvers use); energy is kinetic + strain. Our generalized-alpha equals
Exudyn's on this scene to 1e-12 m (``tests/test_validation/test_ffrf_vs_exudyn.py``), so its
drift is the scheme's, not ours.

``--exudyn`` also runs Exudyn's generalized-alpha (rho_inf = 1 and 0.8) at the largest step on the
same scene and records whether it completes and its time (its twin run, a ``validation.twin_run.TwinRun``, has no
velocities, so no momenta).

Per run: largest relative change of linear and angular momentum, largest relative energy
error, energy drift (mean of the last tenth of the rows minus the first tenth), wall time and
Newton iterations per step. Writes ``DIR/conservation.json`` and ``DIR/conservation.md``.

Run: .venv/bin/python -m bench conservation [--steps 10000] [--sizes 1e-4 5e-5] --out out/bench/conservation
"""

from __future__ import annotations

import argparse
import functools
import json
import time
from pathlib import Path

import numpy as np


def momenta(body, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """Linear and angular momentum about the origin (6,), node by node with the full mass matrix."""
    from ffrf.body.euler_parameters import g_bar, rotation_matrix

    a, omega = rotation_matrix(q[3:7]), g_bar(q[3:7]) @ qd[3:7]
    u = body.nodes + (body.basis @ q[7:]).reshape(-1, 3)
    velocities = qd[:3] + (np.cross(omega, u) + (body.basis @ qd[7:]).reshape(-1, 3)) @ a.T
    forces = (body.mass @ velocities.reshape(-1)).reshape(-1, 3)
    positions = q[:3] + u @ a.T
    return np.concatenate([forces.sum(axis=0), np.cross(positions, forces).sum(axis=0)])


def measure(system, body, result, wall: float) -> dict:
    rows = np.array([momenta(body, q, qd) for q, qd in zip(result.q, result.qd, strict=True)])
    energy = np.array([sum(system.energies(q, qd).values()) for q, qd in zip(result.q, result.qd, strict=True)])
    error = (energy - energy[0]) / energy[0]
    window = max(1, len(error) // 10)
    linear, angular = rows[:, :3], rows[:, 3:]
    return {
        "linear_momentum_rel": float(np.abs(linear - linear[0]).max() / np.linalg.norm(linear[0])),
        "angular_momentum_rel": float(np.abs(angular - angular[0]).max() / np.linalg.norm(angular[0])),
        "energy_error_rel": float(np.abs(error).max()),
        "energy_drift_rel": float(error[-window:].mean() - error[:window].mean()),
        "wall_s": wall,
        "newton_per_step": float(np.mean(result.newton_iterations)),
        "complete": bool(result.complete),
    }


def run_exudyn_points(h: float, steps: int) -> list[dict]:
    """Exudyn on the same scene: completion and time only."""
    from validation.exudyn_ffrf import run_exudyn
    from validation.reduced_body import bar_body
    from validation.single_body_scenes import free_body_scene

    out = []
    for rho_inf in (1.0, 0.8):
        scene = free_body_scene(bar_body(), step=h, t_end=steps * h, rho_inf=rho_inf)
        started = time.perf_counter()
        try:
            run_exudyn(scene)
            complete, note = True, ""
        except RuntimeError as failure:
            complete, note = False, str(failure)
        point = {
            "integrator": f"Exudyn generalized-alpha rho_inf={rho_inf:g}",
            "step_s": h,
            "steps": steps,
            "wall_s": time.perf_counter() - started,
            "complete": complete,
            "note": note,
        }
        print(point, flush=True)
        out.append(point)
    return out


def run(sizes: list[float], steps: int) -> list[dict]:
    from ffrf.errors import NewtonDivergence
    from ffrf.solvers.generalized_alpha import generalized_alpha
    from ffrf.solvers.variational_midpoint import variational_midpoint
    from validation.exudyn_ffrf import ffrf_system
    from validation.reduced_body import bar_body
    from validation.single_body_scenes import free_body_scene

    body = bar_body()
    out = []
    for h in sizes:
        scene = free_body_scene(body, step=h, t_end=steps * h, rho_inf=1.0)
        system, q0, qd0 = ffrf_system(scene)
        every = max(1, steps // 500)
        runs = {
            "generalized-alpha rho_inf=1": functools.partial(
                generalized_alpha, system, q0, qd0, scene.t_end, h, rho_inf=1.0, output_every=every
            ),
            "generalized-alpha rho_inf=0.8": functools.partial(
                generalized_alpha, system, q0, qd0, scene.t_end, h, rho_inf=0.8, output_every=every
            ),
            "variational midpoint": functools.partial(
                variational_midpoint, system, q0, qd0, scene.t_end, h, output_every=every
            ),
        }
        for name, call in runs.items():
            started = time.perf_counter()
            try:
                result = call()
            except NewtonDivergence as failure:
                result = failure.partial
                print(f"  {name} h={h:g}: {failure}")
            point = {
                "integrator": name,
                "step_s": h,
                "steps": steps,
                **measure(system, scene.body, result, time.perf_counter() - started),
            }
            print(
                f"h={h:g} {name}: "
                + ", ".join(f"{k}={v:.3g}" for k, v in point.items() if isinstance(v, float) and k != "step_s"),
                flush=True,
            )
            out.append(point)
    return out


def write(points: list[dict], directory: Path) -> None:
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "conservation.json").write_text(json.dumps(points, indent=2))
    lines = [
        "| integrator | h (s) | steps | linear momentum | angular momentum | energy error | energy drift | "
        "Newton/step | time (s) | completed |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for p in points:
        if "linear_momentum_rel" not in p:  # Exudyn: completion only
            lines.append(
                f"| {p['integrator']} | {p['step_s']:g} | {p['steps']} | | | | | | {p['wall_s']:.1f} | "
                f"{'yes' if p['complete'] else 'no: ' + p['note']} |"
            )
            continue
        lines.append(
            f"| {p['integrator']} | {p['step_s']:g} | {p['steps']} | {p['linear_momentum_rel']:.1e} | "
            f"{p['angular_momentum_rel']:.1e} | {p['energy_error_rel']:.1e} | {p['energy_drift_rel']:.1e} | "
            f"{p['newton_per_step']:.1f} | {p['wall_s']:.1f} | {'yes' if p['complete'] else 'no'} |"
        )
    (directory / "conservation.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=float, nargs="+", default=[1e-4, 5e-5, 2.5e-5])
    parser.add_argument("--steps", type=int, default=10_000)
    parser.add_argument("--out", type=Path, default=Path("out/bench/conservation"))
    parser.add_argument("--exudyn", action="store_true", help="also run Exudyn at the largest step")
    args = parser.parse_args()
    points = run(args.sizes, args.steps)
    if args.exudyn:
        points += run_exudyn_points(max(args.sizes), args.steps)
    write(points, args.out)


if __name__ == "__main__":
    main()
