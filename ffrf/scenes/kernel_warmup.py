"""Compile the solver's kernels once, before the first real run needs them: numba compiles on first use and then
loads from its cache on disk (``cache=True``), so one small run through every kernel a run uses makes every later
run, in this process or another, start warm. Kernels do not depend on the mesh or the number of modes."""

from __future__ import annotations

from ffrf.scenes.linkage_file import linkage_options
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.linkage_scene import build_linkage

__all__ = ["WARMUP_LINKAGE", "warm_kernels"]

#: The paper's Bennett from its DH table with coarse links (12 mm P1 elements, two modes): small enough to build
#: in seconds, and it passes through every kernel of a quasi-static run with stability monitoring.
WARMUP_LINKAGE = {
    "linkage": {
        "dh": {"a": [110, 220, 110, 220], "alpha_deg": [150, 90, 150, 90]},
        "unit": "mm",
        "driver": 3,
        "tool_link": 2,
        "start_angle_deg": -90.0,
        "h": 0.012,
        "order": 1,
        "modes": 2,
    }
}


def warm_kernels(dynamic: bool = False) -> None:
    """Run :data:`WARMUP_LINKAGE` through three quasi-static equilibria with stability monitoring: every kernel
    of a quasi-static run is compiled, or loaded from numba's cache; with ``dynamic`` also two dynamic steps, for
    the kernels of generalized-alpha and its error estimate (what a cross-validation's dynamic runs call)."""
    loop, options, _ = linkage_options(WARMUP_LINKAGE, "the warm-up linkage")
    scene = build_linkage(loop, options)
    run_linkage(scene, mode="quasi_static", n_outputs=3, t_end=0.2, stability=True)
    if dynamic:
        run_linkage(scene, mode="dynamic", n_outputs=3, t_end=0.02, step=0.01)
