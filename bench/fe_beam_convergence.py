"""Convergence of P1 and P2 tetrahedra against beam theory (prism 200 x 12 x 8 mm, PLA).

Usage (from the repository root)::

    .venv/bin/python -m bench fe_beam_convergence [--json out.json]

Prints, for each element order and mesh size h, the relative error of the first
bending (thin and wide direction) and torsion frequencies against Timoshenko
bending theory (Cowper shear coefficient) and Saint-Venant torsion, clamped-free
and free-free. The reference formulas live in ``tests/test_fe_models/ffrf_reference.py``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from bench import ROOT
from bench.report import write_report

CASES = [(1, 0.004), (1, 0.002), (1, 0.001), (2, 0.004), (2, 0.002)]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)
    # the same geometry, theory and mode classifier as the tests; ``tests/`` is not a package (its test folders are
    # imported from it by name, as pytest's rootdir does), so it goes on the path, which mypy does not see
    sys.path.insert(0, str(ROOT / "tests"))
    from test_fe_models import test_ffrf_beam_theory as beam  # type: ignore[import-not-found]

    rows = []
    print(f"{'P':>2} {'h mm':>5} {'bc':>13} {'bend_z %':>9} {'bend_y %':>9} {'torsion %':>10} {'s':>6}")
    for order, h in CASES:
        for bc in ("clamped-free", "free-free"):
            t0 = time.perf_counter()
            fe = beam.fe_first_frequencies(h, order, bc)
            ref = beam.theory(bc)
            errors = {k: 100.0 * (fe[k] / ref[k] - 1.0) if k in fe else float("nan") for k in ref}
            row = dict(
                order=order,
                h_m=h,
                bc=bc,
                errors_percent=errors,
                fe_hz=fe,
                theory_hz=ref,
                seconds=time.perf_counter() - t0,
            )
            rows.append(row)
            print(
                f"{order:2d} {h * 1e3:5.1f} {bc:>13} {errors['bend_z']:9.3f} "
                f"{errors['bend_y']:9.3f} {errors['torsion']:10.3f} {row['seconds']:6.1f}",
                flush=True,
            )
    if args.json:
        write_report(rows, args.json, echo=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
