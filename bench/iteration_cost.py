"""What one Newton iteration of a dynamic step costs, piece by piece, against its floor (issue #22), and how the
pieces grow with the modes per link.

For the default Bennett discretisation (P2, 6 mm) with ``--modes`` fixed-interface modes per link, timed inside
numba (a jitted loop of ``--calls`` calls, best of five; no Python call overhead), warm kernels:

* ``residual_us``: Eq. (G1), ``system_residual``, split into the bodies' terms (Eqs. (F8)-(F11)) and the
  constraints' (Eqs. (J1)-(J3), ``g`` and ``C_q^T lambda``);
* ``back_substitution_us``: one solve with kept LU factors of the iteration matrix (``lu_solve``), the floor of
  an iteration of modified Newton besides the residual;
* ``iteration_matrix_us`` and ``factorisation_us``: Eq. (FP6) and its LU (scipy), what a refactorisation adds;
* a dynamic run of ``--t-end`` s of the ramp at 10 ms steps: ms per step, Newton iterations per step, and per
  iteration (wall time over iterations, Python's share of a step included).

Usage::

    .venv/bin/python -m bench iteration_cost --modes 4 8 16 32 --json out/iteration_cost.json
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np
import scipy.linalg
from numba import njit

from bench.report import write_report
from ffrf.paper.bennett_scene import build_bennett
from ffrf.scenes.assembly import assemble
from ffrf.solvers.common import consistent_accelerations
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.solvers.newton_kernels import lu_solve
from ffrf.system.packed_system import pack_system
from ffrf.system.system_kernels import _body_residuals, _constraint_forces, system_residual


@njit(cache=True)
def _residuals(calls, bodies, joints, q, qd, qdd, lam, gravity, phi):
    total = 0.0
    for _ in range(calls):
        total += system_residual(bodies, joints, q, qd, qdd, lam, gravity, phi)[0][0]
    return total


@njit(cache=True)
def _body_terms(calls, bodies, q, qd, qdd, gravity):
    total = 0.0
    for _ in range(calls):
        total += _body_residuals(bodies, q, qd, qdd, gravity)[0]
    return total


@njit(cache=True)
def _constraint_terms(calls, joints, offsets, q, phi, lam):
    total = 0.0
    for _ in range(calls):
        total += _constraint_forces(joints, offsets, q, phi, lam, np.zeros(q.shape[0]))[0]
    return total


@njit(cache=True)
def _solves(calls, lu, piv, rhs):
    total = 0.0
    for _ in range(calls):
        total += lu_solve(lu, piv, rhs)[0]
    return total


def best_us(run, calls: int) -> float:
    """Microseconds per call of ``run(calls)``, best of five (after one warm call)."""
    run(1)
    best = np.inf
    for _ in range(5):
        started = time.perf_counter()
        run(calls)
        best = min(best, time.perf_counter() - started)
    return 1e6 * best / calls


def measure(modes: int, calls: int, t_end: float) -> dict:
    """The pieces' times and a dynamic run's figures for ``modes`` modes per link."""
    scene = build_bennett("pla", n_modes=modes)
    system = scene.system
    q = assemble(scene).q
    qd = np.zeros_like(q)
    qdd, lam = consistent_accelerations(system, q, qd)
    packed = pack_system(system)
    if packed is None:
        raise RuntimeError("the PLA Bennett scene has no packed form: ffrf.system.packed_system cannot time it")
    bodies, joints, q_, qd_, qdd_, lam_, gravity, phi = packed._kernel_arguments(q, qd, qdd, lam, 0.0)
    matrix = packed.iteration_matrix(q, qd, qdd, lam, 0.0, 1.0, 3e-5, 6e-3)
    lu, piv = scipy.linalg.lu_factor(matrix)
    rhs = np.ones(matrix.shape[0])
    row = {
        "modes_per_link": modes,
        "coordinates": system.n_coordinates,
        "unknowns": matrix.shape[0],
        "residual_us": best_us(lambda c: _residuals(c, bodies, joints, q_, qd_, qdd_, lam_, gravity, phi), calls),
        "body_terms_us": best_us(lambda c: _body_terms(c, bodies, q_, qd_, qdd_, gravity), calls),
        "constraint_terms_us": best_us(lambda c: _constraint_terms(c, joints, bodies[0], q_, phi, lam_), calls),
        "back_substitution_us": best_us(lambda c: _solves(c, lu, piv, rhs), calls),
        "iteration_matrix_us": best_us(
            lambda c: [packed.iteration_matrix(q, qd, qdd, lam, 0.0, 1.0, 3e-5, 6e-3) for _ in range(c)],
            max(1, calls // 20),
        ),
        "factorisation_us": best_us(lambda c: [scipy.linalg.lu_factor(matrix) for _ in range(c)], max(1, calls // 20)),
    }
    generalized_alpha(system, q, qd, 0.05, 1e-2)  # the integrator's kernels, compiled or loaded
    run = generalized_alpha(system, q, qd, t_end, 1e-2, output_every=10)
    iterations = int(run.newton_iterations.sum())
    row.update(
        dynamic_steps=len(run.newton_iterations),
        iterations_per_step=iterations / len(run.newton_iterations),
        ms_per_step=1e3 * run.wall_time / len(run.newton_iterations),
        us_per_iteration=1e6 * run.wall_time / iterations,
    )
    return row


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--modes", type=int, nargs="+", default=[4, 8, 16, 32])
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--t-end", type=float, default=5.0, help="dynamic run from rest, into the ramp (s)")
    parser.add_argument("--json", type=Path, required=True)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    rows = []
    for modes in args.modes:
        rows.append(measure(modes, args.calls, args.t_end))
        print({key: round(value, 2) if isinstance(value, float) else value for key, value in rows[-1].items()})
    report = {"scene": "default PLA Bennett (6 mm P2), 10 ms steps, warm kernels", "rows": rows}
    write_report(report, args.json, echo=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
