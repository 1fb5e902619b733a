"""Textbook buckling checks with known answers (issue #20): the figures behind ``tests/test_textbook``.

1. A von Mises truss of two flexible bars from a scene file, run with ``stability = true`` (quasi-static, on past
   the fold, Eq. (S6)): its snap load against the closed form P_max = 2 k (L0 - L*) z* / L*.
2. A cantilever of n flexible segments joined rigidly: the load where the smallest squared frequency of Eq. (B1)
   at the straight equilibrium reaches zero, against Euler's pi^2 EI / (4 L^2), and against the discrete chain
   of the same structure (beam-theory segments: the structure's error; the FE segment's condensed stiffness:
   the FE segment's and our implementation's), with the observed rate log2(e_n / e_2n).

The geometry, the closed forms and the chain model are ``validation/textbook_cases.py``. Prints one JSON object.

Usage::

    .venv/bin/python -m bench textbook_buckling [--segments 1 2 4 8 16] [--json OUT.json]

Timings are wall-clock on a shared machine (set OPENBLAS_NUM_THREADS=1 there).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from bench.report import write_report
from ffrf import load
from validation.textbook_cases import (
    COLUMN_LOAD,
    EULER_LOAD,
    LOAD_RATE,
    beam_segment_stiffness,
    buckling_load,
    chain_buckling_load,
    column_scene,
    segment_stiffness,
    smallest_squared_frequency,
    truss_closed_form,
    write_truss_scene,
)


def truss(directory: Path) -> dict:
    """The truss's snap from a scene-file run against the closed form."""
    started = time.perf_counter()
    result = load(write_truss_scene(directory)).run()
    result.save(directory / "out")
    metadata = result.metadata
    snap = metadata["stability"]["snaps"][0]
    closed = truss_closed_form()
    return {
        "limit_load_N": snap["time_s"] * LOAD_RATE,
        "closed_form_N": closed["limit_load"],
        "relative_error": snap["time_s"] * LOAD_RATE / closed["limit_load"] - 1.0,
        "euler_load_over_largest_bar_force": closed["euler_load"] / closed["force_flat"],
        "energy_released_J": snap["energy_released_J"],
        "wall_time_s": time.perf_counter() - started,
    }


def column(n: int, directory: Path) -> dict:
    """One row of the convergence table: n segments (n = 1 has no buckling load: the load adds no stiffness)."""
    started = time.perf_counter()
    scene = column_scene(n, directory)
    beam = chain_buckling_load(n, beam_segment_stiffness(n)) if n > 1 else None
    row: dict = {"segments": n, "chain_beam_error": None if beam is None else beam / EULER_LOAD - 1.0}
    if n == 1:
        mu = smallest_squared_frequency(scene)
        row["squared_frequency_change_at_2_euler"] = mu(2.0 * EULER_LOAD / COLUMN_LOAD) / mu(0.0) - 1.0
        row["buckling_load_N"] = None
    else:
        assert beam is not None  # n > 1
        load = buckling_load(scene, EULER_LOAD)
        chain = chain_buckling_load(n, segment_stiffness(scene))
        row.update(
            buckling_load_N=load,
            error_vs_euler=load / EULER_LOAD - 1.0,
            error_vs_chain_of_fe_segments=load / chain - 1.0,
            fe_segment_effect=(chain - beam) / EULER_LOAD,
        )
    row["wall_time_s"] = time.perf_counter() - started
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--segments", type=int, nargs="+", default=[1, 2, 4, 8, 16])
    parser.add_argument("--json", type=Path, help="also write the JSON object to this file")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        rows = [column(n, Path(folder)) for n in args.segments]
        out = {"von_mises_truss": truss(Path(folder)), "euler_load_N": EULER_LOAD, "column": rows}
    errors = [(r["segments"], r["error_vs_euler"]) for r in rows if r["buckling_load_N"] is not None]
    out["rates"] = [
        {"from": a, "to": b, "rate": float(np.log(ea / eb) / np.log(b / a))}
        for (a, ea), (b, eb) in zip(errors, errors[1:], strict=False)
    ]
    if args.json:
        write_report(out, args.json)
    else:
        print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
