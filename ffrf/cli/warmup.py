"""``python -m ffrf warmup``: compile the solver's kernels once after install (the main job's first step)."""

from __future__ import annotations

import argparse
import sys
import time

from ffrf.scenes.kernel_warmup import warm_kernels

__all__ = ["HELP", "configure", "run"]

HELP = "compile the solver's kernels once after install (the main job's first step)"


def configure(parser: argparse.ArgumentParser) -> None:
    """No options: what it compiles is what a default run uses."""


def run(args: argparse.Namespace) -> int:
    """Compile the numba kernels the main job uses, once after install (numba caches them on disk, next to the
    sources): a coarse Bennett through a few quasi-static equilibria (:func:`warm_kernels`). Kernels do not depend
    on the mesh or the number of modes, so the default scene's runs then load them. The dynamic solver's kernels
    (``--dynamic``, the validation's dynamic window) are left to their first use: the main job never calls them
    (issue #22)."""
    print(
        "Compiling the solver's kernels (once after install; later runs load them from numba's cache)", file=sys.stderr
    )
    started = time.perf_counter()
    steps = (("quasi-static and stability kernels", warm_kernels),)
    for k, (name, step) in enumerate(steps, start=1):
        began = time.perf_counter()
        print(f"  [{k}/{len(steps)}] {name} ...", end="", file=sys.stderr, flush=True)
        step()
        print(f" {time.perf_counter() - began:.1f} s", file=sys.stderr)
    print(f"kernels ready in {time.perf_counter() - started:.1f} s", file=sys.stderr)
    return 0
